"""Block models: invariants, analytic layouts and persistence (blockgen.build)."""

import math

import numpy as np
import pytest
import shapely

from rockmass.blockgen import (CONTACT_KINDS, JointSet, arched_cavern, build, check_model, circle,
                               circle_perimeter_m, horseshoe, rectangle)

from ._fixtures import orthogonal_grid, shake_table, square


def _assert_invariants(model):
    inv = check_model(model)
    assert inv["area_balance_rel"] <= 1e-9
    assert inv["max_overlap_m2"] <= 1e-12
    assert inv["n_concave"] == 0
    assert inv["max_contact_length_mismatch_m"] <= 1e-9
    assert inv["ok"]


def test_orthogonal_sets_give_L_over_s_squared_blocks_of_area_s_squared():
    m = orthogonal_grid(side=2.0, spacing=0.25)
    assert m.n_blocks == (2.0 / 0.25) ** 2
    np.testing.assert_allclose(m.area_m2, 0.0625, rtol=1e-12)
    # second moment of a square about its centroid: s^4 / 12
    np.testing.assert_allclose(m.second_moment_m4[:, :2], 0.25 ** 4 / 12, rtol=1e-9)
    np.testing.assert_allclose(m.second_moment_m4[:, 2], 0, atol=1e-15)
    _assert_invariants(m)


def test_orthogonal_grid_contacts_are_the_interior_lines():
    m = orthogonal_grid(side=1.0, spacing=0.25)
    joint = m.contact_kind == CONTACT_KINDS.index("joint")
    # 3 interior lines of each set, each of length 1, each cut into 4 contacts of 0.25
    assert joint.sum() == 24
    np.testing.assert_allclose(m.contact_length_m[joint], 0.25)
    domain = m.contact_kind == CONTACT_KINDS.index("domain")
    assert m.contact_length_m[domain].sum() == pytest.approx(4.0, rel=1e-12)
    assert (m.contact_blocks[domain, 1] == -1).all()


@pytest.mark.parametrize("beta", [0.0, 30.0, 45.0, 72.5, 120.0])
def test_set_at_angle_beta_has_its_spacing_measured_normal_to_it(beta):
    s = 0.1
    m = build(square(1.0), [JointSet(beta, s, origin_xy_m=(0.5, 0.5))])
    n = np.array([-math.sin(math.radians(beta)), math.cos(math.radians(beta))])
    joint = m.contact_kind == CONTACT_KINDS.index("joint")
    # offsets of joint contacts along the normal: the shared boundary of the two blocks
    offsets = []
    for a, b in m.contact_blocks[joint]:
        line = shapely.intersection(shapely.Polygon(m.polygon(a)).boundary,
                                    shapely.Polygon(m.polygon(b)).boundary)
        offsets.append(shapely.get_coordinates(line).mean(axis=0) @ n)
    gaps = np.diff(np.unique(np.round(offsets, 9)))
    np.testing.assert_allclose(gaps, s, rtol=1e-9)
    _assert_invariants(m)


def test_circular_excavation_boundary_matches_the_inscribed_polygon():
    r, n = 0.076, 36
    m = shake_table()
    exc = m.contact_kind == CONTACT_KINDS.index("excavation")
    length = m.contact_length_m[exc].sum()
    assert length == pytest.approx(circle_perimeter_m(r, n), rel=1e-9)
    # documented approximation: 1 - (n/pi) sin(pi/n) ~ pi^2 / (6 n^2)
    assert abs(length - 2 * math.pi * r) / (2 * math.pi * r) < math.pi ** 2 / (6 * n ** 2) * 1.01
    excavated = m.area_m2[m.region == 1].sum()
    assert excavated == pytest.approx(0.5 * n * r * r * math.sin(2 * math.pi / n), rel=1e-9)


def test_shake_table_model_satisfies_the_invariants():
    m = shake_table()
    _assert_invariants(m)
    q = m.quality
    assert q.area_balance["relative_error"] <= 1e-9
    assert q.convex_splits, "blocks around the tunnel are concave before the split"
    glued = m.contact_kind == CONTACT_KINDS.index("glued")
    assert glued.sum() > 0 and (m.contact_source[glued] == -2).all()


def test_total_block_area_plus_excavation_equals_domain_for_staged_cavern():
    domain = np.array([[-60.0, -60], [60, -60], [60, 60], [-60, 60]])
    arch = arched_cavern((0, 20), 20.0, 5.0, 5.0, name="arch")
    bench = rectangle((0, 10), 20.0, 20.0, name="bench")
    m = build(domain, [JointSet(30, 4.0), JointSet(90, 6.0)], excavations=[arch, bench], seed=1)
    _assert_invariants(m)
    rock = m.area_m2[m.region == 0].sum()
    assert rock + m.area_m2[m.region > 0].sum() == pytest.approx(120 * 120, rel=1e-9)
    # the arch stage takes what lies above the bench
    assert m.area_m2[m.region == 2].sum() == pytest.approx(400.0, rel=1e-9)
    assert m.region_names == ("rock", "arch", "bench")


def test_horseshoe_with_random_spacing_is_reproducible_by_seed():
    domain = square(40.0, -20, -20)
    sets = [JointSet(20, 2.0, "exponential"), JointSet(110, 3.0, "lognormal", spacing_std_m=1.0)]
    tunnel = horseshoe((0, -3), 6.0, 3.0)
    a = build(domain, sets, excavations=[tunnel], seed=7)
    b = build(domain, sets, excavations=[tunnel], seed=7)
    c = build(domain, sets, excavations=[tunnel], seed=8)
    np.testing.assert_array_equal(a.xy_m, b.xy_m)
    assert not np.array_equal(a.area_m2.shape, c.area_m2.shape) or not np.allclose(a.area_m2[:5],
                                                                                      c.area_m2[:5])
    _assert_invariants(a)


@pytest.mark.parametrize("dangling", ["glued", "joint", "drop"])
def test_non_persistent_joints_follow_the_dangling_choice(dangling):
    sets = [JointSet(0, 1.0, trace_length_m=3.0, gap_length_m=1.0),
            JointSet(80, 1.5)]
    m = build(square(10.0), sets, dangling=dangling, seed=3)
    _assert_invariants(m)
    glued = m.contact_kind == CONTACT_KINDS.index("glued")
    q = m.quality.dangling
    assert q["rule"] == dangling and q["n_dangling_ends"] > 0
    if dangling == "glued":
        assert glued.sum() > 0 and set(m.contact_source[glued]) <= {0, 1, -2}
    elif dangling == "joint":
        assert not (m.contact_source[glued] >= 0).any()
    else:
        assert q["dropped_length_m"] > 0


def test_traces_are_cut_and_labelled_by_trace_index():
    from rockmass.dfn import TraceMap

    tm = TraceMap.from_polylines([[(0, 0.3), (1, 0.3)], [(0.5, 0), (0.5, 0.6)]])
    m = build(square(1.0), traces=tm)
    _assert_invariants(m)
    trace = m.contact_kind == CONTACT_KINDS.index("trace")
    assert set(m.contact_source[trace]) == {0, 1}
    # trace 1 ends inside the rock at y = 0.6: extended to the top boundary as a glued contact
    assert m.n_blocks == 4


def test_slivers_are_merged_and_reported():
    # a joint 1 mm from a domain edge of a 1 m square with 0.25 m blocks: 1 mm wide slivers
    sets = [JointSet(0, 0.25, origin_xy_m=(0, 0)), JointSet(90, 0.25, origin_xy_m=(0.001, 0))]
    m = build(square(1.0), sets, min_edge_m=0.005)
    assert len(m.quality.slivers_merged) == 4
    assert m.n_blocks == 16
    _assert_invariants(m)


def test_build_does_not_modify_inputs():
    domain = square(1.0)
    before = domain.copy()
    build(domain, [JointSet(10, 0.2)])
    np.testing.assert_array_equal(domain, before)
