"""Joints of known position drawn on real rock: the detectors on a texture they were not made on.

    python benchmarks/bench_texture_faces.py [--sets val,train,tiles,gravel] [--difficulty moderate]
                                             [--detectors auto,learned,ridge,cnn,auto-cnn,fine]
                                             [--limit N]

The plain synthetic faces (:func:`rockmass.imaging.synthetic_face`) draw their joints on a rock
texture of the same module, and the ridge chain's defaults were tuned on them; the learned
detector was trained on faces of the same package (docs/imaging.md §3.1, §9.1). A generator made
by someone else, with real rock texture under exactly known joints, tests what neither can: has
the chain learnt the texture of its own generator? Here every photograph of a set gets the network
of the synthetic face of the same seed and size drawn onto it
(:func:`rockmass.imaging.joints_on_photo`, the style of ``--difficulty``), and beside it the
synthetic face itself (its own texture, same network, same style), so that the two columns differ
by the texture only.

The photographs show fractures of their own that are not in the truth. Their labels (the hand
traces of the rock-face set, the union of the three geologists' masks on the drone tiles), widened
by :data:`IGNORE_MARGIN_PX`, are ignored in the scoring: neither a trace drawn there nor a synthetic
joint there counts (:func:`rockmass.imaging.metrics.trace_accuracy` with ``ignore``); the same
pixels are ignored on the synthetic twin. Fractures the labels leave out (fine cracks, the
rock-face labels mark only the major ones) stay in the scored part, as the clutter of a real photo.

Scoring: the buffered F1 of the synthetic benchmark (3 px), the recall of the joints drawn 1-2, 3-4
and 5-6 px wide apart (``R_w12`` ...; the mean over the photographs that have such joints), dP21
over the scored part, dP20 (since session 28: the traces with at least half their length in the
scored part, against the true ones, so a joint drawn in pieces counts more than once), the largest
error of the three set mean angles, averaged over the
photographs; "auto" also reports on how many faces it kept the ridge filter's, the pixel model's
and the convolutional network's traces (``auto_kept``, ridge/learned/cnn), and "better of the two"
is the mean over the photographs of the higher F1 of the learned and the ridge detector: the most a
per-photo choice between them could reach. ``cnn`` is the learned chain with the shipped network,
``auto-cnn`` "auto" without the network among its candidates (``auto_network_ratio = inf``;
docs/imaging.md §3.6), ``fine`` the map of every joint (``rockmass extract --joints all``, §8.4). Sets: ``val`` and ``train`` of ``../shared/data/rock-face-fractures`` (AGPL;
read, never shipped; about 400 px square), ``tiles``, the 20 drone tiles of
``benchmarks/data/marques2022`` (MIT; 500 px), and ``gravel``, scikit-image's photograph of gravel
(CC0; 512 px; no fractures of its own), under the networks of seeds 1-8. Every photo is drawn at :data:`M_PER_PX` (the
synthetic benchmark's 8 mm per pixel, so the joints have the density in pixels of its faces) with
seed = 1 + its index in the set, sorted by name. Nothing but ``auto_network_ratio`` (chosen on the
``train`` faces with the ``train`` photographs' own labels, docs/imaging.md §3.6) is tuned on these
faces; ``val``, the tiles and the gravel are only measured. Rows also go to
benchmarks/results/bench_texture_faces.json.
"""

from __future__ import annotations

import argparse
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import DETECTOR_NAMES, detector_params, header, save, table  # noqa: E402

#: Scale of the drawn network (m per pixel): the synthetic benchmark's faces' (docs/imaging.md §8).
M_PER_PX = 0.008
#: Buffer of the buffered F1 (px), as on the synthetic faces.
BUFFER_PX = 3.0
#: A photograph's own labelled fractures are ignored within this distance of their labelled pixels
#: (px): the buffer and a few pixels of a stroke's uncertain edge.
IGNORE_MARGIN_PX = 6.0
SETS = ("val", "train", "tiles", "gravel")
#: The ``gravel`` set: scikit-image's gravel photograph (512 x 512 px, CC0, shipped with
#: scikit-image), one face per seed 1..GRAVEL_FACES (other joints on the same rock).
GRAVEL = "skimage:gravel"
GRAVEL_FACES = 8
#: Joint widths (px, inclusive) whose recall is reported apart: the style draws 1-6 px at "moderate".
WIDTH_CLASSES = ((1, 2), (3, 4), (5, 6))
COLUMNS = [("set", "s"), ("texture", "s"), ("detector", "s"), ("faces", "d"), ("F1", ".3f"),
           ("P", ".3f"), ("R", ".3f"), *((f"R_w{lo}{hi}", ".3f") for lo, hi in WIDTH_CLASSES),
           ("dP21_pct", "+.0f"), ("dP20_pct", "+.0f"), ("set_angle_deg", ".1f"), ("auto_kept", "s"), ("ignored_pct", ".1f"),
           ("s_per_face", ".2f")]


def photos(name: str) -> list[tuple[Path | str, Path | None]]:
    """(photo, label) pairs of one set, sorted by name; the tiles' label is their folder of masks;
    the gravel set is :data:`GRAVEL` (no fractures of its own) :data:`GRAVEL_FACES` times."""
    if name == "gravel":
        return [(GRAVEL, None)] * GRAVEL_FACES
    if name == "tiles":
        from bench_imaging_outcrop import tiles

        return [(tile, None) for tile in tiles()]
    from bench_imaging_real import real_pairs

    return real_pairs(name)


def ignore_mask(photo: Path, label: Path | None, shape) -> np.ndarray:
    """The photo's own fractures, widened by :data:`IGNORE_MARGIN_PX` (bool, the photo's shape)."""
    import cv2

    if photo == GRAVEL:
        return np.zeros(shape, dtype=bool)
    if label is None:
        from bench_imaging_outcrop import GEOLOGISTS, mask

        marked = np.zeros(shape, dtype=bool)
        for geologist in GEOLOGISTS:
            marked |= mask(geologist, photo)
    else:
        from rockmass.imaging.labels import label_mask

        marked = label_mask(label)
    if marked.shape != tuple(shape):
        raise SystemExit(f"{label or photo}: label of shape {marked.shape}, photo {tuple(shape)}")
    distance = cv2.distanceTransform(np.where(marked, 0, 255).astype(np.uint8), cv2.DIST_L2, 5)
    return distance <= IGNORE_MARGIN_PX


def score_photo(job) -> list[dict]:
    """Rows of one photo: each detector on the joints drawn on it and on its synthetic twin."""
    import cv2

    from rockmass.imaging import joints_on_photo, synthetic_face
    from rockmass.imaging.extract import extract
    from rockmass.imaging.metrics import buffered_match, trace_accuracy

    photo_path, label, seed, difficulty, detectors = job
    if photo_path == GRAVEL:
        from skimage.data import gravel

        photo = gravel()
    else:
        photo = cv2.imread(str(photo_path), cv2.IMREAD_COLOR)
        if photo is None:
            raise SystemExit(f"{photo_path}: cannot read the photograph")
        photo = np.ascontiguousarray(photo[..., ::-1])
    ignore = ignore_mask(photo_path, label, photo.shape[:2])
    faces = {"real": joints_on_photo(photo, difficulty, seed=seed, m_per_px=M_PER_PX),
             "own": synthetic_face(difficulty, seed=seed, shape_px=photo.shape[:2], m_per_px=M_PER_PX)}
    rows = []
    for texture, face in faces.items():
        for detector in detectors:
            t0 = time.perf_counter()
            result = extract(face.image, m_per_px=face.m_per_px, params=detector_params(detector))
            seconds = time.perf_counter() - t0
            if result.scale.work_factor != 1:  # the ignore mask is on the photo's own pixels
                raise SystemExit(f"{photo_path}: processed down-sampled ({result.scale.work_factor:g}x); "
                                 "this benchmark expects photographs under max_megapixels")
            accuracy = trace_accuracy(result.traces, face.truth, buffer_px=BUFFER_PX, ignore=ignore,
                                      m_per_px=face.m_per_px)
            widths = np.asarray(face.truth.attributes["width_px"])
            by_width = {f"R_w{lo}{hi}": buffered_match(
                result.traces, face.truth.subset((widths >= lo) & (widths <= hi)), buffer_px=BUFFER_PX,
                ignore=ignore, m_per_px=face.m_per_px)[1]
                for lo, hi in WIDTH_CLASSES}
            kept = (result.detector_choice or {}).get("kept")
            name = getattr(photo_path, "name", photo_path)
            rows.append({"photo": name, "seed": seed, "texture": texture, "detector": detector,
                         "F1": accuracy.f1, "P": accuracy.precision, "R": accuracy.recall,
                         "dP21_pct": 100 * accuracy.p21_rel_error,
                         "dP20_pct": 100 * accuracy.p20_rel_error,
                         "set_angle_deg": max(accuracy.set_angle_errors_deg, default=float("nan")),
                         "auto_kept": kept if detector.startswith("auto") else None,
                         "ignored_pct": 100 * float(ignore.mean()), "seconds": seconds, **by_width})
    return rows


def summary(rows: list[dict], set_name: str) -> list[dict]:
    """Means per (texture, detector) over the photographs of one set."""
    out = []
    for texture in ("own", "real"):
        for detector in dict.fromkeys(r["detector"] for r in rows):
            mine = [r for r in rows if r["texture"] == texture and r["detector"] == detector]
            if not mine:
                continue

            def mean(key):
                return float(np.nanmean([r[key] for r in mine]))

            kept = [r["auto_kept"] for r in mine if r["auto_kept"] is not None]
            out.append({"set": set_name, "texture": texture, "detector": detector, "faces": len(mine),
                        "F1": mean("F1"), "P": mean("P"), "R": mean("R"), "dP21_pct": mean("dP21_pct"),
                        "dP20_pct": mean("dP20_pct"),
                        **{key: mean(key) for key in (f"R_w{lo}{hi}" for lo, hi in WIDTH_CLASSES)},
                        "set_angle_deg": mean("set_angle_deg"),
                        "auto_kept": "/".join(str(kept.count(d)) for d in ("ridge", "learned", "cnn"))
                        if kept else None,
                        "ignored_pct": mean("ignored_pct"), "s_per_face": mean("seconds")})
        pairs = {}
        for r in rows:
            if r["texture"] == texture and r["detector"] in ("learned", "ridge"):
                pairs.setdefault((r["photo"], r["seed"]), {})[r["detector"]] = r["F1"]
        best = [max(p.values()) for p in pairs.values() if len(p) == 2]
        if best:  # what a per-photo choice between the two detectors could reach at best
            out.append({"set": set_name, "texture": texture, "detector": "better of the two", "faces": len(best),
                        "F1": float(np.mean(best))})
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sets", default=",".join(SETS),
                        help=f"comma-separated, of {', '.join(SETS)} (default all)")
    parser.add_argument("--difficulty", default="moderate", choices=("easy", "moderate", "hard"))
    parser.add_argument("--detectors", default="auto,learned,ridge,cnn,auto-cnn,fine")
    parser.add_argument("--limit", type=int, default=0, help="first N photos of each set (0: all)")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args(argv)
    sets = [s for s in args.sets.split(",") if s]
    detectors = [d for d in args.detectors.split(",") if d]
    unknown = [s for s in sets if s not in SETS] + [d for d in detectors if d not in DETECTOR_NAMES]
    if unknown or not sets or not detectors or args.limit < 0 or args.workers < 1:
        parser.error(f"bad --sets / --detectors / --limit / --workers ({', '.join(unknown) or 'empty'})")

    print(header(f"joints drawn on real rock ({args.difficulty}), {M_PER_PX * 1000:g} mm/px, "
                 f"buffer {BUFFER_PX:g} px, own fractures ignored within {IGNORE_MARGIN_PX:g} px"))
    payload = {"difficulty": args.difficulty, "m_per_px": M_PER_PX, "buffer_px": BUFFER_PX,
               "ignore_margin_px": IGNORE_MARGIN_PX, "summary": [], "faces": []}
    for set_name in sets:
        pairs = photos(set_name)
        if args.limit:
            pairs = pairs[:args.limit]
        if not pairs:
            print(f"\n{set_name}: no photographs found, skipped")
            continue
        jobs = [(photo, label, index + 1, args.difficulty, detectors)
                for index, (photo, label) in enumerate(pairs)]
        with ProcessPoolExecutor(max_workers=args.workers) as pool:
            rows = [row for rows in pool.map(score_photo, jobs) for row in rows]
        for row in rows:
            row["set"] = set_name
        payload["faces"] += rows
        payload["summary"] += summary(rows, set_name)
        print(f"\n{set_name} ({len(pairs)} photographs)")
        print(table([r for r in payload["summary"] if r["set"] == set_name], COLUMNS))
    suffix = "" if args.difficulty == "moderate" else f"_{args.difficulty}"
    print(f"\nrows: {save('bench_texture_faces' + suffix, payload)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
