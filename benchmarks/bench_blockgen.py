"""Block generation: run time vs area balance for two persistent sets and a circular tunnel.

A square of side L is cut by sets at 30° and 120° with spacing s = L / sqrt(N) (about N blocks) and a
tunnel of radius L/10 at its centre (36-sided). For each size the table reports the build time
(first and warm), the invariant check time, the block count, convex splits and slivers merged, and
the area balance |Σ area − domain area| / domain area (the geometric error; the criterion is 1e-9).

    python benchmarks/bench_blockgen.py [--quick]
"""

from __future__ import annotations

import math
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


def main(quick: bool = False) -> None:
    from rockmass.blockgen import check_model

    sizes = [(1_000, 3), (10_000, 3), (100_000, 1)] if not quick else [(1_000, 1), (10_000, 1)]
    rows = []
    for n, repeat in sizes:
        first, warm, model = timed(case(n), repeat=repeat)
        t0 = time.perf_counter()
        inv = check_model(model) if model.n_blocks <= 20_000 else None
        check_s = time.perf_counter() - t0 if inv else None
        q = model.quality
        rows.append({"target_blocks": n, "blocks": model.n_blocks, "first_s": first, "warm_s": warm,
                     "check_s": check_s, "convex_splits": len(q["convex_splits"]),
                     "slivers_merged": len(q["slivers_merged"]),
                     "area_balance": q["area_balance"]["relative_error"],
                     "invariants_ok": None if inv is None else str(inv["ok"])})
    title = ("block generation: two persistent sets (30°, 120°) + circular tunnel r = L/10 "
             "in an L x L square; target <= 2 s at 1e4 blocks, <= 30 s at 1e5")
    cols = [("target_blocks", "d"), ("blocks", "d"), ("first_s", ".3f"), ("warm_s", ".3f"),
            ("check_s", ".3f"), ("convex_splits", "d"), ("slivers_merged", "d"),
            ("area_balance", ".2e"), ("invariants_ok", "s")]
    print(header(title))
    print(table(rows, cols))
    save("bench_blockgen", {"title": title, "rows": rows})


if __name__ == "__main__":
    main(quick="--quick" in sys.argv)
