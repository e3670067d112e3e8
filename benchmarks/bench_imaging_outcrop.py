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
- ``each geologist``: one geologist's mask at a time, the row giving the mean over the three.

The geologists' own agreement is the ceiling a detector can be judged against: each geologist's
centre lines scored against each other geologist's, at the same tolerance (mean over the six
ordered pairs and the tiles). With "auto" the share of tiles on which it kept the ridge traces and
the detectors' agreement (docs/imaging.md §3.3) are printed. Rows also go to
benchmarks/results/bench_imaging_outcrop.json.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

from _common import header, save, table
from bench_imaging_real import (REAL_COLUMNS, TOLERANCE_PX, _extraction_real, label_skeleton,
                                score_real)

DATA = Path(__file__).resolve().parent / "data" / "marques2022"
GEOLOGISTS = ("O1", "O2", "O3")


def tiles() -> list[Path]:
    """The tile images, sorted by name."""
    return sorted((DATA / "images").glob("*.png"))


def two_of_three(folder: Path) -> Path:
    """Write, into ``folder``, each tile's mask of the pixels at least two geologists marked."""
    import cv2

    folder.mkdir(parents=True, exist_ok=True)
    for tile in tiles():
        votes = sum((cv2.imread(str(DATA / "labels" / g / tile.name), cv2.IMREAD_GRAYSCALE) > 127)
                    .astype(np.uint8) for g in GEOLOGISTS)
        cv2.imwrite(str(folder / tile.name), np.where(votes >= 2, 255, 0).astype(np.uint8))
    return folder


def geologists_agreement() -> dict:
    """Each geologist's centre lines scored against each other's (5 px): mean F1, P, R over the
    ordered pairs and tiles; and each geologist's total line length against the mean of the three
    (how much more or less each one draws), %."""
    from rockmass.imaging.metrics import raster_counts

    scores, lengths = [], dict.fromkeys(GEOLOGISTS, 0)
    for tile in tiles():
        lines = {g: label_skeleton(DATA / "labels" / g / tile.name) for g in GEOLOGISTS}
        for g in GEOLOGISTS:
            lengths[g] += int(lines[g].sum())
        for a in GEOLOGISTS:
            for b in GEOLOGISTS:
                if a == b:
                    continue
                matched_a, n_a, matched_b, n_b = raster_counts(lines[a], lines[b],
                                                               tolerance_px=TOLERANCE_PX)
                p, r = matched_a / max(n_a, 1), matched_b / max(n_b, 1)
                scores.append((2 * p * r / (p + r) if p + r > 0 else 0.0, p, r))
    f, p, r = np.mean(scores, axis=0)
    mean_length = np.mean(list(lengths.values()))
    return dict(split="outcrop", detector="geologist", setting="vs each other geologist",
                images=len(tiles()), F1=float(f), P=float(p), R=float(r),
                length_vs_mean_pct={g: float(100 * (n / mean_length - 1)) for g, n in lengths.items()})


def auto_choice(pairs) -> dict:
    """Which detector "auto" kept on the tiles, and the agreement it measured."""
    from rockmass.imaging.extract import ExtractParams

    agreements = []
    for image, label in pairs:
        shape = label_skeleton(label).shape
        result, _ = _extraction_real(image, shape, ExtractParams(detector="auto"), 3.0, 1.0)
        agreements.append(result.detector_choice["agreement"])
    a = np.array(agreements)
    threshold = ExtractParams().auto_agreement
    return dict(tiles=a.size, agreement_min=float(a.min()), agreement_median=float(np.median(a)),
                agreement_max=float(a.max()), ridge_kept_share=float(np.mean(a > threshold)),
                auto_agreement=threshold)


def main(argv=None) -> int:
    import cv2

    from rockmass.imaging.extract import ExtractParams

    cv2.setNumThreads(1)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--detectors", default="ridge,learned,auto",
                        help="comma-separated ExtractParams.detector values (default all three)")
    args = parser.parse_args(argv)
    detectors = [d.strip() for d in args.detectors.split(",") if d.strip()]
    if not tiles():
        print(f"no tiles at {DATA}: nothing to measure", file=sys.stderr)
        return 2
    print(header("photo -> traces on drone tiles of a rock pavement (Marques Junior et al. 2022)"))
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        majority = two_of_three(Path(tmp) / "two_of_three")
        references = [("consolidated", lambda t: DATA / "labels" / "consolidated" / t.name),
                      ("two of three", lambda t: majority / t.name)]
        for detector in detectors:
            params = ExtractParams(detector=detector)
            for name, label_of in references:
                pairs = [(t, label_of(t)) for t in tiles()]
                rows.append({"split": name, "detector": detector, "setting": "defaults",
                             **score_real(pairs, params, 3.0)})
            each = [score_real([(t, DATA / "labels" / g / t.name) for t in tiles()], params, 3.0)
                    for g in GEOLOGISTS]
            rows.append({"split": "each geologist", "detector": detector, "setting": "defaults",
                         **{k: float(np.mean([e[k] for e in each])) for k in each[0]},
                         "images": each[0]["images"]})
        human = geologists_agreement()
        choice = auto_choice([(t, DATA / "labels" / "consolidated" / t.name) for t in tiles()]) \
            if "auto" in detectors else None
    print(f"\n{DATA} ({len(tiles())} tiles, 500 x 500 px, validation only; masks skeletonised, "
          f"{TOLERANCE_PX:g} px tolerance, joint width 3 px; F1, P, R are means over tiles)")
    print(table(rows, REAL_COLUMNS))
    print("\nthe geologists against each other (same scoring, mean over the six ordered pairs)")
    print(table([human], [c for c in REAL_COLUMNS if c[0] in human]))
    print("each geologist's line length against the mean of the three: " + ", ".join(
        f"{g} {v:+.0f} %" for g, v in human["length_vs_mean_pct"].items()))
    if choice:
        print(f"\nauto: kept the ridge traces on {100 * choice['ridge_kept_share']:.0f} % of the tiles "
              f"(agreement min {choice['agreement_min']:.2f}, median {choice['agreement_median']:.2f}, "
              f"max {choice['agreement_max']:.2f}; threshold {choice['auto_agreement']:g})")
    path = save("bench_imaging_outcrop", {"data": str(DATA), "tolerance_px": TOLERANCE_PX,
                                          "rows": rows, "geologists": human, "auto": choice})
    print(f"\nrows saved to {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
