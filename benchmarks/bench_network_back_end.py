"""The convolutional network's chain with other back-end settings: real labels and drawn joints.

    python benchmarks/bench_network_back_end.py [--splits train,val] [--limit N] [--workers 2]
                                                [--network cnn] [--settings default,...]

The network (docs/imaging.md §3.6) feeds the learned detector's back end at the settings chosen
for the pixel model on real labels (§3.1: hysteresis 0.8 / 0.97, traces of at least 70 px, a
quarter darker than the face, a band of at least one joint width). On joints drawn on real rock it
still misses a third of the length, mostly 1-2 px joints. Which setting drops them, and what does
each cost on the real labels? Per photograph of rock-face-fractures (AGPL; read, never shipped),
the network's chain alone (``pixel_model = "cnn"``) at the default back end and with one or two
settings changed, scored by the two judges of ``bench_network_ratio.py``: the hand labels (major
open fractures only; F1 at 5 px, as ``bench_imaging_real.py``, counts summed per photo as there)
and the exact truth of the joints ``bench_texture_faces.py`` draws onto the same photograph
(buffered F1 at 3 px, the photo's own fractures ignored; ``R_w12`` the recall of the joints drawn
1-2 px wide, a mean over the photos that have some). Nothing is chosen here: the rows are the
ground for choosing the network's back end (on ``train``; ``val`` to measure). ``--network`` scores
another network file (e.g. one trained by ``train_joint_net`` with other face seeds) the same
way, ``--settings`` a subset of the settings. Rows also go to
benchmarks/results/bench_network_back_end.json (``..._<network file stem>.json`` for another
network).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import header, save, table  # noqa: E402
from rockmass.imaging.extract import EVERY_JOINT  # noqa: E402

#: Back-end settings tried (ExtractParams fields), each against the default; names hold no comma
#: (``--settings`` takes them comma-separated), "+" joins two settings changed together.
VARIANTS = {
    "default": {},
    "contrast 0.15": {"min_trace_contrast": 0.15},
    "contrast 0.10": {"min_trace_contrast": 0.10},
    "contrast off": {"min_trace_contrast": float("-inf")},
    "length 40 px": {"min_trace_length_px": 40.0},
    "length 20 px": {"min_trace_length_px": 20.0},
    "prob_low 0.65": {"prob_low": 0.65},
    "prob_low 0.5": {"prob_low": 0.5},
    "width off": {"min_trace_width": 0.0},
    "contrast 0.15 + length 40 px": {"min_trace_contrast": 0.15, "min_trace_length_px": 40.0},
    # every joint the network sees: the back end of rockmass extract --joints all (§8.4)
    "filters off + length 20 px": {key: value for key, value in EVERY_JOINT.items()
                                   if key not in ("detector", "pixel_model")},
}
COLUMNS = [("split", "s"), ("setting", "s"), ("real_F1", ".3f"), ("real_P", ".3f"),
           ("real_R", ".3f"),
           ("real_dP21_pct", "+.0f"), ("drawn_F1", ".3f"), ("drawn_P", ".3f"), ("drawn_R", ".3f"),
           ("drawn_R_w12", ".3f"), ("drawn_dP21_pct", "+.0f"), ("photos", "d")]


def score_photo(job) -> dict:
    """Every variant's scores on one photo (real labels) and on the joints drawn on it."""
    import cv2

    from bench_imaging_real import TOLERANCE_PX, label_skeleton
    from bench_texture_faces import BUFFER_PX, M_PER_PX, ignore_mask
    from rockmass.imaging import joints_on_photo
    from rockmass.imaging.extract import ExtractParams, extract
    from rockmass.imaging.label_scores import score_traces
    from rockmass.imaging.metrics import buffered_match, trace_accuracy

    photo_path, label, seed, network, settings_of = job
    photo = np.ascontiguousarray(cv2.imread(str(photo_path), cv2.IMREAD_COLOR)[..., ::-1])
    truth = label_skeleton(label)
    face = joints_on_photo(photo, "moderate", seed=seed, m_per_px=M_PER_PX)
    ignore = ignore_mask(photo_path, label, photo.shape[:2])
    widths = np.asarray(face.truth.attributes["width_px"])
    thin = face.truth.subset(widths <= 2)
    out = {"photo": photo_path.name}
    for name, settings in settings_of.items():
        params = ExtractParams(detector="learned", pixel_model=network, **settings)
        real = extract(photo, m_per_px=1.0, joint_width_px=3.0, params=params)
        drawn = extract(face.image, m_per_px=M_PER_PX, params=params)
        a = trace_accuracy(drawn.traces, face.truth, buffer_px=BUFFER_PX, ignore=ignore,
                           m_per_px=M_PER_PX)
        thin_recall = (buffered_match(drawn.traces, thin, buffer_px=BUFFER_PX, ignore=ignore,
                                      m_per_px=M_PER_PX)[1] if thin.n_traces else float("nan"))
        out[name] = {"real": score_traces(real.traces, truth, tolerance_px=TOLERANCE_PX)[0],
                     "drawn": [a.f1, a.precision, a.recall, a.p21_rel_error, thin_recall]}
    return out


def rows_of(split: str, photos: list[dict], names) -> list[dict]:
    """One row per variant: the real counts summarised as bench_imaging_real.py does, the drawn
    scores as means over the photos."""
    from bench_imaging_real import summarise_counts

    rows = []
    for name in names:
        real = summarise_counts([p[name]["real"] for p in photos])
        drawn = np.nanmean(np.array([p[name]["drawn"] for p in photos], dtype=float), axis=0)
        rows.append({"split": split, "setting": name, "real_F1": real["F1"], "real_P": real["P"],
                     "real_R": real["R"], "real_dP21_pct": real["dP21_pct"],
                     "drawn_F1": float(drawn[0]), "drawn_P": float(drawn[1]),
                     "drawn_R": float(drawn[2]), "drawn_dP21_pct": 100 * float(drawn[3]),
                     "drawn_R_w12": float(drawn[4]), "photos": len(photos)})
    return rows


def main(argv=None) -> int:
    from bench_network_ratio import add_photo_arguments, checked_splits, results_name, scored_photos

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    add_photo_arguments(parser)
    parser.add_argument("--settings", default=",".join(VARIANTS),
                        help=f"settings to score, comma-separated names of: {', '.join(VARIANTS)}")
    args = parser.parse_args(argv)
    names = [n.strip() for n in args.settings.split(",") if n.strip()]
    if not names or set(names) - set(VARIANTS):
        parser.error(f"--settings takes names of: {', '.join(VARIANTS)}")
    settings_of = {n: VARIANTS[n] for n in names}
    splits = checked_splits(args, parser)
    print(header("the network's chain with other back-end settings: real labels and drawn joints"))
    print(f"network: {args.network}")
    payload = {"network": args.network, "rows": [], "photos": {},
               "variants": {k: {f: str(v) for f, v in s.items()} for k, s in settings_of.items()}}
    for split in splits:
        scored = scored_photos(split, args, score_photo, args.network, settings_of)
        if scored is None:
            continue
        photos, seconds = scored
        rows = rows_of(split, photos, names)
        payload["rows"] += rows
        payload["photos"][split] = photos
        print(f"\n{split}/ ({len(photos)} photographs, {seconds:.0f} s; real: hand "
              "labels, F1 at 5 px; drawn: joints drawn on the same photos, buffered F1 at 3 px)")
        print(table(rows, COLUMNS))
    print(f"\nrows: {save(results_name('bench_network_back_end', args.network), payload)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
