"""Block generation: run time vs area balance for two persistent sets and a circular tunnel.

A square of side L is cut by sets at 30° and 120° with spacing s = L / sqrt(N) (about N blocks) and a
tunnel of radius L/10 at its centre (36-sided). For each size the table reports the build time
(first and warm), the invariant check time, the block count, convex splits, slivers merged, short
edges snapped and left, and the area balance |Σ area − domain area| / domain area (the geometric
error; the criterion is 1e-9). A second table subdivides every rock block of the same model by
potential cracks (Voronoi and triangular) and reports time, counts, the mean sub-block area over the
target size² and the same invariants.

    python benchmarks/bench_blockgen.py [--quick]
"""

from __future__ import annotations

import math
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import header, save, table, timed  # noqa: E402


def case(n_target: int):
    import numpy as np

    from rockmass.blockgen import JointSet, build, circle

    side = 100.0
    s = side / math.sqrt(n_target)
    domain = np.array([[0, 0], [side, 0], [side, side], [0, side]], float)
    sets = [JointSet(30, s), JointSet(120, s)]
    tunnel = circle((side / 2, side / 2), side / 10)
    return lambda: build(domain, sets, excavations=[tunnel], seed=1)


def crack_case(n_parents: int, pattern: str):
    """The same model with ~n_parents joint blocks, every rock block cut into potential cracks of
    size s/√10 (about 10 sub-blocks per joint block of area s²)."""
    import numpy as np

    from rockmass.blockgen import Cracks, JointSet, build, circle

    side = 100.0
    s = side / math.sqrt(n_parents)
    domain = np.array([[0, 0], [side, 0], [side, side], [0, side]], float)
    sets = [JointSet(30, s), JointSet(120, s)]
    tunnel = circle((side / 2, side / 2), side / 10)
    cracks = Cracks(s / math.sqrt(10), pattern=pattern)
    return lambda: build(domain, sets, excavations=[tunnel], seed=1, cracks=cracks)


def main(quick: bool = False) -> None:
    from rockmass.blockgen import check_model

    load = os.getloadavg()[0]  # other work on the machine inflates every time below

    sizes = [(1_000, 3), (10_000, 3), (100_000, 1)] if not quick else [(1_000, 1), (10_000, 1)]
    rows = []
    for n, repeat in sizes:
        first, warm, model = timed(case(n), repeat=repeat)
        t0 = time.perf_counter()
        inv = check_model(model) if model.n_blocks <= 20_000 else None
        check_s = time.perf_counter() - t0 if inv else None
        q = model.quality
        rows.append({"target_blocks": n, "blocks": model.n_blocks, "first_s": first, "warm_s": warm,
                     "check_s": check_s, "convex_splits": len(q.convex_splits),
                     "slivers_merged": len(q.slivers_merged),
                     "edges_snapped": q.edges_snapped["count"],
                     "short_edges_left": q.tiny_edges["count"],
                     "area_balance": q.area_balance["relative_error"],
                     "invariants_ok": None if inv is None else str(inv["ok"])})
    title = ("block generation: two persistent sets (30°, 120°) + circular tunnel r = L/10 "
             "in an L x L square; target <= 2 s at 1e4 blocks, <= 30 s at 1e5")
    cols = [("target_blocks", "d"), ("blocks", "d"), ("first_s", ".3f"), ("warm_s", ".3f"),
            ("check_s", ".3f"), ("convex_splits", "d"), ("slivers_merged", "d"),
            ("edges_snapped", "d"), ("short_edges_left", "d"), ("area_balance", ".2e"),
            ("invariants_ok", "s")]
    print(header(title) + f"\nload average (1 min) at start: {load:.2f}")
    print(table(rows, cols))
    crack_rows = []
    crack_sizes = [(1_000, 1), (10_000, 0)] if not quick else [(1_000, 0)]
    for n, repeat in crack_sizes:
        for pattern in ("voronoi", "triangular"):
            if repeat:
                first, warm, model = timed(crack_case(n, pattern), repeat=repeat)
            else:  # one run only (the largest case)
                t0 = time.perf_counter()
                model = crack_case(n, pattern)()
                first, warm = time.perf_counter() - t0, None
            t0 = time.perf_counter()
            inv = check_model(model) if model.n_blocks <= 30_000 else None
            check_s = time.perf_counter() - t0 if inv else None
            c = model.quality.cracks
            crack_rows.append({
                "joint_blocks": n, "pattern": pattern, "blocks": model.n_blocks,
                "first_s": first, "warm_s": warm, "check_s": check_s,
                "subdivided": c["n_subdivided"], "crack_contacts": c["n_crack_contacts"],
                "mean_area_per_target": c["crack_block_area_m2"]["mean"] / c["target_area_m2"],
                "removed_or_merged": c.get("seeds_removed", c.get("pieces_merged")),
                "edges_snapped": model.quality.edges_snapped["count"],
                "area_balance": model.quality.area_balance["relative_error"],
                "invariants_ok": None if inv is None else str(inv["ok"])})
    crack_title = ("potential cracks: the same model, every rock block subdivided (size s/√10, "
                   "about 10 sub-blocks per joint block); seeds removed (voronoi) or pieces "
                   "merged (triangular) against slivers and short edges")
    crack_cols = [("joint_blocks", "d"), ("pattern", "s"), ("blocks", "d"), ("first_s", ".3f"),
                  ("warm_s", ".3f"), ("check_s", ".3f"), ("subdivided", "d"),
                  ("crack_contacts", "d"), ("mean_area_per_target", ".3f"),
                  ("removed_or_merged", "d"), ("edges_snapped", "d"), ("area_balance", ".2e"),
                  ("invariants_ok", "s")]
    print()
    print(crack_title)
    print(table(crack_rows, crack_cols))
    save("bench_blockgen", {"title": title, "load_average_1min": load, "rows": rows,
                            "cracks_title": crack_title, "cracks_rows": crack_rows})


if __name__ == "__main__":
    main(quick="--quick" in sys.argv)
