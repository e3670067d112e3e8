"""``rockmass boxcount FILE``: box-counting dimension of a trace map or a binary image.

Reads traces (GeoJSON, CSV) or a binary image (PNG, TIFF, JPEG, BMP), counts boxes with
:func:`rockmass.fractal.box_count`, and writes ``boxcount.json``, ``boxcount.png`` and
``manifest.json`` under ``--out DIR`` (all three or none: each is rendered to a temporary file
first and renamed into place only when every one is ready). ``--json`` prints the same result to
stdout. Settings come from ``--config`` (its ``[fractal]`` section), then the flags.
"""

from __future__ import annotations

import argparse
import sys

from .boxcount_stage import produce
from .image_limits import pixel_limit_arg
from .outputs import print_json

__all__ = ["add_parser", "run"]

# kept literal so that building the parser imports nothing heavy; a test checks them against
# rockmass.fractal.METHODS / LINE_RULES and the config model
METHOD_CHOICES = ("raster", "vector")
LINE_RULE_CHOICES = ("supercover", "bresenham")
SKELETONIZE_CHOICES = ("auto", "always", "never")


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register the ``boxcount`` subcommand."""
    p = subparsers.add_parser(
        "boxcount", help="box-counting fractal dimension of traces or a binary image",
        description="Box-counting fractal dimension D of a trace network (GeoJSON / CSV) or a "
                    "binary image, with R², standard error, 95%% interval, local slopes and the "
                    "spread over grid offsets.")
    p.add_argument("file", help="traces (.geojson, .json, .csv) or a binary image "
                                "(.png, .tif, .jpg, .bmp)")
    p.add_argument("--grid", type=int, help="raster grid side N in pixels (default 360)")
    p.add_argument("--method", choices=METHOD_CHOICES, help="raster (default) or exact vector counting")
    p.add_argument("--range", nargs=2, type=float, metavar=("MIN", "MAX"), dest="range_px",
                   help="fit range of box sizes in grid pixels (default: 1 to grid/4)")
    p.add_argument("--offsets", type=int, dest="n_offsets",
                   help="number of shifted box grids for the spread of D (default 8)")
    p.add_argument("--line-rule", choices=LINE_RULE_CHOICES, dest="line_rule",
                   help="rasterisation rule (default supercover)")
    p.add_argument("--window", nargs=4, type=float, metavar=("XMIN", "YMIN", "XMAX", "YMAX"),
                   help="count on this window (metres) instead of the traces' bounding square")
    p.add_argument("--mask", default="auto",
                   help="face outline: 'auto' (the trace map's own window polygon, if any), "
                        "'none', a GeoJSON file with a polygon, or for an image input a mask image "
                        "(non-zero = face)")
    p.add_argument("--threshold", type=float, help="for grey images: pixels above it are traces")
    p.add_argument("--invert", action=argparse.BooleanOptionalAction, default=None,
                   help="dark lines on a light background (--no-invert overrides a config)")
    p.add_argument("--skeletonize", choices=SKELETONIZE_CHOICES,
                   help="thin lines to 1 pixel: auto (default), always, never")
    p.add_argument("--config", help="TOML file; its [fractal] section sets the defaults")
    p.add_argument("--out", help="write boxcount.json, boxcount.png and manifest.json here")
    p.add_argument("--max-pixels", type=pixel_limit_arg, dest="max_pixels", metavar="N",
                   help="refuse images above N pixels, read from the file's header before decoding "
                        "(default 100000000, or the environment variable ROCKMASS_MAX_PIXELS)")
    p.add_argument("--json", action="store_true", help="print the result as JSON on stdout")
    p.set_defaults(handler=run)
    return p


def summary_line(result) -> str:
    """One human-readable line: D, interval, R², range, offsets and P21."""
    lo, hi = result.ci95
    text = (f"D = {result.dimension:.4f}  (95% CI {lo:.4f}–{hi:.4f}, R² = {result.r2:.4f}), "
            f"fit {result.fit_range_px[0]:g}–{result.fit_range_px[1]:g} px "
            f"({int(result.in_fit.sum())} sizes, {result.method} on {result.grid}²); "
            f"over {result.offset_dimensions.size} grid offsets {result.offset_range[0]:.4f}–"
            f"{result.offset_range[1]:.4f} (mean {result.offset_mean:.4f})")
    if result.p21_per_m is not None:
        text += f"; P21 = {result.p21_per_m:.4g} m/m²"
    return text


def run(args) -> int:
    """Handler of ``rockmass boxcount``."""
    document, result = produce(args, args.out)
    if args.json:
        print_json(document)
    else:
        print(summary_line(result))
        for note in result.notes:
            print(f"  note: {note}", file=sys.stderr)
    return 0
