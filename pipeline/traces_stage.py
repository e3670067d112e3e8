"""The work of ``rockmass traces`` and of the ``traces`` stage of ``rockmass run``.

Statistics of a digitised trace map: :func:`compute` reads the map and analyses it (trace-map
statistics and the box-counting dimension); :func:`produce` also writes ``summary.json``,
``rose.png``, ``traces.png`` and ``manifest.json`` into a folder, all of them or none, and with
``gis`` set (``--gis gpkg|shp``) the GIS layers of :func:`gis_layers`.

The command (:mod:`rockmass.traces_cmd`) parses the arguments, calls :func:`produce` and prints;
``rockmass run`` calls :func:`produce` with the arguments it planned.
"""

from __future__ import annotations

import time
from pathlib import Path

from .errors import InputError, reading, reads
from .budgets import check_traces
from .inputs import read_trace_file, read_trace_map, warn
from .outputs import output_set, plot_text

__all__ = ["AREA_CHOICES", "GIS_FORMATS", "area_window", "dimension_entry", "compute", "gis_layers", "produce"]

#: ``--gis`` formats and the file each writes (:func:`rockmass.dfn.gis_io.write_gis`; a Shapefile's
#: other layers go beside it as ``traces_area.shp``, ``traces_nodes.shp``, ``traces_branches.shp``).
GIS_FORMATS = {"gpkg": "traces.gpkg", "shp": "traces.shp"}

#: GIS layers an earlier run wrote (``--gis gpkg|shp``): dropped when this run writes none or the
#: other format, so the folder never holds layers of another map beside this summary
_OWNED = (r"traces\.gpkg", r"traces(_area|_nodes|_branches)?\.(shp|shx|dbf|prj|cpg)")


def dimension_entry(result) -> dict:
    """The "Box-counting Dimension" entry of a summary, from a :class:`~rockmass.fractal.BoxCount`."""
    return {"value": result.dimension, "unit": "-", "ci95": list(result.ci95), "r2": result.r2,
            "fit_range_px": list(result.fit_range_px), "grid": result.grid, "method": result.method,
            "offsets_min": result.offset_range[0], "offsets_max": result.offset_range[1]}


#: ``--area`` (and ``[run] area``) values that choose a stand-in for an unrecorded area.
AREA_CHOICES = {"bbox": "the traces' bounding box", "hull": "the convex hull of the traces"}


def area_window(trace_map, area, file, option: str = "--area"):
    """The sampling window the statistics use, and the ``input.area`` entry that names it.

    ``area``: None (the map's own window polygon; a map without one is bad input, issue 19: the area
    is never chosen silently), ``"bbox"`` / ``"hull"`` (an explicit stand-in), or a GeoJSON file
    with one polygon, in the map's CRS. ``option`` names the setting in messages: ``--area`` or
    ``run.area`` (then spelled as a config key). Returns ``(SamplingWindow, entry)``.
    """
    from .dfn.intensity import sampling_window

    if area is None:
        if trace_map.window_xy_m is None:
            spell = ((lambda v: f'area = "{v}" in [run]') if option == "run.area"
                     else (lambda v: f"{option} {v}"))
            raise InputError(
                f"{file}: the trace map has no sampling area (no window polygon in the file), and "
                "trace statistics need one: P20 and P21 are per unit of the area that was mapped. "
                f"Give {spell('AREA.geojson')} (a polygon of the mapped area), or choose a stand-in "
                f"explicitly: {spell('bbox')} (the traces' bounding box) or {spell('hull')} (their "
                "convex hull); the outputs then name it")
        window = sampling_window(trace_map)
        entry = {"choice": "map_window", "file": None,
                 "text": "the map's own window polygon"}
    elif area in AREA_CHOICES:
        window = sampling_window(trace_map, area)
        entry = {"choice": area, "file": None,
                 "text": f"{AREA_CHOICES[area]} ({option} {area}), a stand-in for the mapped area"}
    else:
        with reading(area, option):
            polygon = read_trace_file(Path(area), option)
        if polygon.window_xy_m is None:
            raise InputError(f"{area}: the {option} file holds no polygon (a GeoJSON Polygon feature, "
                             "or a polygon layer of a GeoPackage or Shapefile, is expected)")
        if polygon.crs != trace_map.crs:
            raise InputError(f"{area}: the {option} polygon is in crs {polygon.crs!r} but the trace "
                             f"map {file} is in {trace_map.crs!r}; give both in one CRS")
        window = sampling_window(trace_map, polygon.window_xy_m)
        entry = {"choice": "file", "file": str(area), "text": f"the polygon of {area}"}
    return window, {**entry, "value": window.area_m2, "unit": "m²", "source": window.source}


@reads("file")
def compute(args):
    """Read and analyse; return (summary dict, trace map with the window used, the
    :class:`~rockmass.dfn.SamplingWindow`, timings).

    Zero-length traces are dropped with a warning and counted in ``input.dropped_zero_length``
    (:func:`rockmass.inputs.drop_zero_length` says why), and a map of more traces than the limit
    is refused before its statistics start (:func:`rockmass.budgets.check_traces`).
    """
    from .dfn import trace_map_statistics
    from .fractal import box_count

    t0 = time.perf_counter()
    trace_map, dropped = read_trace_map(Path(args.file), layer=getattr(args, "layer", None))
    if dropped["count"]:
        warn(dropped["text"])
    if trace_map.n_traces == 0:
        raise InputError(f"{args.file}: the map holds no traces" + (
            f" of any length ({dropped['count']} zero-length traces dropped)"
            if dropped["count"] else ""))
    check_traces(trace_map.n_traces, args.file, getattr(args, "max_traces", None))
    window, area = area_window(trace_map, args.area, args.file, getattr(args, "area_option", "--area"))
    t1 = time.perf_counter()
    summary = trace_map_statistics(trace_map, window=window, n_sets=args.n_sets,
                                   snap_tolerance_m=args.snap_tolerance_m).to_dict()
    t2 = time.perf_counter()
    if window.source != "bounding_box":  # the window is the face mask of the box count
        trace_map = trace_map.with_window(window.polygon)
    dimension = box_count(trace_map)
    t3 = time.perf_counter()
    summary["Box-counting Dimension"] = dimension_entry(dimension)
    summary["input"] = {"path": str(args.file), "n_traces": int(trace_map.n_traces),
                        "frame": trace_map.frame, "crs": trace_map.crs, "area": area,
                        "dropped_zero_length": {k: v for k, v in dropped.items() if k != "text"}}
    timings = {"read_s": t1 - t0, "statistics_s": t2 - t1, "box_count_s": t3 - t2}
    return summary, trace_map, window, timings


def gis_layers(trace_map, window, summary):
    """The map to write as GIS layers, and its branches and nodes.

    Returns ``(TraceMap, BranchesAndNodes)``: the traces with the window used as their area and,
    besides their own attributes, the fields ``set`` (-1: none), ``length`` (of the whole trace),
    ``length_in_area`` (inside the area, as P21 counts it), ``azimuth`` on a map (clockwise from
    North; ``angle_deg``, counter-clockwise from +u, on a face), ``censored``, ``connections`` and
    fractopo's ``VALIDATION_ERRORS`` (:func:`rockmass.dfn.trace_validation.errors_text`). Traces
    that miss the area were not analysed: set -1, length_in_area 0, no angle, no validation text.
    Computed fields replace attributes of the same name.
    """
    import dataclasses

    import numpy as np
    import shapely

    from .dfn import branches_and_nodes
    from .dfn.gis_io import VALIDATION_FIELD
    from .dfn.trace_validation import errors_text

    traces = summary["traces"]
    mapped = trace_map.with_window(window.polygon)
    reaches = shapely.intersects(mapped.to_shapely(), window.polygon)

    def every(values, fill, dtype):
        column = np.full(mapped.n_traces, fill, dtype=dtype)
        column[reaches] = np.asarray(values, dtype=dtype)
        return column

    angles = [np.nan if a is None else a for a in traces["angle_deg"]]
    fields = {
        "set": every(traces["set"], -1, np.int64),
        "length": mapped.lengths_m(),
        "length_in_area": every(traces["length"], 0.0, np.float64),
        ("azimuth" if summary["angle_convention"] == "azimuth" else "angle_deg"): every(angles, np.nan, np.float64),
        "censored": every(traces["censored"], False, bool),
        "connections": every(traces["connections"], 0, np.int64),
        VALIDATION_FIELD: every(errors_text(traces["validation_errors"]), "", object).astype(str),
    }
    mapped = dataclasses.replace(mapped, attributes={**mapped.attributes, **fields})
    network = branches_and_nodes(mapped, snap_tolerance_m=summary["settings"]["snap_tolerance"]["value"],
                                 window=window)
    return mapped, network


def _require_gis(args) -> None:
    """``--gis`` without pyogrio is bad input, found before any work (exit 2, with the pip hint)."""
    if getattr(args, "gis", None):
        from .dfn.gis_io import require_pyogrio

        try:
            require_pyogrio()
        except ImportError as exc:
            raise InputError(f"--gis {args.gis}: {exc}") from exc


def _set_per_trace(trace_map, set_ids):
    """The set of every trace of the map from the sets of the traces that reach its window (the
    statistics leave the others out): -1 (grey in the plot) for a trace outside the window."""
    import numpy as np
    import shapely

    if len(set_ids) == trace_map.n_traces or trace_map.window_xy_m is None:
        return set_ids
    reaches = shapely.intersects(trace_map.to_shapely(), trace_map.window_polygon())
    every = np.full(trace_map.n_traces, -1, dtype=np.int64)
    every[reaches] = set_ids
    return every


def produce(args, out_dir=None):
    """Analyse, and write every output into the folder ``out_dir`` when given; return the summary.

    The work of ``rockmass traces`` (and of the ``traces`` stage of ``rockmass run``).
    """
    from contextlib import ExitStack

    _require_gis(args)
    summary, trace_map, window, timings = compute(args)
    gis = getattr(args, "gis", None)
    if out_dir:
        import numpy as np

        from .atomic import atomic_path, atomic_write_json
        from .dfn.plots import plot_trace_map, rose_diagram
        from .manifest import build_manifest

        traces = summary["traces"]
        set_ids = _set_per_trace(trace_map, np.array(traces["set"], dtype=np.int64))
        set_means = [s["Mean Angle"]["value"] for s in summary["sets"]]
        # all files renamed into place only when every one is written
        with output_set(out_dir, owns=_OWNED) as out, ExitStack() as stack:
            paths = {name: stack.enter_context(atomic_path(out / name))
                     for name in ("rose.png", "traces.png", "summary.json", "manifest.json")}
            rose_diagram(np.array([np.nan if a is None else a for a in traces["angle_deg"]], dtype=float),
                         np.array(traces["length"], dtype=float), paths["rose.png"],
                         set_means_deg=set_means, convention=summary["angle_convention"],
                         title=f"{plot_text(Path(args.file).name)}: trace orientations")
            plot_trace_map(trace_map, paths["traces.png"], set_ids=set_ids,
                           title=f"{plot_text(Path(args.file).name)}: traces by set")
            atomic_write_json(paths["summary.json"], summary)
            if gis:
                from .dfn import write_gis

                gis_map, network = gis_layers(trace_map, window, summary)
                write_gis(gis_map, out / GIS_FORMATS[gis], network)
            manifest = build_manifest(
                command=args.argv,
                inputs=[args.file] + ([args.area] if args.area and args.area not in AREA_CHOICES else []),
                config={"n_sets": args.n_sets, "snap_tolerance_m": args.snap_tolerance_m,
                        "area": args.area, "layer": getattr(args, "layer", None), "gis": gis},
                timings_s=timings)
            atomic_write_json(paths["manifest.json"], manifest)
    return summary
