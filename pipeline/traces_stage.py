"""The work of ``rockmass traces`` and of the ``traces`` stage of ``rockmass run``.

Statistics of a digitised trace map: :func:`compute` reads the map and analyses it (trace-map
statistics and the box-counting dimension); :func:`produce` also writes ``summary.json``,
``rose.png``, ``traces.png`` and ``manifest.json`` into a folder, all of them or none.

The command (:mod:`rockmass.traces_cmd`) parses the arguments, calls :func:`produce` and prints;
``rockmass run`` calls :func:`produce` with the arguments it planned.
"""

from __future__ import annotations

import time
from pathlib import Path

from .errors import InputError, reading, reads
from .inputs import read_polygon_file, read_trace_file
from .outputs import output_set, plot_text

__all__ = ["dimension_entry", "compute", "produce"]


def dimension_entry(result) -> dict:
    """The "Box-counting Dimension" entry of a summary, from a :class:`~rockmass.fractal.BoxCount`."""
    return {"value": result.dimension, "unit": "-", "ci95": list(result.ci95), "r2": result.r2,
            "fit_range_px": list(result.fit_range_px), "grid": result.grid, "method": result.method,
            "offsets_min": result.offset_range[0], "offsets_max": result.offset_range[1]}


@reads("file")
def compute(args):
    """Read and analyse; return (summary dict, trace map, timings)."""
    from .dfn import trace_map_statistics
    from .fractal import box_count

    t0 = time.perf_counter()
    trace_map = read_trace_file(Path(args.file))
    window = None
    if args.area:
        with reading(args.area, "--area"):
            window = read_polygon_file(args.area, "--area")
    if trace_map.n_traces == 0:
        raise InputError(f"{args.file}: the map holds no traces")
    if window is not None:
        trace_map = trace_map.with_window(window)
    t1 = time.perf_counter()
    summary = trace_map_statistics(trace_map, n_sets=args.n_sets,
                                   snap_tolerance_m=args.snap_tolerance_m).to_dict()
    t2 = time.perf_counter()
    dimension = box_count(trace_map)  # the map's window (if any) is the face mask
    t3 = time.perf_counter()
    summary["Box-counting Dimension"] = dimension_entry(dimension)
    summary["input"] = {"path": str(args.file), "n_traces": int(trace_map.n_traces),
                        "frame": trace_map.frame, "crs": trace_map.crs}
    timings = {"read_s": t1 - t0, "statistics_s": t2 - t1, "box_count_s": t3 - t2}
    return summary, trace_map, timings


def produce(args, out_dir=None):
    """Analyse, and write every output into the folder ``out_dir`` when given; return the summary.

    The work of ``rockmass traces`` (and of the ``traces`` stage of ``rockmass run``).
    """
    from contextlib import ExitStack

    summary, trace_map, timings = compute(args)
    if out_dir:
        import numpy as np

        from .atomic import atomic_path, atomic_write_json
        from .dfn.plots import plot_trace_map, rose_diagram
        from .manifest import build_manifest

        traces = summary["traces"]
        set_means = [s["Mean Angle"]["value"] for s in summary["sets"]]
        # all files renamed into place only when every one is written
        with output_set(out_dir) as out, ExitStack() as stack:
            paths = {name: stack.enter_context(atomic_path(out / name))
                     for name in ("rose.png", "traces.png", "summary.json", "manifest.json")}
            rose_diagram(np.array(traces["angle_deg"], dtype=float),
                         np.array(traces["length"], dtype=float), paths["rose.png"],
                         set_means_deg=set_means, title=f"{plot_text(Path(args.file).name)}: trace orientations")
            plot_trace_map(trace_map, paths["traces.png"], set_ids=np.array(traces["set"]),
                           title=f"{plot_text(Path(args.file).name)}: traces by set")
            atomic_write_json(paths["summary.json"], summary)
            manifest = build_manifest(
                command=args.argv, inputs=[args.file] + ([args.area] if args.area else []),
                config={"n_sets": args.n_sets, "snap_tolerance_m": args.snap_tolerance_m},
                timings_s=timings)
            atomic_write_json(paths["manifest.json"], manifest)
    return summary
