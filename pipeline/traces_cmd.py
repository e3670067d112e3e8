"""``rockmass traces FILE``: statistics of a digitised trace map.

Reads traces (GeoJSON or CSV), computes the trace-map statistics of
:func:`rockmass.dfn.trace_map_statistics` (joint sets, P20, P21, trace lengths with censoring,
Mauldon estimators on the window when it is a circle, else on disjoint circles placed inside it,
I-Y-X-E topology) and the box-counting dimension of
:func:`rockmass.fractal.box_count` over the same window, and writes under ``--out DIR``:
``summary.json``, ``rose.png`` (length-weighted, equal-area, axial), ``traces.png`` (the map by set)
and ``manifest.json`` — all of them or none. ``--json`` prints the summary to stdout.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from .errors import InputError
from .inputs import read_polygon_file, read_trace_file
from .outputs import output_folder, print_summary

__all__ = ["add_parser", "run", "compute", "produce"]


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register the ``traces`` subcommand."""
    p = subparsers.add_parser(
        "traces", help="statistics of a digitised trace map (sets, P20, P21, topology, D)",
        description="Joint sets, intensities (P20, P21), trace lengths with censoring, Mauldon "
                    "estimators, topology and the box-counting dimension of a trace map.")
    p.add_argument("file", help="traces (.geojson, .json or .csv)")
    p.add_argument("--area", help="sampling window: a GeoJSON file with one polygon (default: the "
                                  "map's own window, else the traces' bounding box)")
    p.add_argument("--sets", type=int, dest="n_sets",
                   help="number of joint sets (default: chosen by BIC over 1-5)")
    p.add_argument("--snap-tolerance", type=float, dest="snap_tolerance_m",
                   help="topology snap tolerance in metres (default 1e-4 x window diameter)")
    p.add_argument("--out", help="write summary.json, rose.png, traces.png and manifest.json here")
    p.add_argument("--json", action="store_true", help="print the summary as JSON on stdout")
    p.set_defaults(handler=run)
    return p


def dimension_entry(result) -> dict:
    """The "Box-counting Dimension" entry of a summary, from a :class:`~rockmass.fractal.BoxCount`."""
    return {"value": result.dimension, "unit": "-", "ci95": list(result.ci95), "r2": result.r2,
            "fit_range_px": list(result.fit_range_px), "grid": result.grid, "method": result.method,
            "offsets_min": result.offset_range[0], "offsets_max": result.offset_range[1]}


def compute(args):
    """Read and analyse; return (summary dict, trace map, timings)."""
    from .dfn import trace_map_statistics
    from .fractal import box_count

    t0 = time.perf_counter()
    trace_map = read_trace_file(Path(args.file))
    window = read_polygon_file(args.area, "--area") if args.area else None
    if trace_map.n_traces == 0:
        raise InputError(f"{args.file}: the map holds no traces")
    if window is not None:
        trace_map = trace_map.with_window(window)
    t1 = time.perf_counter()
    summary = trace_map_statistics(trace_map, n_sets=args.n_sets,
                                   snap_tolerance_m=args.snap_tolerance_m)
    t2 = time.perf_counter()
    dimension = box_count(trace_map)  # the map's window (if any) is the face mask
    t3 = time.perf_counter()
    summary["Box-counting Dimension"] = dimension_entry(dimension)
    summary["input"] = {"path": str(args.file), "n_traces": int(trace_map.n_traces),
                        "frame": trace_map.frame, "crs": trace_map.crs}
    timings = {"read_s": t1 - t0, "statistics_s": t2 - t1, "box_count_s": t3 - t2}
    return summary, trace_map, timings


def summary_text(summary: dict) -> str:
    """A few human-readable lines: counts, intensities (with their units), sets and D."""
    def value(key, fmt=".4g"):
        q = summary[key]
        text = "undefined" if q["value"] is None else format(q["value"], fmt)
        return text if q.get("unit") in (None, "-") else f"{text} {q['unit']}"

    lines = [f"{value('Number of Traces', 'd')} traces, P20 = {value('Areal Frequency P20')}, "
             f"P21 = {value('Fracture Intensity P21')}, mean length {value('Trace Mean Length')}, "
             f"D_box = {value('Box-counting Dimension', '.4f')}"]
    for s in summary["sets"]:
        spread = s["Circular Spread"]["value"]
        lines.append(f"  set {s['Set']}: mean angle {s['Mean Angle']['value']:.1f}°, spread "
                     f"{'undefined' if spread is None else format(spread, '.1f') + '°'}, "
                     f"{s['Number of Traces']['value']} traces")
    return "\n".join(lines)


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
        with output_folder(out_dir) as out, ExitStack() as stack:
            paths = {name: stack.enter_context(atomic_path(out / name))
                     for name in ("rose.png", "traces.png", "summary.json", "manifest.json")}
            rose_diagram(np.array(traces["angle_deg"], dtype=float),
                         np.array(traces["length"], dtype=float), paths["rose.png"],
                         set_means_deg=set_means, title=f"{Path(args.file).name}: trace orientations")
            plot_trace_map(trace_map, paths["traces.png"], set_ids=np.array(traces["set"]),
                           title=f"{Path(args.file).name}: traces by set")
            atomic_write_json(paths["summary.json"], summary)
            manifest = build_manifest(
                command=args.argv, inputs=[args.file] + ([args.area] if args.area else []),
                config={"n_sets": args.n_sets, "snap_tolerance_m": args.snap_tolerance_m},
                timings_s=timings)
            atomic_write_json(paths["manifest.json"], manifest)
    return summary


def run(args) -> int:
    """Handler of ``rockmass traces``."""
    print_summary(produce(args, args.out), args.json, summary_text)
    return 0
