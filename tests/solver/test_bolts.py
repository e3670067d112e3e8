"""Rock bolts (docs/dem.md §15) against closed forms: pull-out (shear lag, bond slip), a bolted
block on an incline (statics of the bolted block, series stiffness of the two grouted halves),
the energy ledger with bolts, bolt patterns around an opening, and the settings."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from rockmass.solver import (Bolt, BoltPattern, BoltProperties, BoundaryStress, Coulomb, Fix,
                            Settings, Stage, run)

from ._models import hand_model, incline, rect

# pull-out: a bolt grouted over L = 3.025 m in the fixed block 0 (x in [0, 3.5]), its other part
# grouted over 3.9 m in block 1 (x in [-4, -0.1]) which a tension P on its left face pulls off;
# nodes every h = 0.05 m at x = (k + ½) h, so that node k is
# grouted over [kh, (k+1)h] in block 0 and the segment from node k to node k+1 has its midpoint
# at x = (k + 1) h.
H, L, EA, K_BOND, P = 0.05, 3.025, 1e8, 1e8, 1e5
LAM = math.sqrt(K_BOND / EA)  # 1/m: λL ≈ 3


def _pullout(bond_strength, monotonic=False):
    """Static stage (the load P at once; local damping lets block 1 overshoot and come back), or
    with ``monotonic`` a dynamic stage overdamped by mass-proportional damping (ξ = 0.9 at 30 Hz:
    ξ ≈ 3 at block 1's own ~90 rad/s), in which the bolt is loaded without any unloading — the
    path the closed form of bond slip assumes. There block 1 slides on a fixed, frictionless,
    stiff support (block 2), whose contact makes the bolt nodes light (eq. (15.5)), so that
    their damping does not hold block 1 back."""
    blocks = [rect(0.0, -0.5, 3.5, 0.5), rect(-4.0, -0.5, -0.1, 0.5)]
    model = hand_model(blocks + [rect(-4.0, -1.5, -0.1, -0.5)] if monotonic else blocks,
                       [(1, 2)] if monotonic else [])
    bolt = Bolt((-3.975, 0.0), (L, 0.0), "pull", BoltProperties(K_BOND, bond_strength,
                                                                 axial_stiffness_n=EA),
                segments=140)
    stage = (Stage("pull", kind="dynamic", duration_s=2.0, rayleigh_ratio=0.9,
                   rayleigh_mode="mass", rayleigh_frequency_hz=30.0) if monotonic
             else Stage("pull", tolerance=1e-8, max_steps=20_000))
    settings = Settings(joints={"default": Coulomb(1e12, 1e12, 0.0)}, stages=(stage,),
                        gravity_m_s2=(0.0, 0.0),
                        fixes=(Fix("blocks:0,2" if monotonic else "blocks:0"), Fix("blocks:1", "yr")),
                        boundary_stress=(BoundaryStress(("left",), sxx_pa=-P),), bolts=(bolt,))
    result = run(model, settings)
    table = result.bolts
    x = table["x_m"]
    seg = (x > 0) & (x < L - 1e-9)  # segments in block 0, midpoints x + h/2
    return result, table, x[seg] + 0.5 * H, table["axial_force_n"][seg]


def test_pullout_axial_force_follows_the_shear_lag_solution():
    # EA N'' = k_bond N (Farmer 1975), N(0) = P, N(L) = 0: N = P sinh(λ(L − x)) / sinh(λL)
    result, _, xm, force = _pullout(bond_strength=1e9)
    assert result.stages[0].status == "converged"
    exact = P * np.sinh(LAM * (L - xm)) / np.sinh(LAM * L)
    assert np.abs(force - exact).max() < 1e-3 * P  # measured 3.5e-5 P
    # the loaded end's stiffness EA λ tanh(λL): block 1 moves by that plus its own grout and the gap
    assert force[0] == pytest.approx(P * math.sinh(LAM * (L - H)) / math.sinh(LAM * L), rel=1e-3)


def test_pullout_bond_slip_spreads_from_the_loaded_end():
    # with a bond strength s the grout slips over [0, x_s] (there N = P − s x) and the rest
    # is elastic: N_s = P − s x_s = (s/λ) tanh(λ(L − x_s)), so P = s x_s + (s/λ) tanh(λ(L − x_s))
    s = 3.5e4  # elastic limit (s/λ) tanh(λL) = 0.35 P < P < s L = 1.06 P
    result, table, xm, force = _pullout(bond_strength=s, monotonic=True)
    assert np.hypot(*result.velocity_m_s[1]) < 1e-5  # at rest (m/s; 4e-6 measured)
    xs = brentq(lambda a: s * a + s / LAM * math.tanh(LAM * (L - a)) - P, 0.0, L)
    ns = P - s * xs
    exact = np.where(xm <= xs, P - s * xm,
                     ns * np.sinh(LAM * (L - np.minimum(xm, L))) / np.sinh(LAM * (L - xs)))
    assert np.abs(force - exact).max() < 0.01 * P  # measured 1.7e-4 P
    x = table["x_m"]
    slipped = (x > 0) & (table["bond_slip_m"] > 0)
    assert x[slipped].max() == pytest.approx(xs, abs=2 * H)  # x_s = 1.72 m
    assert table["bond_slip_m"][x > xs + 2 * H].max() == 0.0


def test_bolt_pulls_out_when_the_load_exceeds_the_bond_capacity():
    result, table, _, _ = _pullout(bond_strength=P / (1.2 * L))  # s L = P / 1.2
    stage = result.stages[0]
    assert stage.status != "converged"
    in_rock = table["x_m"] > 0
    assert table["bond_slipping"][in_rock].all()
    share = np.where(np.isclose(table["x_m"][in_rock], L), 0.5 * H, H)
    assert np.allclose(table["bond_force_n"][in_rock], P / (1.2 * L) * share, rtol=1e-9)


# a block (2 m × 1 m, 5400 kg) on a 30° slope with friction 20°, bolted across its base by a
# bolt at β = 30° to the slope, pointing up-slope into the base: 1 m in the block, 1.5 m in the base
PSI, PHI, BETA, L1, L2, EA_I, K_I = 30.0, 20.0, 30.0, 1.0, 1.5, 1e7, 9e7


def _bolted_block(yield_force=None, segments=100):
    model = incline(PSI, b=2.0, h=1.0)
    axis = np.array([math.cos(math.radians(PSI - BETA)), math.sin(math.radians(PSI - BETA))])
    bolt = Bolt(tuple(-L1 * axis), tuple(L2 * axis), "slide",
                BoltProperties(K_I, 1e9, axial_stiffness_n=EA_I, yield_force_n=yield_force),
                segments=segments)
    mass = 2700.0 * model.area_m2[1]
    # overdamped (mass-proportional ξ = 1.8 at the block's frequency on the bolt): the block
    # creeps to rest without overshoot, so the joint stays at its friction limit
    omega = math.sqrt(_k_eff() * math.cos(math.radians(BETA)) ** 2 / mass)
    stage = Stage("slide", kind="dynamic", duration_s=1.0, rayleigh_ratio=0.9,
                  rayleigh_mode="mass", rayleigh_frequency_hz=2 * omega / (2 * math.pi))
    settings = Settings(joints={"default": Coulomb(1e10, 1e10, PHI)}, stages=(stage,),
                        fixes=(Fix("blocks:0"),), bolts=(bolt,))
    result = run(model, settings)
    crossing = int(np.flatnonzero(-L1 + np.arange(segments + 1) * (L1 + L2) / segments < 0)[-1])
    down = -np.array([math.cos(math.radians(PSI)), math.sin(math.radians(PSI))])
    return result, mass * 9.81, crossing, float(result.displacement_m[1] @ down)


def _k_eff():
    """Axial stiffness of a bolt across an opening joint: the two grouted halves in series, each
    EA λ tanh(λ L_i) (the pull-out stiffness of the shear-lag solution)."""
    lam = math.sqrt(K_I / EA_I)
    return 1.0 / sum(1.0 / (EA_I * lam * math.tanh(lam * li)) for li in (L1, L2))


def _needed_force(weight):
    """Bolt tension T holding the block at its friction limit: along the slope
    W sin ψ = T cos β + (W cos ψ + T sin β) tan φ."""
    s, c, t = (math.sin(math.radians(PSI)), math.cos(math.radians(PSI)), math.tan(math.radians(PHI)))
    return weight * (s - c * t) / (math.cos(math.radians(BETA)) + math.sin(math.radians(BETA)) * t)


def test_bolted_block_is_held_by_the_statics_force_and_series_stiffness():
    result, weight, crossing, slide = _bolted_block(yield_force=None)
    tension = _needed_force(weight)
    force = result.bolts["axial_force_n"][crossing]
    assert force == pytest.approx(tension, rel=1e-3)  # measured −6e-6
    # the joint opens along the bolt by δ cos β; plus the joint's elastic shear τ b / (k_s b)
    normal = weight * math.cos(math.radians(PSI)) + tension * math.sin(math.radians(BETA))
    joint = normal * math.tan(math.radians(PHI)) / (2.0 * 1e10)
    expected = tension / (_k_eff() * math.cos(math.radians(BETA))) + joint
    assert slide == pytest.approx(expected, rel=0.01)  # measured 0.2 %
    assert not result.bolts["yielded"].any()


def test_bolted_block_slides_once_the_needed_force_exceeds_yield():
    held, weight, crossing, slide_held = _bolted_block(yield_force=None)
    tension = _needed_force(weight)
    above, _, _, slide_above = _bolted_block(yield_force=1.05 * tension)
    assert not above.bolts["yielded"].any()
    assert slide_above == pytest.approx(slide_held, rel=1e-6)
    below, _, _, slide_below = _bolted_block(yield_force=0.95 * tension)
    assert below.bolts["yielded"][crossing]
    assert below.bolts["axial_force_n"][crossing] == pytest.approx(0.95 * tension, rel=1e-9)
    assert slide_below > 1.3 * slide_held
    speed = np.hypot(*below.velocity_m_s[1])
    assert speed > 1e-4  # still sliding at the end (held: < 1e-6)
    assert np.hypot(*held.velocity_m_s[1]) < 1e-6


def test_energy_ledger_closes_with_bolt_slip_and_yield():
    slipping, _, _, _ = _pullout(bond_strength=3.5e4, monotonic=True)
    yielding, weight, _, _ = _bolted_block(yield_force=0.95 * _needed_force(
        9.81 * 2700.0 * 2.0))
    for result, term in ((slipping, "bolt_slip_dissipation_j"),
                         (yielding, "bolt_yield_dissipation_j")):
        energy = result.stages[0].energy
        work = abs(energy["work_gravity_j"]) + abs(energy["work_boundary_j"])
        assert energy[term] > 0.05 * work
        assert abs(energy["residual_j"]) < 1e-3 * work  # measured < 1e-9


def test_bolt_pattern_puts_bolts_normal_to_the_chosen_walls():
    # 3 × 3 blocks of 1 m, the middle one excavated: a 1 m square opening centred at (1.5, 1.5)
    polys = [rect(i, j, i + 1.0, j + 1.0) for j in range(3) for i in range(3)]
    pairs = [(k, k + 1) for k in range(9) if k % 3 != 2] + [(k, k + 3) for k in range(6)]
    model = hand_model(polys, pairs, region=np.array([0, 0, 0, 0, 1, 0, 0, 0, 0]))
    props = BoltProperties(1e8, 1e5, axial_stiffness_n=1e8)
    settings = Settings(
        joints={"default": Coulomb(1e10, 1e10, 40.0)}, gravity_m_s2=(0.0, 0.0),
        fixes=(Fix("blocks:0,1,2,3,5,6,7,8"),),
        stages=(Stage("dig", excavate=(1,), max_steps=20),),
        bolt_patterns=(BoltPattern("dig", 0.8, 0.5, props, segments=4),
                       BoltPattern("dig", 0.6, 0.5, props, walls=("floor",), box_m=(0, 0, 1.6, 3),
                                   segments=2, name="low")))
    table = run(model, settings).bolts
    heads = table["node"] == 0
    names = table["bolt"][heads]
    xy = np.column_stack([table["x_m"], table["y_m"]])
    toe = xy[np.flatnonzero(heads) + np.where([n.startswith("low") for n in names], 2, 4)]
    direction = (toe - xy[heads]) / np.hypot(*(toe - xy[heads]).T)[:, None]
    # perimeter 4 m at spacing 0.5: heads at 0.25, 0.75 m along each wall; roof and sides: 6
    assert sum(not n.startswith("low") for n in names) == 6
    assert sum(n.startswith("low") for n in names) == 1  # floor, head x < 1.6: only x = 1.25
    for head, d in zip(xy[heads], direction):
        # on its wall (set 1e-6 of its length into the rock: tolerances.BOLT_HEAD_INSET)
        x, y = head
        wall = {(0, 1): y, (0, -1): y, (-1, 0): x, (1, 0): x}[tuple(np.round(d).astype(int))]
        assert wall == pytest.approx(2.0 if d.sum() > 0 else 1.0, abs=1e-6)
    assert (table["host_block"] >= 0).all() and (table["host_block"] != 4).all()


def test_bolt_settings_are_checked_and_left_out_of_old_dumps():
    from pydantic import TypeAdapter

    with pytest.raises(ValueError, match="axial_stiffness_n"):
        BoltProperties(1e8, 1e5)
    with pytest.raises(ValueError, match="axial_stiffness_n"):
        BoltProperties(1e8, 1e5, axial_stiffness_n=1e8, diameter_m=0.02)
    props = BoltProperties(1e8, 1e5, youngs_modulus_pa=2e11, diameter_m=0.025,
                           out_of_plane_spacing_m=1.5)
    assert props.per_metre()["axial_stiffness_n"] == pytest.approx(2e11 * math.pi * 0.025 ** 2
                                                                   / 4 / 1.5)
    plain = dict(joints={"default": Coulomb(1e9, 1e9, 30.0)}, stages=(Stage("a"),))
    with pytest.raises(ValueError, match="stage 'b' is not a stage"):
        Settings(**plain, bolts=(Bolt((0, 0), (1, 0), "b", props),))
    dumped = TypeAdapter(Settings).dump_python(Settings(**plain), mode="json")
    assert "bolts" not in dumped and "bolt_patterns" not in dumped  # old hashes unchanged
    with_bolt = Settings(**plain, bolts=(Bolt((0, 0), (1, 0), "a", props),))
    assert TypeAdapter(Settings).dump_python(with_bolt, mode="json")["bolts"][0]["stage"] == "a"



def test_bolt_pattern_of_a_later_stage_bolts_only_the_walls_it_exposed():
    # 3 columns x 4 rows of 1 m blocks; the middle column's row 1 is dug at stage a, row 2 at b
    polys = [rect(i, j, i + 1.0, j + 1.0) for j in range(4) for i in range(3)]
    region = np.zeros(12, int)
    region[[4, 7]] = [1, 2]
    model = hand_model(polys, region=region)
    props = BoltProperties(1e8, 1e5, axial_stiffness_n=1e8)
    rock = ",".join(str(k) for k in range(12) if k not in (4, 7))
    settings = Settings(
        joints={"default": Coulomb(1e10, 1e10, 40.0)}, gravity_m_s2=(0.0, 0.0),
        fixes=(Fix(f"blocks:{rock}"),),
        stages=(Stage("a", excavate=(1,), max_steps=20), Stage("b", excavate=(2,), max_steps=20)),
        bolt_patterns=(BoltPattern("a", 0.8, 0.5, props, segments=2, name="a"),
                       BoltPattern("b", 0.8, 0.5, props, segments=2, name="b")))
    table = run(model, settings).bolts
    heads = table["node"] == 0
    head_y = {name: table["y_m"][heads][table["bolt"][heads] == name]
              for name in set(table["bolt"][heads])}
    from_a = [y for name, y in head_y.items() if name.startswith("a")]
    from_b = [y for name, y in head_y.items() if name.startswith("b")]
    # a: walls of the first opening [1, 2] x [1, 2]: 2 left, 2 right, 2 roof
    assert len(from_a) == 6 and all(1.0 <= y <= 2.0 + 1e-5 for y in np.concatenate(from_a))
    # b: the opening [1, 2] x [1, 3]; only the walls of row 2 are new: 2 left, 2 right, 2 roof
    assert len(from_b) == 6 and all(2.0 <= y <= 3.0 + 1e-5 for y in np.concatenate(from_b))
