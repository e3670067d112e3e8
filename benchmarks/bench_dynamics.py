"""Dynamic accuracy against run time: the energy an elastic impact gains or loses, per time-step
safety factor (docs/dem.md §2.4; issue 16 item 2).

    python benchmarks/bench_dynamics.py [--quick]

A rigid 1 m × 0.5 m block (ρ = 2000 kg/m³) dropped flat from a gap g onto a fixed base on a joint of
k_n = k_s = 1 GPa/m, undamped. Exact mechanics: it rebounds to the height it fell from, so in free
flight after the impact its energy per unit mass g u_y + v²/2 (u_y from the release point) is zero.
The error of one impact is that energy over g·gap. Gaps from 0.8 to 1.2 mm put the closing of the
contact at different places inside a step, which is what the error depends on; the table gives the
largest and the mean error over them, beside ωΔt (ω = √(k_n b/m), the contact's own frequency), the
steps per millisecond of simulated time and the wall time of the drops. The row ``default`` is a
dynamic stage's automatic step (time_step_safety unset).
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import header, save, table  # noqa: E402

from rockmass.blockgen.model import KIND_DOMAIN, BlockModel  # noqa: E402
from rockmass.solver import Coulomb, Fix, Material, Monitor, Settings, Stage, run  # noqa: E402

G = 9.81
RHO, KN, WIDTH, HEIGHT = 2000.0, 1e9, 1.0, 0.5


def drop_model(gap_m: float) -> BlockModel:
    """Block 0: the base [−5, 5] × [−1, 0]; block 1: the block, its base ``gap_m`` above."""
    base = [[-5.0, -1.0], [5.0, -1.0], [5.0, 0.0], [-5.0, 0.0]]
    x, y = WIDTH / 2, gap_m
    block = [[-x, y], [x, y], [x, y + HEIGHT], [-x, y + HEIGHT]]
    outline = np.array([[-5.0, -1.0], [5.0, -1.0], [5.0, 1.0], [-5.0, 1.0]])
    return BlockModel(np.array(base + block, float), np.array([0, 4, 8]), np.zeros(2, int),
                      ("rock",), np.array([[0, -1]]), np.array([10.0]), np.array([KIND_DOMAIN]),
                      np.array([-1]), ("j",), outline)


def impact_error(gap_m: float, safety) -> tuple[float, float, int]:
    """(energy error of the first impact, ωΔt, steps) of one drop."""
    fall = math.sqrt(2 * gap_m / G)
    settings = Settings(joints={"default": Coulomb(KN, KN, 40.0)}, material=Material(RHO),
                        stages=(Stage("drop", "dynamic", duration_s=2.2 * fall, history_every=1),),
                        fixes=(Fix("blocks:0"),), monitors=(Monitor("top", block=1),),
                        time_step_safety=safety)
    result = run(drop_model(gap_m), settings)
    h = result.history
    flight = (h["time_s"] > fall) & (h["top_contact_fy_n"] == 0.0) & (h["top_vy_m_s"] > 0)
    if flight.sum() <= 10:
        raise RuntimeError(f"gap {gap_m} m, safety {safety}: the block did not rebound")
    dt = result.stages[0].time_step_s
    # velocities live at half steps: the position at the same instant is half a step back
    vy = h["top_vy_m_s"][flight]
    energy = G * (h["top_uy_m"][flight] - 0.5 * dt * vy) + 0.5 * vy ** 2
    omega = math.sqrt(KN * WIDTH / (RHO * WIDTH * HEIGHT))
    return float(np.median(energy) / (G * gap_m)), omega * dt, len(h["time_s"])


def main(quick: bool = False) -> None:
    print(header("bench_dynamics: energy error of an elastic impact against the time step"))
    gaps = np.linspace(0.8e-3, 1.2e-3, 5 if quick else 9)
    impact_error(1e-3, None)  # compile outside the timings
    rows = []
    for safety in (0.5, 0.4, 0.3, None, 0.1):
        t0 = time.perf_counter()
        runs = [impact_error(g, safety) for g in gaps]
        wall = time.perf_counter() - t0
        errors = np.array([r[0] for r in runs])
        duration_ms = 1e3 * sum(2.2 * math.sqrt(2 * g / G) for g in gaps)
        rows.append({"safety": "default" if safety is None else f"{safety:g}",
                     "omega_dt": runs[0][1], "max_abs_error_pct": 100 * np.abs(errors).max(),
                     "mean_error_pct": 100 * errors.mean(),
                     "steps_per_ms": sum(r[2] for r in runs) / duration_ms, "wall_s": wall})
    print(table(rows, [("safety", "s"), ("omega_dt", ".3f"), ("max_abs_error_pct", ".2f"),
                       ("mean_error_pct", "+.2f"), ("steps_per_ms", ".0f"), ("wall_s", ".2f")]))
    print(f"{len(gaps)} drops per row (gaps {gaps[0]*1e3:.1f}–{gaps[-1]*1e3:.1f} mm); target: "
          "default row max_abs_error_pct ≤ 1")
    save("bench_dynamics", {"rows": rows, "gaps_m": gaps.tolist()})


if __name__ == "__main__":
    main(quick="--quick" in sys.argv)
