"""``rockmass score``: how well the traces match your own hand-traced photographs.

Extracts every photo of ``--photos`` that has a label of the same name in ``--labels`` (traces
painted red, or white on black: :mod:`rockmass.imaging.labels`) with the settings ``rockmass
extract`` would use, and scores the traces against the label's centre lines as the benchmarks of
docs/imaging.md §8 do: F1, precision and recall at ``--tolerance`` pixels (5), the trace length
error ΔP21 and the trace count error ΔP20, per photo and over all (§3.5). Prints a line per photo
and the scores over all; ``--out DIR`` writes ``scores.csv``, ``summary.json``, ``manifest.json``
and, with ``--review``, ``review/<photo>.png`` (drawn traces near a label green, false traces red,
missed label blue) — all of them or none. ``--json`` prints summary.json. ``--choose-back-end``
also chooses the learned detector's back end for the model on the photos
(:mod:`rockmass.imaging.site_back_end`) and writes it as ``back_end.toml``.

Use it to decide whether the shipped detector serves a site, to compare settings (``--config``)
or a site model (``--pixel-model``, trained by ``train_pixel_model --photos``, §3.2) on photos it
was not trained on.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .image_limits import pixel_limit_arg
from .outputs import print_json

__all__ = ["add_parser", "run"]

#: Photos listed by name when printing: the ones of lowest F1 first, at most this many.
WORST_SHOWN = 10


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register the ``score`` subcommand."""
    p = subparsers.add_parser(
        "score", help="score extracted traces against your hand-traced photographs (F1, P, R, "
                      "length error)",
        description="Extract every labelled photo and score its traces against the hand-traced "
                    "label (centre lines, F1 at a pixel tolerance; docs/imaging.md §3.5).")
    p.add_argument("--photos", required=True, metavar="DIR", help="folder of face photographs")
    p.add_argument("--labels", required=True, metavar="DIR",
                   help="their labels, same file names (any image suffix): traces painted red, or "
                        "white on black")
    p.add_argument("--out", help="write scores.csv, summary.json, manifest.json (and review/) here")
    p.add_argument("--tolerance", type=float, default=5.0, metavar="PX",
                   help="a drawn (labelled) pixel matches within this distance of a labelled "
                        "(drawn) one, pixels of the photograph (default 5)")
    p.add_argument("--review", action="store_true",
                   help="with --out: write review/<photo>.png, the photo with matched traces green, "
                        "false traces red and missed labels blue")
    p.add_argument("--choose-back-end", type=int, nargs="?", metavar="FOLDS", const=0,
                   dest="choose_back_end",
                   help="also choose the learned detector's hysteresis levels and length floor for "
                        "the model on these photos, with a FOLDS-fold estimate of what the choice "
                        "does on photos it did not see (default 5, or the number of photos when "
                        "fewer); prints the config to extract with (--out: back_end.toml)")
    p.add_argument("--config", help="TOML file; its [imaging] section sets width and params")
    p.add_argument("--detector", choices=("auto", "learned", "ridge"), dest="detector",
                   help="joint detector (default auto; learned with --pixel-model)")
    p.add_argument("--pixel-model", dest="pixel_model", metavar="FILE",
                   help="a pixel model of your own (train_pixel_model --photos), a network "
                        "(.onnx), or 'cnn', the shipped convolutional network")
    p.add_argument("--joints", choices=("major", "all"), dest="joints",
                   help="which joints the traces map: 'major' (default, the settings as given) or "
                        "'all' (every joint, hairlines too, as rockmass extract --joints all)")
    p.add_argument("--face-mask", choices=("border", "full", "off"), dest="face_mask",
                   help="limit candidates to the rock face (default border)")
    p.add_argument("--joint-width", type=float, dest="joint_width_px", metavar="PX",
                   help="expected joint width in pixels of the photographs")
    p.add_argument("--bright-lines", action="store_true", dest="bright_lines",
                   help="the joints are lighter than the rock (ridge detector)")
    p.add_argument("--max-pixels", type=pixel_limit_arg, dest="max_pixels", metavar="N",
                   help="refuse photos above N pixels (default 100000000, or ROCKMASS_MAX_PIXELS)")
    p.add_argument("--json", action="store_true", help="print summary.json on stdout")
    p.set_defaults(handler=run)
    return p


def _number(value, spec: str) -> str:
    """``value`` formatted, or "-" when undefined."""
    return "-" if value is None else format(value, spec)


def report_text(document: dict) -> str:
    """The printed report: the photos of lowest F1 first (at most :data:`WORST_SHOWN`), then the
    scores over all photos."""
    rows = sorted(document["photos"], key=lambda row: row["F1"])
    lines = [f"{'photo':<28} {'F1':>6} {'P':>6} {'R':>6} {'dP21':>7}  detector"]
    for row in rows[:WORST_SHOWN]:
        lines.append(f"{Path(row['photo']).name[:28]:<28} {row['F1']:6.3f} "
                     f"{_number(row['precision'], '6.3f'):>6} {_number(row['recall'], '6.3f'):>6} "
                     f"{_number(row['dP21_pct'], '+6.0f'):>6}%  {row['detector']}")
    if len(rows) > WORST_SHOWN:
        lines.append(f"... {len(rows) - WORST_SHOWN} more photos (scores.csv with --out)")
    o = document["overall"]
    lines.append(f"over {o['photos']} photos at {document['tolerance_px']:g} px: F1 {o['F1']:.3f} "
                 f"(precision {_number(o['precision'], '.3f')}, recall {_number(o['recall'], '.3f')}; "
                 f"pooled F1 {o['F1_pooled']:.3f}), trace length {_number(o['dP21_pct'], '+.0f')}% "
                 f"and count {_number(o['dP20_pct'], '+.0f')}% against the labels")
    return "\n".join(lines)


def run(args) -> int:
    """Handler of ``rockmass score``."""
    from .score_stage import produce

    document = produce(args, args.out)
    if args.json:
        print_json(document)
        return 0
    print(report_text(document))
    if document["skipped"]:
        print(f"  note: not scored, their labels mark nothing: {len(document['skipped'])} photo(s) "
              f"({', '.join(Path(p).name for p in document['skipped'][:5])}"
              f"{', ...' if len(document['skipped']) > 5 else ''})", file=sys.stderr)
    if "back_end" in document:
        print(document["back_end"]["report"])
    warned = document["warnings"]
    if warned:
        print(f"  note: extraction notes on {len(warned)} of the photos (summary.json, "
              "'warnings')", file=sys.stderr)
    return 0
