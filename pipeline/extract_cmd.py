"""``rockmass extract PHOTO``: joint traces from a face photograph, with their statistics.

Runs :func:`rockmass.imaging.extract`, then the trace-map statistics of ``rockmass traces`` (joint
sets, P20, P21, lengths, topology) and the box-counting dimension, and writes under ``--out DIR``:
``traces.geojson`` (one LineString per trace in the face frame, properties ``id``, ``set``,
``length_m``, ``angle_deg``), ``summary.json`` (statistics, parameters, scale, timings, units,
warnings, and under ``extraction.face_mask`` whether a face mask or ROI limited the traces and
the share of the photo it left out), ``overlay.png`` (traces by set over the photo, and the
sampling window's outline when it is not the photo's edge), ``rose.png``, ``manifest.json``
and, with ``--debug``, the intermediate images ``debug_*.png`` — all of them or none.

Without a scale (``--m-per-px``, ``--control-points`` or ``[imaging] m_per_px``) a GeoTIFF's pixel
size is the scale (a north-up, projected grid in metres: :mod:`rockmass.imaging.georef`; recorded
as ``input.georeference`` in summary.json); otherwise everything is in pixels and labelled so,
with a warning.
"""

from __future__ import annotations

import argparse
import sys

from .extract_stage import produce
from .image_limits import pixel_limit_arg
from .outputs import print_json

__all__ = ["add_parser", "run"]


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
    width = p.add_mutually_exclusive_group()
    width.add_argument("--joint-width", type=float, dest="joint_width_px", metavar="PX",
                       help="expected joint width in pixels of the photo (default: 3 pixels of "
                            "the working grid, the photo down-sampled to max_megapixels; the "
                            "learned detector caps a wider one at that)")
    width.add_argument("--joint-width-m", type=float, dest="joint_width_m", metavar="M",
                       help="expected joint width in metres on the face (needs a scale)")
    p.add_argument("--face-dip", type=float, dest="face_dip_deg", help="dip of the face plane, deg")
    p.add_argument("--face-dip-direction", type=float, dest="face_dip_direction_deg",
                   help="dip direction of the face plane, deg")
    roi = p.add_mutually_exclusive_group()
    roi.add_argument("--roi", help="region of interest: GeoJSON polygon in metres on the face frame")
    roi.add_argument("--roi-px", dest="roi_px",
                     help="region of interest: GeoJSON polygon in image pixels (x = column, y = row "
                          "down, as image annotation tools write it)")
    mask = p.add_mutually_exclusive_group()
    mask.add_argument("--face-mask", choices=("border", "full", "off"), dest="face_mask",
                      help="where traces may be found when no ROI is given: 'border' (default) "
                           "leaves out a band along the image border (1 %% of the short side); "
                           "'full' also leaves out over-exposed regions, large smooth ones "
                           "(shotcrete, lining, sky) and large strongly coloured ones (machinery); "
                           "'off' uses the whole photo (see docs/imaging.md §2.1). --roi / --roi-px "
                           "replace it")
    mask.add_argument("--no-face-mask", action="store_const", const="off", dest="face_mask",
                      help="same as --face-mask off")
    p.add_argument("--bright-lines", action="store_true", dest="bright_lines",
                   help="look for bright joints (filled joints, veins, mortar) instead of dark ones; "
                        "set --joint-width to their full width (about 8 px for the mortar of "
                        "skimage's brick photo), or recessed joints split into their two bright rims")
    p.add_argument("--detector", choices=("auto", "learned", "ridge"), dest="detector",
                   help="joint detector: 'learned' (the shipped pixel classifier; docs/imaging.md "
                        "§3.1), 'ridge' (multi-scale ridge filter: bright joints, and clean images "
                        "whose faint hairlines count as joints; the default with --bright-lines) "
                        "or 'auto' (the default: runs both and keeps the ridge filter's traces "
                        "when the learned detector confirms most of them, i.e. on a clean photo, "
                        "and the convolutional network's when it finds clearly more joint length "
                        "than the pixel model; summary.json says which, docs/imaging.md §3.3, §3.6)")
    p.add_argument("--joints", choices=("major", "all"), dest="joints",
                   help="which joints to map: 'major' (the default: the settings as given, which "
                        "by default map the major discontinuities a geologist traces by hand) or "
                        "'all' (every joint the photo shows, hairlines too: the convolutional "
                        "network with the trace filters off, over the config file's settings; "
                        "not with --detector, --pixel-model or --bright-lines; "
                        "docs/imaging.md §8.4)")
    p.add_argument("--pixel-model", dest="pixel_model", metavar="FILE",
                   help="the learned detector's model: 'cnn' (the shipped convolutional network), "
                        "'mlp' (the shipped pixel model, the default), or a file: one trained on "
                        "your own labelled photos by python -m rockmass.imaging.train_pixel_model "
                        "--photos DIR --labels DIR (.npz), or a network (.onnx)")
    p.add_argument("--sets", type=int, dest="n_sets", help="number of joint sets (default: by BIC)")
    p.add_argument("--config", help="TOML file; its [imaging] section sets scale, width and params")
    # its own destination: ``rockmass --debug`` (tracebacks) is the global flag of the same name
    p.add_argument("--debug", "--debug-images", dest="debug_images", action="store_true",
                   help="also write the intermediate images")
    p.add_argument("--max-pixels", type=pixel_limit_arg, dest="max_pixels", metavar="N",
                   help="refuse images above N pixels, read from the file's header before decoding "
                        "(default 100000000, or the environment variable ROCKMASS_MAX_PIXELS)")
    p.add_argument("--json", action="store_true", help="print summary.json on stdout")
    p.set_defaults(handler=run)
    return p


def run(args) -> int:
    """Handler of ``rockmass extract``."""
    summary = produce(args, args.out)
    if args.json:
        print_json(summary)
    else:
        from .traces_cmd import summary_text

        if summary["statistics"]:
            print(summary_text(summary["statistics"]))
        confident = summary.get("statistics_confident") or {}
        if confident.get("traces_left_out"):
            print(f"without the {confident['traces_left_out']} traces of joint score under "
                  f"{confident['min_joint_score']:g}:")
            print(summary_text(confident["statistics"]) if confident["statistics"]
                  else "  no trace left")
        choice = summary["extraction"].get("detector_choice")
        if choice:  # "auto": which detector's traces these are, and why
            print(auto_choice_text(choice))
        if getattr(args, "joints", None) == "all":
            print("joints: every joint the photo shows, hairlines too (--joints all: the "
                  "network, trace filters off; docs/imaging.md §8.4); the statistics without "
                  "low joint scores come closer to a hand-traced map of major discontinuities")
        georeference = summary["input"].get("georeference")
        if georeference:  # the scale came from the photo's GeoTIFF tags
            print(f"scale: {georeference['m_per_px']:.6g} m/px from the GeoTIFF tags "
                  f"({georeference['crs']}; docs/imaging.md §1.1)")
        for warning in summary["extraction"]["warnings"]:
            print(f"  warning: {warning}", file=sys.stderr)
    return 0


def auto_choice_text(choice) -> str:
    """One line on what ``detector = "auto"`` kept and why (``detector_choice`` of summary.json).

    Examples
    --------
    >>> auto_choice_text({"kept": "ridge", "agreement": 0.7, "auto_agreement": 0.55})
    "detector: auto kept the ridge detector's traces (agreement 0.70 > 0.55; docs/imaging.md §3.3)"
    >>> auto_choice_text({"kept": "cnn", "agreement": 0.2, "auto_agreement": 0.55,
    ...                   "network_length_ratio": 1.5, "auto_network_ratio": 1.2})[:58]
    "detector: auto kept the convolutional network's traces (it"
    >>> auto_choice_text({"kept": "learned", "agreement": 0.2, "auto_agreement": 0.55,
    ...                   "network_length_ratio": 1.1, "auto_network_ratio": 1.3}).split("; ")[1]
    "the network's trace length 1.10 times the pixel model's < 1.3"
    """
    agreement = (f"agreement {choice['agreement']:.2f} {'>' if choice['kept'] == 'ridge' else '<='} "
                 f"{choice['auto_agreement']:g}")
    ratio = choice.get("network_length_ratio")
    if choice["kept"] == "cnn":
        return (f"detector: auto kept the convolutional network's traces (its trace length "
                f"{ratio:.2f} times the pixel model's >= {choice['auto_network_ratio']:g}; "
                f"{agreement}; docs/imaging.md §3.6)")
    network = "" if ratio is None else (f"; the network's trace length {ratio:.2f} times the "
                                        f"pixel model's < {choice['auto_network_ratio']:g}")
    return f"detector: auto kept the {choice['kept']} detector's traces ({agreement}{network}; " \
           f"docs/imaging.md §3.3)"
