"""Rounded corners (docs/dem.md §3.1, UDEC's rounding d): the arcs, and contacts that pass over a
corner.

Closed forms used here: a corner with turn θ (interior angle π − θ) rounded with radius r has its arc
centre r / cos(θ/2) from the vertex along the bisector and its tangent points r tan(θ/2) from the
vertex; a rounded block is its polygon of arc centres grown by r, so two rounded corners touch
along the line through their arc centres with the gap |C_b − C_a| − r_a − r_b.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from rockmass.solver import Coulomb, Material, Settings, Stage, Fix, run
from rockmass.solver.engine import Engine, rounded_corners

from ._models import hand_model, rect

KN = 1e9
D = 0.01  # rounding (m)


def _corners(poly, rounding):
    loc = np.asarray(poly, float)
    off = np.array([0, len(loc)])
    edge = np.roll(loc, -1, axis=0) - loc
    normal = np.column_stack([edge[:, 1], -edge[:, 0]]) / np.hypot(*edge.T)[:, None]
    return rounded_corners(loc, off, normal, rounding)


def test_square_and_triangle_corner_arcs_follow_the_closed_form():
    """Square (θ = 90°): centres (±(½ − r), ±(½ − r)), tangent r. Equilateral triangle (θ = 120°):
    centre 2r from the vertex towards the centroid, tangent r√3."""
    centre, tangent, radius = _corners(rect(-0.5, -0.5, 0.5, 0.5), D)
    assert radius[0] == D
    np.testing.assert_allclose(np.abs(centre), 0.5 - D, rtol=0, atol=1e-15)
    np.testing.assert_allclose(tangent, D, rtol=1e-12)
    tri = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, math.sqrt(3) / 2]])
    centroid = tri.mean(axis=0)
    centre, tangent, radius = _corners(tri, D)
    np.testing.assert_allclose(tangent, D * math.sqrt(3), rtol=1e-12)
    towards = (centroid - tri) / np.hypot(*(centroid - tri).T)[:, None]
    np.testing.assert_allclose(centre, tri + 2 * D * towards, rtol=0, atol=1e-14)


def test_sharp_sliver_gets_the_largest_radius_that_keeps_half_of_each_edge_flat():
    """A 2° sliver: tan(θ/2) = tan(89°) at the sharp corners, so r = ½ L_short /(tan 89° + tan 1°)
    ... the binding edge is found by the closed form over all three edges."""
    tip = math.radians(2.0)
    tri = np.array([[0.0, 0.0], [1.0, 0.0], [math.cos(tip), math.sin(tip)]])
    centre, tangent, radius = _corners(tri, 0.05)
    edges = np.roll(tri, -1, axis=0) - tri
    length = np.hypot(*edges.T)
    turn = np.array([math.pi - tip, math.pi - (math.pi - tip) / 2, math.pi - (math.pi - tip) / 2])
    unit = np.tan(turn / 2)
    expected = min(0.05, *(0.5 * length[k] / (unit[k] + unit[(k + 1) % 3]) for k in range(3)))
    assert radius[0] == pytest.approx(expected, rel=1e-12)
    assert radius[0] < 0.05
    flat = length - tangent - np.roll(tangent, -1)
    assert (flat >= 0.5 * length - 1e-12).all()
    # the largest such radius: the binding edge keeps exactly half flat (independent of the formula)
    assert (flat / length).min() == pytest.approx(0.5, rel=1e-12)


def _sweep_engine():
    """Block 0 fixed, its top-right corner at the origin; block 1 a unit square on top of it."""
    model = hand_model([rect(-4, -1, 0, 0), rect(-1, 0, 0, 1)], [(0, 1)])
    settings = Settings(joints={"default": Coulomb(KN, KN, 30.0)}, material=Material(2500),
                        fixes=(Fix("blocks:0"),), rounding_m=D, contact_tolerance_m=D,
                        stages=(Stage("s", "static"),))
    return Engine(model, settings)


def _place(eng, left_x, overlap):
    eng.pos[1] = (left_x + 0.5, 0.5 - overlap)
    eng.rebuild()
    eng.detect()
    return eng.contact_table()


def test_block_sliding_off_a_corner_follows_the_rounded_closed_form():
    """Block 1, pressed δ₀ into block 0's top face, slides right over block 0's corner.

    While the flat parts overlap (face width w = −x_left > 2d): two slots, overlap δ₀ each, total
    force k_n δ₀ w, normal vertical. Then the two rounded corners: arc centres (−d, −d) and
    (x_left + d, d − δ₀), h = 2d − w apart horizontally, so the overlap is
    2d − √(h² + (2d − δ₀)²) along the normal (h, 2d − δ₀)/|·| — continuous with the face phase at
    w = 2d, turning smoothly to horizontal — until the corners part."""
    eng = _sweep_engine()
    d0 = 0.2 * D
    forces = []
    for left in np.linspace(-0.1, 0.02, 600):  # steps of 0.2 mm, none at w = 2d exactly
        table = _place(eng, left, d0)
        w = -left
        force = float(np.sum(table["normal_stress_pa"] * table["length_m"]))
        forces.append(force)
        if w > 2 * D + 1e-9:
            assert len(table["x_m"]) == 2
            np.testing.assert_allclose(table["overlap_m"], d0, rtol=1e-9)
            np.testing.assert_allclose(table["ny"], 1.0, rtol=0, atol=1e-12)
            assert force == pytest.approx(KN * d0 * w, rel=1e-9)
            continue
        h = 2 * D - w
        centre_gap = math.hypot(h, 2 * D - d0)
        overlap = 2 * D - centre_gap
        if overlap < -D:  # beyond the detection gap: no contact
            assert len(table["x_m"]) == 0
            continue
        assert len(table["x_m"]) == 1
        assert table["overlap_m"][0] == pytest.approx(overlap, abs=1e-12)
        np.testing.assert_allclose([table["nx"][0], table["ny"][0]],
                                   [h / centre_gap, (2 * D - d0) / centre_gap], atol=1e-9)
        # the joint law on the closed-form overlap (whatever length the slot stands for) ...
        assert table["normal_stress_pa"][0] == pytest.approx(KN * max(overlap, 0.0), rel=1e-9,
                                                             abs=1e-3)
        # ... over the face part it stands for (at least d)
        length = max(w, D) if w >= 0 else D
        assert force == pytest.approx(KN * max(overlap, 0.0) * length, rel=1e-9, abs=1e-6)
    # no jump anywhere along the sweep (steps of 0.2 mm): the largest change between neighbours
    # is a small part of the face force at w = 0.1 m (measured 0.55 %, on the steep corner phase)
    jumps = np.abs(np.diff(forces))
    assert jumps.max() < 0.02 * KN * d0 * 0.1


def test_corner_to_corner_touch_is_along_the_centre_line():
    """Block 1 rotated 45°, its lowest corner just above block 0's top-right corner, offset
    diagonally: one slot, normal along the arc centres, gap |C₁ − C₀| − 2d."""
    eng = _sweep_engine()
    s = math.sqrt(0.5)
    # place block 1 (a unit square) rotated 45°: its lowest vertex at (x_v, y_v)
    x_v, y_v = 0.001, 0.0005
    eng.rot[1] = math.radians(45.0)
    eng.pos[1] = (x_v, y_v + s)
    eng.rebuild()
    eng.detect()
    table = eng.contact_table()
    c0 = np.array([-D, -D])
    c1 = np.array([x_v, y_v + D * math.sqrt(2)])  # r / cos(45°) above the lowest vertex
    gap = np.hypot(*(c1 - c0)) - 2 * D
    assert len(table["x_m"]) == 1
    assert table["overlap_m"][0] == pytest.approx(-gap, abs=1e-12)
    n = (c1 - c0) / np.hypot(*(c1 - c0))
    np.testing.assert_allclose([table["nx"][0], table["ny"][0]], n, atol=1e-12)


def test_corner_only_touches_of_four_blocks_start_open_under_insitu_stress():
    """Four squares meeting at a point under in-situ stress: the diagonal pairs touch only at the
    point; their rounded corners are (2√2 − 2) d apart, so they stay open (zero force) and the
    faces alone hold the stress in equilibrium at step 1."""
    from rockmass.solver import InSituStress

    blocks = [rect(-1, -1, 0, 0), rect(0, -1, 1, 0), rect(0, 0, 1, 1), rect(-1, 0, 0, 1)]
    model = hand_model(blocks, [(0, 1), (1, 2), (2, 3), (3, 0)])
    settings = Settings(joints={"default": Coulomb(KN, KN, 30.0)}, material=Material(2500),
                        gravity_m_s2=(0.0, 0.0), rounding_m=0.05,
                        insitu=InSituStress(sxx_pa=2e6, syy_pa=1e6),
                        fixes=(Fix("left", "x"), Fix("right", "x"), Fix("bottom", "y"),
                               Fix("top", "y")),
                        stages=(Stage("hold", "static", max_steps=50),))
    eng = Engine(model, settings)
    eng.detect()
    from rockmass.solver.loading import apply_insitu

    apply_insitu(eng, settings.insitu)
    eng.detect()
    table = eng.contact_table()
    diagonal = (table["block_a"] + table["block_b"]) % 2 == 0  # pairs (0, 2) and (1, 3)
    assert diagonal.sum() == 2
    np.testing.assert_allclose(table["overlap_m"][diagonal], -(2 * math.sqrt(2) - 2) * 0.05,
                               rtol=1e-9)
    assert (table["normal_stress_pa"][diagonal] == 0).all()
    result = run(model, settings)
    assert result.stages[0].max_displacement_m < 1e-12


def test_face_shorter_than_the_rounded_corners_carries_its_insitu_stress():
    """A 3 cm strip Q stands on block P beside P's corner: with d = 5 cm, P's rounded corner covers
    the whole 3 cm face, so the pair is one rounded-corner slot, not a face. It must still carry the
    face's in-situ load, the traction σ·n × 3 cm resolved on the slot's own normal and tangent
    (else Q, pushed down by the boundary traction on its top, sinks into P: 5.1e-6 m after these
    400 steps); the slot's point is not the face centre, so a little moment is left (8e-9 m)."""
    from rockmass.solver import BoundaryStress, InSituStress
    from rockmass.solver import _kernels as K
    from rockmass.solver.loading import apply_insitu

    w, syy = 0.03, 1e6
    blocks = [rect(0, 0, 2, 1), np.array([[0, 1], [w, 1], [w, 2], [0, 2]], float), rect(w, 1, 2, 2)]
    model = hand_model(blocks, [(0, 1), (0, 2), (1, 2)])
    settings = Settings(joints={"default": Coulomb(10 * KN, 10 * KN, 30.0)}, material=Material(2500),
                        gravity_m_s2=(0.0, 0.0), rounding_m=0.05,
                        insitu=InSituStress(sxx_pa=2e6, syy_pa=syy),
                        boundary_stress=(BoundaryStress(("left", "right", "top"), from_insitu=True),),
                        fixes=(Fix("bottom", "y"), Fix("bottom", "x")),
                        stages=(Stage("hold", "static", max_steps=400, tolerance=1e-30),))
    eng = Engine(model, settings)
    eng.detect()
    apply_insitu(eng, settings.insitu)
    pair = int(np.flatnonzero((eng.pa == 0) & (eng.pb == 1))[0])
    active = eng.S[pair, :, K.ACT] != 0
    assert active.sum() == 1  # a rounded-corner slot, not a two-slot face
    # the slot's force vector, F_n n − F_s t (t = (−n_y, n_x)), is the face's traction σ·n w
    slot = eng.S[pair, np.flatnonzero(active)[0]]
    n, t = slot[[K.NX, K.NY]], np.array([-slot[K.NY], slot[K.NX]])
    assert abs(n[0]) > 0.1  # the corner slot's normal is not the face's (0, 1)
    np.testing.assert_allclose(slot[K.FN] * n - slot[K.FS] * t, [0.0, syy * w], rtol=0,
                               atol=1e-9 * syy * w)
    result = run(model, settings)
    strip = np.hypot(*result.displacement_m[1])
    assert strip < 1e-7, strip


def test_block_sliding_off_an_incline_over_its_corner_keeps_the_energy_ledger():
    """A block slides down a 30° incline (φ = 10°) off the lower end of a 2 m base, tips over the
    rounded corner and falls. A jump in the contact force as it passes the corner would create or
    destroy energy; the ledger (gravity work = kinetic + strain + slip dissipation) closes to
    2e-4 of the work in with the small step used for dynamic ledgers elsewhere (safety 0.1;
    measured 4.2e-5), and the block really went over: it ends below the base's top corner."""
    from ._models import incline

    settings = Settings(joints={"default": Coulomb(1e9, 1e9, 10.0)}, material=Material(2000),
                        fixes=(Fix("blocks:0"),), time_step_safety=0.1, rounding_m=0.02,
                        stages=(Stage("slide", "dynamic", duration_s=1.1),))
    result = run(incline(30.0, base_length=2.0), settings)
    st = result.stages[0]
    assert result.ok, result.diagnostic
    e = st.energy
    work_in = e["work_gravity_j"] + e["work_boundary_j"]
    assert abs(e["residual_j"]) < 2e-4 * work_in, e["residual_j"] / work_in
    corner_y = -math.sin(math.radians(30.0))  # the base's lower top corner, (−cos 30°, −sin 30°)
    final = result.frames[-1]
    assert final.position_m[1, 1] < corner_y


def test_default_rounding_is_one_percent_of_the_median_edge_of_the_block_model():
    """A base with a T-junction vertex on its top face (edges 4, 1, 2, 2, 1 m) under a 0.5 m
    square (4 × 0.5 m): the median of the nine block-model edges is 1 m, so d = 1 cm. (The solver
    drops the collinear vertex for its own polygons; the median is of the model's edges.)"""
    base = np.array([[-2.0, -1.0], [2.0, -1.0], [2.0, 0.0], [0.0, 0.0], [-2.0, 0.0]])
    model = hand_model([base, rect(0.0, 0.0, 0.5, 0.5)], [(0, 1)])
    settings = Settings(joints={"default": Coulomb(KN, KN, 30.0)}, material=Material(2500),
                        stages=(Stage("s", "static"),))
    eng = Engine(model, settings)
    assert eng.median_edge_m == pytest.approx(1.0, rel=1e-12)
    assert eng.rounding_m == pytest.approx(0.01, rel=1e-12)


@pytest.mark.parametrize("how", ["cracks", "rounding_m"])
def test_default_rounding_is_the_one_the_block_model_was_built_for(how):
    """blockgen keeps every edge >= 2d for its own d (given, or 1 % of a typical edge: the cut
    blocks' median, or half the crack size when cracks subdivide them), recorded in
    quality["tolerances"]; the solver must round with that d, not re-derive another from the
    finished model's edges (1 % of their median: 0.0073 m against 0.005 m with the cracks here)."""
    from rockmass.blockgen import Cracks, JointSet, build

    kwargs = {"cracks": Cracks(size_m=1.0)} if how == "cracks" else {"rounding_m": 0.05}
    model = build([(0, 0), (20, 0), (20, 20), (0, 20)],
                  [JointSet(angle_deg=30.0, spacing_m=2.3), JointSet(angle_deg=110.0, spacing_m=3.1)],
                  **kwargs)
    settings = Settings(joints={"default": Coulomb(KN, KN, 30.0)}, material=Material(2500),
                        stages=(Stage("s", "static"),))
    eng = Engine(model, settings)
    built_for = model.quality.tolerances.rounding_m
    assert built_for == (0.05 if how == "rounding_m" else pytest.approx(0.005))
    assert abs(eng.median_edge_m * 0.01 - built_for) > 0.2 * built_for  # the two rules differ here
    assert eng.rounding_m == built_for
    assert Engine(model, replace(settings, rounding_m=0.02)).rounding_m == 0.02

