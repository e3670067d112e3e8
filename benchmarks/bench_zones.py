"""Deformable blocks: zone updates per second against the error of the answer, and what zoning a
cavern costs against what it changes.

    python benchmarks/bench_zones.py [--quick] [--cavern]

Table 1 — zones alone (docs/dem.md §16.7, problems 19–21). A circular opening of radius a in a
plate under σ_xx = 10, σ_yy = 20 MPa (Kirsch; elastic) and under hydrostatic 30 MPa in
Mohr–Coulomb rock (Salençon) and in Hoek–Brown rock (σ_ci = 10 MPa, GSI 100, m_i = 10;
Carranza-Torres & Fairhurst): the quarter model of tests/solver/test_zones.py at 12–48 zones
around the quarter. Per row: zones, steps to equilibrium (unbalanced ratio 1e-7), wall time,
zone updates per second (zones × steps / time: stress update, nodal forces and node motion), and
the error — Kirsch: the wall's radial displacement and the hoop stress extrapolated to the wall,
in % of their peaks; Salençon, Hoek–Brown: the plastic radius from the yielded area.

Table 2 (``--cavern``) — the seed-000 cavern of samples/solve_cavern.toml, rigid, against
samples/solve_cavern_deformable.toml (the blocks within about two spans of the opening zoned at
2 m, Mohr–Coulomb): wall time, steps, the first static stage's time step (density-scaled
nodes, docs/dem.md §16.6), pieces and pairs, the crown and wall
displacements and the largest boundary displacement after the last bench, failed blocks and the
yielded area. A few minutes on two cores.

Rows also go to benchmarks/results/bench_zones.json.
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

_HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(_HERE))
if str(_HERE.parent) not in sys.path:  # the opening model of tests/solver
    sys.path.append(str(_HERE.parent))
from _common import header, save, table  # noqa: E402

from rockmass.solver.zones import Elastic, HoekBrown, MohrCoulomb  # noqa: E402
from tests.solver._zone_models import (hoek_brown_plastic_radius, kirsch_errors, opening,  # noqa: E402
                                      salencon_plastic_radius)

K_BULK, G_SHEAR = 10e9, 6e9
NU = (3 * K_BULK - 2 * G_SHEAR) / (2 * (3 * K_BULK + G_SHEAR))


def zones_table(quick: bool) -> list[dict]:
    rows = []
    sizes = (12, 24) if quick else (12, 24, 32, 48)
    opening(Elastic(K_BULK, G_SHEAR), 8, 1.2, 10e6, 20e6, NU)  # compile
    for nt in sizes:
        z, wall, _radii, nt_, info, secs = opening(Elastic(K_BULK, G_SHEAR), nt, 1.08, 10e6, 20e6,
                                                   NU)
        eu, eh, _ring = (100 * e for e in kirsch_errors(z, wall, nt_, 10e6, 20e6, G_SHEAR, NU))
        rows.append({"problem": "Kirsch", "sectors": nt, "zones": len(z.tri), "steps": info["steps"],
                     "wall_s": secs, "zone_updates_per_s": len(z.tri) * info["steps"] / secs,
                     "error_1_pct": eu, "error_2_pct": eh, "what": "u_r wall, hoop wall"})
    mc = MohrCoulomb(K_BULK, G_SHEAR, cohesion_pa=3e6, friction_deg=30.0, tension_pa=1e6)
    hb = HoekBrown(K_BULK, G_SHEAR, sigma_ci_pa=10e6, gsi=100.0, mi=10.0)
    for problem, model, exact in (
            ("Salençon", mc, salencon_plastic_radius(1.0, 30e6, 0.0, 3e6, 30.0)),
            ("Hoek-Brown", hb, hoek_brown_plastic_radius(1.0, 30e6, 0.0, 10e6, hb.mb, hb.s))):
        for nt in sizes:  # hydrostatic 30 MPa; the plastic radius from the yielded area
            z, *_rest, info, secs = opening(model, nt, 1.05, 30e6, 30e6, NU)
            rp = math.sqrt(1.0 + 4 * z.plastic_area() / math.pi)
            rows.append({"problem": problem, "sectors": nt, "zones": len(z.tri),
                         "steps": info["steps"], "wall_s": secs,
                         "zone_updates_per_s": len(z.tri) * info["steps"] / secs,
                         "error_1_pct": 100 * (rp / exact - 1), "error_2_pct": None,
                         "what": f"plastic radius (exact {exact:.3f} a)"})
    return rows


def _mm(metres: float | None) -> float | None:
    """A monitor's displacement in mm; None (printed "-") when its point has no block left (the
    crown's block failed and was taken out)."""
    return None if metres is None else 1e3 * metres


def cavern_row(config: str, label: str) -> dict:
    """One run of a cavern config with the measures of table 2."""
    from rockmass.solve_stage import prepare
    from rockmass.solver import run

    _doc, model, settings, _inputs, _t = prepare(config)
    t0 = time.perf_counter()
    r = run(model, settings)
    secs = time.perf_counter() - t0
    last = r.stages[-1]
    zs = r.zone_summary() if r.zones else {}
    return {"model": label, "wall_s": secs, "steps": sum(s.steps for s in r.stages),
            "dt_first_stage_s": r.stages[0].time_step_s,
            "pieces": r.info["blocks"], "pairs": r.info["pairs"],
            "zones": r.info.get("zones", 0), "status": r.status,
            "crown_mm": _mm(last.monitors.get("crown")),
            "left_wall_mm": _mm(last.monitors.get("left_wall")),
            "right_wall_mm": _mm(last.monitors.get("right_wall")),
            "boundary_mm": 1e3 * last.max_displacement_boundary_equilibrium_m,
            "failed_blocks": sum(len(s.failed_blocks) for s in r.stages),
            "plastic_area_m2": zs.get("plastic_area_m2", 0.0)}


def main(quick: bool = False, cavern: bool = False) -> None:
    print(header("deformable blocks: zones per second against error (docs/dem.md §16)"))
    rows = zones_table(quick)
    print(table(rows, [("problem", "s"), ("sectors", "d"), ("zones", "d"), ("steps", "d"),
                       ("wall_s", ".2f"), ("zone_updates_per_s", ".3g"), ("error_1_pct", "+.3f"),
                       ("error_2_pct", "+.3f"), ("what", "s")]))
    payload = {"zones": rows}
    if cavern:
        root = _HERE.parent / "samples"
        crows = [cavern_row(str(root / "solve_cavern.toml"), "rigid"),
                 cavern_row(str(root / "solve_cavern_deformable.toml"), "zoned near the opening")]
        print()
        print(table(crows, [("model", "s"), ("wall_s", ".0f"), ("steps", "d"),
                            ("dt_first_stage_s", ".3g"), ("pieces", "d"),
                            ("pairs", "d"), ("zones", "d"), ("status", "s"), ("crown_mm", ".2f"),
                            ("left_wall_mm", ".2f"), ("right_wall_mm", ".2f"),
                            ("boundary_mm", ".2f"), ("failed_blocks", "d"),
                            ("plastic_area_m2", ".1f")]))
        payload["cavern"] = crows
    save("bench_zones", payload)


if __name__ == "__main__":
    main(quick="--quick" in sys.argv, cavern="--cavern" in sys.argv)
