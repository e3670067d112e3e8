"""``rockmass extract PHOTO``: joint traces from a face photograph, with their statistics.

Runs :func:`rockmass.imaging.extract`, then the trace-map statistics of ``rockmass traces`` (joint
sets, P20, P21, lengths, topology) and the box-counting dimension, and writes under ``--out DIR``:
``traces.geojson`` (one LineString per trace in the face frame, properties ``id``, ``set``,
``length_m``, ``angle_deg``), ``summary.json`` (statistics, parameters, scale, timings, units,
warnings), ``overlay.png`` (traces by set over the photo), ``rose.png``, ``manifest.json`` and, with
``--debug``, the intermediate images ``debug_*.png`` — all of them or none.

Without a scale (``--m-per-px``, ``--control-points`` or ``[imaging] m_per_px``) everything is in
pixels and labelled so, with a warning.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

from .errors import InputError
from .inputs import read_polygon_file
from .outputs import output_folder, print_json
from .traces_cmd import dimension_entry

__all__ = ["add_parser", "run", "compute", "produce"]


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register the ``extract`` subcommand."""
    p = subparsers.add_parser(
        "extract", help="joint traces from a face photograph (+ sets, intensities, D)",
        description="Segment a face photograph into joint traces (polylines in metres on the face "
                    "frame) and analyse them.")
    p.add_argument("photo", help="JPEG, PNG or TIFF photograph (grey or colour, 8 or 16 bit)")
    p.add_argument("--out", required=True, help="output folder")
    scale = p.add_mutually_exclusive_group()
    scale.add_argument("--m-per-px", type=float, dest="m_per_px", help="scale, metres per pixel")
    scale.add_argument("--control-points", nargs=5, type=float, dest="control_points",
                       metavar=("ROW1", "COL1", "ROW2", "COL2", "DISTANCE_M"),
                       help="two pixel positions and the distance between them on the face, metres")
    p.add_argument("--joint-width", type=float, dest="joint_width_px",
                   help="expected joint width in pixels (default 3)")
    p.add_argument("--face-dip", type=float, dest="face_dip_deg", help="dip of the face plane, deg")
    p.add_argument("--face-dip-direction", type=float, dest="face_dip_direction_deg",
                   help="dip direction of the face plane, deg")
    roi = p.add_mutually_exclusive_group()
    roi.add_argument("--roi", help="region of interest: GeoJSON polygon in metres on the face frame")
    roi.add_argument("--roi-px", dest="roi_px",
                     help="region of interest: GeoJSON polygon in image pixels (x = column, y = row "
                          "down, as image annotation tools write it)")
    p.add_argument("--bright-lines", action="store_true", dest="bright_lines",
                   help="look for bright joints (filled joints, veins, mortar) instead of dark ones; "
                        "set --joint-width to their full width (about 8 px for the mortar of "
                        "skimage's brick photo), or recessed joints split into their two bright rims")
    p.add_argument("--sets", type=int, dest="n_sets", help="number of joint sets (default: by BIC)")
    p.add_argument("--config", help="TOML file; its [imaging] section sets scale, width and params")
    p.add_argument("--debug", action="store_true", help="also write the intermediate images")
    p.add_argument("--json", action="store_true", help="print summary.json on stdout")
    p.set_defaults(handler=run)
    return p


def _settings(args, document=None):
    """The ``[imaging]`` settings as a dict: from ``document`` (a validated RockmassConfig, e.g. the
    one ``rockmass run`` planned with) when given, else from ``--config`` (or the defaults), then
    overridden by the flags given."""
    from .config import ImagingConfig, load_config

    section = ImagingConfig()
    if document is None and args.config:
        document = load_config(args.config)
    if document is not None:
        section = document.imaging or section
    values = section.model_dump()
    for key in ("m_per_px", "joint_width_px", "face_dip_deg", "face_dip_direction_deg"):
        if getattr(args, key) is not None:
            values[key] = getattr(args, key)
    if args.bright_lines:
        values["params"] = {**values["params"], "line_polarity": "bright"}
    return values


def compute(args, document=None):
    """Extract and analyse; return (summary, extraction, traces with sets, image, set ids, timings,
    settings used). ``document``: the validated config to take ``[imaging]`` from instead of
    loading ``args.config``."""
    import dataclasses

    import numpy as np

    from .dfn import trace_map_statistics
    from .fractal import box_count
    from .imaging import extract
    from .imaging.enhance import read_photo
    from .imaging.extract import STEPS, ExtractParams
    from .progress import step_bar

    settings = _settings(args, document)
    path = Path(args.photo)
    t0 = time.perf_counter()
    try:
        image = read_photo(path)
    except OSError as exc:
        raise InputError(f"{path}: cannot read the photograph: {exc.strerror or exc}") from exc
    except ValueError as exc:
        raise InputError(f"{path}: {exc}") from None
    roi = None
    if args.roi:
        roi = {"uv_m": read_polygon_file(args.roi, "--roi")}
    elif args.roi_px:
        roi = {"rc_px": read_polygon_file(args.roi_px, "--roi-px")[:, ::-1]}
    control = None
    if args.control_points:
        r1, c1, r2, c2, distance = args.control_points
        control = {"rc_px": [(r1, c1), (r2, c2)], "distance_m": distance}
    t1 = time.perf_counter()
    with warnings.catch_warnings(), step_bar("extract", STEPS) as bar:
        warnings.simplefilter("ignore", UserWarning)  # recorded in the result's warnings instead
        try:
            result = extract(image, m_per_px=settings["m_per_px"], control_points=control,
                             joint_width_px=settings["joint_width_px"], roi=roi,
                             face_dip_deg=settings["face_dip_deg"],
                             face_dip_direction_deg=settings["face_dip_direction_deg"],
                             params=ExtractParams(**settings["params"]), debug=args.debug,
                             progress=bar)
        except ValueError as exc:
            raise InputError(f"{path}: {exc}") from None
    t2 = time.perf_counter()
    traces = result.traces
    unit = result.scale.units
    summary = {"input": {"path": str(path), "shape_px": list(image.shape[:2])},
               "extraction": result.summary()}
    set_ids = np.full(traces.n_traces, -1, dtype=np.int64)
    if traces.n_traces >= 1:
        stats = trace_map_statistics(traces, n_sets=args.n_sets, length_unit=unit)
        set_ids = np.asarray(stats["traces"]["set"], dtype=np.int64)
        dimension = box_count(traces)
        stats["Box-counting Dimension"] = dimension_entry(dimension)
        summary["statistics"] = stats
    else:
        summary["statistics"] = None
        summary["extraction"]["warnings"].append("no trace was found: nothing to analyse")
    attributes = {**traces.attributes, "set": set_ids}
    traces = dataclasses.replace(traces, attributes=attributes)
    timings = {"read_s": t1 - t0, "extract_s": t2 - t1, "analyse_s": time.perf_counter() - t2}
    return summary, result, traces, image, set_ids, timings, settings


def produce(args, out_dir, document=None):
    """Extract, analyse and write every output into the folder ``out_dir``; return the summary.

    The work of ``rockmass extract`` (and of the ``extract`` stage of ``rockmass run``, which passes
    its planned, validated ``document`` so that the config file is not read again).
    """
    from contextlib import ExitStack

    import numpy as np

    summary, result, traces, image, set_ids, timings, settings = compute(args, document)
    from .atomic import atomic_path, atomic_write_json
    from .dfn import write_traces
    from .dfn.plots import rose_diagram
    from .imaging.overlay import plot_overlay
    from .manifest import build_manifest

    name = Path(args.photo).name
    with output_folder(out_dir) as out, ExitStack() as stack:
        files = ["traces.geojson", "summary.json", "overlay.png", "rose.png", "manifest.json"]
        files += [f"debug_{key}.png" for key in result.debug]
        paths = {f: stack.enter_context(atomic_path(out / f)) for f in files}
        write_traces(traces, paths["traces.geojson"])
        plot_overlay(image, traces, paths["overlay.png"], m_per_px=result.scale.m_per_px,
                     set_ids=set_ids, title=f"{name}: {traces.n_traces} traces")
        stats = summary["statistics"]
        angles = np.asarray(traces.attributes["angle_deg"], dtype=float)
        lengths = traces.lengths_m()
        means = [s["Mean Angle"]["value"] for s in stats["sets"]] if stats else None
        rose_diagram(angles, lengths, paths["rose.png"], set_means_deg=means,
                     title=f"{name}: trace orientations")
        for key, array in result.debug.items():
            _write_debug_image(array, paths[f"debug_{key}.png"])
        atomic_write_json(paths["summary.json"], summary)
        atomic_write_json(paths["manifest.json"], build_manifest(
            command=args.argv, inputs=[args.photo] + [p for p in (args.roi, args.roi_px, args.config) if p],
            config={"imaging": settings}, timings_s=timings))
    return summary


def run(args) -> int:
    """Handler of ``rockmass extract``."""
    summary = produce(args, args.out)
    if args.json:
        print_json(summary)
    else:
        from .traces_cmd import summary_text

        if summary["statistics"]:
            print(summary_text(summary["statistics"]))
        for warning in summary["extraction"]["warnings"]:
            print(f"  warning: {warning}", file=sys.stderr)
    return 0


def _write_debug_image(array, path) -> None:
    """An intermediate image as 8-bit PNG (scaled to 0-255)."""
    import cv2
    import numpy as np

    a = np.asarray(array, dtype=np.float64)
    lo, hi = float(np.min(a)), float(np.max(a))
    scaled = np.zeros(a.shape, np.uint8) if hi <= lo else np.round(255 * (a - lo) / (hi - lo)).astype(np.uint8)
    if not cv2.imwrite(str(path), scaled):
        raise OSError(f"could not write {path}")
