"""Trace statistics: run time and error side by side, on trace maps with known answers.

    python benchmarks/bench_trace_stats.py [--quick]

1. Poisson (Boolean) segment networks of about 10^2, 10^3 and 10^4 traces in a square window: two
   sets of segments of one length L, centres a Poisson process of density λ (per set λ_k), axial
   angles θ = μ_k + ½ VM(0, κ_k) (von Mises on 2θ). Expectations for a stationary network
   (docs/fractures.md §§5, 8; Mauldon et al. 2001; Santaló 1976 for the crossing density):

   - P21 = λ L, P20 (end-counting rule, m / 2A) = λ;
   - Mauldon on the inscribed circle: P21 = λ L, P20 = λ, mean trace length = L; the same pooled
     over the disjoint circles :func:`rockmass.dfn.mauldon.inscribed_circles` places in a 3:1 strip;
   - X nodes per area = Σ_{j<k} λ_j λ_k L² E|sin(θ_j - θ_k)| + Σ_k ½ λ_k² L² E|sin(θ - θ')|
     (E|sin| of two independent draws, here by quadrature over the two von Mises laws);
   - joint sets: 2 sets (BIC), means μ_k, circular spread ½ √(-2 ln A1(κ_k)) with A1 = I1 / I0.

   Each statistic is timed (first call and the median of warm calls) next to its error. The errors
   of a single realisation are statistical, so the table also gives z = error / (expected sampling
   sd): about |z| < 3 is a pass. The sds are first-order: √(count) for the X nodes and the Mauldon
   intersections (Poisson), 2√N for the ends inside (they come in pairs), √N L / A for P21 (N
   traces of length L), spread / √N_k for a set's mean angle and spread / √(2 N_k) for its spread.
2. A regular grid of n + n window-spanning lines (exact: P21 = 2n / W, P20 = 0 with every end on
   the window edge, X = n², E = 4n, I = Y = 0; on a circle of radius r the lines at |offset| < r give
   2 intersections each, m = 0; Mauldon's P21 = n / 4r is compared with the true 2n / W).

Rows also go to benchmarks/results/bench_trace_stats.json.
"""

from __future__ import annotations

import sys

import numpy as np

from _common import header, save, table, timed

SETS = ((30.0, 20.0, 0.6), (120.0, 40.0, 0.4))  # (mean angle deg, kappa of 2θ, share of traces)
LENGTH_M = 1.0


def boolean_network(n_expected: int, seed: int):
    """Two-set Boolean segment map: ``n_expected`` centres expected in a W x W window, λ = 1 / L²."""
    from rockmass.dfn import TraceMap

    rng = np.random.default_rng(seed)
    side = float(np.sqrt(n_expected)) * LENGTH_M  # W = √n L, so λ = n / W² = 1 / L²
    density = n_expected / side**2
    lo, hi = -0.5 * LENGTH_M, side + 0.5 * LENGTH_M  # centres of every segment that can reach the window
    segments, set_ids = [], []
    for k, (mean, kappa, share) in enumerate(SETS):
        count = rng.poisson(share * density * (hi - lo) ** 2)
        centre = rng.uniform(lo, hi, size=(count, 2))
        theta = np.radians(mean) + 0.5 * rng.vonmises(0.0, kappa, size=count)
        half = 0.5 * LENGTH_M * np.column_stack([np.cos(theta), np.sin(theta)])
        segments.append(np.hstack([centre - half, centre + half]))
        set_ids.append(np.full(count, k))
    window = np.array([[0.0, 0.0], [side, 0.0], [side, side], [0.0, side]])
    tm = TraceMap.from_segments(np.vstack(segments), attributes={"set": np.concatenate(set_ids)},
                                window=window)
    return tm, side, density


def mean_abs_sin(kappa_a: float, kappa_b: float, delta_deg: float, n: int = 2001) -> float:
    """E|sin(θ_a - θ_b)| for θ = μ + ½ VM(0, κ) laws with means δ apart (quadrature on a grid)."""
    from scipy.special import i0e

    x = np.linspace(-np.pi, np.pi, n, endpoint=False)  # doubled-angle offsets
    def density(kappa):  # von Mises on 2θ, normalised on the grid
        w = np.exp(kappa * (np.cos(x) - 1.0)) / (2 * np.pi * i0e(kappa))
        return w / w.sum()
    wa, wb = density(kappa_a), density(kappa_b)
    theta_a = 0.5 * x
    theta_b = np.radians(delta_deg) + 0.5 * x
    return float(wa @ np.abs(np.sin(theta_a[:, None] - theta_b[None, :])) @ wb)


def expected_crossings_per_area(density: float) -> float:
    total = 0.0
    for j, (mj, kj, sj) in enumerate(SETS):
        for k, (mk, kk, sk) in enumerate(SETS):
            if k < j:
                continue
            factor = 0.5 if j == k else 1.0
            total += factor * (sj * density) * (sk * density) * LENGTH_M**2 * mean_abs_sin(kj, kk, mk - mj)
    return total


def spread_deg(kappa: float) -> float:
    from scipy.special import i0e, i1e

    return float(np.degrees(0.5 * np.sqrt(-2.0 * np.log(i1e(kappa) / i0e(kappa)))))


def row(size, statistic, first, warm, value, expected, sd, unit):
    error = value - expected
    return dict(traces=size, statistic=statistic, unit=unit, first_s=first, warm_s=warm, value=value,
                expected=expected, rel_error_pct=100 * error / expected if expected else None,
                z=error / sd if sd else None)


def poisson_rows(n_expected: int, seed: int, repeat: int) -> list[dict]:
    from rockmass.dfn import (fit_sets_2d, mauldon_circle, trace_intensity, trace_map_statistics,
                              trace_topology)

    tm, side, density = boolean_network(n_expected, seed)
    area = side**2
    n_in = density * area
    tol = 1e-6 * side
    rows = []
    first, warm, ti = timed(lambda: trace_intensity(tm, edge_tolerance_m=tol), repeat)
    rows.append(row(n_expected, "P21 (window)", first, warm, ti.p21_per_m, density * LENGTH_M,
                    np.sqrt(n_in) * LENGTH_M / area, "m/m²"))
    # ends come in pairs: m = Σ (ends of trace i inside), Var m ≈ 4 λ A, so sd(P20) = √(λA) / A
    rows.append(row(n_expected, "P20 (ends m/2A)", first, warm, ti.p20_per_m2, density,
                    np.sqrt(n_in) / area, "1/m²"))
    r = 0.5 * side
    first, warm, ma = timed(lambda: mauldon_circle(tm, (r, r), r, tolerance_m=tol), repeat)
    circle_n = density * np.pi * r * r
    rows.append(row(n_expected, "Mauldon P21", first, warm, ma.p21_per_m, density * LENGTH_M,
                    np.sqrt(4 * r * density * LENGTH_M) / (4 * r), "m/m²"))
    rows.append(row(n_expected, "Mauldon P20", first, warm, ma.p20_per_m2, density,
                    2 * np.sqrt(circle_n) / (2 * np.pi * r * r), "1/m²"))
    rows.append(row(n_expected, "Mauldon mean length", first, warm, ma.mean_length_m, LENGTH_M,
                    LENGTH_M * np.sqrt(1 / (4 * r * density * LENGTH_M) + 1 / circle_n), "m"))
    # a 3:1 strip of the map: three disjoint circles of 0.9 x its half-width, counts pooled
    from rockmass.dfn.mauldon import mauldon_circles

    strip = [(0.0, 0.0), (side, 0.0), (side, side / 3), (0.0, side / 3)]
    first, warm, mp = timed(lambda: mauldon_circles(tm, window=strip, tolerance_m=tol), repeat)
    k, rc = mp.n_circles, mp.radius_m
    pooled_m = density * np.pi * rc * rc * k
    rows.append(row(n_expected, f"Mauldon P21, {k} circles in 3:1", first, warm, mp.p21_per_m,
                    density * LENGTH_M, np.sqrt(4 * k * rc * density * LENGTH_M) / (4 * k * rc), "m/m²"))
    rows.append(row(n_expected, f"Mauldon P20, {k} circles in 3:1", first, warm, mp.p20_per_m2, density,
                    2 * np.sqrt(pooled_m) / (2 * np.pi * k * rc * rc), "1/m²"))
    first, warm, topo = timed(lambda: trace_topology(tm, snap_tolerance_m=tol), repeat)
    x_expected = expected_crossings_per_area(density) * area
    rows.append(row(n_expected, "X nodes", first, warm, float(topo.n_x), x_expected,
                    np.sqrt(x_expected), "-"))
    rows.append(row(n_expected, "I+Y ends inside", first, warm, float(topo.n_i + topo.n_y),
                    2 * n_in, 2 * np.sqrt(n_in), "-"))
    first, warm, sets = timed(lambda: fit_sets_2d(tm), max(1, repeat // 4))
    rows.append(row(n_expected, "sets found (BIC)", first, warm, float(sets.n_sets), 2.0, None, "-"))
    for k, (mean, kappa, share) in enumerate(SETS):
        if sets.n_sets != len(SETS):
            break
        n_k = share * density * (side + LENGTH_M) ** 2
        err = (sets.mean_angle_deg[k] - mean + 90.0) % 180.0 - 90.0
        rows.append(row(n_expected, f"set {k + 1} mean angle", first, warm, mean + err, mean,
                        spread_deg(kappa) / np.sqrt(n_k), "deg"))
        rows.append(row(n_expected, f"set {k + 1} spread", first, warm, float(sets.spread_deg[k]),
                        spread_deg(kappa), spread_deg(kappa) / np.sqrt(2 * n_k), "deg"))
    first, warm, _ = timed(lambda: trace_map_statistics(tm, snap_tolerance_m=tol), max(1, repeat // 4))
    rows.append(dict(traces=n_expected, statistic="trace_map_statistics (all)", unit="-",
                     first_s=first, warm_s=warm))
    return rows


def grid_rows(n_lines: int, repeat: int) -> list[dict]:
    from rockmass.dfn import TraceMap, mauldon_circle, trace_intensity, trace_topology

    side = 10.0
    offsets = (np.arange(n_lines) + 0.5) * side / n_lines
    horizontal = np.column_stack([np.zeros(n_lines), offsets, np.full(n_lines, side), offsets])
    vertical = np.column_stack([offsets, np.zeros(n_lines), offsets, np.full(n_lines, side)])
    window = np.array([[0.0, 0.0], [side, 0.0], [side, side], [0.0, side]])
    tm = TraceMap.from_segments(np.vstack([horizontal, vertical]), window=window)
    tol = 1e-6 * side
    size = 2 * n_lines
    rows = []
    first, warm, ti = timed(lambda: trace_intensity(tm, edge_tolerance_m=tol), repeat)
    rows.append(row(size, "grid P21", first, warm, ti.p21_per_m, 2 * n_lines / side, None, "m/m²"))
    rows.append(row(size, "grid P20", first, warm, ti.p20_per_m2, 0.0, None, "1/m²"))
    first, warm, topo = timed(lambda: trace_topology(tm, snap_tolerance_m=tol), max(1, repeat // 4))
    rows.append(row(size, "grid X nodes", first, warm, float(topo.n_x), float(n_lines**2), None, "-"))
    rows.append(row(size, "grid E nodes", first, warm, float(topo.n_e), float(4 * n_lines), None, "-"))
    rows.append(row(size, "grid I+Y nodes", first, warm, float(topo.n_i + topo.n_y), 0.0, None, "-"))
    r = 0.3725 * side  # centre ± r falls between grid lines for n = 50 and 500: no tangency
    centre = 0.5 * side
    first, warm, ma = timed(lambda: mauldon_circle(tm, (centre, centre), r, tolerance_m=tol), repeat)
    n_hit = 2 * 2 * int(np.count_nonzero(np.abs(offsets - centre) < r))
    rows.append(row(size, "grid Mauldon n", first, warm, float(ma.n_intersections), float(n_hit), None, "-"))
    # against the grid's true P21: the estimator's error from the few, regularly placed lines
    rows.append(row(size, "grid Mauldon P21", first, warm, ma.p21_per_m, 2 * n_lines / side, None, "m/m²"))
    return rows


COLUMNS = [("traces", "d"), ("statistic", "s"), ("unit", "s"), ("first_s", ".4f"), ("warm_s", ".4f"),
           ("value", ".5g"), ("expected", ".5g"), ("rel_error_pct", "+.2f"), ("z", "+.2f")]


def main(quick: bool = False) -> None:
    print(header("trace statistics: run time and error on maps with known answers"))
    sizes = (100, 1_000) if quick else (100, 1_000, 10_000)
    poisson = []
    for size in sizes:
        poisson += poisson_rows(size, seed=size + 1, repeat=8 if size < 10_000 else 2)
    print("\n1. two-set Poisson segment networks (L = 1 m; sets 30 deg / kappa 20 and 120 deg / "
          "kappa 40, 60 / 40 %);\n   expected values of the stationary network, z = error / sampling sd")
    print(table(poisson, COLUMNS))
    grid = []
    for n_lines in (50, 500):
        grid += grid_rows(n_lines, repeat=4)
    print("\n2. regular grids of n + n window-spanning lines in a 10 m square (exact answers)")
    print(table(grid, COLUMNS))
    path = save("bench_trace_stats", {"poisson": poisson, "grid": grid})
    print(f"\nrows written to {path}")


if __name__ == "__main__":
    main(quick="--quick" in sys.argv)
