"""DEM stress tests (issue 6, "Stability"): stiff and soft joints with the automatic time step, a
block 10³ times smaller than its neighbours, a user time step at 0.9 of the stable limit, sliver
blocks from near-parallel joint sets, and an overlap beyond the limit that must stop the stage with
a diagnostic. Every Result is checked for NaN / inf in all its arrays and in its JSON dict.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from rockmass.solver import Coulomb, Fix, Material, Monitor, Settings, Stage, run
from rockmass.solver.engine import Engine

from ._models import hand_model, incline, jointed_rectangle, rect
from ._models_advanced import finite_arrays


def _assert_finite(result):
    assert finite_arrays(result) == []
    json.dumps(result.to_json_dict(), allow_nan=False)  # raises on NaN / inf


def _settle(kn: float, friction: float = 60.0):
    """21 blocks of two joint sets settling under gravity (bottom fixed, sides on x rollers)."""
    settings = Settings(joints={"default": Coulomb(kn, kn, friction)}, material=Material(2500),
                        fixes=(Fix("bottom"), Fix("left", "x"), Fix("right", "x")),
                        stages=(Stage("settle", "static", max_steps=50_000),))
    return run(jointed_rectangle(4.0, 3.0, 1.0), settings)


def test_joint_stiffness_range_with_automatic_time_step():
    """k_n = k_s = 1e8 and 1e12 Pa/m, automatic step: both converge (a few hundred steps), all
    finite, no slip (φ = 60°), so the settlement is elastic and scales as 1/k: the ratio of the
    largest displacements is 10⁴ within 1 % (measured 0.02 %); the step scales as 1/√k (100×)."""
    soft, stiff = _settle(1e8), _settle(1e12)
    for result in (soft, stiff):
        _assert_finite(result)
        st = result.stages[0]
        assert st.status == "converged" and st.slipping_contacts == 0
    s0, s1 = soft.stages[0], stiff.stages[0]
    assert s0.max_displacement_m / s1.max_displacement_m == pytest.approx(1e4, rel=0.01)
    assert s0.time_step_s / s1.time_step_s == pytest.approx(100.0, rel=1e-6)


def test_block_size_ratio_1000():
    """A 1 mm block on a 1 m block on a fixed base (length ratio 10³, mass ratio 10⁶): the static
    stage converges, then 10 ms of dynamics stay at rest; the small block carries its own weight
    (contact force = m g within 1e-3) with the closure m g/(k_n b) relative to the big block."""
    tiny = 1e-3
    model = hand_model([rect(-2, -1, 2, 0), rect(-0.5, 0, 0.5, 1), rect(0, 1, tiny, 1 + tiny)],
                       [(0, 1), (1, 2)])
    kn, rho, g = 1e10, 2500.0, 9.81
    settings = Settings(joints={"default": Coulomb(kn, kn, 30.0)}, material=Material(rho),
                        fixes=(Fix("blocks:0"),), monitors=(Monitor("tiny", block=2),),
                        stages=(Stage("settle", "static", max_steps=200_000),
                                Stage("hold", "dynamic", duration_s=0.01)))
    result = run(model, settings)
    _assert_finite(result)
    assert [s.status for s in result.stages] == ["converged", "completed"]
    weight = rho * g * tiny * tiny
    assert result.history["tiny_contact_fy_n"][-1] == pytest.approx(weight, rel=1e-3)
    closure = result.displacement_m[1, 1] - result.displacement_m[2, 1]
    assert closure == pytest.approx(weight / (kn * tiny), rel=0.02)
    assert np.abs(result.velocity_m_s).max() < 1e-6


def test_user_time_step_at_0_9_of_the_limit():
    """Δt = 0.9 × the solver's stable limit (Engine.stable_time_step on the same contacts) for
    20 000 undamped dynamic steps of a block on a 10° incline (no slip): the run completes, the
    kinetic energy stays bounded (below the work of gravity, no growth between the first and last
    quarter); 1.01 × the limit is refused with the limit in the message."""
    model = incline(10.0)
    joints = {"default": Coulomb(1e9, 1e9, 60.0)}
    base = dict(joints=joints, material=Material(2000), fixes=(Fix("blocks:0"),))
    eng = Engine(model, Settings(stages=(Stage("probe", "dynamic", duration_s=1.0),), **base))
    eng.detect()
    limit = eng.stable_time_step()
    dt = 0.9 * limit
    stage = Stage("run", "dynamic", duration_s=20_000 * dt * (1 - 1e-9), time_step_s=dt,
                  history_every=50, frames=0)
    result = run(model, Settings(stages=(stage,), **base))
    _assert_finite(result)
    st = result.stages[0]
    assert st.status == "completed" and st.steps == 20_000
    assert st.stable_time_step_s == pytest.approx(limit, rel=1e-9)
    ke = result.history["kinetic_energy_j"]
    assert ke.max() < 2 * abs(st.energy["work_gravity_j"]) + 1e-12
    quarter = len(ke) // 4
    assert ke[-quarter:].max() < 1.5 * ke[:quarter].max()
    bad = Stage("run", "dynamic", duration_s=0.01, time_step_s=1.01 * limit)
    with pytest.raises(ValueError, match="stable limit"):
        run(model, Settings(stages=(bad,), **base))


@pytest.mark.parametrize("merge", [True, False])
def test_sliver_blocks_from_near_parallel_sets(merge):
    """Sets at 30° and 32° (plus a cross set at 110°) cut slivers; with blockgen's sliver merging
    off the area ratio exceeds 10³. Gravity settling converges, 50 ms of dynamics follow, all
    finite, no overlap, displacements of elastic size (< 1 mm)."""
    from rockmass.blockgen import JointSet, build

    model = build(rect(0, 0, 4, 3),
                  [JointSet(30.0, 0.7, origin_xy_m=(0.1, 0.2), name="a"),
                   JointSet(32.0, 0.9, origin_xy_m=(0.3, 0.1), name="b"),
                   JointSet(110.0, 1.0, origin_xy_m=(0.2, 0.2), name="c")], merge_slivers=merge)
    if not merge:
        assert model.area_m2.max() / model.area_m2.min() > 1e3
    settings = Settings(joints={"default": Coulomb(1e10, 1e10, 35.0)}, material=Material(2500),
                        fixes=(Fix("bottom"), Fix("left", "x"), Fix("right", "x")),
                        stages=(Stage("settle", "static", max_steps=20_000),
                                Stage("dyn", "dynamic", duration_s=0.05)))
    result = run(model, settings)
    _assert_finite(result)
    assert result.status == "ok"
    assert [s.status for s in result.stages] == ["converged", "completed"]
    assert result.stages[-1].max_displacement_m < 1e-3


def test_overlap_beyond_the_limit_stops_with_a_diagnostic():
    """Joints of k_n = 1e5 Pa/m under a 1 m × 0.5 m block: the static closure mg/(k_n b) = 0.1 m is
    far beyond the overlap limit (half the rounding length). The first stage stops with status
    "overlap", the run with it (the second stage never starts), the diagnostic names the two blocks
    and a likely cause (the joint stiffness), and every number of the Result is finite."""
    settings = Settings(joints={"default": Coulomb(1e5, 1e5, 30.0)}, material=Material(2000),
                        fixes=(Fix("blocks:0"),), monitors=(Monitor("top", block=1),),
                        stages=(Stage("settle", "static", max_steps=100_000),
                                Stage("later", "dynamic", duration_s=0.1)))
    result = run(incline(0.0), settings)
    _assert_finite(result)
    assert result.status == "overlap" and not result.ok
    assert len(result.stages) == 1
    st = result.stages[0]
    assert st.status == "overlap" and st.converged is False
    assert st.diagnostic is not None and result.diagnostic == st.diagnostic
    assert "blocks 0 and 1" in st.diagnostic
    assert "stiffness" in st.diagnostic
    limit = result.info["overlap_limit_m"]
    assert 0 < -result.displacement_m[1, 1] < 4 * limit  # stopped soon after the limit
    assert json.loads(json.dumps(result.to_json_dict()))["status"] == "overlap"
