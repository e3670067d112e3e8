"""Running a study: one task per case, on any executor, written as each case finishes.

A case (:class:`rockmass.study_config.StudyCase`) runs :func:`run_case`, a plain top-level function
of the installed package that takes and returns plain data (picklable, small), so it runs the same in
this process, in a local process pool or on a Dask worker:

1. build the block model of the case's ``[blocks]`` section (:func:`rockmass.blockgen.build`) and
   check its invariants;
2. box-count the joint network: the joint segments of the sets (drawn by
   :func:`rockmass.blockgen.joint_set_segments`, the builder's own seeding rule, so they are the
   model's joints) and any traces, clipped to the domain, rasterised on the ``[fractal]`` grid
   (360 x 360 by default, 1-pixel lines, as Jiang et al. did, docs/fractal.md §1) with the domain as the face:
   D_box with R², its spread over shifted grids, and P21;
3. run the DEM stages of ``[solve]`` when the base has one (:func:`rockmass.solver.run`) and
   classify the case (:func:`case_outcome`): ``ok`` (every static stage reached equilibrium, no
   block failed), ``failed_blocks`` (blocks kept moving, falling, sliding or rotating, and the
   solver took them out; the rest reached equilibrium without them), ``not_converged`` (a static
   stage reached ``max_steps`` without equilibrium), ``unstable`` / ``overlap`` (the solver stopped
   the run) or ``error`` (an exception: a missing file, a bad model, a lost worker). Displacements
   are those of the blocks that stay in equilibrium (failed blocks and slivers below the solver's
   size cap left out), so a fall is never a displacement: ``max_displacement_m`` (boundary or
   overall, as ``study.displacement`` says) is filled for ``ok`` and ``failed_blocks`` only, and
   the failed blocks are counted apart (number, area, mechanisms). The monitoring points fixed on
   the excavation boundary (crown, walls, invert) give the last stage's displacements there.

Numba runs one thread per task (``numba.set_num_threads(1)``), and worker processes get
``NUMBA_NUM_THREADS``, ``OMP_NUM_THREADS``, ``MKL_NUM_THREADS`` and ``OPENBLAS_NUM_THREADS`` = 1
before they import numpy (local pool: set when the processes are spawned; Dask: its nanny's
defaults, and again by the worker plugin): the workers are the parallelism, and a case's numbers do
not depend on how many threads computed them. Each worker loads the compiled kernels once, before
its first case (:func:`init_worker`: a tiny case through blocks, box counting and a few DEM steps;
the local pool's initializer, a Dask worker plugin, which also covers workers that join later).
Local pools and Dask get the cases longest first (:func:`case_cost`, an estimate from the config:
blocks x step cap), so that a long case does not start last and leave the other workers idle. The
results are the same whatever the executor, worker count and order.

The parent process is the only writer: each finished case goes to ``cases/<id>/case.json``
(atomically), then ``results.csv`` is rebuilt from all finished cases in case order (atomically), so
a killed study loses at most the cases that were running. Re-running it keeps every case whose
``case.json`` holds the same case id, the current :data:`RECORD_VERSION` and an outcome other than
``error``: the chain is deterministic, so a case that failed blocks, did not converge or was
stopped by the solver would end the same way again (change its config to change it); ``error``
cases (and records of an older rockmass, whose displacements may include falls) run again.
"""

from __future__ import annotations

import json
import math
import os
import time
import traceback
from pathlib import Path
from typing import Any, Callable

from .dfn.polygon import polygon_area
from .solver.failure import MECHANISMS, mechanism_counts
from .solver.result import FAILED_STATUSES, STATUS_FAILED_BLOCKS, STATUS_OK

__all__ = ["run_case", "joint_network_segments", "CSV_COLUMNS", "results_rows", "csv_text",
           "run_tasks", "init_worker", "load_finished", "case_domain_xy", "case_cost",
           "case_outcome", "outcome_counts", "outcome_summary", "OUTCOMES", "IN_EQUILIBRIUM",
           "RETRIED", "displacement_m",
           "failed_mechanism_counts", "MONITOR_COLUMNS"]

CASE_FILE = "case.json"
RESULTS_FILE = "results.csv"

# the columns after the case's own parameters (wall_time_s last: the only one that varies between
# runs of the same study, so the rest can be compared as they are)
CSV_COLUMNS = ("d_box", "d_box_r2", "d_box_stderr", "d_box_offset_sd", "p21_per_m", "p32",
               "n_joint_segments", "n_blocks", "n_contacts", "max_displacement_m",
               "max_displacement_boundary_m", "max_displacement_overall_m",
               "crown_displacement_m", "left_wall_displacement_m", "right_wall_displacement_m",
               "invert_displacement_m", "failed_blocks", "failed_area_m2", "failed_mechanisms",
               "worst_ratio", "converged", "solve_status", "steps", "broken_contacts",
               "new_cracks", "detached_blocks", "plastic_area_m2", "status", "error", "wall_time_s")

#: A case's outcome (results.csv ``status``), in the order reports list them.
OUTCOMES = ("ok", "failed_blocks", "not_converged", "unstable", "overlap", "error")
#: Outcomes whose model (what is left of it) ended in equilibrium: ``max_displacement_m`` is
#: filled for them only.
IN_EQUILIBRIUM = ("ok", "failed_blocks")
#: Outcomes a re-run of the study runs again; a case of any other outcome is kept (deterministic).
RETRIED = ("error",)
#: Version of case.json records; a record of another version runs again on resume (version 1,
#: before outcomes, counted falls as displacements; version 2 counted frictional joints touched
#: at a corner as broken and had no new_cracks).
RECORD_VERSION = 3
#: Monitoring points on the excavation boundary -> results.csv column.
MONITOR_COLUMNS = {"crown": "crown_displacement_m", "left_wall": "left_wall_displacement_m",
                   "right_wall": "right_wall_displacement_m",
                   "invert": "invert_displacement_m"}


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


# one thread per worker process for every threaded library (set before numpy is imported)
THREAD_ENV = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
              "OPENBLAS_NUM_THREADS": "1"}

_WARM = {"count": 0, "seconds": None}  # init_worker calls in this process, time of the first

# a tiny case (12 m square, two sets, a tunnel, a few steps of each stage): loads every kernel the
# chain uses from numba's on-disk cache (or compiles it) without any case paying for it
_WARMUP_CONFIG = {
    "blocks": {"domain": {"width_m": 12.0, "height_m": 12.0, "origin_xy_m": [-6.0, -6.0]},
               "two_sets": {"alpha_deg": 30.0, "theta_deg": 60.0, "spacing_m": [3.0, 4.0]},
               "excavations": [{"shape": "circle", "name": "t", "center_xy_m": [0.0, 0.0],
                                "radius_m": 2.0, "n_sides": 12}]},
    "fractal": {"grid": 64, "n_offsets": 2},
    "solve": {"material": {"density_kg_m3": 2650.0},
              "joints": {"default": {"model": "coulomb", "kn_pa_m": 1e9, "ks_pa_m": 5e8,
                                     "friction_deg": 30.0}},
              "insitu": {"syy_pa": 1e6, "sxx_pa": 1e6},
              "fixes": [{"where": "bottom", "dofs": "y"}, {"where": "left", "dofs": "x"},
                        {"where": "right", "dofs": "x"}],
              "boundary_stress": [{"sides": ["top"], "from_insitu": True}],
              "stages": [{"name": "equilibrium", "max_steps": 20},
                         {"name": "t", "excavate": ["t"], "max_steps": 20}]},
}


def init_worker() -> None:
    """Set up a worker process, once: one thread per threaded library (:data:`THREAD_ENV`; numba's
    is also set per task by :func:`run_case`), then warm the compiled kernels with a tiny case so
    that the first real case does not pay for loading them. Never raises (warming is an
    optimisation); a second call in the same process only counts itself."""
    os.environ.update(THREAD_ENV)
    _WARM["count"] += 1
    if _WARM["count"] > 1:
        return
    t0 = time.perf_counter()
    try:
        limit_threads()
        from .config import RockmassConfig

        document = RockmassConfig.model_validate(_WARMUP_CONFIG)
        path = Path(os.getcwd()) / "warmup.toml"  # names no file
        model = _build_model(document, path)
        _fractal(document, path, model)
        _solve(document, path, model)
    except Exception:  # noqa: BLE001 - warming is an optimisation, never a failure
        pass
    _WARM["seconds"] = time.perf_counter() - t0


def _exit_with_parent(parent_pid: int, every_s: float = 0.5) -> None:
    """End this worker process as soon as ``parent_pid`` is no longer its parent (the study was
    killed, even by SIGKILL, which no handler sees): a daemon thread polls :func:`os.getppid`."""
    import threading

    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(every_s)
        os._exit(1)

    threading.Thread(target=watch, name="rockmass-parent-watch", daemon=True).start()


def _init_pool_worker(parent_pid: int) -> None:
    """Initializer of a local pool's worker: end with the study (:func:`_exit_with_parent`), then
    :func:`init_worker`."""
    _exit_with_parent(parent_pid)
    init_worker()


def _stop_pool(pool) -> None:
    """Cancel the queued cases and end the pool's worker processes now (a case they were running is
    abandoned; a re-run of the study runs it again). ``ProcessPoolExecutor`` has no public way to
    end busy workers, hence its ``_processes``."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        if process.is_alive():
            process.terminate()
    for process in processes:
        process.join(timeout=5)


def dask_worker_plugin():
    """A Dask ``WorkerPlugin`` that runs :func:`init_worker` once on every worker of the cluster,
    including workers that join later (``client.register_plugin``)."""
    from distributed.diagnostics.plugin import WorkerPlugin

    class RockmassWorkerInit(WorkerPlugin):
        name = "rockmass-init-worker"
        idempotent = True  # registering it again (another study on the cluster) is a no-op

        def setup(self, worker):
            init_worker()

    return RockmassWorkerInit()


def case_domain_xy(document):
    """The polygon of a case's block domain: ``[blocks.domain]``, or the window of the
    ``[[dfn.sections]]`` entry its ``[blocks.dfn_section]`` names. Raises ``ValueError`` (or
    ``AttributeError``) for a config without either (its case reports it)."""
    cfg = document.blocks
    if cfg.domain is not None:
        return cfg.domain.xy_m()
    name = cfg.dfn_section.section
    window = next((s.window_uv_m for s in document.dfn.sections if s.name == name), None)
    if window is None:
        raise ValueError(f"blocks.dfn_section.section: no [[dfn.sections]] entry named {name!r}")
    return window


def case_cost(document) -> float:
    """Relative cost of a case, from its config alone, to order cases longest first: an estimate
    of the block count (1 + the joint crossings in the domain: area x sum over pairs of sets of
    P21_i P21_j |sin(angle between them)|; a DFN section counts as area x P32^2 / 2) times the
    solver's step cap (the sum of the stages' max_steps; 1 without [solve]). Only the order of the
    cases of one study depends on it, never a result."""
    cfg = document.blocks
    try:
        area = polygon_area(case_domain_xy(document))
        sets = []  # (P21 per m, angle rad)
        for js in cfg.joint_sets():
            persistence = 1.0
            if js.trace_length_m is not None and js.gap_length_m is not None:
                persistence = js.trace_length_m / (js.trace_length_m + js.gap_length_m)
            sets.append((persistence / js.spacing_m, math.radians(js.angle_deg)))
        crossings = sum(p * q * abs(math.sin(a - b)) for i, (p, a) in enumerate(sets)
                        for q, b in sets[i + 1:])
        if cfg.dfn_section is not None and document.dfn is not None:
            p32 = sum(s.intensity.value for s in document.dfn.sets)
            crossings += 0.5 * p32 * p32
        blocks = 1.0 + area * crossings
        solve = document.solve
        steps = float(sum(st.max_steps for st in solve.stages)) if solve is not None else 1.0
        return blocks * steps
    except Exception:  # noqa: BLE001 - an estimate: a config it does not understand costs 1
        return 1.0


def joint_network_segments(document, config_path, model=None, traces=None):
    """(n, 4) segments ``x0, y0, x1, y1`` of the joint network of a ``[blocks]`` section, clipped
    to its domain: the joint sets as the builder drew them (the builder's own seeding rule,
    :func:`rockmass.blockgen.joint_set_segments`) and the traces.

    ``traces``: the TraceMap that cut the model (the DFN section :func:`_build_model` generated, or
    the trace file it read), so they are not made again; None: read / generate what the config
    names. Dangling-end extensions, excavation outlines and potential cracks are not joints and are
    left out (Jiang et al. count the joint network drawn on the section).
    """
    import numpy as np
    import shapely

    from .blockgen import joint_set_segments

    cfg = document.blocks
    if model is not None:
        domain_xy = np.asarray(model.domain_xy_m, float)
    else:
        domain_xy = np.asarray(cfg.domain.xy_m(), float)
    domain = shapely.Polygon(domain_xy)
    parts = [np.asarray(raw, float).reshape(-1, 4)
             for raw in joint_set_segments(cfg.joint_sets(), domain_xy, cfg.seed)]
    if traces is None:
        traces = _traces(document, config_path)
    if traces is not None:
        parts.append(np.asarray(traces.segments(), float).reshape(-1, 4))
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


def _dfn_section(document, config_path):
    """``(TraceMap, window)`` of the case's ``[blocks.dfn_section]``
    (:func:`rockmass.blocks_stage.dfn_section_traces`), or None without one."""
    from .blocks_stage import dfn_section_traces

    if document.blocks.dfn_section is None:
        return None
    return dfn_section_traces(document, config_path)


def _traces(document, config_path, section=None):
    """The TraceMap that cuts the case's blocks: the DFN ``section``'s (generated when not given),
    the ``blocks.traces`` file's, or None."""
    from .inputs import read_trace_file

    if document.blocks.dfn_section is not None:
        return (section or _dfn_section(document, config_path))[0]
    path = document.blocks.traces_path(config_path)
    return None if path is None else read_trace_file(path, "blocks.traces", quiet=True)


def _build_model(document, config_path, section=None):
    """The case's block model, built and checked as ``rockmass blocks`` builds it
    (:func:`rockmass.blocks_stage.compute`); ``section``: the ``(TraceMap, window)`` of its DFN
    section when already generated (:func:`_dfn_section`)."""
    import types

    from .blocks_stage import compute

    _, model, _, _ = compute(types.SimpleNamespace(config=config_path), document, section)
    return model


def _fractal(document, config_path, model, traces=None) -> dict:
    """D_box (with R², standard error, spread over shifted grids), P21 and the segment count of
    the case's joint network (:func:`joint_network_segments`; ``traces`` as it takes them)."""
    from .config import FractalConfig
    from .fractal import box_count

    fcfg = document.fractal or FractalConfig()
    segs = joint_network_segments(document, config_path, model, traces)
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
    dfn = document.dfn
    if dfn is None or document.blocks.dfn_section is None or not dfn.sets:
        return None
    if any(s.intensity.measure != "P32" for s in dfn.sets):
        return None
    return float(sum(s.intensity.value for s in dfn.sets))


def case_outcome(result) -> tuple[str, str | None]:
    """Outcome of a case's DEM run and its reason (None for ``ok`` and ``failed_blocks``, whose
    failed blocks are described by their own columns).

    Parameters
    ----------
    result : rockmass.solver.Result
        The run; ``result.status`` is one of ok, failed_blocks, overlap, unstable.

    Returns
    -------
    (str, str or None)
        The first that applies: ``overlap`` / ``unstable`` (the solver stopped the run; reason: its
        diagnostic); ``not_converged`` (a static stage with ``converged`` False — it ran out of
        ``max_steps``, with or without failed blocks: the blocks left are not at rest; reason: the
        stage and the solver's diagnostic, which names the worst block); ``failed_blocks`` (blocks
        failed and were taken out, every static stage reached equilibrium without them); ``ok``.

    Raises
    ------
    ValueError
        ``result.status`` is none of the solver's statuses (the case becomes an ``error``).
    """
    if result.status in FAILED_STATUSES:  # the solver stopped the run: the study exits 1
        return result.status, f"solver stopped ({result.status}): {result.diagnostic}"
    if result.status not in (STATUS_OK, STATUS_FAILED_BLOCKS):
        raise ValueError(f"unknown solver status {result.status!r} (expected ok, failed_blocks, "
                         f"{', '.join(FAILED_STATUSES)})")
    for s in result.stages:  # the solver says why (its diagnostic names the worst block)
        if s.converged is False:
            return "not_converged", f"stage {s.name!r}: {s.diagnostic}"
    return result.status, None


def _failed_blocks(stages) -> dict:
    """The failed blocks of every stage: count, total area, mechanisms (``"fall:2 slide:1"`` and
    counts) and the list (each with its stage)."""
    listed = [{"stage": s.name, **fb} for s in stages for fb in s.failed_blocks]
    counts = mechanism_counts(listed)
    return {"failed_blocks": len(listed),
            "failed_area_m2": float(sum(fb["area_m2"] for fb in listed)),
            "failed_mechanisms": " ".join(f"{m}:{n}" for m, n in counts.items()),
            "failed_mechanism_counts": counts, "failed_block_list": listed}


def _solve(document, config_path, model) -> dict:
    """The case's DEM stages (:func:`rockmass.solve_stage.solve`) summed up for results.csv, with
    its ``outcome`` and ``reason`` (:func:`case_outcome`); {} without ``[solve]``.

    Displacements are the last stage's over the blocks in equilibrium (failed blocks and slivers
    left out): ``max_displacement_boundary_m`` of those on the excavation boundary,
    ``max_displacement_overall_m`` of any; the monitors' (crown, walls, invert) from the last stage.
    ``worst_ratio``: the largest per-block unbalanced ratio at the end of the static stages (of the
    last stage when every stage is dynamic).
    """
    from .solve_stage import solve as solve_stages

    if document.solve is None:
        return {}
    from .solver.runner import reference_stage

    settings = document.solve.to_settings(model, config_path)
    result = solve_stages(model, settings, config_path)
    ref = reference_stage(settings)
    # broken before the reference state (all of them if the run stopped in that stage)
    cracks_before = (result.stages[ref].broken_contacts
                     if ref is not None and len(result.stages) > ref else 0)
    outcome, reason = case_outcome(result)
    last = result.stages[-1]
    stages = [{"name": s.name, "kind": s.kind, "status": s.status, "steps": int(s.steps),
               "converged": s.converged,
               "max_displacement_equilibrium_m": float(s.max_displacement_equilibrium_m),
               "max_displacement_boundary_equilibrium_m":
                   float(s.max_displacement_boundary_equilibrium_m),
               "max_displacement_any_block_m": float(s.max_displacement_m),
               "monitors": {k: float(v) for k, v in s.monitors.items()},
               "failed_blocks": len(s.failed_blocks), "worst_block": int(s.worst_block),
               "worst_ratio": float(s.worst_ratio), "unbalanced_ratio": float(s.unbalanced_ratio),
               "broken_contacts": int(s.broken_contacts), "wall_time_s": float(s.wall_time_s),
               "diagnostic": s.diagnostic}
              for s in result.stages]
    static = [s for s in result.stages if s.kind == "static"] or [last]
    converged = outcome in IN_EQUILIBRIUM
    out = {"max_displacement_boundary_m": float(last.max_displacement_boundary_equilibrium_m),
           "max_displacement_overall_m": float(last.max_displacement_equilibrium_m),
           **{col: (float(last.monitors[name]) if name in last.monitors else None)
              for name, col in MONITOR_COLUMNS.items()},
           **_failed_blocks(result.stages),
           "worst_ratio": float(max(s.worst_ratio for s in static)),
           "converged": bool(converged), "solve_status": str(result.status),
           "steps": int(sum(s.steps for s in result.stages)),
           "broken_contacts": int(last.broken_contacts),
           # bonds broken after the initial equilibrium: the cracks the excavation made
           "new_cracks": int(last.broken_contacts - cracks_before),
           "detached_blocks": int(last.detached_blocks),
           # deformable blocks (docs/dem.md §16): the area of the zones that yielded; none if rigid
           "plastic_area_m2": (result.zone_summary()["plastic_area_m2"] if result.zones
                               else None),
           "stages": stages,
           "diagnostic": result.diagnostic, "outcome": outcome, "reason": reason}
    return out


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
        The task's keys (without ``config``) plus the measured values, ``status`` (the outcome:
        one of :data:`OUTCOMES`; ``ok`` without ``[solve]``), ``error`` (the reason for
        not_converged / unstable / overlap / error, else None), ``record_version`` and
        ``timings_s``. Never raises for a failure of the case itself: a study goes on with the
        other cases.
    """
    from .config import RockmassConfig

    limit_threads()
    numba_threads = _numba_threads()
    t0 = time.perf_counter()
    cpu0 = time.process_time()
    started = time.time()
    out = {k: task[k] for k in ("case", "case_id", "params", "realization", "seed")}
    out.update({"status": "ok", "error": None, "record_version": RECORD_VERSION})
    timings = {}
    try:
        document = RockmassConfig.model_validate(task["config"])
        path = task["config_path"]
        t = time.perf_counter()
        section = _dfn_section(document, path)  # generated once: the blocks and the box count
        model = _build_model(document, path, section)
        timings["blocks_s"] = time.perf_counter() - t
        out.update({"n_blocks": int(model.n_blocks), "n_contacts": int(model.n_contacts)})
        t = time.perf_counter()
        out.update(_fractal(document, path, model, _traces(document, path, section)))
        out["p32"] = _p32(document)
        timings["boxcount_s"] = time.perf_counter() - t
        t = time.perf_counter()
        solved = _solve(document, path, model)
        timings["solve_s"] = time.perf_counter() - t
        out["status"] = solved.pop("outcome", "ok")
        out["error"] = solved.pop("reason", None)
        out.update(solved)
    except Exception as exc:  # noqa: BLE001 - a failed case is a result, not the study's end
        out["status"] = "error"
        out["error"] = f"{type(exc).__name__}: {exc}"
        out["traceback"] = traceback.format_exc(limit=8)
    out["timings_s"] = timings
    out["wall_time_s"] = time.perf_counter() - t0
    # CPU time of the worker process during the case (wall >> CPU: the worker waited for a core)
    out["cpu_time_s"] = time.process_time() - cpu0
    out["started_at"], out["finished_at"] = started, time.time()  # epoch s: the schedule
    out["worker_pid"] = os.getpid()
    out["numba_threads"] = numba_threads  # in the thread that ran the case
    out["worker_warmups"] = _WARM["count"]  # init_worker calls in this process (1 on a worker)
    return out


def _numba_threads() -> int | None:
    try:
        import numba
    except ImportError:  # pragma: no cover - numba is a dependency
        return None
    return int(numba.get_num_threads())


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
    """(header, rows) of results.csv: one row per finished case (any outcome), in case order.

    A ``label`` column follows ``case_id`` when a case has a label (``[[study.cases]]`` ``label``).
    ``max_displacement_m`` is the record's boundary or overall displacement (``displacement``),
    over the blocks in equilibrium, for the outcomes in :data:`IN_EQUILIBRIUM` only; empty for a
    case whose model is not in equilibrium (not_converged, unstable, overlap, error).
    """
    param_paths: list[str] = []
    for case in cases:
        for p in case.params:
            if p not in param_paths:
                param_paths.append(p)
    labelled = any(case.label for case in cases)  # a label column when the study names its cases
    header = ["case", "case_id", *(["label"] if labelled else []), *param_paths, "realization", "seed",
              *CSV_COLUMNS]
    rows = []
    for case in cases:
        rec = finished.get(case.case_id)
        if rec is None:
            continue
        values = dict(rec)
        values["max_displacement_m"] = displacement_m(rec, displacement)
        row = [str(case.index), case.short_id, *([case.label] if labelled else []),
               *[_cell(case.params.get(p)) for p in param_paths],
               str(case.realization), str(case.seed),
               *[_cell(values.get(c)) for c in CSV_COLUMNS]]
        rows.append(row)
    return header, rows


def displacement_m(record: dict, displacement: str = "boundary") -> float | None:
    """A case's maximum displacement over its blocks in equilibrium (``displacement``: "boundary"
    or "overall"), or None when its outcome is not in :data:`IN_EQUILIBRIUM` or it has no
    ``[solve]``: the only displacement a study compares, plots or averages."""
    if record.get("status") not in IN_EQUILIBRIUM:
        return None
    return record.get("max_displacement_boundary_m" if displacement == "boundary"
                      else "max_displacement_overall_m")


def outcome_counts(records) -> dict[str, int]:
    """Number of cases per outcome (every key of :data:`OUTCOMES`, in that order); ``records``:
    an iterable of case records."""
    counts = {o: 0 for o in OUTCOMES}
    for rec in records:
        status = rec.get("status")
        counts[status if status in counts else "error"] += 1
    return counts


def failed_mechanism_counts(records) -> dict[str, int]:
    """Failed blocks per mechanism over the cases whose outcome is ``failed_blocks``."""
    counts: dict[str, int] = {}
    for rec in records:
        if rec.get("status") == "failed_blocks":
            for m, n in (rec.get("failed_mechanism_counts") or {}).items():
                counts[m] = counts.get(m, 0) + int(n)
    return {m: counts[m] for m in MECHANISMS if counts.get(m)}


def outcome_summary(records, n_cases: int) -> str:
    """One line: how many of the study's ``n_cases`` cases ended in equilibrium (``ok``) and what
    happened to the others, e.g. ``"5 of 8 cases in equilibrium; 2 with failed blocks (3 blocks:
    fall 2, slide 1); 1 not converged"`` (``"; 2 not run"`` for cases without a record)."""
    records = list(records)
    counts = outcome_counts(records)
    parts = [f"{counts['ok']} of {n_cases} cases in equilibrium"]
    if counts["failed_blocks"]:
        mech = failed_mechanism_counts(records)
        blocks = sum(mech.values())
        detail = ", ".join(f"{m} {n}" for m, n in mech.items())
        parts.append(f"{counts['failed_blocks']} with failed blocks ({blocks} "
                     f"block{'s' if blocks != 1 else ''}{': ' + detail if detail else ''})")
    for outcome, label in (("not_converged", "not converged"), ("unstable", "unstable"),
                           ("overlap", "overlap"), ("error", "error")):
        if counts[outcome]:
            parts.append(f"{counts[outcome]} {label}")
    if len(records) < n_cases:
        parts.append(f"{n_cases - len(records)} not run")
    return "; ".join(parts)


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
    case.json holds the same id, :data:`RECORD_VERSION` and an outcome of :data:`OUTCOMES` other
    than those re-run (:data:`RETRIED`: ``error``); anything else runs again."""
    finished = {}
    for case in cases:
        path = out_dir / "cases" / case.short_id / CASE_FILE
        try:
            rec = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        if (rec.get("case_id") == case.case_id and rec.get("record_version") == RECORD_VERSION
                and rec.get("status") in OUTCOMES and rec.get("status") not in RETRIED):
            finished[case.case_id] = rec
    return finished


# ------------------------------------------------------------------------------------ executors


def _result(future, task: dict) -> dict:
    """A finished future's result; a failure of the executor itself (a worker process killed, a
    broken pool, a lost Dask worker) becomes an ``error`` case that a re-run retries."""
    try:
        return future.result()
    except Exception as exc:  # noqa: BLE001 - run_case never raises: this is the executor failing
        out = {k: task[k] for k in ("case", "case_id", "params", "realization", "seed")}
        out.update({"status": "error", "error": f"executor: {type(exc).__name__}: {exc}",
                    "record_version": RECORD_VERSION, "timings_s": {}, "wall_time_s": None})
        return out


def _longest_first(tasks: list[dict]) -> list[dict]:
    """Tasks by decreasing estimated cost (``task["cost"]``, :func:`case_cost`), then case order:
    the longest-processing-time-first rule, so that the last case to start is a short one."""
    return sorted(tasks, key=lambda t: (-float(t.get("cost") or 0.0), t["case"]))


def run_tasks(tasks: list[dict], on_done: Callable[[dict], None], *, workers: int = 1,
              scheduler: str | None = None, client=None) -> str:
    """Run ``run_case`` over ``tasks`` and call ``on_done(result)`` in this process as each one
    finishes (any order). Returns a description of the executor.

    ``client`` (a connected Dask client; ``scheduler``: its address, for the description): on that
    Dask cluster; else ``workers`` > 1: a local process pool (spawned processes, one thread each);
    else serially in this process, in case order. Pools and Dask get the tasks longest first
    (``task["cost"]``).
    """
    if not tasks:
        return "none (every case was finished)"
    if client is not None:
        from dask.distributed import as_completed

        # one thread per library and the kernels loaded, once per worker (and on workers that join)
        client.register_plugin(dask_worker_plugin())
        ordered = _longest_first(tasks)
        futures = {client.submit(run_case, t, key=f"rockmass-case-{t['case_id'][:16]}-{i}",
                                 pure=False, priority=len(ordered) - i): t
                   for i, t in enumerate(ordered)}
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

    # spawned processes inherit this environment: one thread per library before numpy loads
    saved = {k: os.environ.get(k) for k in THREAD_ENV}
    os.environ.update(THREAD_ENV)
    try:
        pool = ProcessPoolExecutor(max_workers=workers,
                                   mp_context=multiprocessing.get_context("spawn"),
                                   initializer=_init_pool_worker, initargs=(os.getpid(),))
        try:
            futures = {pool.submit(run_case, t): t for t in _longest_first(tasks)}
            pending = set(futures)
            while pending:
                done, pending = wait(pending, return_when=FIRST_COMPLETED)
                for fut in sorted(done, key=lambda f: futures[f]["case"]):
                    on_done(_result(fut, futures[fut]))
        except BaseException:  # Ctrl-C, SIGTERM (study_cmd makes it one), a failing callback
            _stop_pool(pool)
            raise
        pool.shutdown(wait=True)
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    return f"local process pool ({workers} workers)"
