"""The work of ``rockmass boxcount`` and of the ``boxcount`` stage of ``rockmass run``.

Box-counting dimension of a trace map or a binary image: :func:`compute` reads the input, resolves
the ``[fractal]`` settings (config, then flags) and counts; :func:`produce` also writes
``boxcount.json``, ``boxcount.png`` and ``manifest.json`` into a folder, all three or none.

The command (:mod:`rockmass.boxcount_cmd`) parses the arguments, calls :func:`produce` and prints;
``rockmass run`` calls :func:`produce` with the arguments it planned.
"""

from __future__ import annotations

import time
from pathlib import Path

from .errors import InputError, reading, reads
from .inputs import read_polygon_file, read_trace_file
from .outputs import output_set, plot_text

__all__ = ["TRACE_SUFFIXES", "IMAGE_SUFFIXES", "FLAGS", "compute", "produce"]

TRACE_SUFFIXES = (".geojson", ".json", ".csv", ".gpkg", ".shp")  # dfn.read_traces; GIS files need pyogrio
IMAGE_SUFFIXES = (".png", ".tif", ".tiff", ".jpg", ".jpeg", ".bmp")

# config field -> the flag that sets it, so errors name what the user typed
FLAGS = {"grid": "--grid", "method": "--method", "range_px": "--range", "n_offsets": "--offsets",
         "line_rule": "--line-rule", "threshold": "--threshold", "invert": "--invert",
         "skeletonize": "--skeletonize"}


def _resolve_settings(args, image_side: int | None, document=None):
    """The FractalConfig from ``document`` (a validated RockmassConfig, e.g. the one ``rockmass
    run`` planned with) or else ``--config`` (or defaults), overridden by the flags given.

    For an image the grid is the image's own (padded) side, so a fit range is checked against it.
    """
    from pydantic import ValidationError

    from .config import FractalConfig, load_config, problems_from_validation_error

    base = FractalConfig()
    if document is None and args.config:
        document = load_config(args.config)
    if document is not None:
        base = document.fractal or base
    overrides = {k: getattr(args, k) for k in FLAGS if getattr(args, k) is not None}
    if "range_px" in overrides:
        overrides["range_px"] = tuple(overrides["range_px"])
    if image_side is not None:
        overrides["grid"] = image_side
    data = {**base.model_dump(), **overrides}
    try:
        return FractalConfig.model_validate(data)
    except ValidationError as exc:
        problems = problems_from_validation_error(exc, FractalConfig, data)
        raise InputError("; ".join(f"{FLAGS.get(field.split('.')[0].split('[')[0], field)} "
                                   f"(or [fractal] {field} in the config): {message}"
                                   for field, message in problems)) from None


def _load_input(path: Path, max_pixels: int | None = None):
    """('traces', TraceMap) or ('image', ndarray), by suffix; unreadable files are bad input."""
    suffix = path.suffix.lower()
    if suffix in TRACE_SUFFIXES:
        return "traces", read_trace_file(path)
    if suffix in IMAGE_SUFFIXES:
        return "image", _read_image_file(path, "input", max_pixels)
    raise InputError(f"{path}: unknown file type {suffix or '(none)'}; expected traces "
                     f"({', '.join(TRACE_SUFFIXES)}) or an image ({', '.join(IMAGE_SUFFIXES)})")


def _load_mask(spec: str, kind: str, max_pixels: int | None = None):
    if spec == "auto":
        return "auto"
    if spec == "none":
        return None
    with reading(spec, "--mask"):
        if kind == "image":
            return _read_image_file(Path(spec), "--mask", max_pixels)
        return read_polygon_file(spec, "--mask")


def _read_image_file(path: Path, what: str, max_pixels: int | None = None):
    """The image at ``path``, once its header is within the pixel limit (``--max-pixels``)."""
    from .fractal import read_image
    from .image_limits import check_image_pixels

    check_image_pixels(path, max_pixels)

    try:
        return read_image(path)
    except OSError as exc:
        raise InputError(f"{path}: cannot read the {what} image: {exc.strerror or exc}") from exc


@reads("file")
def compute(args, document=None) -> tuple[dict, object, dict]:
    """Read, count and fit; return the JSON document, the BoxCount and the settings used.
    ``document``: the validated config to take ``[fractal]`` from instead of loading
    ``args.config``."""
    from .fractal import box_count
    from .fractal.image import padded_side

    path = Path(args.file)
    t0 = time.perf_counter()
    kind, data = _load_input(path, getattr(args, "max_pixels", None))
    if kind == "image" and args.grid is not None:
        raise InputError("--grid applies to traces; an image is counted on its own pixel grid")
    if kind == "image" and args.window is not None:
        raise InputError("--window applies to traces, not to an image")
    if kind == "image":
        from .fractal.rasterize import MAX_GRID

        side = padded_side(*data.shape)
        if side > MAX_GRID:  # the image is its own grid: say so, not "--grid" (nobody gave one)
            raise InputError(f"{path}: the image is {data.shape[1]} x {data.shape[0]} pixels "
                             f"(counted on its own grid, padded to {side}); at most {MAX_GRID} "
                             "pixels a side can be box-counted — downsample it first")
    settings = _resolve_settings(args, padded_side(*data.shape) if kind == "image" else None,
                                 document)
    mask = _load_mask(args.mask, kind, getattr(args, "max_pixels", None))
    t1 = time.perf_counter()
    try:
        result = box_count(data, kind=kind, grid=settings.grid, method=settings.method,
                           fit_range_px=settings.range_px, window=args.window, mask=mask,
                           n_offsets=settings.n_offsets, line_rule=settings.line_rule,
                           threshold=settings.threshold, invert=settings.invert,
                           skeletonize=settings.skeletonize)
    except ValueError as exc:
        raise InputError(f"{path}: {exc}") from None
    t2 = time.perf_counter()
    info = {"path": str(path), "kind": kind}
    if kind == "traces":
        info.update(n_traces=int(data.n_traces), frame=data.frame)
    else:
        info.update(shape=list(data.shape), dtype=str(data.dtype))
    document = {"input": info, "settings": settings.model_dump(mode="json"), **result.to_dict()}
    timings = {"read_s": t1 - t0, "count_and_fit_s": t2 - t1}
    return document, result, {"settings": settings, "timings": timings}


def produce(args, out_dir=None, document=None):
    """Count and fit, and write every output into the folder ``out_dir`` when given; return
    (document, BoxCount).

    The work of ``rockmass boxcount`` (and of the ``boxcount`` stage of ``rockmass run``, which
    passes its planned, validated ``document`` so that the config file is not read again).
    """
    from contextlib import ExitStack

    data, result, extra = compute(args, document)
    if out_dir:
        from .atomic import atomic_path, atomic_write_json
        from .fractal.plot import plot_box_count
        from .manifest import build_manifest

        t0 = time.perf_counter()
        with output_set(out_dir) as out, ExitStack() as stack:
            # every file is renamed into place only if all of them were written
            png = stack.enter_context(atomic_path(out / "boxcount.png"))
            js = stack.enter_context(atomic_path(out / "boxcount.json"))
            plot_box_count(result, png, title=f"{plot_text(Path(args.file).name)}: box counting")
            atomic_write_json(js, data)
            timings = {**extra["timings"], "write_s": time.perf_counter() - t0}
            manifest = build_manifest(command=args.argv,
                                      config={"fractal": extra["settings"].model_dump(mode="json")},
                                      inputs=[args.file], timings_s=timings,
                                      extra={"dimension": result.dimension})
            mf = stack.enter_context(atomic_path(out / "manifest.json"))
            atomic_write_json(mf, manifest)
    return data, result
