"""History points on the excavation boundary (:mod:`rockmass.solver.monitoring`).

Expected points come from each excavation's own definition (blockgen's formulas for the rectangle,
the arched cavern, the circle and the horseshoe, or a plain loop over the excavation outline),
never from the union of blocks that the module works on; displacements from the closed form of a
rigid motion. Tolerance 1e-9 m: blockgen snaps every node to a dyadic grid of ~1e-12 of the model
size, so the block outline of an opening matches its definition to ~1e-10 m here.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import shapely

from rockmass.blockgen import (JointSet, arched_cavern, build, circle, horseshoe,
                               polygon_excavation, rectangle)
from rockmass.solver.monitoring import (POINT_NAMES, BoundaryPoint, boundary_points,
                                        point_displacement, point_displacement_from,
                                        point_positions)

SAMPLES = Path(__file__).resolve().parents[2] / "samples"
TOL = 1e-9

# a rectangle of known coordinates in a box cut by two oblique sets (offsets chosen so that no
# joint runs through a wall midpoint)
RECT = dict(center=(5.5, 4.25), width=4.0, height=2.5)


def _sets():
    return [JointSet(30.0, 1.3, origin_xy_m=(0.1, 0.2), name="a"),
            JointSet(115.0, 1.7, origin_xy_m=(0.3, 0.05), name="b")]


@pytest.fixture(scope="module")
def rect_model():
    return build([(0, 0), (12, 0), (12, 9), (0, 9)], _sets(),
                 excavations=[rectangle(RECT["center"], RECT["width"], RECT["height"],
                                        name="drift")])


@pytest.fixture(scope="module")
def cavern():
    """samples/blocks_cavern.toml, built as ``rockmass blocks`` builds it; with its [blocks]."""
    from rockmass.config import load_config

    cfg = load_config(SAMPLES / "blocks_cavern.toml").blocks
    model = build(cfg.domain.xy_m(), cfg.joint_sets(), None,
                  [e.to_excavation() for e in cfg.excavations], dangling=cfg.dangling,
                  seed=cfg.seed)
    return model, cfg


def _by_name(points):
    return {p.name: p for p in points}


def _assert_points(points, expected):
    got = _by_name(points)
    assert [p.name for p in points] == list(POINT_NAMES)
    for name, xy in expected.items():
        np.testing.assert_allclose(got[name].point_xy_m, xy, rtol=0, atol=TOL, err_msg=name)


def _assert_attached(model, regions, points):
    """Each point's block stays (not in ``regions``), touches the point, and local = p - c."""
    polys = model.to_shapely()
    opening = shapely.union_all(polys[np.isin(model.region, regions)])
    for p in points:
        assert model.region[p.block] not in regions, p
        assert shapely.distance(polys[p.block], shapely.Point(p.point_xy_m)) < TOL, p
        # the block is rock beside the opening, not in it
        assert shapely.intersection(polys[p.block], opening).area < 1e-9 * model.area_m2[p.block]
        np.testing.assert_array_equal(p.local_xy_m, p.point_xy_m - model.centroid_xy_m[p.block])


def _wall_x(outline_xy, y):
    """Left-most and right-most crossing of the horizontal line at y with a closed outline (a
    plain loop over its edges, independent of the module's vectorised crossings)."""
    xs = []
    n = len(outline_xy)
    for i in range(n):
        (xa, ya), (xb, yb) = outline_xy[i], outline_xy[(i + 1) % n]
        if (ya - y) * (yb - y) <= 0 and ya != yb:
            xs.append(xa + (y - ya) / (yb - ya) * (xb - xa))
    return min(xs), max(xs)


# ------------------------------------------------------------------------------- positions --
def test_rectangle_points_are_edge_midpoints(rect_model):
    (cx, cy), w, h = RECT["center"], RECT["width"], RECT["height"]
    points = boundary_points(rect_model, [1])
    _assert_points(points, {"crown": (cx, cy + h / 2), "invert": (cx, cy - h / 2),
                            "left_wall": (cx - w / 2, cy), "right_wall": (cx + w / 2, cy)})
    _assert_attached(rect_model, [1], points)


def test_stage_names_and_ids_give_the_same_points(rect_model):
    by_id = boundary_points(rect_model, 1)
    by_name = boundary_points(rect_model, ["drift", 1, "drift"])
    for a, b in zip(by_id, by_name):
        assert (a.name, a.block) == (b.name, b.block)
        np.testing.assert_array_equal(a.point_xy_m, b.point_xy_m)


def test_sample_cavern_points_follow_the_excavation_sequence(cavern):
    """Arch, then bench 1, then bench 2 of samples/blocks_cavern.toml; expected values from the
    config's numbers and blockgen's definitions (arched cavern: floor at center y, walls of height
    h, apex at y0 + h + f; rectangle: center ± height/2)."""
    model, cfg = cavern
    arch, bench1, bench2 = cfg.excavations
    assert model.region_names[1:] == (arch.name, bench1.name, bench2.name)
    ax, ay = arch.center_xy_m
    apex = ay + arch.wall_height_m + arch.arch_rise_m
    half = arch.span_m / 2
    b1_bottom = bench1.center_xy_m[1] - bench1.height_m / 2
    b2_bottom = bench2.center_xy_m[1] - bench2.height_m / 2
    assert (apex, ay, b1_bottom, b2_bottom) == (20.0, 10.0, -5.0, -20.0)  # the sample as written

    # arch alone: mid-height (ay + apex)/2 lies above the walls, on the arch's chords
    points = boundary_points(model, [1])
    mid = 0.5 * (ay + apex)
    left, right = _wall_x(arched_cavern(arch.center_xy_m, arch.span_m, arch.wall_height_m,
                                        arch.arch_rise_m).xy_m, mid)
    _assert_points(points, {"crown": (ax, apex), "invert": (ax, ay), "left_wall": (left, mid),
                            "right_wall": (right, mid)})
    radius = (arch.span_m ** 2 / 4 + arch.arch_rise_m ** 2) / (2 * arch.arch_rise_m)
    circle_x = math.sqrt(radius ** 2 - (mid - (apex - radius)) ** 2)
    assert 0 < circle_x - right < 0.1  # inside the arc, on a chord
    _assert_attached(model, [1], points)
    # the arch's floor is the top of bench 1, still in place: the invert rides on a bench block
    assert model.region[_by_name(points)["invert"].block] == 2

    points = boundary_points(model, ["arch", "bench 1"])
    mid = 0.5 * (b1_bottom + apex)
    _assert_points(points, {"crown": (ax, apex), "invert": (ax, b1_bottom),
                            "left_wall": (ax - half, mid), "right_wall": (ax + half, mid)})
    _assert_attached(model, [1, 2], points)
    assert model.region[_by_name(points)["invert"].block] == 3

    points = boundary_points(model, [3, 2, 1])
    mid = 0.5 * (b2_bottom + apex)
    _assert_points(points, {"crown": (ax, apex), "invert": (ax, b2_bottom),
                            "left_wall": (ax - half, mid), "right_wall": (ax + half, mid)})
    _assert_attached(model, [1, 2, 3], points)
    assert (model.region[[p.block for p in points]] == 0).all()


@pytest.mark.parametrize("n_sides, crown_factor", [(36, 1.0), (30, math.cos(math.pi / 30))])
def test_circle_points_on_the_inscribed_polygon(n_sides, crown_factor):
    """36 sides: the crown is a vertex (r above the centre); 30 sides: 90° falls mid-chord, at the
    apothem r cos(π/n). 0° and 180° are vertices in both: the walls are at the centre ± r."""
    c, r = (0.61, 0.305), 0.076
    model = build([(0, 0), (1.22, 0), (1.22, 0.61), (0, 0.61)],
                  [JointSet(45, 0.05, origin_xy_m=(0.013, 0.0)),
                   JointSet(135, 0.05, origin_xy_m=(0.007, 0.0))],
                  excavations=[circle(c, r, n_sides=n_sides)])
    points = boundary_points(model, ["tunnel"])
    _assert_points(points, {"crown": (c[0], c[1] + crown_factor * r),
                            "invert": (c[0], c[1] - crown_factor * r),
                            "left_wall": (c[0] - r, c[1]), "right_wall": (c[0] + r, c[1])})
    _assert_attached(model, [1], points)


def test_horseshoe_points():
    """Flat invert at y0, walls of height h, semicircular roof of radius s/2: crown y0 + h + s/2,
    mid-height y0 + (h + s/2)/2 <= y0 + h, so the walls are at x0 ± s/2."""
    (x0, y0), s, h = (0.5, -3.0), 6.0, 4.0
    model = build([(-10, -10), (10, -10), (10, 10), (-10, 10)], _sets(),
                  excavations=[horseshoe((x0, y0), s, h, name="hs")])
    points = boundary_points(model, [1])
    mid = y0 + (h + s / 2) / 2
    _assert_points(points, {"crown": (x0, y0 + h + s / 2), "invert": (x0, y0),
                            "left_wall": (x0 - s / 2, mid), "right_wall": (x0 + s / 2, mid)})
    _assert_attached(model, [1], points)


def test_asymmetric_opening_uses_its_centroid_and_mid_height():
    """An L-shaped drift (no symmetry): the vertical line goes through the L's area centroid."""
    l_shape = np.array([[2.0, 2.0], [8.0, 2.0], [8.0, 4.0], [4.0, 4.0], [4.0, 7.0], [2.0, 7.0]])
    model = build([(0, 0), (10, 0), (10, 9), (0, 9)], _sets(),
                  excavations=[polygon_excavation(l_shape, name="L")])
    # centroid x of the L: (6·2·5 + 2·3·3) / (12 + 6) = 78 / 18
    xc = (12 * 5.0 + 6 * 3.0) / 18
    points = boundary_points(model, [1])
    _assert_points(points, {"crown": (xc, 4.0), "invert": (xc, 2.0),
                            "left_wall": (2.0, 4.5), "right_wall": (4.0, 4.5)})
    _assert_attached(model, [1], points)


# --------------------------------------------------------------------------- displacement --
def _rigid(pos0, angle, shift):
    """Every block turned by ``angle`` about the origin and shifted by ``shift``."""
    c, s = math.cos(angle), math.sin(angle)
    q = np.array([[c, -s], [s, c]])
    return pos0 @ q.T + shift, np.full(len(pos0), angle), q


def test_points_sit_where_they_were_found_at_rest(cavern):
    model, _ = cavern
    points = boundary_points(model, [1, 2])
    xy = point_positions(points, model.centroid_xy_m, np.zeros(model.n_blocks))
    np.testing.assert_allclose(xy, [p.point_xy_m for p in points], rtol=0, atol=1e-12)


def test_zero_motion_gives_zero_displacement(cavern):
    model, _ = cavern
    points = boundary_points(model, [1])
    pos0, rot0 = model.centroid_xy_m, np.zeros(model.n_blocks)
    u = point_displacement(points, pos0, rot0, pos0)
    assert set(u) == {f"{n}_{c}" for n in POINT_NAMES for c in ("ux_m", "uy_m", "u_m")}
    assert all(v == 0.0 for v in u.values())
    pos, rot, _ = _rigid(pos0, 0.3, (1.0, -2.0))
    assert all(v == 0.0 for v in point_displacement_from(points, pos, rot, pos, rot).values())


def test_rigid_motion_moves_every_point_by_the_rigid_motion(cavern):
    """All blocks turned by θ about the origin and shifted by t: a point p goes to Q p + t."""
    model, _ = cavern
    points = boundary_points(model, [1, 2, 3])
    angle, shift = 0.37, np.array([0.25, -1.5])
    pos, rot, q = _rigid(model.centroid_xy_m, angle, shift)
    u = point_displacement(points, pos, rot, model.centroid_xy_m)
    for p in points:
        expected = q @ p.point_xy_m + shift - p.point_xy_m
        assert u[f"{p.name}_ux_m"] == pytest.approx(expected[0], abs=1e-12)
        assert u[f"{p.name}_uy_m"] == pytest.approx(expected[1], abs=1e-12)
        assert u[f"{p.name}_u_m"] == pytest.approx(np.hypot(*expected), abs=1e-12)


def test_displacement_from_a_reference_is_the_motion_between_placements(cavern):
    """Reference: rigid motion A; now: rigid motion B; u = (Q_B p + t_B) - (Q_A p + t_A). With the
    reference as built it is point_displacement."""
    model, _ = cavern
    pos0 = model.centroid_xy_m
    points = boundary_points(model, [1])
    ref_pos, ref_rot, qa = _rigid(pos0, -0.2, np.array([0.1, 0.05]))
    pos, rot, qb = _rigid(pos0, 0.45, np.array([-0.3, 0.7]))
    u = point_displacement_from(points, pos, rot, ref_pos, ref_rot)
    for p in points:
        expected = (qb @ p.point_xy_m + (-0.3, 0.7)) - (qa @ p.point_xy_m + (0.1, 0.05))
        got = (u[f"{p.name}_ux_m"], u[f"{p.name}_uy_m"])
        assert got == pytest.approx(tuple(expected), abs=1e-12)
    same = point_displacement_from(points, pos, rot, pos0, np.zeros(model.n_blocks))
    assert same == pytest.approx(point_displacement(points, pos, rot, pos0), abs=1e-15)


def test_one_block_turning_moves_only_its_point(rect_model):
    """Block b turned by θ about its own centroid: its point moves by (R(θ) - I) l, the others
    not at all (unless they share the block)."""
    model = rect_model
    points = boundary_points(model, [1])
    crown = _by_name(points)["crown"]
    rot = np.zeros(model.n_blocks)
    rot[crown.block] = theta = 0.8
    u = point_displacement(points, model.centroid_xy_m, rot, model.centroid_xy_m)
    lx, ly = crown.local_xy_m
    expected = (math.cos(theta) * lx - math.sin(theta) * ly - lx,
                math.sin(theta) * lx + math.cos(theta) * ly - ly)
    assert (u["crown_ux_m"], u["crown_uy_m"]) == pytest.approx(expected, abs=1e-12)
    for p in points:
        if p.block != crown.block:
            assert u[f"{p.name}_u_m"] == 0.0


def test_small_rotation_displacement_has_no_cancellation(cavern):
    """A turn of δ ~ 1e-10 rad from a reference turned by θ0 = 0.3 rad: u = δ R(θ0) (-l_y, l_x)
    to a relative O(δ). Differences of cosines and sines taken plainly would lose ~1e-16 / δ =
    1e-6 of it to round-off."""
    model, _ = cavern
    points = boundary_points(model, [1])
    theta0 = 0.3
    ref_rot = np.full(model.n_blocks, theta0)
    rot = ref_rot + 1e-10
    delta = rot[0] - ref_rot[0]  # exact (Sterbenz): the turn actually applied
    pos = model.centroid_xy_m
    u = point_displacement_from(points, pos, rot, pos, ref_rot)
    c, s = math.cos(theta0), math.sin(theta0)
    for p in points:
        lx, ly = p.local_xy_m
        ex, ey = delta * (-c * ly - s * lx), delta * (-s * ly + c * lx)
        assert u[f"{p.name}_ux_m"] == pytest.approx(ex, rel=1e-8, abs=0)
        assert u[f"{p.name}_uy_m"] == pytest.approx(ey, rel=1e-8, abs=0)


def test_frames_broadcast_over_leading_axes(rect_model):
    """pos (n_frames, n_blocks, 2): one value per frame, equal to each frame alone."""
    model = rect_model
    points = boundary_points(model, [1])
    frames = [_rigid(model.centroid_xy_m, a, np.array([a, -a]))[:2] for a in (0.0, 0.1, -0.4)]
    pos = np.stack([f[0] for f in frames])
    rot = np.stack([f[1] for f in frames])
    u = point_displacement(points, pos, rot, model.centroid_xy_m)
    assert point_positions(points, pos, rot).shape == (3, 4, 2)
    for i, (p_i, r_i) in enumerate(frames):
        one = point_displacement(points, p_i, r_i, model.centroid_xy_m)
        for key, value in one.items():
            assert u[key].shape == (3,)
            assert u[key][i] == pytest.approx(value, abs=1e-15)


def test_inputs_are_not_modified(rect_model):
    model = rect_model
    points = boundary_points(model, [1])
    pos, rot, _ = _rigid(model.centroid_xy_m, 0.2, np.array([1.0, 2.0]))
    ref_pos, ref_rot = model.centroid_xy_m.copy(), np.zeros(model.n_blocks)
    for a in (pos, rot, ref_pos, ref_rot):
        a.setflags(write=False)  # any write would raise
    before = [a.copy() for a in (pos, rot, ref_pos, ref_rot)]
    point_positions(points, pos, rot)
    point_displacement(points, pos, rot, ref_pos)
    point_displacement_from(points, pos, rot, ref_pos, ref_rot)
    for a, b in zip((pos, rot, ref_pos, ref_rot), before):
        np.testing.assert_array_equal(a, b)


# ---------------------------------------------------------------------------------- errors --
@pytest.mark.parametrize("regions, match", [([7], r"regions \[7\]"), (0, r"regions \[0\]"),
                                            ([1, 9], r"regions \[9\]"),
                                            (["bench 9"], r"regions \['bench 9'\]"),
                                            ([], "regions is empty")])
def test_regions_that_select_nothing_are_named(cavern, regions, match):
    model, _ = cavern
    with pytest.raises(ValueError, match=match) as info:
        boundary_points(model, regions)
    assert "'arch'" in str(info.value)  # lists the model's stages


def test_region_of_wrong_type_is_a_type_error(rect_model):
    with pytest.raises(TypeError, match="regions"):
        boundary_points(rect_model, [1.0])


def test_separate_parts_missed_by_a_line_give_the_largest_part(cavern):
    """Arch and bench 2 without bench 1: the mid-height line y = 0 falls between them; the points
    are those of bench 2 (360 m² against the arch's ~196 m²), with a warning."""
    model, cfg = cavern
    bench2 = cfg.excavations[2]
    (bx, by), w, h = bench2.center_xy_m, bench2.width_m, bench2.height_m
    with pytest.warns(UserWarning, match=r"regions \[1, 3\] has 2 separate parts"):
        points = boundary_points(model, [1, 3])
    _assert_points(points, {"crown": (bx, by + h / 2), "invert": (bx, by - h / 2),
                            "left_wall": (bx - w / 2, by), "right_wall": (bx + w / 2, by)})
    _assert_attached(model, [1, 3], points)


def test_twin_tunnels_use_the_larger_tunnel():
    """Tunnels of radius 1 at x = 3 and 1.5 at x = 9 (two stages): the area centroid x = (1·3 +
    2.25·9) / 3.25 ≈ 7.15 lies between them, so the points are those of the larger tunnel (a
    36-gon: vertices at 90° steps, so the points are at its centre ± r)."""
    model = build([(0, 0), (12, 0), (12, 8), (0, 8)], _sets(),
                  excavations=[circle((3.0, 4.0), 1.0, name="small"),
                               circle((9.0, 4.0), 1.5, name="large")])
    with pytest.warns(UserWarning, match="largest part"):
        points = boundary_points(model, ["small", "large"])
    _assert_points(points, {"crown": (9.0, 5.5), "invert": (9.0, 2.5), "left_wall": (7.5, 4.0),
                            "right_wall": (10.5, 4.0)})
    _assert_attached(model, [1, 2], points)


def test_opening_on_the_domain_outline_warns():
    """A cut reaching the top of the domain: no rock above its crown."""
    model = build([(0, 0), (8, 0), (8, 6), (0, 6)], _sets(),
                  excavations=[rectangle((4.0, 5.0), 2.0, 2.0, name="cut")])
    with pytest.warns(UserWarning, match="crown .* no rock beyond"):
        points = boundary_points(model, [1])
    np.testing.assert_allclose(points[0].point_xy_m, (4.0, 6.0), atol=TOL)


def test_bad_placements_are_named(rect_model):
    points = boundary_points(rect_model, [1])
    n = rect_model.n_blocks
    with pytest.raises(ValueError, match="rot must have shape"):
        point_displacement(points, np.zeros((n, 2)), np.zeros(n - 1), np.zeros((n, 2)))
    with pytest.raises(ValueError, match="pos has 2 blocks"):
        point_positions(points, np.zeros((2, 2)), np.zeros(2))
    with pytest.raises(ValueError, match="block must be >= 0"):
        BoundaryPoint("crown", -1, (0, 0), (0, 0))
    twice = [points[0], BoundaryPoint("crown", 0, (0, 0), (0, 0))]
    with pytest.raises(ValueError, match=r"repeated: \['crown'\]"):
        point_positions(twice, np.zeros((n, 2)), np.zeros(n))
