"""What choosing the learned back end costs on large photographs, beside what it buys.

    python benchmarks/bench_choose_back_end.py [--photos 3] [--megapixels 12[,16,24]] [--faces DIR]
    python benchmarks/bench_choose_back_end.py --working-grids 1.5,2.5,4,8 [--faces DIR]

A site geologist's photographs are 12-24 MP. ``rockmass score --choose-back-end`` (docs/imaging.md
§3.5) extracts each labelled photo with the 18 back-end settings of
:data:`rockmass.imaging.site_back_end.BACK_END_GRID`, the probability map computed once per photo.
This benchmark writes field-like synthetic faces (:func:`rockmass.imaging.synthetic_field.field_face`,
seeds 1..n, the truth's centre lines drawn 3 px wide as the label, white on black) at each size and
runs, each in a fresh process (2 cores, as ``rockmass`` runs):

- ``rockmass score`` (the photos extracted once, at the defaults): the base cost;
- ``rockmass score --choose-back-end 2``: the choice, with two folds of consecutive photos.

It prints the wall time per photo and the peak resident memory of the process beside the scores:
F1 at 5 px at the default back end, the setting chosen, its F1 on the same photos (the best of 18:
optimistic) and each fold's photos at the setting chosen on the other fold (``held_out_F1``, the
choice's own estimate for photos it did not see). Rows also go to
benchmarks/results/bench_choose_back_end.json.

Drawing a field-like face takes minutes at these sizes (about 4 at 12 MP, 20 at 24 MP on one
core). With ``--faces DIR`` the faces are kept in ``DIR/<MP>MP`` and drawn only when missing, so
two versions of the code can be timed back to back on the same photographs.

The F1 of these faces is no judge of the detector on large photographs: ``field_face`` keeps its
feature sizes in pixels and grows its joint count with the area. ``--working-grids`` shows it
instead of timing the choice: the share of each face the label covers at 400 x 400 and
1000 x 1500 px (seed 1, drawn the same way) and at each size, and ``rockmass score --detector
learned`` with each ``max_megapixels`` given (rows to
benchmarks/results/bench_choose_back_end_working_grids.json).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import header, save, table  # noqa: E402

#: Face sides (rows, cols) per size, 3:4 as a camera's.
SHAPES = {12: (3000, 4000), 16: (3464, 4619), 24: (4243, 5657)}
GRID_COLUMNS = [("MP", "d"), ("photos", "d"), ("label_pct", ".1f"), ("max_megapixels", "g"),
                ("F1", ".3f"), ("P", ".3f"), ("R", ".3f"), ("dP21_pct", "+.0f"),
                ("s_per_photo", ".1f")]
COLUMNS = [("MP", "d"), ("photos", "d"), ("command", "s"), ("s_per_photo", ".1f"), ("peak_MB", ".0f"),
           ("F1_defaults", ".3f"), ("chosen", "s"), ("F1_chosen", ".3f"), ("held_out_F1", ".3f")]


def write_faces(folder: Path, shape: tuple[int, int], n: int) -> tuple[Path, Path]:
    """n field-like faces of ``shape`` (rows, cols) and their labels, as PNG files in ``folder`` (those already
    there kept; the others drawn two at a time, one per core: drawing is not what is timed)."""
    from concurrent.futures import ProcessPoolExecutor

    photos, labels = folder / "photos", folder / "labels"
    photos.mkdir(parents=True, exist_ok=True)
    labels.mkdir(exist_ok=True)
    names = {_name(seed) for seed in range(1, n + 1)}
    missing = [seed for seed in range(1, n + 1)
               if not ((photos / _name(seed)).is_file() and (labels / _name(seed)).is_file())]
    with ProcessPoolExecutor(max_workers=2) as pool:
        list(pool.map(_write_face, [photos] * len(missing), [labels] * len(missing),
                      [shape] * len(missing), missing))
    extra = sorted(p.name for p in photos.iterdir() if p.name not in names)
    if extra:
        raise SystemExit(f"{photos}: photos other than the {n} of this run ({', '.join(extra)})")
    return photos, labels


def _name(seed: int) -> str:
    return f"face{seed:02d}.png"


def _write_face(photos: Path, labels: Path, shape: tuple[int, int], seed: int) -> None:
    """Face ``seed`` of ``shape`` as ``face<seed>.png`` in ``photos``, its truth's centre lines
    drawn 3 px wide, white on black, under the same name in ``labels``."""
    import cv2
    import numpy as np

    from rockmass.imaging.metrics import render_traces
    from rockmass.imaging.synthetic_field import field_face

    face = field_face(seed=seed, shape_px=shape, m_per_px=0.008 * 1000 / shape[0])
    lines = render_traces(face.truth, face.image.shape[:2], face.m_per_px)
    label = cv2.dilate(lines.astype(np.uint8), np.ones((3, 3), np.uint8)) * 255
    image = face.image if face.image.ndim == 2 else face.image[..., ::-1]
    for folder, picture in ((photos, image), (labels, label)):  # whole files or none
        part = folder / f".{_name(seed)}.part.png"
        cv2.imwrite(str(part), picture)
        part.replace(folder / _name(seed))


def run(args: list[str]) -> tuple[dict, float, float]:
    """(summary.json, wall seconds, peak resident MB) of ``rockmass score`` in a fresh process
    (its own peak, from the rusage of its exit)."""
    import os

    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        t0 = time.perf_counter()
        child = subprocess.Popen([sys.executable, "-m", "rockmass", "score", *args, "--json"],
                                 stdout=out, stderr=err)
        _, status, usage = os.wait4(child.pid, 0)  # the child's own peak memory
        seconds = time.perf_counter() - t0
        if os.waitstatus_to_exitcode(status) != 0:
            err.seek(0)
            raise RuntimeError(f"rockmass score failed: {err.read().decode()}")
        out.seek(0)
        return json.loads(out.read()), seconds, usage.ru_maxrss / 1024


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--photos", type=int, default=3, help="photos per size (default 3)")
    parser.add_argument("--megapixels", default="12",
                        help="sizes, of 12, 16, 24 (default 12; drawing a field-like face takes "
                             "minutes at these sizes)")
    parser.add_argument("--faces", type=Path,
                        help="keep the faces in this folder (DIR/<MP>MP) and draw only those "
                             "missing (default: a temporary folder)")
    parser.add_argument("--working-grids", default="",
                        help="instead of the timing: score with the learned detector at each of "
                             "these max_megapixels (e.g. 1.5,2.5,4,8) and print label coverage")
    args = parser.parse_args(argv)
    sizes = [int(v) for v in args.megapixels.split(",") if v.strip()]
    if args.working_grids:
        return working_grids(sizes, args, [float(v) for v in args.working_grids.split(",")])
    print(header("rockmass score --choose-back-end on large photographs (field-like synthetic faces)"))
    rows = []
    for megapixels in sizes:
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp) if args.faces is None else args.faces / f"{megapixels}MP"
            photos, labels = write_faces(folder, SHAPES[megapixels], args.photos)
            base = ["--photos", str(photos), "--labels", str(labels)]
            scored, seconds, peak = run(base)
            rows.append({"MP": megapixels, "photos": args.photos, "command": "score",
                         "s_per_photo": seconds / args.photos, "peak_MB": peak,
                         "F1_defaults": scored["overall"]["F1"]})
            chosen, seconds, peak = run([*base, "--choose-back-end", "2"])
            back_end = chosen["back_end"]
            rows.append({"MP": megapixels, "photos": args.photos,
                         "command": "score --choose-back-end 2",
                         "s_per_photo": seconds / args.photos, "peak_MB": peak,
                         "F1_defaults": back_end["at_given_settings"]["F1"],
                         "chosen": "/".join(f"{v:g}" for v in back_end["settings"].values()),
                         "F1_chosen": back_end["cross_validated"]["F1"],
                         "held_out_F1": back_end["chosen_without_the_photos_scored"]["F1"]})
            print(table(rows[-2:], COLUMNS), flush=True)
    print("\nall rows")
    print(table(rows, COLUMNS))
    print("\nchosen: prob_low/prob_high/min_trace_length_px; F1 at 5 px of the photograph, means "
          "over the photos; peak_MB: the peak resident set of the command's process")
    path = save("bench_choose_back_end", {"rows": rows, "shapes": {str(k): v for k, v in SHAPES.items()}})
    print(f"\nrows saved to {path}")
    return 0


def _label_share(labels: Path) -> float:
    """Mean share of the label images' pixels that mark a trace."""
    import cv2
    import numpy as np

    return float(np.mean([(cv2.imread(str(p), cv2.IMREAD_GRAYSCALE) > 0).mean()
                          for p in sorted(labels.iterdir())]))


def working_grids(sizes, args, grids) -> int:
    """The ``--working-grids`` run (module notes)."""
    print(header("field-like faces: label coverage, and the learned detector at several working "
                 "grids"))
    with tempfile.TemporaryDirectory() as tmp:
        small = []
        for rows_px, cols_px in ((400, 400), (1000, 1500)):
            _, labels = write_faces(Path(tmp) / f"{rows_px}x{cols_px}", (rows_px, cols_px), 1)
            small.append(f"{rows_px} x {cols_px} px {100 * _label_share(labels):.1f} %")
    print("label coverage (3 px centre lines), seed 1: " + ", ".join(small))
    rows = []
    for megapixels in sizes:
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp) if args.faces is None else args.faces / f"{megapixels}MP"
            photos, labels = write_faces(folder, SHAPES[megapixels], args.photos)
            share = 100 * _label_share(labels)
            for grid in grids:
                config = Path(tmp) / "grid.toml"
                config.write_text(f"[imaging.params]\nmax_megapixels = {grid!r}\n")
                scored, seconds, _ = run(["--photos", str(photos), "--labels", str(labels),
                                          "--detector", "learned", "--config", str(config)])
                overall = scored["overall"]
                rows.append({"MP": megapixels, "photos": args.photos, "label_pct": share,
                             "max_megapixels": grid, "F1": overall["F1"], "P": overall["precision"],
                             "R": overall["recall"], "dP21_pct": overall["dP21_pct"],
                             "s_per_photo": seconds / args.photos})
                print(table(rows[-1:], GRID_COLUMNS), flush=True)
    print("\nall rows")
    print(table(rows, GRID_COLUMNS))
    print("\nF1, P, R at 5 px of the photograph, means over the photos; dP21 over all photos")
    path = save("bench_choose_back_end_working_grids", {"rows": rows, "label_coverage": small})
    print(f"\nrows saved to {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
