"""Deformable blocks in a run: zones as pieces of the contact search (docs/dem.md §16.8).

Closed forms with joints and zones together: a zoned column settling on its joints, two zoned
blocks with non-matching zonings sharing a joint, a zoned block sliding down an incline, a mixed
rigid/deformable model in in-situ equilibrium from the first step, and the energy ledger closing
with the plastic work of the zones.
"""

import math

import numpy as np
import pytest

from rockmass.solver import (BoundaryStress, Coulomb, Fix, InSituStress, Material, Monitor,
                             Settings, Stage, run)
from rockmass.solver.settings import Deformable
from rockmass.solver.zones import Elastic, MohrCoulomb

from ._models import hand_model, incline, jointed_rectangle, rect

RHO, G = 2500.0, 9.81
KB, GB = 2e9, 1.2e9
M = KB + 4 * GB / 3  # constrained modulus


def _column_settings(kn, deformable, stages=None, **kw):
    return Settings(joints={"default": Coulomb(kn, kn, 40.0)},
                    stages=stages or (Stage("gravity", tolerance=1e-7),),
                    fixes=(Fix("blocks:0"), Fix("left", dofs="x"), Fix("right", dofs="x")),
                    deformable=deformable, material=Material(density_kg_m3=RHO), **kw)


def _settlement(result, level):
    """Mean vertical settlement of the nodes that started at height ``level``."""
    z = result.zones
    start = z["nodes_m"] - z["node_displacement_m"]
    at = np.isclose(start[:, 1], level)
    assert at.sum() >= 3
    return -z["node_displacement_m"][at, 1].mean()


def test_zoned_column_on_a_joint_settles_by_joint_closure_and_its_own_weight():
    """A 4 m zoned block on a joint of k_n (rollers on its sides, on a fixed rigid base): the base
    closes by ρgH/k_n and the top settles ρgH/k_n + ρgH²/2M more."""
    height, kn = 4.0, 5e9
    model = hand_model([rect(0, -1, 2, 0), rect(0, 0, 2, height)], pairs=[(0, 1)])
    r = run(model, _column_settings(kn, (Deformable("blocks:1", Elastic(KB, GB), 0.5),)))
    assert r.status == "ok" and r.stages[0].converged
    assert r.info["deformable_blocks"] == 1 and r.info["zones"] > 20
    closure = RHO * G * height / kn
    assert _settlement(r, 0.0) == pytest.approx(closure, rel=0.01)
    assert _settlement(r, height) == pytest.approx(closure + RHO * G * height ** 2 / (2 * M),
                                                   rel=0.01)
    ledger = r.stages[0].energy
    assert abs(ledger.residual_j) < 1e-4 * ledger.work_gravity_j


def test_two_zoned_blocks_with_different_zonings_share_a_joint():
    """Two 2 m blocks zoned at 0.4 and 0.3 m (their nodes do not meet on the joint between them)
    stacked on a fixed base: the joints close by their own loads, 2ρgh/k_n at the base and
    ρgh/k_n between them, and the top settles by those plus ρg(2h)²/2M."""
    h, kn = 2.0, 4e9
    model = hand_model([rect(0, -1, 1.5, 0), rect(0, 0, 1.5, h), rect(0, h, 1.5, 2 * h)],
                       pairs=[(0, 1), (1, 2)])
    deformable = (Deformable("blocks:1", Elastic(KB, GB), 0.4),
                  Deformable("blocks:2", Elastic(KB, GB), 0.3))
    r = run(model, _column_settings(kn, deformable))
    assert r.stages[0].converged
    base = 2 * RHO * G * h / kn
    middle = RHO * G * h / kn
    z = r.zones
    start = z["nodes_m"] - z["node_displacement_m"]
    parent = z["parent_block"][z["zone_block"]]
    upper_nodes = np.unique(z["triangles"][parent == 2])
    lower_nodes = np.unique(z["triangles"][parent == 1])
    at_h = np.isclose(start[:, 1], h)
    lower_top = -z["node_displacement_m"][np.intersect1d(lower_nodes, np.flatnonzero(at_h)), 1]
    upper_bottom = -z["node_displacement_m"][np.intersect1d(upper_nodes, np.flatnonzero(at_h)), 1]
    # the lower block: its base closure and its shortening under its own weight and the upper's
    shortening = (RHO * G * h * h + RHO * G * h ** 2 / 2) / M
    assert lower_top.mean() == pytest.approx(base + shortening, rel=0.01)
    assert upper_bottom.mean() - lower_top.mean() == pytest.approx(middle, rel=0.02)
    assert _settlement(r, 2 * h) == pytest.approx(base + middle + RHO * G * (2 * h) ** 2 / (2 * M),
                                                  rel=0.01)


@pytest.mark.parametrize("psi, phi", [(30.0, 20.0)])
def test_zoned_block_slides_down_an_incline_at_the_rigid_acceleration(psi, phi):
    """A zoned block slides like a rigid one, a = g(sin ψ − cos ψ tan φ) within 2 %."""
    duration = 0.2
    settings = Settings(joints={"default": Coulomb(1e9, 1e9, phi)},
                        stages=(Stage("slide", "dynamic", duration_s=duration, history_every=1),),
                        material=Material(RHO), fixes=(Fix("blocks:0"),),
                        monitors=(Monitor("top", block=1),),
                        deformable=(Deformable("blocks:1", Elastic(KB, GB), 0.2),))
    r = run(incline(psi), settings)
    h = r.history
    down = -(h["top_vx_m_s"] * math.cos(math.radians(psi)) + h["top_vy_m_s"]
             * math.sin(math.radians(psi)))
    late = h["time_s"] > duration / 2
    a = np.polyfit(h["time_s"][late], down[late], 1)[0]
    expected = G * (math.sin(math.radians(psi)) - math.cos(math.radians(psi))
                    * math.tan(math.radians(phi)))
    assert a == pytest.approx(expected, rel=0.02)


def test_mixed_rigid_and_zoned_blocks_start_in_in_situ_equilibrium():
    """A jointed rectangle, half of its blocks zoned, under a uniform in-situ stress held by its
    boundary: zones and contacts start at the same stress, so nothing moves."""
    model = jointed_rectangle(4.0, 3.0, 1.0)
    half = "box:0,0,2,3"
    settings = Settings(joints={"default": Coulomb(1e10, 5e9, 35.0)},
                        stages=(Stage("hold", tolerance=1e-6, max_steps=2000),),
                        gravity_m_s2=(0.0, 0.0), insitu=InSituStress(sxx_pa=4e6, syy_pa=6e6),
                        boundary_stress=(BoundaryStress(("left", "right", "top", "bottom"),
                                                        from_insitu=True),),
                        fixes=(Fix("bottom", dofs="y"), Fix("left", dofs="x")),
                        deformable=(Deformable(half, Elastic(5e9, 3e9), 0.3),))
    r = run(model, settings)
    assert r.info["zones"] > 50
    assert r.stages[0].converged and r.stages[0].steps <= 500
    assert np.max(np.abs(r.zones["node_displacement_m"])) < 1e-9
    assert np.max(np.hypot(*r.displacement_m.T)) < 1e-9
    s = r.zones["stress_pa"]
    assert np.allclose(s[:, 0], 4e6, rtol=1e-6) and np.allclose(s[:, 1], 6e6, rtol=1e-6)


def test_energy_ledger_closes_with_the_zones_plastic_work():
    """A Mohr–Coulomb block pressed by a rigid platen moving down at a constant rate: the zones
    yield, and the stage's ledger (work in = Δ kinetic + Δ strain (joints and zones) + slip +
    damping + the zones' plastic work) closes to 1 % of the work done."""
    model = hand_model([rect(0, -1, 1, 0), rect(0, 0, 1, 2), rect(0, 2, 1, 3)],
                       pairs=[(0, 1), (1, 2)])
    from rockmass.solver import VelocityInput
    from rockmass.solver.settings import TableHistory

    rate = -0.02
    history = TableHistory(np.array([0.0, 1.0]), np.array([rate, rate]))
    settings = Settings(joints={"default": Coulomb(5e10, 5e10, 40.0)},
                        stages=(Stage("press", "dynamic", duration_s=0.15,
                                      rayleigh_ratio=0.05, rayleigh_frequency_hz=500.0),),
                        gravity_m_s2=(0.0, 0.0), material=Material(RHO),
                        fixes=(Fix("blocks:0"), Fix("blocks:2", dofs="x"),
                               Fix("blocks:2", dofs="r")),
                        velocity_inputs=(VelocityInput("blocks:2", "y", history),),
                        deformable=(Deformable("blocks:1", MohrCoulomb(
                            KB, GB, cohesion_pa=0.5e6, friction_deg=30.0, tension_pa=0.2e6),
                            0.2),))
    r = run(model, settings)
    ledger = r.stages[0].energy
    assert ledger.zone_plastic_dissipation_j > 0.1 * ledger.work_boundary_j
    assert abs(ledger.residual_j) < 0.01 * ledger.work_boundary_j
    assert (r.zones["plastic_state"] & 4).any()  # yielded in shear


def test_a_zoned_keyblock_fails_whole_and_is_reported_once():
    """A zoned block hanging under a fixed roof on a joint without tension falls: all its zones are
    taken out together and the stage reports one failed block of its whole area, a fall."""
    model = hand_model([rect(0, 0, 2, 1), rect(0.5, -1, 1.5, 0)], pairs=[(0, 1)])
    settings = Settings(joints={"default": Coulomb(1e9, 1e9, 30.0)},
                        stages=(Stage("hang", max_steps=30_000),),
                        material=Material(RHO), fixes=(Fix("blocks:0"),),
                        deformable=(Deformable("blocks:1", Elastic(KB, GB), 0.25),))
    r = run(model, settings)
    stage = r.stages[0]
    assert len(stage.failed_blocks) == 1
    failed = stage.failed_blocks[0]
    assert failed["mechanism"] == "fall" and failed["area_m2"] == pytest.approx(1.0)
    zoned = r.zones["parent_block"][r.zones["zone_block"]] == 1
    assert not r.zones["live"][zoned].any()  # every zone of the block is out


def test_monitors_on_a_zoned_keyblock_that_fell_report_the_failure_whether_by_block_or_by_point():
    """The failure names one zone of the fallen block and a monitor by point follows the zone under
    its point: ``rockmass solve``'s summary compares them by their block, so neither monitor reports
    the fall as a displacement (found by review: the point monitor printed u = 6 cm)."""
    from rockmass.solve_stage import _monitor_summary

    model = hand_model([rect(0, 0, 2, 1), rect(0.5, -1, 1.5, 0)], pairs=[(0, 1)])
    settings = Settings(joints={"default": Coulomb(1e9, 1e9, 30.0)},
                        stages=(Stage("hang", max_steps=30_000),),
                        material=Material(RHO), fixes=(Fix("blocks:0"),),
                        monitors=(Monitor("by_block", block=1), Monitor("by_point", point_xy_m=(0.7, -0.8))),
                        deformable=(Deformable("blocks:1", Elastic(KB, GB), 0.25),))
    result = run(model, settings)
    summary = _monitor_summary(result, result.pieces, settings)  # as rockmass solve passes them
    assert summary["by_block"]["block"] != summary["by_point"]["block"]  # two zones of one block
    for name in ("by_block", "by_point"):
        assert summary[name]["failed"]["stage"] == "hang", name
        assert "final_displacement_m" not in summary[name], name


def test_a_zoned_block_shaken_through_its_own_nodes_keeps_the_ledger():
    """A zoned block on a fixed base row, its sides and base moved by a velocity input (the nodes
    on the domain outline are prescribed): the work the boundary does through them is booked, so
    the dynamic stage's ledger closes."""
    from rockmass.solver import Sine, VelocityInput

    model = hand_model([rect(0, 0, 1, 0.5)], pairs=[])
    shake = Sine(amplitude=0.05, frequency_hz=20.0, cycles=2)
    settings = Settings(joints={"default": Coulomb(1e9, 1e9, 30.0)},
                        stages=(Stage("shake", "dynamic", duration_s=0.1),),
                        material=Material(RHO),
                        velocity_inputs=(VelocityInput("bottom", "x", shake),),
                        fixes=(Fix("bottom", dofs="y"),),
                        deformable=(Deformable("blocks:0", Elastic(KB, GB), 0.1),))
    r = run(model, settings)
    ledger = r.stages[0].energy
    assert r.status == "ok"
    assert ledger.work_boundary_j > 0
    # measured 0.5 % (the zones' strain energy is the plain ½σ:C:σ, not the leapfrog's shadow form
    # that makes the contacts' exact); without booking the prescribed nodes' work it is ~100 %
    assert abs(ledger.residual_j) < 1e-2 * ledger.work_boundary_j


def test_chosen_blocks_smaller_than_the_minimum_area_stay_rigid():
    """``min_block_area_m2``: of two chosen blocks, the sliver (0.02 m²) stays rigid."""
    model = hand_model([rect(0, -1, 2, 0), rect(0, 0, 2, 1), rect(0, 1, 2, 1.01)],
                       pairs=[(0, 1), (1, 2)])
    settings = _column_settings(5e9, (Deformable("blocks:1,2", Elastic(KB, GB), 0.25,
                                                 min_block_area_m2=0.05),),
                                stages=(Stage("gravity", max_steps=50),))
    r = run(model, settings)
    assert r.info["deformable_blocks"] == 1
    parents = r.zones["parent_block"][r.zones["zone_block"]]
    assert set(np.unique(parents)) == {1}
