"""Where the learned detector loses the thin joints: the pixel model's training against the trace filters.

    python benchmarks/bench_pixel_training.py [--variants default,ignore-minor,...] [--faces N]

The learned detector (docs/imaging.md §3.1) finds 0.85 of the plain synthetic faces' trace length
and misses their thin, faint joints. Two things could be the cause: the pixel model (trained on
field-like faces whose thin, faint minor cracks are negatives, so it may have learned that a thin
dark line is not a joint), or what comes after it (the hysteresis levels and the trace filters
chosen on real photographs, whose labels mark the major discontinuities only). This benchmark
separates the two.

1. The shipped model at its defaults, without the trace filters (contrast, band width, the 70 px
   floor, 20 px kept), and at lower hysteresis levels without them, on the plain "moderate" faces
   and on the real training photographs: how much each step costs on each.
2. Pixel models retrained (:mod:`rockmass.imaging.train_pixel_model`, ``--faces`` field-like faces,
   default 80) with the variants of its options, each scored at the detector's defaults: the
   default recipe (the shipped model, retrained here), ``--ignore-minor-cracks`` (the field faces'
   minor cracks left out of the negatives, :func:`rockmass.imaging.synthetic_field.minor_crack_mask`),
   that with as many plain faces as half the field faces, and that with ``--tunnel-style`` field
   faces (half-casts, shotcrete), and ``--wide-crevices`` (a quarter of the field faces' major joints
   drawn as 12-30 px dark crevices labelled at the centre), with half of them, and with 10-20 px
   crevices. Columns: training time, model size, then F1 and dP21 on each set.
3. ``--seed-spread``: the default recipe and ``--wide-crevices``, each trained from five seeds
   (``--seed`` 10 000, the shipped model's, to 50 000), on the plain faces and on both real splits:
   how much the training seed alone moves the scores, and whether an option's gain outlasts it.
   This section reads ``val/``, to report the spread of what is shipped and to check a candidate
   recipe once; nothing in it is tuned.

Sets (1000 x 1500 px synthetic faces at 0.008 m/px, buffered F1 at 3 px; the real photographs as in
bench_imaging_real.py, F1 at 5 px, means over images): plain "moderate" faces and TUNNEL_STYLE
field faces, seeds 100-102 (the chain's tuning seeds, not the benchmark seeds 1-3 of
bench_imaging_real.py nor the training seeds 10 000+), and ``rock-face-fractures/train`` (skipped
when absent; ``val/`` is read only by section 3). One core
(OMP_NUM_THREADS=1 is set for the training runs). Rows also go to
benchmarks/results/bench_pixel_training.json.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _common import header, save, table
from bench_imaging_real import DATA, real_pairs, score_real, score_synthetic

SEEDS = (100, 101, 102)
VARIANTS = {
    "default": [],
    "ignore-minor": ["--ignore-minor-cracks"],
    "ignore-minor+plain40": ["--ignore-minor-cracks", "--plain-faces", "40"],
    "ignore-minor+tunnel": ["--ignore-minor-cracks", "--tunnel-style"],
    "wide-crevices": ["--wide-crevices"],
    "wide-crevices-0.5": ["--wide-crevices", "0.5"],
    "wide-crevices-10-20px": ["--wide-crevices", "0.25", "--crevice-width", "10", "20"],
}
#: Section 3: the recipes and the training seeds (10 000 is the shipped model's).
SPREAD_RECIPES = ("default", "wide-crevices")
TRAINING_SEEDS = (10_000, 20_000, 30_000, 40_000, 50_000)
INF = float("-inf")
#: Step 1: the shipped model's defaults, then without the trace filters, then lower levels.
FILTER_STEPS = (
    ("defaults (0.8/0.97, filters, 70 px)", {}),
    ("no contrast filter", dict(min_trace_contrast=INF)),
    ("no contrast or width filter", dict(min_trace_contrast=INF, min_trace_width=0.0)),
    ("no filters, 20 px", dict(min_trace_contrast=INF, min_trace_width=0.0, min_trace_length_px=20.0)),
    ("0.5/0.9, no filters, 20 px", dict(prob_low=0.5, prob_high=0.9, min_trace_contrast=INF,
                                        min_trace_width=0.0, min_trace_length_px=20.0)),
)


def faces():
    from rockmass.imaging.synthetic import synthetic_face
    from rockmass.imaging.synthetic_field import TUNNEL_STYLE, field_face

    return {"moderate": lambda s: synthetic_face("moderate", seed=s, shape_px=(1000, 1500),
                                                 m_per_px=0.008),
            "tunnel": lambda s: field_face(seed=s, shape_px=(1000, 1500), m_per_px=0.008,
                                           style=TUNNEL_STYLE)}


def score_all(params, pairs, *, synthetic=("moderate", "tunnel"), real_name="real") -> dict:
    """F1 and dP21 of one setting on the ``synthetic`` sets (plain faces, tunnel faces) and on the
    real photographs ``pairs`` (columns ``real_name``_F1, _dP21)."""
    row = {}
    for name, make in faces().items():
        if name in synthetic:
            s = score_synthetic(make, SEEDS, params)
            row[f"{name}_F1"], row[f"{name}_dP21"] = s["F1"], s["dP21_%"]
    if pairs:
        r = score_real(pairs, params, 3.0)
        row[f"{real_name}_F1"], row[f"{real_name}_dP21"] = r["F1"], r["dP21_pct"]
    return row


def train(out: Path, options, faces_per_run: int) -> float:
    """Train a pixel model to ``out`` with the command-line ``options``, on one core; seconds."""
    command = [sys.executable, "-m", "rockmass.imaging.train_pixel_model", "--out", str(out),
               "--faces", str(faces_per_run), *options]
    t0 = time.perf_counter()
    subprocess.run(command, check=True, capture_output=True, env={**os.environ, "OMP_NUM_THREADS": "1"})
    return time.perf_counter() - t0


def seed_spread(faces_per_run: int, splits: dict) -> list:
    """Section 3: each recipe of :data:`SPREAD_RECIPES` trained from each seed of
    :data:`TRAINING_SEEDS`, scored at the detector's defaults on the plain faces and on the real
    ``splits`` (name -> photo pairs)."""
    from rockmass.imaging.extract import ExtractParams

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in TRAINING_SEEDS:
            for recipe in SPREAD_RECIPES:
                out = Path(tmp) / f"{recipe}_{seed}.npz"
                elapsed = train(out, [*VARIANTS[recipe], "--seed", str(seed)], faces_per_run)
                params = ExtractParams(detector="learned", pixel_model=str(out))
                row = {"recipe": recipe, "seed": seed, "train_s": elapsed,
                       **score_all(params, [], synthetic=("moderate",))}
                for name, pairs in splits.items():
                    row.update(score_all(params, pairs, synthetic=(), real_name=name))
                rows.append(row)
                print(f"  {recipe}, seed {seed}: trained in {elapsed:.0f} s", flush=True)
    return rows


def spread_summary(rows, splits) -> list:
    """Per recipe: the mean, smallest and largest F1 over the seeds on each set, and per seed the
    difference of each later recipe from the first (its gain over the default recipe)."""
    import numpy as np

    sets = ["moderate", *splits]
    out = []
    for recipe in SPREAD_RECIPES:
        chosen = [r for r in rows if r["recipe"] == recipe]
        line = {"recipe": recipe}
        base = {r["seed"]: r for r in rows if r["recipe"] == SPREAD_RECIPES[0]}
        for name in sets:
            f1 = np.array([r[f"{name}_F1"] for r in chosen])
            line[f"{name}_F1"] = f"{f1.mean():.3f} ({f1.min():.3f}-{f1.max():.3f})"
            if recipe != SPREAD_RECIPES[0]:
                gain = f1 - np.array([base[r["seed"]][f"{name}_F1"] for r in chosen])
                line[f"{name}_gain"] = f"{gain.mean():+.3f} ({gain.min():+.3f}..{gain.max():+.3f})"
        out.append(line)
    return out


SCORE_COLUMNS = [("moderate_F1", ".3f"), ("moderate_dP21", "+.1f"), ("tunnel_F1", ".3f"),
                 ("tunnel_dP21", "+.1f"), ("real_F1", ".3f"), ("real_dP21", "+.1f")]


def main(argv=None) -> int:
    import cv2

    from rockmass.imaging.extract import ExtractParams
    from rockmass.imaging.learned import MODEL_FILE

    cv2.setNumThreads(1)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variants", default=",".join(VARIANTS),
                        help=f"comma-separated training variants (default all: {', '.join(VARIANTS)})")
    parser.add_argument("--faces", type=int, default=80, help="field-like faces per training run")
    parser.add_argument("--no-filters-table", action="store_true", help="skip step 1")
    parser.add_argument("--seed-spread", action="store_true",
                        help="section 3 only: recipes x training seeds, on train/ and val/ (~10 min)")
    args = parser.parse_args(argv)
    variants = [v.strip() for v in args.variants.split(",") if v.strip()]
    unknown = [v for v in variants if v not in VARIANTS]
    if unknown:
        parser.error(f"--variants: unknown {unknown}; choose from {list(VARIANTS)}")

    print(header("learned detector: pixel model training against the trace filters"))
    if args.seed_spread:
        splits = {name: real_pairs(name) for name in ("train", "val")
                  if (DATA / name / "images").is_dir()}
        rows = seed_spread(args.faces, splits)
        print(f"\n3. training seed against recipe ({args.faces} field-like faces each; seed "
              f"{TRAINING_SEEDS[0]} is the shipped model's), at the detector's defaults")
        print(table(rows, [("recipe", "s"), ("seed", "d"), ("train_s", ".0f"),
                           ("moderate_F1", ".3f"), ("moderate_dP21", "+.1f"),
                           *[(f"{n}_{c}", f) for n in splits for c, f in (("F1", ".3f"),
                                                                            ("dP21", "+.1f"))]]))
        summary = spread_summary(rows, splits)
        print("\nF1 over the seeds: mean (smallest-largest); gain over the default recipe, seed by "
              "seed: mean (smallest..largest)")
        print(table(summary, [("recipe", "s"), *[(f"{n}_{c}", "s") for n in ["moderate", *splits]
                                                 for c in ("F1", "gain")]]))
        print(f"\nrows saved to {save('bench_pixel_training_seeds', {'rows': rows, 'summary': summary})}")
        return 0
    pairs = real_pairs("train") if (DATA / "train" / "images").is_dir() else []
    if not pairs:
        print("real training photographs absent: the real columns are skipped")
    payload: dict = {"seeds": list(SEEDS), "steps": [], "variants": []}

    if not args.no_filters_table:
        rows = [{"setting": label, **score_all(ExtractParams(detector="learned", **extra), pairs)}
                for label, extra in FILTER_STEPS]
        print(f"\n1. shipped model ({MODEL_FILE.name}), trace filters removed one by one "
              f"(synthetic seeds {list(SEEDS)}; real: train/)")
        print(table(rows, [("setting", "s"), *SCORE_COLUMNS]))
        payload["steps"] = rows

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in variants:
            out = Path(tmp) / f"{name.replace('+', '_')}.npz"
            elapsed = train(out, VARIANTS[name], args.faces)
            rows.append({"variant": name, "train_s": elapsed, "model_bytes": out.stat().st_size,
                         **score_all(ExtractParams(detector="learned", pixel_model=str(out)), pairs)})
            print(f"  {name}: trained in {elapsed:.0f} s", flush=True)
    print(f"\n2. retrained pixel models ({args.faces} field-like faces each), at the detector's defaults")
    print(table(rows, [("variant", "s"), ("train_s", ".0f"), ("model_bytes", "d"), *SCORE_COLUMNS]))
    payload["variants"] = rows
    print(f"\nrows saved to {save('bench_pixel_training', payload)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
