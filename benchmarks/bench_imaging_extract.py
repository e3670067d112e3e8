"""Photo -> traces with the ridge filter: accuracy by difficulty, throughput, run time against error.

    python benchmarks/bench_imaging_extract.py [--quick]

1. Accuracy over the synthetic difficulty levels (1500 x 1000 px faces, 0.008 m/px, seeds 1-3: not
   the tuning seeds 100+): buffered F1 (3 px), P21 and P20 errors, the largest set-angle error,
   D_box error, node-count error, run time. Targets at "moderate": F1 >= 0.85, |dP21| <= 10 %,
   set angle error <= 3 deg, |dD_box| <= 0.05. Two more rows run the chain without trace linking
   and border extension (``link_gap_px = 0``, ``border_extend_px = 0``): the fragmentation they
   remove shows in dP20 and the node-count error.
2. Throughput at 2, 12 and 24 MP (moderate faces; the 12 and 24 MP faces are the same network at a
   finer pixel), with accuracy and peak memory (ru_maxrss of a fresh process per size); the learned
   detector (``detector="learned"``) and the default, "auto" (both detectors, the ridge traces kept
   on a clean face such as these), at 12 and 24 MP too. Target >= 1 MP/s on 2 cores (issue 22:
   >= 2 MP/s whole process at 12-24 MP), <= 2 GB at 24 MP.
3. Run time against error for the main knobs: down-sampling (max_megapixels) and filter scales.

Every row but the learned and auto throughput ones runs the ridge filter (``detector="ridge"``):
the chain these targets and knobs were set for (the learned detector's accuracy on these plain
faces is in bench_imaging_real.py and docs/imaging.md §3.1; the default detector, "auto", keeps the
ridge traces on them, docs/imaging.md §3.3).
Rows also go to benchmarks/results/bench_imaging_extract.json.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time

import numpy as np

from _common import header, save, table

COLUMNS = [("level", "s"), ("setting", "s"), ("MP", ".1f"), ("F1", ".3f"), ("dP21_%", "+.1f"),
           ("dP20_%", "+.1f"), ("angle_err_deg", ".2f"), ("dD_box", "+.3f"), ("node_err", ".2f"),
           ("time_s", ".2f")]


def run_case(difficulty, seed, shape_px=(1000, 1500), m_per_px=0.008, params=None, joint_width=3.0):
    from rockmass.imaging.extract import ExtractParams, extract
    from rockmass.accuracy import trace_accuracy
    from rockmass.imaging.synthetic import synthetic_face

    face = synthetic_face(difficulty, seed=seed, shape_px=shape_px, m_per_px=m_per_px)
    t0 = time.perf_counter()
    result = extract(face.image, m_per_px=m_per_px, joint_width_px=joint_width,
                     params=params or ExtractParams(detector="ridge"))
    elapsed = time.perf_counter() - t0
    # accuracy on the grid the chain worked on (the buffer is 3 working pixels)
    acc = trace_accuracy(result.traces, face.truth, m_per_px=m_per_px / result.scale.work_factor)
    return dict(MP=face.image.size / 1e6, F1=acc.f1, dP21_pct=100 * acc.p21_rel_error,
                dP20_pct=100 * acc.p20_rel_error, angle_err_deg=acc.max_set_angle_error_deg,
                dD_box=acc.d_box_error, node_err=acc.node_count_error, time_s=elapsed,
                processing=result.scale.processing)


def mean_row(rows, **labels):
    keys = ["MP", "F1", "dP21_pct", "dP20_pct", "angle_err_deg", "dD_box", "node_err", "time_s"]
    out = {k: float(np.mean([r[k] for r in rows])) for k in keys}
    out["dP21_%"], out["dP20_%"] = out.pop("dP21_pct"), out.pop("dP20_pct")
    out["worst_angle_err_deg"] = float(max(r["angle_err_deg"] for r in rows))
    out["worst_abs_dP21_%"] = float(max(abs(r["dP21_pct"]) for r in rows))
    return {**labels, **out}


def child(size_mp: float, detector: str = "ridge") -> None:
    """One throughput case in this (fresh) process; prints a JSON row."""
    import resource

    from rockmass.imaging.extract import ExtractParams

    params = ExtractParams(detector=detector)
    run_case("moderate", 1, shape_px=(200, 300), m_per_px=0.04, params=params)  # warm-up: imports, caches
    h = int(round(np.sqrt(size_mp * 1e6 / 1.5)))
    w = int(round(1.5 * h))
    scale = 12.0 / w  # same 12 m x 8 m face at every size
    # the generator draws joints 1-6 px wide at any size, so the default joint width stays right
    row = run_case("moderate", 1, shape_px=(h, w), m_per_px=scale, params=params)
    row["peak_MB"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    row["MP_per_s"] = row["MP"] / row["time_s"]
    print(json.dumps(row))


def main(quick: bool = False) -> None:
    from rockmass.imaging.extract import ExtractParams

    print(header("photo -> traces: accuracy, throughput and run time vs error (synthetic faces)"))
    seeds = [1] if quick else [1, 2, 3]
    accuracy = []
    for level in ("easy", "moderate", "hard"):
        rows = [run_case(level, s) for s in seeds]
        accuracy.append(mean_row(rows, level=level, setting=f"defaults, seeds {seeds}"))
    unlinked = ExtractParams(detector="ridge", link_gap_px=0.0, border_extend_px=0.0)
    for level in ("moderate", "hard"):
        rows = [run_case(level, s, params=unlinked) for s in seeds]
        accuracy.append(mean_row(rows, level=level, setting="no linking, no border (before)"))
    print("\n1. accuracy by difficulty (1500 x 1000 px, mean over seeds); the last two rows switch "
          "off\n   trace linking and border extension (the chain before them) for comparison")
    print(table(accuracy, COLUMNS + [("worst_angle_err_deg", ".2f"), ("worst_abs_dP21_%", ".1f")]))

    throughput = []
    for detector, size in [("ridge", 2.0), ("ridge", 12.0), ("ridge", 24.0), ("learned", 12.0),
                           ("learned", 24.0), ("auto", 12.0), ("auto", 24.0)]:
        out = subprocess.run([sys.executable, __file__, "--child", str(size), detector],
                             capture_output=True, text=True, check=True)
        row = json.loads(out.stdout.strip().splitlines()[-1])
        row.update(level="moderate", setting=f"{detector}, {size:g} MP")
        throughput.append(row)
    print("\n2. throughput (moderate face, fresh process per size; peak = ru_maxrss incl. face generation)")
    print(table(throughput, [("setting", "s"), ("MP", ".1f"), ("time_s", ".2f"), ("MP_per_s", ".2f"),
                             ("peak_MB", ".0f"), ("F1", ".3f"), ("dP21_pct", "+.1f"),
                             ("dP20_pct", "+.1f"), ("angle_err_deg", ".2f"), ("dD_box", "+.3f"),
                             ("node_err", ".2f"), ("processing", "s")]))

    curve = []
    knobs = [(label, ExtractParams(detector="ridge", **kw)) for label, kw in (
        ("max_megapixels=4 (default)", {}), ("max_megapixels=1", dict(max_megapixels=1.0)),
        ("max_megapixels=0.5", dict(max_megapixels=0.5)), ("max_megapixels=8", dict(max_megapixels=8.0)),
        ("n_scales=1", dict(n_scales=1)), ("n_scales=5", dict(n_scales=5, scale_spread=3.0)),
        ("scale_spread=4", dict(scale_spread=4.0)))]
    size = (1400, 2100)  # 2.9 MP moderate faces, same 12 m x 8 m
    for label, params in knobs:
        rows = [run_case("moderate", s, shape_px=size, m_per_px=12.0 / size[1], params=params)
                for s in seeds[:2]]
        curve.append(mean_row(rows, level="moderate", setting=label))
    print("\n3. run time vs error, moderate 2.9 MP faces")
    print(table(curve, COLUMNS))
    path = save("bench_imaging_extract", {"accuracy": accuracy, "throughput": throughput,
                                          "curve": curve})
    print(f"\nrows written to {path}")


if __name__ == "__main__":
    if len(sys.argv) > 2 and sys.argv[1] == "--child":
        child(float(sys.argv[2]), *sys.argv[3:4])
    else:
        main(quick="--quick" in sys.argv)
