"""Running a study: one task per case, on any executor, written as each case finishes.

A case (:class:`rockmass.study_config.StudyCase`) runs :func:`run_case`, a plain top-level function
of the installed package that takes and returns plain data (picklable, small), so it runs the same in
this process, in a local process pool or on a Dask worker:

1. build the block model of the case's ``[blocks]`` section (:func:`rockmass.blockgen.build`) and
   check its invariants;
2. box-count the joint network: the joint segments of the sets (regenerated from the same seeds the
   builder used, so they are the model's joints) and any traces, clipped to the domain, rasterised
   on the ``[fractal]`` grid (360 x 360 by default, 1-pixel lines, as Jiang et al. seed 000 §4.1)
   with the domain as the face: D_box with R², its spread over shifted grids, and P21;
3. run the DEM stages of ``[solve]`` when the base has one (:func:`rockmass.solver.run`): the
   maximum displacement after the last stage (of the blocks on the excavation boundary, and of any
   block), whether every stage converged, and how many blocks ended inside the opening (fallen
   or falling: their displacement is a fall, and while they fall the stage does not converge).

Numba runs one thread per task (``numba.set_num_threads(1)``; pools also get
``NUMBA_NUM_THREADS=1``): the workers are the parallelism, and a case's numbers do not depend on
how many threads computed them. The results are the same whatever the executor and worker count.

The parent process is the only writer: each finished case goes to ``cases/<id>/case.json``
(atomically), then ``results.csv`` is rebuilt from all finished cases in case order (atomically), so
a killed study loses at most the cases that were running; re-running it skips every case whose
``case.json`` holds the same case id with status ``ok``.
"""

from __future__ import annotations

import json
import math
import os
import time
import traceback
from pathlib import Path
from typing import Any, Callable

__all__ = ["run_case", "joint_network_segments", "CSV_COLUMNS", "results_rows", "csv_text",
           "run_tasks", "init_worker", "load_finished"]

CASE_FILE = "case.json"
RESULTS_FILE = "results.csv"

# the columns after the case's own parameters (wall_time_s last: the only one that varies between
# runs of the same study, so the rest can be compared as they are)
CSV_COLUMNS = ("d_box", "d_box_r2", "d_box_stderr", "d_box_offset_sd", "p21_per_m", "p32",
               "n_joint_segments", "n_blocks", "n_contacts", "max_displacement_m",
               "max_displacement_boundary_m", "max_displacement_overall_m", "converged",
               "solve_status", "steps", "broken_contacts", "detached_blocks", "status", "error", "wall_time_s")


# ------------------------------------------------------------------------------------ workers


def limit_threads() -> int | None:
    """One numba thread for the calling thread (the study's workers are the parallelism); returns
    the previous count (None when numba cannot be imported)."""
    try:
        import numba
    except ImportError:  # pragma: no cover - numba is a dependency
        return None
    previous = numba.get_num_threads()
    numba.set_num_threads(1)
    return previous


def init_worker() -> None:
    """Initializer of a local worker process: one numba thread, kernels loaded once (from numba's
    on-disk cache when it has them) so that the first case does not pay for them."""
    os.environ["NUMBA_NUM_THREADS"] = "1"
    os.environ["OMP_NUM_THREADS"] = "1"
    try:
        import numba

        numba.set_num_threads(1)
        from .solver import _kernels  # noqa: F401  (compiled lazily per signature; import is cheap)
    except Exception:  # noqa: BLE001 - warming is an optimisation, never a failure
        pass


def joint_network_segments(document, config_path, model=None):
    """(n, 4) segments ``x0, y0, x1, y1`` of the joint network of a ``[blocks]`` section, clipped
    to its domain: the joint sets as the builder generated them (same seeds) and the traces.

    Dangling-end extensions, excavation outlines and potential cracks are not joints and are left
    out (Jiang et al. count the joint network drawn on the section).
    """
    import numpy as np
    import shapely

    from .blockgen.joints import set_segments
    from .blocks_cmd import dfn_section_traces
    from .inputs import read_trace_file

    cfg = document.blocks
    if model is not None:
        domain_xy = np.asarray(model.domain_xy_m, float)
    else:
        domain_xy = np.asarray(cfg.domain.xy_m(), float)
    domain = shapely.Polygon(domain_xy)
    parts = []
    sets = cfg.joint_sets()
    if sets:
        children = np.random.SeedSequence(cfg.seed).spawn(len(sets))
        for i, js in enumerate(sets):  # as rockmass.blockgen.build draws them
            raw = set_segments(js, domain_xy, np.random.default_rng(children[i]), i)
            parts.append(np.asarray(raw, float).reshape(-1, 4))
    traces = None
    path = cfg.traces_path(config_path)
    if path is not None:
        traces = read_trace_file(path, "blocks.traces")
    if cfg.dfn_section is not None:
        traces, _ = dfn_section_traces(document, config_path)
    if traces is not None:
        segs = traces.segments() if hasattr(traces, "segments") else np.asarray(traces, float)
        parts.append(np.asarray(segs, float).reshape(-1, 4))
    if not parts:
        return np.empty((0, 4))
    segs = np.concatenate(parts)
    lines = shapely.linestrings(segs.reshape(-1, 2, 2))
    clipped = shapely.intersection(lines, domain)
    out = []
    for geom in shapely.get_parts(clipped[~shapely.is_empty(clipped)]):
        if geom.geom_type != "LineString":  # touching points of the outline
            continue
        xy = np.asarray(geom.coords)
        out.append(np.column_stack([xy[:-1], xy[1:]]))
    return np.concatenate(out) if out else np.empty((0, 4))


def _build_model(document, config_path):
    from .blockgen import build, check_model
    from .blocks_cmd import _field_message, dfn_section_traces
    from .errors import InputError, RunError
    from .inputs import read_trace_file

    cfg = document.blocks
    domain_xy = None if cfg.domain is None else cfg.domain.xy_m()
    traces = None
    try:
        path = cfg.traces_path(config_path)
        if path is not None:
            traces = read_trace_file(path, "blocks.traces")
        if cfg.dfn_section is not None:
            traces, window = dfn_section_traces(document, config_path)
            domain_xy = window if domain_xy is None else domain_xy
        model = build(domain_xy, cfg.joint_sets(), traces, [e.to_excavation() for e in cfg.excavations],
                      dangling=cfg.dangling, seed=cfg.seed, rounding_m=cfg.rounding_m,
                      min_edge_m=cfg.min_edge_m, merge_slivers=cfg.merge_slivers,
                      convex=cfg.convex, snap_edges=cfg.snap_edges,
                      cracks=None if cfg.cracks is None else cfg.cracks.to_cracks())
    except InputError:
        raise
    except ValueError as exc:
        raise InputError(f"{config_path}: {_field_message(exc)}") from exc
    invariants = check_model(model)
    if not invariants["ok"]:
        raise RunError(f"the block model fails its invariants {invariants}")
    return model


def _fractal(document, config_path, model) -> dict:
    from .config import FractalConfig
    from .fractal import box_count

    fcfg = document.fractal or FractalConfig()
    segs = joint_network_segments(document, config_path, model)
    if not len(segs):
        return {"d_box": None, "d_box_r2": None, "d_box_stderr": None, "d_box_offset_sd": None,
                "p21_per_m": 0.0, "n_joint_segments": 0}
    bc = box_count(segs, kind="traces", grid=fcfg.grid, method=fcfg.method,
                   fit_range_px=fcfg.range_px, mask=model.domain_xy_m, n_offsets=fcfg.n_offsets,
                   line_rule=fcfg.line_rule)
    spread = float(bc.offset_dimensions.std(ddof=1)) if len(bc.offset_dimensions) > 1 else 0.0
    return {"d_box": float(bc.dimension), "d_box_r2": float(bc.r2), "d_box_stderr": float(bc.stderr),
            "d_box_offset_sd": spread, "p21_per_m": float(bc.p21_per_m),
            "n_joint_segments": int(len(segs))}


def _p32(document) -> float | None:
    """Total P32 (m²/m³, one-sided) of the ``[dfn]`` sets when blocks are cut by a DFN section and
    every set is given by P32; None otherwise (2D joint sets have no P32)."""
    dfn = getattr(document, "dfn", None)
    if dfn is None or document.blocks.dfn_section is None or not dfn.sets:
        return None
    if any(getattr(s.intensity, "measure", None) != "P32" for s in dfn.sets):
        return None
    return float(sum(s.intensity.value for s in dfn.sets))


def _solve(document, config_path, model) -> dict:
    from .errors import InputError
    from .solver import run as solver_run

    solve = getattr(document, "solve", None)
    if solve is None:
        return {}
    settings = solve.to_settings(model, config_path)
    try:
        result = solver_run(model, settings)
    except ValueError as exc:
        raise InputError(f"{config_path}: solve: {exc}") from exc
    last = result.stages[-1]
    stages = [{"name": s.name, "status": s.status, "steps": int(s.steps), "converged": s.converged,
               "max_displacement_m": float(s.max_displacement_m),
               "max_displacement_boundary_m": float(s.max_displacement_boundary_m),
               "unbalanced_ratio": float(s.unbalanced_ratio),
               "broken_contacts": int(s.broken_contacts), "wall_time_s": float(s.wall_time_s)}
              for s in result.stages]
    converged = all(s.converged is not False for s in result.stages) and result.status == "ok"
    return {"max_displacement_boundary_m": float(last.max_displacement_boundary_m),
            "max_displacement_overall_m": float(last.max_displacement_m),
            "converged": bool(converged), "solve_status": str(result.status),
            "steps": int(sum(s.steps for s in result.stages)),
            "broken_contacts": int(last.broken_contacts),
            "detached_blocks": int(last.detached_blocks), "stages": stages,
            "diagnostic": result.diagnostic}


def run_case(task: dict) -> dict:
    """Run one case: blocks, box count, DEM. A plain function of plain data (a Dask/pool task).

    Parameters
    ----------
    task : dict
        ``case`` (index), ``case_id``, ``config`` (the case's TOML data), ``config_path`` (for the
        files it names), ``params``, ``realization``, ``seed``.

    Returns
    -------
    dict
        The task's keys (without ``config``) plus the measured values, ``status`` ("ok" or
        "failed"), ``error`` (the reason, or None) and ``timings_s``. Never raises for a failure of
        the case itself: a study goes on with the other cases.
    """
    from .config import RockmassConfig

    limit_threads()
    t0 = time.perf_counter()
    out = {k: task[k] for k in ("case", "case_id", "params", "realization", "seed")}
    out.update({"status": "ok", "error": None})
    timings = {}
    try:
        document = RockmassConfig.model_validate(task["config"])
        path = task["config_path"]
        t = time.perf_counter()
        model = _build_model(document, path)
        timings["blocks_s"] = time.perf_counter() - t
        out.update({"n_blocks": int(model.n_blocks), "n_contacts": int(model.n_contacts)})
        t = time.perf_counter()
        out.update(_fractal(document, path, model))
        out["p32"] = _p32(document)
        timings["boxcount_s"] = time.perf_counter() - t
        t = time.perf_counter()
        out.update(_solve(document, path, model))
        timings["solve_s"] = time.perf_counter() - t
    except Exception as exc:  # noqa: BLE001 - a failed case is a result, not the study's end
        out["status"] = "failed"
        out["error"] = f"{type(exc).__name__}: {exc}"
        out["traceback"] = traceback.format_exc(limit=8)
    out["timings_s"] = timings
    out["wall_time_s"] = time.perf_counter() - t0
    out["worker_pid"] = os.getpid()
    return out


# ------------------------------------------------------------------------------------ results


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "" if not math.isfinite(value) else repr(value)
    if isinstance(value, (list, tuple, dict)):
        return json.dumps(value, separators=(",", ":"))
    return str(value)


def results_rows(cases, finished: dict, displacement: str = "boundary") -> tuple[list[str], list[list[str]]]:
    """(header, rows) of results.csv: one row per finished case, in case order."""
    param_paths: list[str] = []
    for case in cases:
        for p in case.params:
            if p not in param_paths:
                param_paths.append(p)
    header = ["case", "case_id", *param_paths, "realization", "seed", *CSV_COLUMNS]
    rows = []
    for case in cases:
        rec = finished.get(case.case_id)
        if rec is None:
            continue
        values = dict(rec)
        key = "max_displacement_boundary_m" if displacement == "boundary" else \
            "max_displacement_overall_m"
        values["max_displacement_m"] = rec.get(key)
        row = [str(case.index), case.short_id,
               *[_cell(case.params.get(p)) for p in param_paths],
               str(case.realization), str(case.seed),
               *[_cell(values.get(c)) for c in CSV_COLUMNS]]
        rows.append(row)
    return header, rows


def csv_text(header: list[str], rows: list[list[str]]) -> str:
    import csv
    import io

    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(header)
    writer.writerows(rows)
    return buf.getvalue()


def load_finished(out_dir: Path, cases) -> dict:
    """Finished cases in ``out_dir/cases``: case id -> record, for cases of this study whose
    case.json holds the same id and status ok (anything else runs again)."""
    finished = {}
    for case in cases:
        path = out_dir / "cases" / case.short_id / CASE_FILE
        try:
            rec = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        if rec.get("case_id") == case.case_id and rec.get("status") == "ok":
            finished[case.case_id] = rec
    return finished


# ------------------------------------------------------------------------------------ executors


def _result(future, task: dict) -> dict:
    """A finished future's result; a failure of the executor itself (a worker process killed, a
    broken pool, a lost Dask worker) becomes a failed case that a re-run retries."""
    try:
        return future.result()
    except Exception as exc:  # noqa: BLE001 - run_case never raises: this is the executor failing
        out = {k: task[k] for k in ("case", "case_id", "params", "realization", "seed")}
        out.update({"status": "failed", "error": f"executor: {type(exc).__name__}: {exc}",
                    "timings_s": {}, "wall_time_s": None})
        return out


def run_tasks(tasks: list[dict], on_done: Callable[[dict], None], *, workers: int = 1,
              scheduler: str | None = None, client=None) -> str:
    """Run ``run_case`` over ``tasks`` and call ``on_done(result)`` in this process as each one
    finishes (any order). Returns a description of the executor.

    ``scheduler`` (or an already connected Dask ``client``): a Dask cluster; else ``workers`` > 1: a
    local process pool (spawned processes, one numba thread each); else serially in this process.
    """
    if not tasks:
        return "none (every case was finished)"
    if client is not None or scheduler is not None:
        from dask.distributed import as_completed

        client.run(init_worker)  # one numba thread and the kernels loaded, once per worker
        futures = {client.submit(run_case, t, key=f"rockmass-case-{t['case_id'][:16]}-{i}",
                                 pure=False): t for i, t in enumerate(tasks)}
        try:
            for fut in as_completed(list(futures), loop=client.loop):
                on_done(_result(fut, futures[fut]))
        except BaseException:
            client.cancel(list(futures))
            raise
        return f"dask ({scheduler or client.scheduler.address})"
    if workers <= 1:
        previous = limit_threads()
        try:
            for t in tasks:
                on_done(run_case(t))
        finally:
            if previous is not None:
                import numba

                numba.set_num_threads(previous)
        return "serial"
    import multiprocessing
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

    pool = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                               initializer=init_worker)
    try:
        futures = {pool.submit(run_case, t): t for t in tasks}
        pending = set(futures)
        while pending:
            done, pending = wait(pending, return_when=FIRST_COMPLETED)
            for fut in sorted(done, key=lambda f: futures[f]["case"]):
                on_done(_result(fut, futures[fut]))
    except BaseException:
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown(wait=True)
    return f"local process pool ({workers} workers)"
