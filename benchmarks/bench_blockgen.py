"""Block generation: run time vs area balance for two persistent sets and a circular tunnel.

A square of side L is cut by sets at 30° and 120° with spacing s = L / sqrt(N) (about N blocks) and a
tunnel of radius L/10 at its centre (36-sided). For each size the table reports the build time
(first and warm), the invariant check time, the block count, convex splits, slivers merged, short
edges snapped and left, and the area balance |Σ area − domain area| / domain area (the geometric
error; the criterion is 1e-9). A second table subdivides every rock block of the same model by
potential cracks (Voronoi and triangular) and reports time, counts, the mean sub-block area over the
target size² and the same invariants.

A third table cuts blocks from traces, the path where joints end in intact rock and each dangling end
is extended to the first line it meets: a random map (uniform centres and angles, half-lengths
0.5–3 m, 0.3 traces/m²) and the traces of a DFN plane section (the three sets of
samples/blocks_dfn_section.toml on a W x W window with its 6 m horseshoe drift), at about 10³, 10⁴
and 10⁵ blocks. Beside the build time (first and warm; wall and CPU) it reports the dangling ends,
the (ray, segment) pairs the spatial index returned per end (the ray search's work), and the area
balance and invariants; up to 2·10⁴ blocks it also builds the model with one domain-long ray per end
(the algorithm before issue 20) in the same run and reports its time and whether the two models are
identical, array for array.

    python benchmarks/bench_blockgen.py [--quick]   (--help lists the options)
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


#: blocks per m² (measured) of the random map below and of the seed-001 DFN section with its drift
_TRACE_BLOCKS_PER_M2 = 0.88
_DFN_BLOCKS_PER_M2 = 0.218


def trace_case(n_target: int):
    """A random trace map in a square sized for about ``n_target`` blocks: (traces, build)."""
    import numpy as np

    from rockmass.blockgen import build

    side = math.sqrt(n_target / _TRACE_BLOCKS_PER_M2)
    rng = np.random.default_rng(20)  # fixed seed: one map per size
    n = int(0.3 * side * side)
    centre = rng.uniform(0, side, (n, 2))
    angle = rng.uniform(0, np.pi, n)
    half = rng.uniform(0.5, 3.0, n)[:, None] * np.column_stack([np.cos(angle), np.sin(angle)])
    traces = np.stack([centre - half, centre + half], axis=1)
    domain = np.array([[0, 0], [side, 0], [side, side], [0, side]], float)
    return n, lambda: build(domain, traces=traces, seed=1)


def dfn_case(n_target: int):
    """Traces of the seed-001 DFN section on a W x W window with a 6 m horseshoe drift, W sized
    for about ``n_target`` blocks: (traces, build)."""
    from rockmass.blockgen import build, horseshoe
    from rockmass.config import load_config
    from rockmass.dfn.orientation import normal_from_dip
    from rockmass.dfn.section import generate_section

    sample = Path(__file__).resolve().parents[1] / "samples" / "blocks_dfn_section.toml"
    doc = load_config(sample)
    sec = doc.dfn.sections[0]
    w = math.sqrt(n_target / _DFN_BLOCKS_PER_M2)
    window = [(-w / 2, 0.0), (w / 2, 0.0), (w / 2, w), (-w / 2, w)]
    traces = generate_section([s.to_spec() for s in doc.dfn.sets], sec.point_m,
                              normal_from_dip(sec.dip_deg, sec.dip_direction_deg), window,
                              seed=doc.dfn.seed, realization=0)
    drift = horseshoe((0.0, w / 2), 6.0, 3.0, name="drift")
    return traces.n_traces, lambda: build(window, traces=traces, excavations=[drift], seed=1)


class _RayCounter:
    """Counts the dangling ends and the (ray, segment) pairs of every ray search while active;
    ``domain_long`` casts every ray at full length at once (the search before issue 20)."""

    def __init__(self, domain_long: bool = False):
        from rockmass.blockgen import network

        self.network, self.original = network, network._ray_hits
        self.domain_long, self.rays, self.pairs = domain_long, 0, 0

    def __call__(self, origins, directions, segments, max_len, **kw):
        if self.domain_long:
            kw["first_len"] = max_len
        t, pairs = self.original(origins, directions, segments, max_len, **kw)
        self.rays, self.pairs = self.rays + len(origins), self.pairs + pairs
        return t, pairs

    def __enter__(self):
        self.network._ray_hits = self
        return self

    def __exit__(self, *exc):
        self.network._ray_hits = self.original


def _same_model(a, b) -> bool:
    import numpy as np

    return (a.n_blocks == b.n_blocks and all(np.array_equal(getattr(a, f), getattr(b, f)) for f in (
        "xy_m", "offsets", "region", "contact_blocks", "contact_kind", "contact_source",
        "contact_length_m")))


def trace_rows(sizes, check_model):
    rows = []
    for path, make in (("random map", trace_case), ("dfn section", dfn_case)):
        for n, repeat in sizes:
            n_traces, fn = make(n)
            cpu = []

            def run():
                t0 = time.process_time()
                out = fn()
                cpu.append(time.process_time() - t0)
                return out

            with _RayCounter() as count:
                first, warm, model = timed(run, repeat=repeat)
            per_end = count.pairs / max(count.rays, 1)
            old_s = same = None
            if model.n_blocks <= 20_000:
                with _RayCounter(domain_long=True) as old_count:
                    t0 = time.perf_counter()
                    old = fn()
                    old_s = time.perf_counter() - t0
                same = str(_same_model(model, old))
                old_per_end = old_count.pairs / max(old_count.rays, 1)
            inv = check_model(model) if model.n_blocks <= 20_000 else None
            q = model.quality
            rows.append({
                "path": path, "target_blocks": n, "traces": int(n_traces), "blocks": model.n_blocks,
                "first_s": first, "warm_s": warm if repeat else None, "warm_cpu_s": cpu[-1],
                "dangling_ends": q.dangling["n_dangling_ends"], "pairs_per_end": per_end,
                "domain_long_s": old_s,
                "domain_long_pairs_per_end": old_per_end if old_s is not None else None,
                "identical_to_domain_long": same,
                "area_balance": q.area_balance["relative_error"],
                "invariants_ok": None if inv is None else str(inv["ok"])})
    return rows


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
    trace_sizes = ([(1_000, 3), (10_000, 2), (100_000, 1)] if not quick
                   else [(1_000, 1), (10_000, 1)])
    t_rows = trace_rows(trace_sizes, check_model)
    trace_title = ("blocks from traces (dangling ends extended to the first line as glued "
                   "contacts): a random map and a seed-001 DFN section with a drift; target "
                   "<= 2 s at 1e4 blocks, <= 25 s at 1e5 (DFN section); domain_long = one "
                   "domain-long ray per end, the search before issue 20")
    trace_cols = [("path", "s"), ("target_blocks", "d"), ("traces", "d"), ("blocks", "d"),
                  ("first_s", ".3f"), ("warm_s", ".3f"), ("warm_cpu_s", ".3f"),
                  ("dangling_ends", "d"), ("pairs_per_end", ".2f"), ("domain_long_s", ".3f"),
                  ("domain_long_pairs_per_end", ".1f"), ("identical_to_domain_long", "s"),
                  ("area_balance", ".2e"), ("invariants_ok", "s")]
    print()
    print(trace_title)
    print(table(t_rows, trace_cols))
    save("bench_blockgen", {"title": title, "load_average_1min": load, "rows": rows,
                            "cracks_title": crack_title, "cracks_rows": crack_rows,
                            "traces_title": trace_title, "traces_rows": t_rows})


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help="sizes 1e3 and 1e4 only, one warm run (a few seconds)")
    main(quick=parser.parse_args().quick)
