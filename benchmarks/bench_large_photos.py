"""The joint detectors on large photographs of one face: the working grid against accuracy and time.

    python benchmarks/bench_large_photos.py [--megapixels 1.5,12,24] [--grids 1.5,2.5,4,8]
                                            [--detectors learned,auto] [--style tunnel|field]
                                            [--seeds 3] [--levels default,none] [--tag NAME]

A site geologist's photographs are 12-24 MP; the chain runs the detectors on a working grid of at
most ``max_megapixels`` (default 4, docs/imaging.md §1). Whether that grid costs a large
photograph accuracy needs the same face photographed with more pixels: the same joints, each
k times wider in pixels. ``field_face`` with ``FieldStyle.feature_scale`` = k draws that (its
sizes in pixels times k, its counts per area over k², at ``m_per_px / k``: the same network in
metres, docs/imaging.md §9.1). Here k = sqrt(MP / 1.5), so every size shows the faces of the
1000 x 1500 px benchmark faces (8 x 12 m at 8 mm per pixel; the 1.5 MP row is those faces).

Faces: seeds 1-3 (``--seeds n``: 1-n; 1-3 are the benchmark seeds of bench_imaging_real.py),
``TUNNEL_STYLE`` by default (half-casts and shotcrete) or the default ``FieldStyle``. Each face
is extracted at each working grid (``max_megapixels``; a grid of the photo's size or larger
runs the photo as it is, and only the first such grid is run) and scored against its truth with
the buffered match of docs/imaging.md (8.1)-(8.3) at 3 px of the 1.5 MP face (24 mm on the
face) whatever the size and the grid, so the rows compare like with like. ``--levels
default,none`` also runs the learned detector on the working grid alone (``learned_levels =
[]``), to separate the grid from the choice among the coarser ones.

Columns: the photo's size and k, the detector, the grid given and the grid run (MP), F1,
precision, recall, ΔP21, the extraction's wall time per photo (2 cores; the faces are drawn
beforehand, two at a time, and not timed) and, per face, the grid level the learned detector
kept (1: the working grid; 2, 4: coarsened so many times, docs/imaging.md §3.4) and its F1.
Rows also go to benchmarks/results/bench_large_photos_<style>.json (``..._<style>_<NAME>.json``
with ``--tag NAME``, so that a partial run keeps the full one).
"""

from __future__ import annotations

import argparse
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import header, save, table  # noqa: E402

#: The reference face: 1000 x 1500 px at 8 mm per pixel (1.5 MP).
BASE_SHAPE, BASE_M_PER_PX, BASE_MEGAPIXELS = (1000, 1500), 0.008, 1.5
#: Buffer half-width of the match, in pixels of the reference face.
BUFFER_PX = 3.0
COLUMNS = [("MP", "g"), ("k", ".2f"), ("detector", "s"), ("grid_given", "g"), ("grid_run", ".2f"),
           ("F1", ".3f"), ("P", ".3f"), ("R", ".3f"), ("dP21_pct", "+.1f"), ("s_per_photo", ".2f"),
           ("levels_kept", "s"), ("F1_per_face", "s")]


def feature_scale(megapixels: float) -> float:
    """k such that a photo of ``megapixels`` shows the reference face k times larger in pixels."""
    return float(np.sqrt(megapixels / BASE_MEGAPIXELS))


def draw(megapixels: float, seed: int, style_name: str):
    """Face ``seed`` of the reference network photographed at ``megapixels``."""
    from rockmass.imaging.synthetic_field import TUNNEL_STYLE, FieldStyle, field_face

    k = feature_scale(megapixels)
    style = replace(TUNNEL_STYLE if style_name == "tunnel" else FieldStyle(), feature_scale=k)
    shape = (round(BASE_SHAPE[0] * k), round(BASE_SHAPE[1] * k))
    return field_face(seed=seed, shape_px=shape, m_per_px=BASE_M_PER_PX / k, style=style)


def score(face, detector: str, grid: float, level_mode: str = "default") -> dict:
    """Buffered scores of one extraction at one working grid (with the coarser grids of
    ``learned_levels`` when ``level_mode`` is "default", without them when "none"), its wall
    time and the grid level the learned detector kept."""
    from rockmass.imaging.extract import ExtractParams, extract
    from rockmass.imaging.metrics import trace_accuracy

    t0 = time.perf_counter()
    result = extract(face.image, m_per_px=face.m_per_px,
                     params=ExtractParams(detector=detector, max_megapixels=grid,
                                          **({} if level_mode == "default" else {"learned_levels": []})))
    seconds = time.perf_counter() - t0
    accuracy = trace_accuracy(result.traces, face.truth, m_per_px=BASE_M_PER_PX, buffer_px=BUFFER_PX)
    # work_factor: working-grid pixels per photo pixel
    work = face.image.shape[0] * face.image.shape[1] * result.scale.work_factor ** 2 / 1e6
    levels = result.learned_levels
    return {"F1": accuracy.f1, "P": accuracy.precision, "R": accuracy.recall,
            "dP21_pct": 100 * accuracy.p21_rel_error, "grid_run": work, "s": seconds,
            "level": 1 if levels is None else int(levels["kept"])}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--megapixels", default="1.5,12,24", help="photo sizes (default 1.5,12,24)")
    parser.add_argument("--grids", default="1.5,2.5,4,8", help="max_megapixels values (default 1.5,2.5,4,8)")
    parser.add_argument("--detectors", default="learned,auto")
    parser.add_argument("--style", choices=("tunnel", "field"), default="tunnel")
    parser.add_argument("--seeds", type=int, default=3, help="faces per size: seeds 1..n (default 3)")
    parser.add_argument("--levels", default="default",
                        help="learned_levels: default, none (the working grid alone), or both")
    parser.add_argument("--tag", default="", help="suffix of the results file")
    args = parser.parse_args(argv)
    seeds = tuple(range(1, args.seeds + 1))
    level_modes = [v.strip() for v in args.levels.split(",") if v.strip()]
    if not set(level_modes) <= {"default", "none"} or args.seeds < 1:
        parser.error("--levels takes default and/or none; --seeds at least 1")
    try:
        sizes = [float(v) for v in args.megapixels.split(",") if v.strip()]
        grids = [float(v) for v in args.grids.split(",") if v.strip()]
    except ValueError as error:
        parser.error(f"--megapixels and --grids take comma-separated numbers: {error}")
    if not sizes or not grids or min(sizes + grids) <= 0:
        parser.error("--megapixels and --grids need values > 0")
    detectors = [v.strip() for v in args.detectors.split(",") if v.strip()]
    if not detectors or not set(detectors) <= {"learned", "auto", "ridge"}:
        parser.error("--detectors takes learned, auto and/or ridge")
    print(header(f"joint detectors on large photographs of one face ({args.style} style, "
                 f"seeds {seeds[0]}-{seeds[-1]})"))
    rows = []
    for megapixels in sizes:
        with ProcessPoolExecutor(max_workers=2) as pool:
            faces = list(pool.map(draw, [megapixels] * len(seeds), seeds, [args.style] * len(seeds)))
        runs = [(d, mode) for d in detectors for mode in (level_modes if d != "ridge" else ["default"])]
        # grids of the photo's size or larger all run the photo as it is: the first of them only
        useful = [g for g in grids if g < megapixels] + [g for g in grids if g >= megapixels][:1]
        for (detector, levels), grid in ((run, grid) for run in runs for grid in useful):
            scores = [score(face, detector, grid, levels) for face in faces]
            mean = {key: float(np.mean([s[key] for s in scores])) for key in scores[0]
                    if key != "level"}
            rows.append({"MP": megapixels, "k": feature_scale(megapixels),
                         "detector": detector if levels == "default" else f"{detector}, grid only",
                         "grid_given": grid, "grid_run": mean["grid_run"], "F1": mean["F1"],
                         "P": mean["P"], "R": mean["R"], "dP21_pct": mean["dP21_pct"],
                         "s_per_photo": mean["s"],
                         "levels_kept": "/".join(str(s["level"]) for s in scores),
                         "F1_per_face": "/".join(f"{s['F1']:.2f}" for s in scores)})
            print(table(rows[-1:], COLUMNS), flush=True)
    print("\nall rows")
    print(table(rows, COLUMNS))
    print(f"\nk: the photo's pixels per pixel of the reference face; F1, P, R: buffered match at "
          f"{BUFFER_PX:g} px of the 1.5 MP face ({1000 * BUFFER_PX * BASE_M_PER_PX:g} mm), means over "
          f"the faces; dP21: mean relative error of the trace length")
    name = "_".join(["bench_large_photos", args.style, *([args.tag] if args.tag else [])])
    path = save(name, {"rows": rows, "style": args.style, "seeds": list(seeds), "megapixels": sizes,
                       "grids": grids, "detectors": detectors, "levels": level_modes})
    print(f"\nrows saved to {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
