"""Photo -> traces on a second real labelled set: drone tiles of a rock pavement, three geologists.

    python benchmarks/bench_imaging_outcrop.py [--detectors ridge,learned,auto]

The data are 20 tiles (500 x 500 px, 5 cm/px) of a drone orthophoto of a karstified carbonate
pavement, each with the fractures segmented by three geologists (O1, O2, O3) and the authors'
consolidated mask (the pixels all three marked): Marques Junior et al. (2022), MIT licence,
shipped in ``benchmarks/data/marques2022`` with its source, licence and citation
(``README.md`` there). They are used only to measure: no setting, threshold or weight of rockmass
was chosen on them.

Scoring is that of ``bench_imaging_real.py`` (docs/imaging.md §8.1): masks skeletonised, traces
drawn as 1-px lines, F1 at a 5 px tolerance (25 cm here) averaged over the tiles, dP21 = drawn over
labelled line length - 1 over all tiles, run with the default settings and no scale (pixels), as
for the rock-face set. Three references:

- ``consolidated``: the authors' mask, all three geologists;
- ``two of three``: the pixels at least two geologists marked;
- ``each geologist``: one geologist's mask at a time (the 60 tile-geologist pairs pooled).

The geologists, scored the same way, say what these labels allow: each geologist against each
other geologist (the 120 ordered pairs of tiles; the analogue of the ``each geologist`` row), and
each against the pixels both other geologists marked (each left out in turn; the analogue of the
``consolidated`` row), with the range of one geologist's line length against another's. With
"auto" the share of tiles on which it kept the ridge traces and the detectors' agreement
(docs/imaging.md §3.3) are printed.

With ``--site-models``, what a user's own labels buy on this kind of image (docs/imaging.md §3.2),
in two folds fixed beforehand: a pixel model is trained on the first ten tiles by name (labels: the
pixels at least two geologists marked; photos only, ``--faces 0``, and with the shipped recipe's
synthetic faces) and scored on the other ten against each geologist, then the other way round,
beside the shipped model on the same tiles, at the learned detector's default thresholds and
filters. Each site model is trained with ``--choose-back-end 5``, which also chooses its
hysteresis levels and length floor by cross-validation on its ten training tiles
(:mod:`rockmass.imaging.site_back_end`), and is scored again with them; the shipped model too
gets its back end chosen on the training tiles (no model trained). The F1 each choice reported
on the training tiles is printed beside the held-out one: the best setting's (``cv_F1``, a best
of 18, optimistic) and, since session 21, that of each training fold at the setting chosen on the
other training folds (``ho_F1``, the choice's own estimate of what it does on tiles it did not
see, :func:`rockmass.imaging.site_back_end.held_out_score`). The models stay in a temporary
folder. Rows also go to benchmarks/results/bench_imaging_outcrop.json
(``..._site_models.json`` with ``--site-models``).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

from _common import detector_params, header, save, table
from bench_imaging_real import REAL_COLUMNS, TOLERANCE_PX, _extraction_real, score_real

from rockmass.imaging.metrics import summarise_counts

DATA = Path(__file__).resolve().parent / "data" / "marques2022"
GEOLOGISTS = ("O1", "O2", "O3")
#: Folds of the back-end choice on a site model's ten training tiles (two tiles each).
SITE_FOLDS = 5


def tiles() -> list[Path]:
    """The tile images, sorted by name."""
    return sorted((DATA / "images").glob("*.png"))


def mask(reference: str, tile: Path) -> np.ndarray:
    """The bool mask of ``tile`` in ``labels/<reference>`` (a geologist or "consolidated")."""
    import cv2

    path = DATA / "labels" / reference / tile.name
    grey = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    if grey is None:
        raise OSError(f"{path}: cannot read the mask of tile {tile.name}")
    return grey > 127


def two_of_three(folder: Path) -> Path:
    """Write, into ``folder``, each tile's mask of the pixels at least two geologists marked."""
    import cv2

    folder.mkdir(parents=True, exist_ok=True)
    for tile in tiles():
        votes = sum(mask(g, tile).astype(np.uint8) for g in GEOLOGISTS)
        cv2.imwrite(str(folder / tile.name), np.where(votes >= 2, 255, 0).astype(np.uint8))
    return folder


def geologists_rows() -> tuple[list[dict], dict]:
    """The geologists scored as the detectors are (centre lines, 5 px), as rows of the table:

    - against each other geologist (the six ordered pairs on every tile: the analogue of a
      detector against "each geologist");
    - against the pixels both other geologists marked (each left out in turn: the analogue of a
      detector against the consolidated mask of all three).

    Also the smallest and largest drawn over true line length - 1 of an ordered pair (all tiles),
    %: how much more one geologist draws than another."""
    from rockmass.imaging.metrics import raster_counts
    from rockmass.imaging.skeleton_graph import skeletonize

    pairwise, left_out, pair_counts = [], [], {}
    for tile in tiles():
        masks = {g: mask(g, tile) for g in GEOLOGISTS}
        lines = {g: skeletonize(m) for g, m in masks.items()}
        for a in GEOLOGISTS:
            others = [b for b in GEOLOGISTS if b != a]
            both = skeletonize(masks[others[0]] & masks[others[1]])
            left_out.append(raster_counts(lines[a], both, tolerance_px=TOLERANCE_PX))
            for b in others:
                counts = raster_counts(lines[a], lines[b], tolerance_px=TOLERANCE_PX)
                pairwise.append(counts)
                pair_counts.setdefault((a, b), []).append(counts)
    ratios = [100 * (sum(c[1] for c in v) / sum(c[3] for c in v) - 1) for v in pair_counts.values()]
    rows = [{"split": name, "detector": "geologist", "setting": setting,
             "images": len(counts), **summarise_counts(counts)}
            for name, setting, counts in (("each other geologist", "each ordered pair", pairwise),
                                          ("both other geologists", "each left out", left_out))]
    rows[0]["dP21_pct"] = None  # every pair counted both ways: 0 by construction; see the range
    return rows, {"pair_dP21_min_pct": float(min(ratios)), "pair_dP21_max_pct": float(max(ratios))}


def auto_choice(params) -> dict:
    """Which detector "auto" kept on the tiles, and the agreement it measured."""
    kept, agreements = [], []
    for tile in tiles():  # the extractions the scoring made (cached); no shape: not enlarged
        result, _ = _extraction_real(tile, None, params, 3.0, 1.0)
        kept.append(result.detector_choice["kept"])
        agreements.append(result.detector_choice["agreement"])
    a = np.array(agreements)
    return dict(tiles=a.size, agreement_min=float(a.min()), agreement_median=float(np.median(a)),
                agreement_max=float(a.max()), ridge_kept_share=float(np.mean(np.array(kept) == "ridge")),
                cnn_kept_share=float(np.mean(np.array(kept) == "cnn")),
                auto_agreement=params.auto_agreement)


def site_model_rows(folder: Path, majority: Path) -> list[dict]:
    """Two-fold site models (see the module notes): per fold and model, the scores on the held-out
    ten tiles against each geologist, with the training time; for the back ends chosen on the ten
    training tiles, the settings chosen and the F1 the choice's cross-validation reported there
    (optimistic) beside the held-out F1."""
    from bench_own_photos import chosen_text, train

    from rockmass.imaging.extract import ExtractParams
    from rockmass.imaging.learned import MODEL_FILE, load_model
    from rockmass.imaging.site_back_end import choose_back_end

    ordered = tiles()
    half = len(ordered) // 2
    folds = [(ordered[:half], ordered[half:]), (ordered[half:], ordered[:half])]
    rows = []
    for k, (trained_on, held_out) in enumerate(folds):
        each = [(t, DATA / "labels" / g / t.name) for g in GEOLOGISTS for t in held_out]
        fold = f"tiles {held_out[0].stem}-{held_out[-1].stem}"
        shipped = ExtractParams(detector="learned")
        rows.append({"split": fold, "detector": "learned", "setting": "shipped model",
                     **score_real(each, shipped, 3.0)})
        # the shipped model's own back end chosen on the training tiles (no model is trained)
        choice = choose_back_end([(t, majority / t.name) for t in trained_on],
                                 lambda pairs, fold: MODEL_FILE, folds=SITE_FOLDS)
        rows.append({"split": fold, "detector": "learned",
                     "setting": "shipped model, back end chosen", "chosen": chosen_text(choice.settings),
                     "cv_F1": choice.chosen.f1, "ho_F1": choice.held_out.f1, **score_real(each, replace(shipped, **choice.settings),
                                                             3.0)})
        for synthetic in (False, True):
            recipe = "tiles + synthetic faces" if synthetic else "tiles only"
            model, seconds = train(trained_on, folder / f"fold{k}_{synthetic}", synthetic=synthetic,
                                   label_of=lambda tile: majority / tile.name,
                                   choose_back_end=SITE_FOLDS)
            params = ExtractParams(detector="learned", pixel_model=str(model))
            rows.append({"split": fold, "detector": "learned", "setting": f"site model, {recipe}",
                         "train_s": seconds, **score_real(each, params, 3.0)})
            back_end = load_model(model).info["back_end"]
            rows.append({"split": fold, "detector": "learned",
                         "setting": f"site model, {recipe}, back end chosen", "train_s": seconds,
                         "chosen": chosen_text(back_end["settings"]),
                         "cv_F1": back_end["cross_validated"]["F1"],
                         "ho_F1": back_end["chosen_without_the_photos_scored"]["F1"],
                         **score_real(each, replace(params, **back_end["settings"]), 3.0)})
    return rows


def main(argv=None) -> int:
    import cv2

    from rockmass.imaging.extract import ExtractParams

    cv2.setNumThreads(1)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--detectors", default="ridge,learned,auto",
                        help="comma-separated ExtractParams.detector values (default all three), "
                             "cnn (the convolutional network alone) or auto-cnn (auto without it, "
                             "auto_network_ratio = inf; docs/imaging.md §3.6)")
    parser.add_argument("--site-models", action="store_true",
                        help="only the two-fold site models (pixel models trained on ten tiles, "
                             "scored on the other ten)")
    args = parser.parse_args(argv)
    detectors = [d.strip() for d in args.detectors.split(",") if d.strip()]
    if not tiles():
        print(f"no tiles at {DATA}: nothing to measure", file=sys.stderr)
        return 2
    if args.site_models:
        return _site_models()
    print(header("photo -> traces on drone tiles of a rock pavement (Marques Junior et al. 2022)"))
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        majority = two_of_three(Path(tmp) / "two_of_three")
        references = [("consolidated", lambda t: DATA / "labels" / "consolidated" / t.name),
                      ("two of three", lambda t: majority / t.name)]
        for detector in detectors:
            params = detector_params(detector)
            for name, label_of in references:
                pairs = [(t, label_of(t)) for t in tiles()]
                rows.append({"split": name, "detector": detector, "setting": "defaults",
                             **score_real(pairs, params, 3.0)})
            each = [(t, DATA / "labels" / g / t.name) for g in GEOLOGISTS for t in tiles()]
            rows.append({"split": "each geologist", "detector": detector, "setting": "defaults",
                         **score_real(each, params, 3.0)})
        human, spread = geologists_rows()
        choice = auto_choice(ExtractParams(detector="auto")) if "auto" in detectors else None
    print(f"\n{DATA} ({len(tiles())} tiles, 500 x 500 px, validation only; masks skeletonised, "
          f"{TOLERANCE_PX:g} px tolerance, joint width 3 px; F1, P, R are means over the "
          "(tile, reference) pairs, 'images' their number)")
    print(table(rows, REAL_COLUMNS))
    print("\nthe geologists scored the same way: against each other, and each against the pixels "
          "both others marked")
    print(table(human, [c for c in REAL_COLUMNS if c[0] not in ("dP20_pct", "s_per_image", "MP_per_s")]))
    print(f"one geologist's line length against another's, over all tiles: "
          f"{spread['pair_dP21_min_pct']:+.0f} to {spread['pair_dP21_max_pct']:+.0f} %")
    if choice:
        print(f"\nauto: kept the ridge traces on {100 * choice['ridge_kept_share']:.0f} % of the tiles, "
              f"the network's on {100 * choice['cnn_kept_share']:.0f} % "
              f"(agreement min {choice['agreement_min']:.2f}, median {choice['agreement_median']:.2f}, "
              f"max {choice['agreement_max']:.2f}; threshold {choice['auto_agreement']:g})")
    path = save("bench_imaging_outcrop", {"data": str(DATA), "tolerance_px": TOLERANCE_PX,
                                          "rows": rows, "geologists": human,
                                          "geologists_length_spread": spread, "auto": choice})
    print(f"\nrows saved to {path}")
    return 0


def _site_models() -> int:
    print(header("site models on drone tiles of a rock pavement (Marques Junior et al. 2022), two "
                 "folds of ten tiles"))
    with tempfile.TemporaryDirectory() as tmp:
        rows = site_model_rows(Path(tmp), two_of_three(Path(tmp) / "two_of_three"))
    print(f"\n{DATA}: trained on ten tiles (labels: two of three geologists), scored on the other "
          f"ten against each geologist ('split' names them; {TOLERANCE_PX:g} px, joint width 3 px, "
          "the learned detector's default thresholds and filters unless 'back end chosen')")
    print(table(rows, [*REAL_COLUMNS[:3], ("train_s", ".0f"), *REAL_COLUMNS[3:],
                       ("chosen", "s"), ("cv_F1", ".3f"), ("ho_F1", ".3f")]))
    print(f"\nchosen: prob_low/prob_high/min_trace_length_px chosen on the ten training tiles "
          f"({SITE_FOLDS} folds; for a site model by train_pixel_model --choose-back-end, for the "
          f"shipped model by rockmass.imaging.site_back_end.choose_back_end with it in every fold); "
          f"cv_F1: the F1 the choice reported there (the best of the settings tried: optimistic); "
          f"ho_F1: its estimate for tiles it did not see (each training fold at the setting "
          f"chosen on the other training folds)")
    # the folds hold as many (tile, geologist) pairs each: the mean of their F1 is the mean over all
    both = {setting: float(np.mean([r["F1"] for r in rows if r["setting"] == setting]))
            for setting in dict.fromkeys(r["setting"] for r in rows)}
    print("\nF1 over both folds (every tile scored once, by a model that did not see it): "
          + ", ".join(f"{setting} {f1:.3f}" for setting, f1 in both.items()))
    path = save("bench_imaging_outcrop_site_models", {"data": str(DATA), "tolerance_px": TOLERANCE_PX,
                                                      "rows": rows, "F1_both_folds": both})
    print(f"\nrows saved to {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
