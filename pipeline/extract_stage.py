"""The work of ``rockmass extract`` and of the ``extract`` stage of ``rockmass run``.

Joint traces from a face photograph, with their statistics: :func:`compute` reads the photograph,
extracts the traces (:func:`rockmass.imaging.extract`) and analyses them; :func:`produce` also
writes ``traces.geojson``, ``summary.json``, ``overlay.png``, ``rose.png``, ``manifest.json`` and
the ``debug_*.png`` images into a folder, all of them or none. Each trace of ``traces.geojson``
carries fractopo's validation labels in ``VALIDATION_ERRORS`` (:mod:`rockmass.dfn.trace_validation`;
flagged, never fixed), counted in ``summary.json`` under ``statistics.validation``.

The command (:mod:`rockmass.extract_cmd`) parses the arguments, calls :func:`produce` and prints;
``rockmass run`` calls :func:`produce` with the arguments it planned.
"""

from __future__ import annotations

import time
import warnings
from pathlib import Path

from .errors import InputError, reading, reads
from .inputs import read_polygon_file
from .outputs import output_set, plot_text
from .traces_stage import dimension_entry

__all__ = ["compute", "produce", "imaging_settings", "read_photograph", "extract_params"]

#: names ``rockmass extract`` may write besides those of the new set (``--debug-images``).
_OWNED = (r"debug_.+\.png", r"traces_map\.geojson")


def imaging_settings(args, document=None):
    """The ``[imaging]`` settings as a dict: from ``document`` (a validated RockmassConfig, e.g. the
    one ``rockmass run`` planned with) when given, else from ``--config`` (or the defaults), then
    overridden by the flags given."""
    if document is None and args.config:
        from .config import load_config

        document = load_config(args.config)
    if document is not None and document.imaging is not None:
        values = document.imaging.model_dump()
    else:  # no [imaging] section: the defaults, without importing pydantic for them
        values = _imaging_defaults()
    for key in ("m_per_px", "face_dip_deg", "face_dip_direction_deg"):  # flags a command may lack
        if getattr(args, key, None) is not None:
            values[key] = getattr(args, key)
    for key, other in (("joint_width_px", "joint_width_m"), ("joint_width_m", "joint_width_px")):
        if getattr(args, key, None) is not None:  # a width on the command line replaces the file's
            values[key], values[other] = getattr(args, key), None
    if getattr(args, "joints", None) == "all":  # ``rockmass run`` plans args without it
        values["params"] = _every_joint(values["params"], args)
    if args.bright_lines:
        values["params"] = {**values["params"], "line_polarity": "bright"}
    if getattr(args, "detector", None) is not None:  # ``rockmass run`` plans args without it
        values["params"] = {**values["params"], "detector": args.detector}
    if getattr(args, "face_mask", None) is not None:  # likewise
        values["params"] = {**values["params"], "face_mask": args.face_mask}
    if getattr(args, "pixel_model", None) is not None:  # likewise
        values["params"] = {**values["params"], "pixel_model": str(args.pixel_model)}
    if values["params"].get("pixel_model") is not None:
        _check_pixel_model(values["params"]["pixel_model"])
    return values


def _every_joint(params: dict, args) -> dict:
    """``params`` with the settings of ``--joints all``
    (:data:`rockmass.imaging.extract.EVERY_JOINT`) over them, as every flag goes over the config
    file; refused beside a flag that picks another detector, model or joint polarity."""
    from .imaging.extract import EVERY_JOINT

    clashes = [flag for flag, given in (("--detector", getattr(args, "detector", None)),
                                        ("--pixel-model", getattr(args, "pixel_model", None)),
                                        ("--bright-lines", args.bright_lines or None))
               if given is not None]
    if clashes:
        raise InputError(f"--joints all runs the convolutional network on dark joints (detector "
                         f"'learned', pixel model 'cnn'); it cannot be given with "
                         f"{' or '.join(clashes)}")
    return {**params, **EVERY_JOINT}


def _imaging_defaults() -> dict:
    """``ImagingConfig().model_dump()``, the ``[imaging]`` settings of a run without that section,
    written out so that ``rockmass extract`` without ``--config`` does not import pydantic and the
    config models (a test holds the two equal)."""
    return {"m_per_px": None, "joint_width_px": None, "joint_width_m": None, "face_dip_deg": None,
            "face_dip_direction_deg": None, "params": {}}


def _check_pixel_model(path) -> None:
    """A model file given by ``--pixel-model`` or ``imaging.params.pixel_model`` must load before
    anything is written (exit 2 naming it)."""
    from .imaging.learned import load_model

    try:
        load_model(path)
    except (OSError, ValueError) as error:  # missing, or not a model (load_model says which)
        raise InputError(f"imaging.params.pixel_model / --pixel-model: {error}") from error


def read_photograph(path: Path, max_pixels_option: int | None = None):
    """(image, pixel limit in force): the photograph at ``path`` read as
    :func:`rockmass.imaging.enhance.read_photo` reads it, refused from its header before decoding
    when it has more pixels than the limit (``--max-pixels``, :mod:`rockmass.image_limits`).

    Raises
    ------
    InputError
        The file cannot be read as a photograph, or is too large (the message names it).
    """
    from .image_limits import check_image_pixels, max_pixels
    from .imaging.enhance import read_photo

    check_image_pixels(path, max_pixels_option)  # from the header, before decoding
    pixel_limit = max_pixels(max_pixels_option)
    try:
        return read_photo(path, pixel_limit), pixel_limit
    except OSError as exc:
        raise InputError(f"{path}: cannot read the photograph: {exc.strerror or exc}") from exc
    except ValueError as exc:
        raise InputError(f"{path}: {exc}") from None


def extract_params(settings: dict, config=None):
    """The :class:`rockmass.imaging.ExtractParams` of ``settings["params"]`` (from
    :func:`imaging_settings`); a refused value is bad input naming ``config`` (the file, when the
    settings came from one) and the field."""
    from .imaging.extract import ExtractParams

    try:
        return ExtractParams(**settings["params"])
    except (TypeError, ValueError) as exc:
        where = f"{config}: " if config else ""
        raise InputError(f"{where}imaging.params: {exc}") from None


@reads("photo")
def compute(args, document=None):
    """Extract and analyse; return (summary, extraction, traces with sets, image, set ids, timings,
    settings used). ``document``: the validated config to take ``[imaging]`` from instead of
    loading ``args.config``."""
    import dataclasses

    import numpy as np

    from .imaging import extract
    from .imaging.extract import STEPS, ExtractParams
    from .progress import step_bar

    settings = imaging_settings(args, document)
    path = Path(args.photo)
    t0 = time.perf_counter()
    image, pixel_limit = read_photograph(path, getattr(args, "max_pixels", None))
    roi = None
    if args.roi:
        with reading(args.roi, "--roi"):
            roi = {"uv_m": read_polygon_file(args.roi, "--roi")}
    elif args.roi_px:
        with reading(args.roi_px, "--roi-px"):
            roi = {"rc_px": read_polygon_file(args.roi_px, "--roi-px")[:, ::-1]}
    control = None
    if args.control_points:
        r1, c1, r2, c2, distance = args.control_points
        control = {"rc_px": [(r1, c1), (r2, c2)], "distance_m": distance}
    georeference = None
    if settings["m_per_px"] is None and control is None:  # a GeoTIFF's pixel size is its scale
        from .imaging.georef import read_georeference

        georeference = read_georeference(path, pixel_limit)
        if georeference is not None:
            settings = {**settings, "m_per_px": georeference.m_per_px}
    t1 = time.perf_counter()
    with warnings.catch_warnings(), step_bar("extract", STEPS) as bar:
        warnings.simplefilter("ignore", UserWarning)  # recorded in the result's warnings instead
        try:
            result = extract(image, m_per_px=settings["m_per_px"], control_points=control,
                             joint_width_px=settings["joint_width_px"],
                             joint_width_m=settings["joint_width_m"], roi=roi,
                             face_dip_deg=settings["face_dip_deg"],
                             face_dip_direction_deg=settings["face_dip_direction_deg"],
                             params=ExtractParams(**settings["params"]), debug=args.debug_images,
                             progress=bar)
        except ValueError as exc:
            if roi is not None and str(exc).startswith("roi"):  # the region's file is at fault
                flag, roi_file = ("--roi", args.roi) if args.roi else ("--roi-px", args.roi_px)
                raise InputError(f"{roi_file}: {flag}: {exc} (photo {path})") from None
            raise InputError(f"{path}: {exc}") from None
    t2 = time.perf_counter()
    traces = result.traces
    unit = result.scale.units
    summary = {"input": {"path": str(path), "shape_px": list(image.shape[:2])},
               "extraction": result.summary()}
    if georeference is not None:  # docs/imaging.md §1.1
        summary["input"]["georeference"] = georeference.to_dict()
    set_ids = np.full(traces.n_traces, -1, dtype=np.int64)
    validation = np.full(traces.n_traces, "", dtype=str)
    if traces.n_traces >= 1:
        from .dfn.trace_validation import errors_text

        stats, summary["statistics"] = _statistics(traces, args.n_sets, unit)
        set_ids = np.array(stats.traces.set_id, dtype=np.int64)
        validation = errors_text(stats.traces.validation_errors)
        summary["statistics_confident"] = _confident_statistics(traces, args.n_sets, unit,
                                                                summary["statistics"])
    else:
        summary["statistics"] = summary["statistics_confident"] = None
        summary["extraction"]["warnings"].append("no trace was found: nothing to analyse")
    # fractopo's VALIDATION_ERRORS per trace (issue 19): what fractopo would flag, never fixed here
    attributes = {**traces.attributes, "set": set_ids, "VALIDATION_ERRORS": validation}
    traces = dataclasses.replace(traces, attributes=attributes)
    timings = {"read_s": t1 - t0, "extract_s": t2 - t1, "analyse_s": time.perf_counter() - t2}
    return summary, result, traces, image, set_ids, timings, settings


def _statistics(traces, n_sets, unit):
    """(TraceMapStatistics, its summary dict with the box-counting dimension) of a trace map."""
    from .dfn import trace_map_statistics
    from .fractal import box_count

    stats = trace_map_statistics(traces, n_sets=n_sets, length_unit=unit)
    return stats, {**stats.to_dict(), "Box-counting Dimension": dimension_entry(box_count(traces))}


def _confident_statistics(traces, n_sets, unit, every: dict) -> dict:
    """The statistics of the traces whose ``joint_score`` reaches
    :data:`rockmass.imaging.trace_score.LOW_SCORE` (docs/imaging.md §7.1), with how many were left
    out; ``statistics`` is None when none reaches it, and ``every`` (the statistics of all the
    traces) when none is left out. The window (and so the area of P20, P21) is that of all the
    traces. When the kept traces cannot carry the ``n_sets`` asked for (too few distinct angles),
    their sets are chosen by BIC and ``note`` says why."""
    import numpy as np

    from .imaging.trace_score import LOW_SCORE

    keep = np.asarray(traces.attributes["joint_score"], dtype=float) >= LOW_SCORE
    entry = {"min_joint_score": LOW_SCORE, "traces_kept": int(keep.sum()),
             "traces_left_out": int((~keep).sum()), "statistics": None}
    if keep.all():
        entry["statistics"] = every
    elif keep.any():
        confident = traces.subset(keep)
        try:
            entry["statistics"] = _statistics(confident, n_sets, unit)[1]
        except ValueError as exc:  # n_sets fitted all traces but not the fewer kept ones
            if n_sets is None:
                raise
            entry["statistics"] = _statistics(confident, None, unit)[1]
            entry["note"] = f"{exc}: the kept traces' sets were chosen by BIC"
    return entry


def produce(args, out_dir, document=None):
    """Extract, analyse and write every output into the folder ``out_dir``; return the summary.

    The work of ``rockmass extract`` (and of the ``extract`` stage of ``rockmass run``, which passes
    its planned, validated ``document`` so that the config file is not read again).
    """
    from contextlib import ExitStack

    import numpy as np

    plotting = _import_plotting_in_background()
    summary, result, traces, image, set_ids, timings, settings = compute(args, document)
    plotting.join()
    from .atomic import atomic_path, atomic_write_json
    from .imaging.extract import infinities_as_text
    from .dfn import write_traces
    from .dfn.plots import rose_diagram
    from .imaging.overlay import plot_overlay
    from .manifest import build_manifest

    name = plot_text(Path(args.photo).name)
    with output_set(out_dir, owns=_OWNED) as out, ExitStack() as stack:
        files = ["traces.geojson", "summary.json", "overlay.png", "rose.png", "manifest.json"]
        files += [f"debug_{key}.png" for key in result.debug]
        georeference = summary["input"].get("georeference")
        files += ["traces_map.geojson"] if georeference else []
        paths = {f: stack.enter_context(atomic_path(out / f)) for f in files}
        write_traces(traces, paths["traces.geojson"])
        if georeference:  # the same traces on the GeoTIFF's map (docs/imaging.md §1.1)
            from .imaging.georef import GeoReference, to_map

            write_traces(to_map(traces, GeoReference.from_dict(georeference), image.shape[0]),
                         paths["traces_map.geojson"])
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
            config={"imaging": {**settings, "params": infinities_as_text(settings["params"])}},
            timings_s=timings))
    return summary


def _import_plotting_in_background():
    """Start importing matplotlib's figure, Agg backend, line collections and polar axes in a
    thread of their own, and return the thread.

    The overlay and rose are drawn last, and their imports are the largest of the command's
    (``python -X importtime``); this thread runs them while the photograph is decoded and the
    chain runs, mostly in OpenCV and NumPy calls that release the GIL. The main thread imports the
    same modules when it draws: a module being imported by this thread is waited for, not imported
    twice; none of these modules imports rockmass, so the two threads cannot wait on each other."""
    import threading

    def load():
        import matplotlib

        matplotlib.use("Agg", force=False)
        import matplotlib.backends.backend_agg  # noqa: F401
        import matplotlib.collections  # noqa: F401
        import matplotlib.figure  # noqa: F401
        import matplotlib.projections.polar  # noqa: F401

    thread = threading.Thread(target=load, name="import-matplotlib", daemon=True)
    thread.start()
    return thread


def _write_debug_image(array, path) -> None:
    """An intermediate image as 8-bit PNG (scaled to 0-255)."""
    import cv2
    import numpy as np

    a = np.asarray(array, dtype=np.float64)
    lo, hi = float(np.min(a)), float(np.max(a))
    scaled = np.zeros(a.shape, np.uint8) if hi <= lo else np.round(255 * (a - lo) / (hi - lo)).astype(np.uint8)
    if not cv2.imwrite(str(path), scaled):
        raise OSError(f"could not write {path}")
