"""Regenerate ``scanline_seed001.csv`` (deterministic: the same file on every machine).

    python samples/make_scanline_sample.py

A synthetic scanline survey across the three joint sets of Kiran & Juneja (2022), Table 1 (dip / dip direction
50/270, 80/10 and 70/150; mean trace lengths 12, 9 and 10 m). Choices of this sample, not of the
paper: each set is a Poisson network of one-sided intensity P32 = 1.5 m²/m³ with Fisher scatter
κ = 30; the scanline trends 135°, plunges 10° and is 30 m long (it meets all three sets at 40–55°
from their planes, so none is in the Terzaghi blind zone).

A line of direction t meets the fractures of a set whose poles are n at rate P32 · E|n·t|
(docs/fractures.md §7), and the poles of the fractures it meets are biased towards t by the factor |n·t|.
Both follow from thinning: draw Poisson(P32 · L) candidate fractures with Fisher poles, keep each
with probability |n·t|, place the kept ones uniformly along the line. Distances are then rounded to
the centimetre and orientations to the degree, as a tape and a compass read them; trace lengths are
exponential about the table's means (0.1 m), and ``termination`` is the number of trace ends seen
(0, 1 or 2). The file's header comments carry the line geometry that ``rockmass scanline`` reads.

Randomness: ``SeedSequence(SEED)`` with one child per set (docs/design.md §3.5).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rockmass.dfn.atomic import atomic_open
from rockmass.dfn import dip_from_normal, pole_from_dip, sample_fisher, vector_from_trend_plunge

HERE = Path(__file__).resolve().parent
SEED = 1
TREND_DEG, PLUNGE_DEG, LENGTH_M = 135.0, 10.0, 30.0
KAPPA = 30.0
P32 = 1.5
#: Seed 001, Table 1: dip (deg), dip direction (deg), mean trace length (m).
SETS = ((50.0, 270.0, 12.0), (80.0, 10.0, 9.0), (70.0, 150.0, 10.0))


def make_rows() -> list[tuple[float, int, int, float, int]]:
    """Rows (distance, dip, dip_direction, trace_length, termination), sorted by distance."""
    line = vector_from_trend_plunge(TREND_DEG, PLUNGE_DEG)
    rows = []
    for child, (dip, dip_direction, trace_mean) in zip(np.random.SeedSequence(SEED).spawn(len(SETS)), SETS):
        rng = np.random.default_rng(child)
        n_candidates = rng.poisson(P32 * LENGTH_M)
        poles = sample_fisher(rng, pole_from_dip(dip, dip_direction), KAPPA, n_candidates)
        kept = poles[rng.random(n_candidates) < np.abs(poles @ line)]
        distance = rng.uniform(0.0, LENGTH_M, kept.shape[0])
        trace = rng.exponential(trace_mean, kept.shape[0])
        ends = rng.integers(0, 3, kept.shape[0])
        dips, directions = dip_from_normal(kept)
        for row in zip(distance, dips, directions, trace, ends):
            rows.append(row)
    rows.sort(key=lambda r: r[0])
    return [(round(d, 2), int(round(a)), int(round(b)) % 360, round(t, 1), int(e)) for d, a, b, t, e in rows]


def main() -> None:
    lines = [
        "# Synthetic scanline across the three joint sets of Kiran & Juneja 2022 (Table 1), made by",
        "# samples/make_scanline_sample.py: Fisher kappa = 30, P32 = 1.5 m2/m3 per set.",
        f"# trend: {TREND_DEG:g}",
        f"# plunge: {PLUNGE_DEG:g}",
        f"# length: {LENGTH_M:g}",
        "distance_m,dip_deg,dip_direction_deg,trace_length_m,termination",
    ]
    lines += [f"{d:.2f},{a},{b},{t:.1f},{e}" for d, a, b, t, e in make_rows()]
    with atomic_open(HERE / "scanline_seed001.csv", newline="") as handle:
        handle.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
