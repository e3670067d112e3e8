"""When should "auto" keep the convolutional network's traces? ``auto_network_ratio`` on real labels
and on joints drawn on real rock, side by side.

    python benchmarks/bench_network_ratio.py [--splits train,val] [--limit N] [--workers 2]
                                             [--network cnn] [--network-setting NAME]

"auto" (docs/imaging.md §3.3, §3.6) keeps the ridge filter's traces on a clean photo; otherwise
the pixel model's, unless the network's chain finds at least ``auto_network_ratio`` times their
total length. Two judges disagree about what a detector should draw: the hand labels of the real
photographs (rock-face-fractures, major open fractures only; F1 at 5 px, as
``bench_imaging_real.py``) and the exact truth of the joints ``bench_texture_faces.py`` draws onto
the same photographs (buffered F1 at 3 px, the photo's own fractures ignored). Per photograph
and per face, "auto" is run with the network off (its choice between the ridge filter and the
pixel model, and the pixel model's traces) and the network's chain alone; the choice for every
ratio follows from their trace lengths (``network_length_ratio``), since "auto" keeps exactly the
traces of the chain it picks run alone (tests/imaging/test_joint_net.py). The ratio was chosen on
``train`` (:func:`chosen_ratio`: the smallest ratio whose mean real F1 is not below the pixel
model's alone, i.e. the network costs the real labels nothing there): 1.3; ``val`` is only
measured. ``--network FILE`` scores another network (another training seed) in "auto" the same
way, ``--network-setting`` the network's chain at one of ``bench_network_back_end.py``'s other
back-end settings (e.g. ``"length 20 px"``; printed only). Rows
also go to benchmarks/results/bench_network_ratio.json (``..._<network file stem>.json`` for
another network).
"""

from __future__ import annotations

import argparse
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import RESULTS, detector_params, header, save, table  # noqa: E402
from bench_network_back_end import VARIANTS  # noqa: E402  (the back-end settings tried)

RATIOS = (1.0, 1.1, 1.2, 1.3, 1.5, 2.0, float("inf"))
COLUMNS = [("split", "s"), ("ratio", "g"), ("real_F1", ".3f"), ("real_P", ".3f"), ("real_R", ".3f"),
           ("real_dP21_pct", "+.0f"), ("real_cnn", "d"), ("drawn_F1", ".3f"), ("drawn_P", ".3f"),
           ("drawn_R", ".3f"), ("drawn_dP21_pct", "+.0f"), ("drawn_cnn", "d"), ("photos", "d")]


def _runs(image, network, network_settings, **scale):
    """(auto without the network, the chain of ``network`` alone, at the learned detector's
    back end with ``network_settings`` changed) of one image."""
    from rockmass.imaging.extract import extract

    auto = extract(image, params=detector_params("auto-cnn"), **scale)
    network = extract(image, params=detector_params("learned", pixel_model=network,
                                                    **network_settings), **scale)
    return auto, network


def score_photo(job) -> dict:
    """The three candidate trace sets' scores on one photo and on the joints drawn on it."""
    import cv2

    from bench_imaging_real import TOLERANCE_PX, label_skeleton
    from bench_texture_faces import M_PER_PX, BUFFER_PX, ignore_mask
    from rockmass.imaging import joints_on_photo
    from rockmass.imaging.extract import extract, network_length_ratio
    from rockmass.imaging.label_scores import score_traces
    from rockmass.imaging.metrics import trace_accuracy

    photo_path, label, seed, network_file, network_settings = job
    photo = np.ascontiguousarray(cv2.imread(str(photo_path), cv2.IMREAD_COLOR)[..., ::-1])
    out = {"photo": photo_path.name}
    auto, network = _runs(photo, network_file, network_settings, m_per_px=1.0, joint_width_px=3.0)
    truth = label_skeleton(label)
    ridge = auto.traces if auto.detector_choice["kept"] == "ridge" else None
    learned = extract(photo, m_per_px=1.0, joint_width_px=3.0,
                      params=detector_params("learned")).traces if ridge is not None else auto.traces
    out["real"] = {"ratio": network_length_ratio(network.traces, learned), "kept": auto.detector_choice["kept"],
                   **{name: score_traces(traces, truth, tolerance_px=TOLERANCE_PX)[0]
                      for name, traces in (("auto", auto.traces), ("learned", learned),
                                           ("cnn", network.traces))}}
    face = joints_on_photo(photo, "moderate", seed=seed, m_per_px=M_PER_PX)
    ignore = ignore_mask(photo_path, label, photo.shape[:2])
    auto, network = _runs(face.image, network_file, network_settings, m_per_px=M_PER_PX)
    learned = (auto.traces if auto.detector_choice["kept"] == "learned" else
               extract(face.image, m_per_px=M_PER_PX, params=detector_params("learned")).traces)

    def accuracy(traces):
        a = trace_accuracy(traces, face.truth, buffer_px=BUFFER_PX, ignore=ignore, m_per_px=M_PER_PX)
        return [a.f1, a.precision, a.recall, a.p21_rel_error]

    out["drawn"] = {"ratio": network_length_ratio(network.traces, learned),
                    "kept": auto.detector_choice["kept"],
                    "auto": accuracy(auto.traces), "cnn": accuracy(network.traces)}
    return out


def keeps_network(scores: dict, ratio: float) -> bool:
    """Whether "auto" with ``auto_network_ratio = ratio`` keeps the network's traces on a photo
    (``inf``: the network is not run)."""
    return bool(scores["kept"] != "ridge" and np.isfinite(ratio) and scores["ratio"] >= ratio)


def rows_of(split: str, photos: list[dict]) -> list[dict]:
    """One row per ratio: the scores over the photographs of what "auto" would keep (real: the
    pixel counts summarised as bench_imaging_real.py does; drawn: means over the faces)."""
    from bench_imaging_real import summarise_counts

    rows = []
    for ratio in RATIOS:
        real = [p["real"]["cnn" if keeps_network(p["real"], ratio) else "auto"] for p in photos]
        drawn = np.array([p["drawn"]["cnn" if keeps_network(p["drawn"], ratio) else "auto"]
                          for p in photos], dtype=float)
        scores = summarise_counts(real)
        rows.append({"split": split, "ratio": ratio, "real_F1": scores["F1"], "real_P": scores["P"],
                     "real_R": scores["R"], "real_dP21_pct": scores["dP21_pct"],
                     "real_cnn": sum(keeps_network(p["real"], ratio) for p in photos),
                     "drawn_F1": float(np.nanmean(drawn[:, 0])),
                     "drawn_P": float(np.nanmean(drawn[:, 1])),
                     "drawn_R": float(np.nanmean(drawn[:, 2])),
                     "drawn_dP21_pct": 100 * float(np.nanmean(drawn[:, 3])),
                     "drawn_cnn": sum(keeps_network(p["drawn"], ratio) for p in photos),
                     "photos": len(photos)})
    return rows


def chosen_ratio(rows: list[dict]) -> float:
    """The smallest ratio whose mean real F1 is not below that of the pixel model alone (the
    ``inf`` row): the rule ``auto_network_ratio`` was chosen by on ``train``."""
    alone = next(r["real_F1"] for r in rows if not np.isfinite(r["ratio"]))
    return min(r["ratio"] for r in rows if r["real_F1"] >= alone)


def _print_rows(split: str, rows: list[dict]) -> None:
    print(table(rows, COLUMNS))
    print(f"{split}: smallest ratio whose real F1 is not below the pixel model's alone: "
          f"{chosen_ratio(rows):g}" + (" (the rule auto_network_ratio was chosen by)"
                                       if split == "train" else " (measured only)"))


def add_photo_arguments(parser: argparse.ArgumentParser) -> None:
    """``--splits``, ``--limit``, ``--workers`` and ``--network`` of a script that scores the
    rock-face-fractures photographs one by one (this one and ``bench_network_back_end.py``)."""
    parser.add_argument("--splits", default="train,val")
    parser.add_argument("--limit", type=int, default=0, help="first N photos of each split (0: all)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--network", default="cnn",
                        help="the network: cnn (the shipped one) or an .onnx file")


def results_name(script: str, network: str) -> str:
    """The results file's name (no suffix) of ``script`` run with ``network``: the script's own
    for the shipped network, ``<script>_<file stem>`` for another."""
    return script if network == "cnn" else f"{script}_{Path(network).stem}"


def checked_splits(args, parser: argparse.ArgumentParser) -> list[str]:
    """The splits of :func:`add_photo_arguments`' arguments, or a usage error."""
    splits = [s for s in args.splits.split(",") if s]
    if not splits or set(splits) - {"train", "val"} or args.limit < 0 or args.workers < 1:
        parser.error("--splits takes train and/or val; --limit >= 0, --workers >= 1")
    return splits


def scored_photos(split: str, args, score, *extra):
    """``score((photo, label, seed, *extra))`` of every photograph of a split (the first
    ``args.limit``), in ``args.workers`` processes, and the seconds taken; None when the split has
    no labelled photographs. The seed of the joints drawn on a photo is 1 + its index."""
    from bench_imaging_real import real_pairs

    pairs = real_pairs(split)
    if not pairs:
        print(f"\n{split}: no labelled photographs found, skipped")
        return None
    pairs = pairs[:args.limit] if args.limit else pairs
    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.workers) as pool:
        photos = list(pool.map(score, [(p, label, k + 1, *extra)
                                       for k, (p, label) in enumerate(pairs)]))
    return photos, time.perf_counter() - t0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    add_photo_arguments(parser)
    parser.add_argument("--network-setting", choices=list(VARIANTS), default="default",
                        help="the network's chain at this back-end setting of "
                             "bench_network_back_end.py instead of the learned detector's; "
                             "rows of a setting other than the default are printed, not saved")
    parser.add_argument("--from-json", action="store_true",
                        help="recompute the rows from the saved per-photo scores")
    args = parser.parse_args(argv)
    splits = checked_splits(args, parser)
    print(header("auto_network_ratio: real labels and joints drawn on the same photographs"))
    network_settings = VARIANTS[args.network_setting]
    print(f"network: {args.network}, its chain's back end: {args.network_setting}")
    payload = {"network": args.network, "ratios": list(RATIOS), "rows": [], "photos": {}}
    if args.from_json:
        import json

        saved = json.loads((RESULTS / f"{results_name('bench_network_ratio', args.network)}.json")
                           .read_text())
        for split in splits:
            print(f"\n{split}/ (rows recomputed from the saved per-photo scores)")
            _print_rows(split, rows_of(split, saved["photos"][split]))
        return 0
    for split in splits:
        scored = scored_photos(split, args, score_photo, args.network, network_settings)
        if scored is None:
            continue
        photos, seconds = scored
        rows = rows_of(split, photos)
        payload["rows"] += rows
        payload["photos"][split] = photos
        print(f"\n{split}/ ({len(photos)} photographs, {seconds:.0f} s; real: hand "
              "labels, F1 at 5 px, means over photos; drawn: joints drawn on the same photos, "
              "buffered F1 at 3 px; *_cnn: photos where auto keeps the network's traces)")
        _print_rows(split, rows)
    if not network_settings:  # the rows of another back end are printed only
        print(f"\nrows: {save(results_name('bench_network_ratio', args.network), payload)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
