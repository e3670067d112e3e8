"""DEM solver: contact updates per second and their growth with model size, time step against
accuracy, and the work skipped by sleeping blocks and the static-only path — run time beside error.

    python benchmarks/bench_solver.py [--quick] [--scaling-only]

``--scaling-only``: Table 1 alone (results in bench_solver_scaling.json); ``--shapes-only``: Table 1b
alone (bench_solver_shapes.json).

Table 1 — scaling. Square domains cut by two joint sets into 10³, 10⁴ and 5·10⁴ blocks, in-situ
stress with a gravity gradient written into the contacts and applied on the sides (the model starts
in equilibrium, so the "error" columns are the unbalanced ratio — after the first step alone
(``step1_unbalanced``: the in-situ balance itself) and after all steps — and the largest displacement,
all ideally at round-off). Cost per contact slot update and its ratio to the smallest model (target:
≥ 10⁶ slot updates/s per core at 10⁴ blocks; cost at 5·10⁴ within 1.3× of 10³).

Table 1b — block shape. The same measurement on the regular blocks of Table 1 and on irregular
blocks cut from traces, the models users solve: the seed-001 DFN plane section with its drift and
a random trace map (the trace models of benchmarks/bench_blockgen.py), about 10³ and 10⁴ blocks
each. Models and sizes are interleaved and the whole round repeated, so that load on a shared
machine falls on all of them alike; each row keeps its fastest round (target, issue 20: ≥ 3·10⁶
slot updates/s per core on the irregular blocks).

Table 2 — time step. A block sliding down a 30° incline (φ = 20°): error of the displacement after
0.2 s against ½ g (sin ψ − cos ψ tan φ) t², and the energy-ledger residual over the work in, for
time-step safety factors 0.1–0.9 of the Gershgorin limit.

Table 3 — sleeping blocks. A tunnel excavated in a large jointed domain, static relaxation with
and without sleeping (docs/design.md §6): wall time, steps, speed-up, and the largest difference in
block displacement it adds.

Table 4 — static-only path. The same model stepped as a static stage and as a dynamic stage with
quiet boundaries and Rayleigh damping: time per step of each (what a static run does not pay).
"""

from __future__ import annotations

import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import header, save, table  # noqa: E402

from rockmass.blockgen import JointSet, build, circle  # noqa: E402
from rockmass.blockgen.model import KIND_JOINT, BlockModel  # noqa: E402
from rockmass.solver import (BoundaryStress, Coulomb, Fix, InSituStress, Material, Monitor,  # noqa: E402
                             QuietBoundary, Settings, Stage)
from rockmass.solver.runner import run  # noqa: E402

ROCK = Material(2700.0, 20e9, 12e9)


def jointed_square(n_blocks: int, side_m: float = 100.0, tunnel_radius_m: float | None = None):
    """Two sets (30°, 100°) spaced so that about ``n_blocks`` blocks cut the square."""
    spacing = side_m / math.sqrt(n_blocks / 1.05)
    h = side_m / 2
    dom = [(-h, -h), (h, -h), (h, h), (-h, h)]
    sets = [JointSet(angle_deg=30.0, spacing_m=spacing, origin_xy_m=(0.13, 0.07)),
            JointSet(angle_deg=100.0, spacing_m=spacing, origin_xy_m=(0.11, 0.05))]
    exc = [circle((0.0, 0.0), tunnel_radius_m, name="tunnel")] if tunnel_radius_m else []
    return build(dom, sets, excavations=exc)


def insitu_settings(stages, **kw):
    return Settings(joints={"default": Coulomb(20e9, 10e9, 40.0, cohesion_pa=kw.pop("cohesion", 0.0))},
                    material=ROCK, stages=stages,
                    insitu=InSituStress(sxx_pa=4e6, syy_pa=5e6, gravity_gradient=True, k0=0.6),
                    boundary_stress=(BoundaryStress(("left", "right", "top"), from_insitu=True),),
                    fixes=(Fix("bottom"),), **kw)


def scaling(sizes, steps):
    rows = []
    base = None
    for n in sizes:
        t0 = time.perf_counter()
        model = jointed_square(n)
        t_build = time.perf_counter() - t0
        st = insitu_settings((Stage("steps", max_steps=steps, tolerance=1e-30),))
        # one step first: compiles, and its unbalanced ratio is the in-situ balance itself
        first = run(model, replace(st, stages=(Stage("warm", max_steps=1, tolerance=1e-30),)))
        res = run(model, st)
        stage = res.stages[0]
        slots = len(res.contacts["x_m"])
        per_step = stage.wall_time_s / stage.steps
        cost_ns = per_step / slots * 1e9
        base = base or cost_ns
        rows.append({"blocks": model.n_blocks, "pairs": res.info["pairs"], "slots": slots,
                     "build_s": t_build, "ms_per_step": per_step * 1e3,
                     "slot_updates_per_s": slots / per_step, "ns_per_slot": cost_ns,
                     "cost_ratio": cost_ns / base,
                     "step1_unbalanced": first.stages[0].unbalanced_ratio,
                     "unbalanced_ratio": stage.unbalanced_ratio,
                     "max_disp_m": stage.max_displacement_m})
    return rows


def _model_builders():
    """Name -> build(n_blocks) for Table 1b: the regular sets and the two trace models."""
    from bench_blockgen import dfn_case, trace_case

    return {"regular sets": jointed_square,
            "dfn section": lambda n: dfn_case(n)[1](),
            "random map": lambda n: trace_case(n)[1]()}


def _slot_rate(model, steps: int) -> dict:
    """One timed run of ``steps`` static steps in in-situ equilibrium (after one compiling step)."""
    st = insitu_settings((Stage("steps", max_steps=steps, tolerance=1e-30),))
    run(model, replace(st, stages=(Stage("warm", max_steps=1, tolerance=1e-30),)))
    res = run(model, st)
    stage = res.stages[0]
    slots = len(res.contacts["x_m"])
    per_step = stage.wall_time_s / max(stage.steps, 1)
    return {"blocks": model.n_blocks, "slots": slots, "steps": stage.steps, "status": stage.status,
            "vertices_per_block": len(model.xy_m) / model.n_blocks,
            "slot_updates_per_s": slots / per_step if stage.steps else 0.0,
            "ns_per_slot": per_step / max(slots, 1) * 1e9,
            "unbalanced_ratio": stage.unbalanced_ratio}


def block_shapes(sizes, steps, rounds: int = 2):
    """Table 1b: slot update rate by block shape, models and sizes interleaved, best of ``rounds``."""
    builders = _model_builders()
    models = {(name, n): build(n) for n in sizes for name, build in builders.items()}
    best: dict = {}
    for _ in range(rounds):
        for key, model in models.items():
            row = _slot_rate(model, steps)
            if key not in best or row["slot_updates_per_s"] > best[key]["slot_updates_per_s"]:
                best[key] = row
    regular = {n: best[("regular sets", n)]["ns_per_slot"] for n in sizes}
    return [{"model": name, "target_blocks": n, **row,
             "cost_vs_regular": row["ns_per_slot"] / regular[n]}
            for (name, n), row in best.items()]


def _print_block_shapes(quick: bool, steps: int) -> list:
    """Table 1b, run and printed."""
    t1b = block_shapes((1000, 3000) if quick else (1000, 10000), steps)
    print("\nTable 1b — slot updates per second by block shape (regular sets against blocks cut "
          f"from traces; {steps} static steps in in-situ equilibrium, interleaved, best of 2 rounds)")
    print(table(t1b, [("model", ""), ("target_blocks", "d"), ("blocks", "d"),
                      ("vertices_per_block", ".2f"), ("slots", "d"), ("status", ""),
                      ("slot_updates_per_s", ".3g"), ("ns_per_slot", ".0f"),
                      ("cost_vs_regular", ".2f"), ("unbalanced_ratio", ".1e")]))
    return t1b


def incline(psi_deg=30.0, b=1.0, h=0.5):
    c, s = math.cos(math.radians(psi_deg)), math.sin(math.radians(psi_deg))
    rot = np.array([[c, -s], [s, c]])
    base = np.array([[-5, -1], [5, -1], [5, 0], [-5, 0.0]]) @ rot.T
    top = np.array([[-b / 2, 0], [b / 2, 0], [b / 2, h], [-b / 2, h]]) @ rot.T
    return BlockModel(np.vstack([base, top]), [0, 4, 8], [0, 0], ("rock",), [[0, 1]], [b],
                      [KIND_JOINT], [0], ("j",), np.array([[-6, -3], [6, -3], [6, 3], [-6, 3.0]]))


def time_step_accuracy(safeties):
    psi, phi, t_end = 30.0, 20.0, 0.2
    accel = 9.81 * (math.sin(math.radians(psi)) - math.cos(math.radians(psi)) * math.tan(math.radians(phi)))
    model = incline(psi)
    rows = []
    for f in safeties:
        st = Settings(joints={"default": Coulomb(1e9, 1e9, phi)}, material=Material(2000.0),
                      stages=(Stage("slide", "dynamic", duration_s=t_end, history_every=1),),
                      fixes=(Fix("blocks:0"),), monitors=(Monitor("top", block=1),),
                      time_step_safety=f)
        run(model, st)  # compile / warm
        t0 = time.perf_counter()
        res = run(model, st)
        wall = time.perf_counter() - t0
        h = res.history
        t = h["time_s"][-1]
        d = math.hypot(h["top_ux_m"][-1], h["top_uy_m"][-1])
        # the block starts unloaded and settles onto the joint: compare with the exact slide from t=0
        exact = 0.5 * accel * t ** 2
        e = res.stages[0].energy
        work = e["work_gravity_j"] + e["work_boundary_j"]
        rows.append({"safety": f, "dt_s": res.stages[0].time_step_s, "steps": res.stages[0].steps,
                     "wall_s": wall, "disp_error_pct": 100 * (d - exact) / exact,
                     "ledger_residual": e["residual_j"] / work})
    return rows


def sleeping(n_blocks, max_steps):
    model = jointed_square(n_blocks, side_m=120.0, tunnel_radius_m=5.0)
    stages = (Stage("initial", max_steps=max_steps), Stage("excavate", excavate=(1,), max_steps=max_steps))
    rows = []
    ref = None
    for sleep in (False, True):
        st = insitu_settings(stages, sleep=sleep, cohesion=0.5e6)
        res = run(model, st)
        exc = res.stages[1]
        disp = res.displacement_m
        row = {"sleep": sleep, "blocks": model.n_blocks, "steps": exc.steps, "wall_s": exc.wall_time_s,
               "status": exc.status, "converged": exc.converged,
               "failed_blocks": len(exc.failed_blocks), "max_disp_m": exc.max_displacement_boundary_m}
        if ref is None:
            ref = (disp, exc.wall_time_s)
            row.update(speedup=1.0, disp_diff_m=0.0)
        else:
            row.update(speedup=ref[1] / exc.wall_time_s, disp_diff_m=float(np.abs(disp - ref[0]).max()))
        rows.append(row)
    return rows


def static_only(n_blocks, steps):
    model = jointed_square(n_blocks)
    rows = []
    for kind in ("static", "dynamic"):
        if kind == "static":
            stage = Stage("s", max_steps=steps, tolerance=1e-30)
        else:
            stage = Stage("d", "dynamic", duration_s=1.0, rayleigh_ratio=0.02,
                          rayleigh_frequency_hz=5.0, rayleigh_mode="mass")
        st = insitu_settings((stage,), quiet=QuietBoundary(("left", "right")) if kind == "dynamic" else None)
        if kind == "dynamic":  # a fixed number of steps: the duration follows from the step
            probe = run(model, replace(st, stages=(replace(stage, duration_s=1e-9),)))
            dt = probe.stages[0].time_step_s
            st = replace(st, stages=(replace(stage, duration_s=steps * dt),))
        res = run(model, st)
        s = res.stages[0]
        rows.append({"stage": kind, "blocks": model.n_blocks, "steps": s.steps, "status": s.status,
                     "ms_per_step": 1e3 * s.wall_time_s / s.steps,
                     "max_disp_m": s.max_displacement_m})
    return rows


def main(argv):
    quick = "--quick" in argv
    print(header("DEM solver benchmark"))
    sizes = (1000, 5000) if quick else (1000, 10000, 50000)
    steps = 100 if quick else 200
    if "--shapes-only" in argv:
        t1b = _print_block_shapes(quick, steps)
        save("bench_solver_shapes", {"block_shapes": t1b})
        return
    t1 = scaling(sizes, steps)
    print("\nTable 1 — contact updates per second and growth with size "
          f"({steps} static steps, in-situ equilibrium)")
    print(table(t1, [("blocks", "d"), ("pairs", "d"), ("slots", "d"), ("build_s", ".2f"),
                     ("ms_per_step", ".3f"), ("slot_updates_per_s", ".3g"), ("ns_per_slot", ".0f"),
                     ("cost_ratio", ".2f"), ("step1_unbalanced", ".1e"), ("unbalanced_ratio", ".1e"),
                     ("max_disp_m", ".1e")]))
    if "--scaling-only" in argv:
        save("bench_solver_scaling", {"scaling": t1})
        return
    t1b = _print_block_shapes(quick, steps)
    t2 = time_step_accuracy((0.1, 0.25, 0.5, 0.9))
    print("\nTable 2 — time step against accuracy (incline 30°, φ = 20°, 0.2 s)")
    print(table(t2, [("safety", ".2f"), ("dt_s", ".3g"), ("steps", "d"), ("wall_s", ".3f"),
                     ("disp_error_pct", "+.3f"), ("ledger_residual", "+.1e")]))
    t3 = sleeping(1500 if quick else 6000, 20000 if quick else 60000)
    print("\nTable 3 — sleeping blocks (excavation of a 5 m tunnel in a 120 m square)")
    print(table(t3, [("sleep", ""), ("blocks", "d"), ("steps", "d"), ("wall_s", ".2f"),
                     ("status", ""), ("converged", ""), ("failed_blocks", "d"), ("speedup", ".2f"),
                     ("max_disp_m", ".4g"),
                     ("disp_diff_m", ".2e")]))
    t4 = static_only(2000 if quick else 10000, steps)
    print("\nTable 4 — static-only path (same model, same number of steps)")
    print(table(t4, [("stage", ""), ("blocks", "d"), ("steps", "d"), ("status", ""), ("ms_per_step", ".3f"),
                     ("max_disp_m", ".2e")]))
    save("bench_solver", {"scaling": t1, "block_shapes": t1b, "time_step": t2, "sleeping": t3,
                          "static_only": t4})


if __name__ == "__main__":
    main(sys.argv[1:])
