"""What a user's own labelled photographs buy: pixel models trained on real photos, scored on
photos they never saw.

    python benchmarks/bench_own_photos.py [--sizes 10,25,50,99] [--quick]

A site geologist with hand-traced photographs of their own rock can train the learned detector's
pixel model on them (``python -m rockmass.imaging.train_pixel_model --photos DIR --labels DIR
--out FILE``, docs/imaging.md §3.2) and extract with ``--pixel-model FILE``. This benchmark plays
that user with ``../shared/data/rock-face-fractures`` (AGPL-3.0, read from the shared folder; the
models it trains stay in a temporary folder and are never shipped): it trains on the first n
photos of ``train/`` (sorted by name; photos only, ``--faces 0``; and all 99 with the synthetic
faces of the shipped recipe too) and scores each model on the 44 photos of ``val/`` at the
detector's default thresholds and filters (chosen for the shipped model), and the photos-only
model of all 99 at the hysteresis levels and length floor ``--choose-back-end 5`` chose for it
on ``train/`` (:mod:`rockmass.imaging.site_back_end`; not with ``--quick``), F1 / P / R at 5 px,
ΔP21 and ΔP20 as in ``bench_imaging_real.py``, beside the shipped model (synthetic faces only);
then on the plain synthetic moderate faces (seeds 1-3, buffered F1 at 3 px). Prints the training
time and the model size. Skips (exit 0) when the data folder is absent.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import header, save, table  # noqa: E402
from bench_imaging_real import DATA, real_pairs, score_real, score_synthetic  # noqa: E402

COLUMNS = [("model", "s"), ("photos", "d"), ("train_s", ".1f"), ("model_bytes", "d"), ("F1", ".3f"),
           ("P", ".3f"), ("R", ".3f"), ("dP21_pct", "+.0f"), ("dP20_pct", "+.0f"),
           ("moderate_F1", ".3f"), ("moderate_dP21_%", "+.1f"), ("chosen", "s"), ("cv_F1", ".3f")]
#: Folds of the back-end choice on train/ (train_pixel_model --choose-back-end).
BACK_END_FOLDS = 5
#: The settings it chooses, in the order the tables print them.
CHOSEN = ("prob_low", "prob_high", "min_trace_length_px")


def chosen_text(settings) -> str:
    """The chosen settings as the tables print them: prob_low/prob_high/min_trace_length_px."""
    return "/".join(f"{settings[name]:g}" for name in CHOSEN)


def train_label(photo: Path) -> Path:
    """The label of a photo of the labelled set's ``train/``."""
    return DATA / "train" / "labels" / f"{photo.stem}.png"


def train(photos: list[Path], folder: Path, *, synthetic: bool, label_of=train_label,
          choose_back_end: int | None = None) -> tuple[Path, float]:
    """Train a pixel model on ``photos``, with or without the shipped recipe's synthetic faces;
    (model path, seconds). ``label_of(photo)`` is the label file of a photo. With
    ``choose_back_end`` = K the back end is chosen for it by K-fold cross-validation on the photos
    (``--choose-back-end K``; the model's ``info["back_end"]``)."""
    from rockmass.imaging.train_pixel_model import main as train_pixel_model

    images, labels = folder / f"images_{len(photos)}", folder / f"labels_{len(photos)}"
    images.mkdir(parents=True)
    labels.mkdir()
    for photo in photos:  # symbolic links: the photos themselves are not copied
        (images / photo.name).symlink_to(photo)
        label = label_of(photo)
        (labels / f"{photo.stem}{label.suffix}").symlink_to(label)
    out = folder / f"model_{len(photos)}_{'mixed' if synthetic else 'photos'}.npz"
    args = ["--photos", str(images), "--labels", str(labels), "--out", str(out)]
    if choose_back_end is not None:
        args += ["--choose-back-end", str(choose_back_end)]
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):  # its report of the fit (progress goes to stderr)
        train_pixel_model(args if synthetic else ["--faces", "0", *args])
    return out, time.perf_counter() - t0


def main(argv=None) -> int:
    import cv2

    from rockmass.imaging.extract import ExtractParams
    from rockmass.imaging.learned import MODEL_FILE, load_model
    from rockmass.imaging.synthetic import synthetic_face

    cv2.setNumThreads(1)
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="10,25,50,99",
                        help="numbers of train/ photos to train on (default 10,25,50,99)")
    parser.add_argument("--quick", action="store_true", help="sizes 10 and 99, one synthetic seed")
    args = parser.parse_args(argv)
    sizes = [10, 99] if args.quick else [int(n) for n in args.sizes.split(",") if n.strip()]

    print(header("pixel models trained on labelled photographs, scored on photographs never seen"))
    if not (DATA / "train" / "images").is_dir() or not (DATA / "val" / "images").is_dir():
        print(f"skipped: no labelled photographs at {DATA} (set ROCKMASS_REAL_DATA)")
        return 0
    photos = [image for image, _ in real_pairs("train")]
    val = real_pairs("val")
    seeds = [1] if args.quick else [1, 2, 3]

    def moderate(seed):
        return synthetic_face("moderate", seed=seed, shape_px=(1000, 1500), m_per_px=0.008)

    def row(label, model, n_photos, seconds, settings=None):
        params = ExtractParams(pixel_model=None if model is None else str(model), **(settings or {}))
        real = score_real(val, params, 3.0)
        plain = score_synthetic(moderate, seeds, params)
        path = MODEL_FILE if model is None else model
        return {"model": label, "photos": n_photos, "train_s": seconds,
                "model_bytes": path.stat().st_size, **real,
                "moderate_F1": plain["F1"], "moderate_dP21_%": plain["dP21_%"]}

    rows = [row("shipped (synthetic faces only)", None, 0, None)]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for n in sizes:
            model, seconds = train(photos[:n], folder, synthetic=False)
            rows.append(row(f"first {n} train/ photos", model, n, seconds))
        (folder / "mixed").mkdir()
        model, seconds = train(photos, folder / "mixed", synthetic=True)
        rows.append(row("all train/ photos + synthetic faces", model, len(photos), seconds))
        if not args.quick:  # the back end chosen for the photos-only model on train/
            (folder / "chosen").mkdir()
            model, seconds = train(photos, folder / "chosen", synthetic=False,
                                   choose_back_end=BACK_END_FOLDS)
            back_end = load_model(model).info["back_end"]
            chosen = back_end["settings"]
            rows.append({**row(f"all train/ photos, back end chosen ({BACK_END_FOLDS}-fold)", model,
                               len(photos), seconds, chosen),
                         "chosen": chosen_text(chosen),
                         "cv_F1": back_end["cross_validated"]["F1"]})
    print(f"\nval/ ({len(val)} photos, never trained on; 5 px; detector defaults unless chosen) "
          f"and plain synthetic moderate faces (seeds {seeds}, 3 px)")
    print(table(rows, COLUMNS))
    print(f"\nchosen: {'/'.join(CHOSEN)} chosen by --choose-back-end {BACK_END_FOLDS} on train/ (the "
          "row is scored with them); cv_F1: the F1 its cross-validation reported on train/ (the "
          "best of the settings tried: optimistic)")
    path = save("bench_own_photos_quick" if args.quick else "bench_own_photos", {"rows": rows})
    print(f"\nrows saved to {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
