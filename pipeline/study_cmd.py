"""``rockmass study CONFIG --out DIR [--workers N] [--scheduler ADDRESS]``: many cases of one chain.

CONFIG is a rockmass config (its ``[blocks]``, ``[solve]``, ``[fractal]``, ... sections are the
*base*) with a ``[study]`` section (:mod:`rockmass.study_config`) that varies fields over a grid
and/or a list, with a number of realizations (seeds). Each case builds its block model, box-counts
its joint network (D_box with R², P21) and runs its DEM stages (:mod:`rockmass.study`).

Writes under ``--out``:

- ``cases/<case id>/case.json``: one per finished case (its config, parameters, seed, every value
  measured, timings), written atomically as the case finishes, and beside it ``config.toml``, the
  case as a config of its own (``rockmass solve cases/<id>/config.toml --out DIR`` reruns it with
  every output of the single-stage commands);
- ``results.csv``: one row per finished case in case order, rebuilt (atomically) after every case;
- ``report.html``: self-contained (images embedded): the cases per outcome, D_box against the
  maximum displacement of the cases in equilibrium coloured by θ (Jiang et al., Figs. 7–8,
  docs/sources.md §1; failed-block cases apart), the spread over realizations, the cases not in equilibrium with
  their reason, the table;
- ``manifest.json``: command, config and its hash, seeds, executor, counts, timings.

Every case is validated before any runs (exit 2 naming the study field and the case). Each case
ends with an outcome (results.csv ``status``, :data:`rockmass.study.OUTCOMES`): ok, failed_blocks,
not_converged, unstable, overlap or error. Re-running the same study skips every finished case
(same case id = hash of the resolved case config) of any outcome but ``error`` (the chain is
deterministic). Cases that fail are recorded with their error or diagnostic, the others go on.
Exit code: 0 when every case ended ok, failed_blocks or not_converged (blocks that fail and stages
that do not converge are results of the study, counted in its summary); 1 when a case ended in
error (a re-run retries it) or was stopped by the solver (overlap, unstable: a re-run keeps it).

Executors: ``--scheduler ADDRESS`` (or the ``DASK_SCHEDULER_ADDRESS`` environment variable) runs on
a Dask cluster (``pip install rockmass[dask]``; the workers need rockmass installed); otherwise a
local pool of ``--workers`` processes (default: the number of CPUs), or serially with
``--workers 1``.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import time
from collections.abc import Iterator

from .errors import InputError, RunError

__all__ = ["add_parser", "run"]


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1, got {value}")
    return value


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register the ``study`` subcommand."""
    p = subparsers.add_parser(
        "study", help="run a study (grid / list of config fields x realizations) locally or on Dask",
        description="Run the chain (blocks, box counting, DEM) for every case of a [study] "
                    "section: results.csv, per-case folders, report.html and manifest.json. "
                    "Resumable: finished cases are skipped.")
    p.add_argument("config", help="TOML file with the base sections and a [study] section")
    p.add_argument("--out", required=True, help="study folder (results.csv, cases/, report.html, "
                                                "manifest.json); re-use it to resume")
    p.add_argument("--workers", type=_positive_int, default=None,
                   help="local worker processes (default: the number of CPUs; 1 runs serially)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="Dask scheduler address (default: $DASK_SCHEDULER_ADDRESS; without "
                        "either, cases run locally)")
    p.add_argument("--connect-timeout", type=float, default=30.0, metavar="SECONDS",
                   help="how long to try to reach the Dask scheduler (default 30)")
    p.add_argument("--list", action="store_true",
                   help="validate, print the cases (id, parameters, seed, finished or not) and exit")
    p.add_argument("--json", action="store_true", help="print the study summary as JSON")
    p.set_defaults(handler=run)
    return p


def _log(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def _connect(address: str, timeout_s: float):
    try:
        from dask.distributed import Client
    except ImportError as exc:
        raise InputError(f"--scheduler {address}: Dask is not installed (pip install "
                         "'rockmass[dask]')") from exc
    try:
        return Client(address, timeout=f"{max(timeout_s, 0.1)}s", set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise InputError(f"--scheduler {address}: cannot reach the Dask scheduler: {exc}") from exc


def _preflight(pending, config_path) -> None:
    """Build the blocks and solver settings of the first pending case whose input files are all
    there: a ``[solve]`` that does not fit the model (an excavation name that is not a region, a
    selector) is bad input, found before any case runs. A case with a missing input file is left to
    fail on its own (its error is its result)."""
    from .study import _build_model

    case = next((c for c in pending if "missing" not in c.inputs.values()), None)
    if case is None or case.document.solve is None:
        return
    solve = case.document.solve
    try:
        model = _build_model(case.document, config_path)
    except RunError:
        return  # a failing case is the case's result, not a config error
    solve.to_settings(model, config_path)


def _read_case_traces(path, owner) -> None:
    """The trace map that cuts a case's blocks, read whole (its warnings come when the case runs)."""
    from .inputs import read_trace_file

    read_trace_file(path, "blocks.traces", quiet=True)


def _read_case_history(path, owner) -> None:
    """A ``type = "csv"`` velocity history of a case's ``[solve]`` (``owner``: its history
    table), read whole."""
    owner.read(path)


#: File keys (key paths without list indices) whose content a study reads before any case runs,
#: and how: ``check(path, owner)``, ``owner`` the config table that holds the key. These are the
#: file keys a case reads (:func:`rockmass.study_config._case_files`; ``solve.blocks_file`` is
#: refused in a study, :func:`rockmass.study_config.expand_cases`); another would be read when its
#: case runs.
_CASE_FILE_CHECKS = {("blocks", "traces"): _read_case_traces,
                     ("solve", "velocity_inputs", "history", "file"): _read_case_history}


def _owner(document, keys):
    """The config table that holds the file key at ``keys`` (a key path of
    :func:`rockmass.strict.file_fields`)."""
    node = document
    for key in keys[:-1]:
        node = node[key] if isinstance(key, int) or isinstance(node, dict) else getattr(node, key)
    return node


def _check_case_files(cases, config_path, digests: dict) -> None:
    """Read the content of every file the cases read before the first case runs (issue 18): a
    broken file is bad input (exit 2) naming the config, the field, the file and the case, not an
    error found case by case after others ran. Each distinct file is read once.

    A missing file that every case reads (a base config's ``[solve]`` history, say) is bad input
    too: no case could run. One that only some cases read (a grid over ``blocks.traces``) is left
    to fail its own cases (a re-run retries them once the file is there)."""
    from .errors import reading
    from .study_config import _case_files, _show
    from .strict import config_file

    def where(case) -> str:
        return (f"study case {case.index}: {case.text}; no "
                "case has run")

    checked: set[str] = set()
    missing: dict[str, tuple[str, dict]] = {}  # path -> (field, {case index: case} reading it)
    for case in cases:
        for keys, name in _case_files(case.document):
            field = _show(keys)
            path = config_file(config_path, name)
            key = os.fspath(path)
            if digests.get(key) is None:
                missing.setdefault(key, (field, {}))[1][case.index] = case
                continue
            check = _CASE_FILE_CHECKS.get(tuple(k for k in keys if not isinstance(k, int)))
            if check is None or key in checked:
                continue
            checked.add(key)
            try:
                with reading(path, field, config=config_path):
                    check(path, _owner(case.document, keys))
            except InputError as exc:
                raise InputError(f"{exc} ({where(case)})") from None
    for key, (field, readers) in missing.items():
        if len(readers) == len(cases):
            raise InputError(f"{config_path}: {field}: {os.path.basename(key)}: no such file, and "
                             "every case reads it (paths are relative to the config file; "
                             f"{where(next(iter(readers.values())))})")


def _check_memory_budget(pending, config_path, workers: int) -> None:
    """Refuse (exit 2), before any case runs, a study whose largest case needs more memory than
    the limit when ``workers`` cases run at once (:mod:`rockmass.budgets`): each worker builds
    and solves one case at a time, so the memory is the workers times the largest case's blocks
    (:func:`rockmass.blocks_stage.block_memory_estimate`), whatever the number of cases and
    realizations. The message names the field, the case and the estimate."""
    from .blocks_stage import block_memory_estimate
    from .budgets import check_memory
    from .study import case_domain_xy

    largest = None
    for case in pending:
        cfg = case.document.blocks
        try:
            estimate = block_memory_estimate(cfg, case_domain_xy(case.document), cfg.joint_sets())
        except (ValueError, AttributeError):  # the case reports it when it runs
            continue
        if estimate is not None and (largest is None or estimate[0] > largest[0][0]):
            largest = estimate, case
    if largest is None:
        return
    (needed, field, what, fix), case = largest
    check_memory(workers * needed, f"{config_path}: {field}",
                 f"{workers} worker(s) at once, each on a case of up to {what} (study case "
                 f"{case.index}: {case.text}, the largest of "
                 f"{len(pending)} cases to run)",
                 f"{fix}, or run fewer workers (--workers)")


def _case_header(case, config_path) -> str:
    """The comment lines that head a case's config.toml: where it comes from, how to rerun it."""
    return (f"# study case {case.index} ({case.case_id}) of {os.path.abspath(config_path)}\n"
            f"# {case.text}; realization {case.realization}, "
            f"seed {case.seed}\n# rerun it alone with its outputs: rockmass solve config.toml "
            "--out DIR (or rockmass blocks)\n")


def _write_case_config(folder, case, config_path) -> None:
    """``folder/config.toml``: the case as a config of its own (atomically), headed by
    :func:`_case_header`."""
    from .atomic import atomic_write_text
    from .study_config import standalone_config, toml_text

    atomic_write_text(folder / "config.toml", _case_header(case, config_path)
                      + toml_text(standalone_config(case, config_path)))


def _remove_debris(out) -> None:
    """Temporary files that a killed study left in ``out`` and its case folders."""
    from .outputs import remove_write_debris

    for folder in [out, *sorted((out / "cases").glob("*/"))]:
        if folder.is_dir() and not folder.is_symlink():
            remove_write_debris(folder)


@contextlib.contextmanager
def _terminate_as_interrupt() -> Iterator[None]:
    """Within the block, SIGTERM stops the study as Ctrl-C does (its workers ended, the finished
    cases kept, exit 130) instead of killing this process and leaving its pool workers behind."""
    import signal

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    try:
        previous = signal.signal(signal.SIGTERM, interrupt)
    except ValueError:  # not the main thread: leave signals alone
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def run(args) -> int:
    """Handler of ``rockmass study``."""
    from .atomic import atomic_write_json, atomic_write_text
    from .outputs import output_folder, print_json, refuse_links
    from .solver.result import FAILED_STATUSES
    from .study import (CASE_FILE, RESULTS_FILE, RETRIED, case_cost, csv_text,
                        displacement_m, load_finished, outcome_counts, outcome_summary,
                        results_rows, run_tasks)
    from .study_config import expand_cases, input_records, load_study

    t_start = time.perf_counter()
    document, raw = load_study(args.config)
    digests: dict = {}  # each file the cases read, hashed once (case ids, then the manifest)
    cases = expand_cases(document, raw, args.config, digests)
    study = document.study
    t_cases = time.perf_counter()

    from pathlib import Path

    out_path = Path(args.out)
    if out_path.is_dir():  # never write (or read cases) through a link inside --out (issue 18)
        refuse_links(out_path, ["cases", *(f"cases/{c.short_id}" for c in cases)])
    finished = load_finished(out_path, cases) if out_path.is_dir() else {}
    pending = [c for c in cases if c.case_id not in finished]
    if args.list:
        for c in cases:
            state = "finished" if c.case_id in finished else "pending"
            print(f"{c.index:5d}  {c.short_id}  {state:8s}  r={c.realization} seed={c.seed}  "
                  f"{c.text}")
        return 0

    scheduler = args.scheduler or os.environ.get("DASK_SCHEDULER_ADDRESS") or None
    workers = args.workers if args.workers is not None else (os.cpu_count() or 1)
    workers = max(1, min(workers, len(pending) or 1))
    client = None
    if pending:
        _check_case_files(pending, args.config, digests)
        # a Dask worker runs one case at a time, in memory of its own
        _check_memory_budget(pending, args.config, workers if scheduler is None else 1)
        _preflight(pending, args.config)
        if scheduler is not None:
            client = _connect(scheduler, args.connect_timeout)

    config_path = os.path.abspath(args.config)
    tasks = [{"case": c.index, "case_id": c.case_id, "config": c.raw, "config_path": config_path,
              "params": c.params, "realization": c.realization, "seed": c.seed,
              "cost": case_cost(c.document)} for c in pending]  # cost: pools run longest first
    by_id = {c.case_id: c for c in cases}
    failed: dict[str, dict] = {}
    counter = {"done": 0}
    executor = "none"
    status = "interrupted"
    interrupted = False
    if out_path.is_dir():
        _remove_debris(out_path)
    with output_folder(args.out) as out:
        def write_results():
            header, rows = results_rows(cases, {**finished, **failed}, study.displacement)
            atomic_write_text(out / RESULTS_FILE, csv_text(header, rows))

        def on_done(result: dict) -> None:
            case = by_id[result["case_id"]]
            record = {**result, "case_id": case.case_id, "config": case.raw}
            folder = out / "cases" / case.short_id
            _write_case_config(folder, case, args.config)
            atomic_write_json(folder / CASE_FILE, record, nan_as_null=True)  # last: marks it done
            if result["status"] in RETRIED:
                failed[case.case_id] = record
            else:  # any other outcome is the case's result (kept on resume)
                finished[case.case_id] = record
                failed.pop(case.case_id, None)
            write_results()
            counter["done"] += 1
            _log(f"[{counter['done']}/{len(pending)}] case {case.index} ({case.short_id}) "
                 f"{case.text} r={case.realization}: "
                 f"{_case_outcome_text(result, displacement_m(result, study.displacement))} "
                 f"({result.get('wall_time_s') or 0.0:.1f} s)")

        for case in cases:  # folders of an older rockmass, or copied without it
            folder = out / "cases" / case.short_id
            if case.case_id in finished and not (folder / "config.toml").exists():
                _write_case_config(folder, case, args.config)
        _log(f"rockmass study: {len(cases)} cases, {len(cases) - len(pending)} already finished "
             f"(skipped), {len(pending)} to run")
        write_results()
        t_run = time.perf_counter()
        try:
            with _terminate_as_interrupt():
                executor = run_tasks(tasks, on_done, workers=workers, scheduler=scheduler,
                                     client=client)
            stopped = [r for r in finished.values() if r.get("status") in FAILED_STATUSES]
            status = "complete" if not failed and not stopped else "failed cases"
        except KeyboardInterrupt:
            interrupted = True
        finally:
            if client is not None:
                client.close()
            t_end = time.perf_counter()
            from .study_report import write_report

            records = [r for c in cases for r in [finished.get(c.case_id) or
                                                  failed.get(c.case_id)] if r is not None]
            summary = {"cases": len(cases), "finished": len(finished), "failed": len(failed),
                       "skipped": len(cases) - len(pending), "ran": counter["done"],
                       "executor": executor, "status": status,
                       "outcomes": outcome_counts(records),
                       "outcome_summary": outcome_summary(records, len(cases))}
            try:
                write_report(out / "report.html", document, cases, finished, failed, summary,
                             args.config)
            except Exception as exc:  # noqa: BLE001 - a report problem must not hide the results
                _log(f"rockmass study: report.html not written: {type(exc).__name__}: {exc}")
            timings = {"cases_s": t_cases - t_start, "run_s": t_end - t_run,
                       "total_s": t_end - t_start,
                       "case_wall_time_sum_s": sum(r.get("wall_time_s", 0.0)
                                                   for r in finished.values())}
            manifest = _study_manifest(args, document, cases, timings,
                                       {**summary, "workers": workers if scheduler is None else None,
                                        "scheduler": scheduler})
            manifest["inputs"] += input_records(digests)  # hashed once, by expand_cases
            atomic_write_json(out / "manifest.json", manifest)
    if interrupted:
        _log(f"rockmass study: interrupted: {len(finished)} of {len(cases)} cases are finished and "
             f"kept in {out_path} (results.csv, report.html); run the same command again to "
             "resume")
        return 130
    if args.json:
        print_json(summary)
    else:
        print(f"{len(finished)}/{len(cases)} cases finished ({summary['skipped']} skipped, "
              f"{summary['ran']} run, {len(failed)} failed) with {executor} in "
              f"{t_end - t_run:.1f} s; {out_path / RESULTS_FILE}, {out_path / 'report.html'}")
        print(summary["outcome_summary"])
    problems = _problems(len(failed), len(stopped), len(cases), summary["outcomes"])
    if problems:
        raise RunError("; ".join(problems))
    return 0


def _case_outcome_text(result: dict, displacement: float | None) -> str:
    """One case's outcome for the progress log: D_box and the displacement, and why it stopped
    when it did not end ``ok``."""
    d = result.get("d_box")
    what = (f"D_box {d:.4f}" if d is not None else "D_box -") + \
           (f", max displacement {displacement * 1e3:.3g} mm" if displacement is not None else "")
    status = result["status"]
    if status == "failed_blocks":
        return (f"{what} (blocks in equilibrium); blocks failed: {result.get('failed_blocks')} "
                f"({result.get('failed_mechanisms')})")
    if status == "not_converged":
        return f"{what}; NOT CONVERGED: {result['error']}"
    if status != "ok":
        return f"FAILED: {result['error']}"
    return what


def _study_manifest(args, document, cases, timings: dict, extra: dict) -> dict:
    """manifest.json of a study: the command, config, seeds (root, rule, per realization),
    timings and the run's summary with the case ids (the inputs' digests are added by the
    caller)."""
    from .manifest import build_manifest

    study = document.study
    return build_manifest(
        command=args.argv, config=document, inputs=[args.config],
        seeds={"root": study.seed, "realizations": study.realizations,
               "rule": "realization r: 63 bits of SeedSequence(root, spawn_key=(r,)), "
                       "written into " + ", ".join(study.seed_fields or ["blocks.seed"]),
               "by_realization": sorted({(c.realization, c.seed) for c in cases})},
        timings_s=timings, extra={**extra, "case_ids": {c.short_id: c.index for c in cases}})


def _problems(n_failed: int, n_stopped: int, n_cases: int, outcomes: dict) -> list[str]:
    """What makes a finished study exit non-zero: cases that failed (retried on a re-run) and
    cases the solver stopped (kept on a re-run: the solver is deterministic)."""
    from .solver.result import FAILED_STATUSES

    problems = []
    if n_failed:
        problems.append(f"{n_failed} of {n_cases} cases failed (their error is in "
                        "results.csv and cases/<id>/case.json); re-run the same command to retry "
                        "them")
    if n_stopped:
        kinds = ", ".join(f"{outcomes[k]} {k}" for k in FAILED_STATUSES if outcomes.get(k))
        problems.append(f"{n_stopped} of {n_cases} cases were stopped by the solver "
                        f"({kinds}; the diagnostic is in results.csv); a re-run keeps them (the "
                        "solver is deterministic): change their config")
    return problems
