"""Edges shorter than the minimum edge 2d collapse consistently, keep convexity and exact areas."""

import math

import numpy as np
import pytest
import shapely

from rockmass.blockgen import Cracks, JointSet, build, check_model, circle
from rockmass.blockgen.model import KIND_EXCAVATION, KIND_TRACE

from ._fixtures import square

EPS = 0.002  # the tiny edge, well below min_edge = 2 · rounding_m = 0.01
ROUNDING = 0.005


def _edges(model):
    """Lengths of every block edge (an independent recomputation from the vertices)."""
    out = []
    for i in range(model.n_blocks):
        xy = model.polygon(i)
        out.append(np.hypot(*(np.roll(xy, -1, axis=0) - xy).T))
    return np.concatenate(out)


def _near_concurrent_traces():
    # x = 0.5, y = 0.5 and a 60° line crossing y = 0.5 at x = 0.5 + EPS: nodes EPS apart
    t = math.tan(math.radians(60))
    return np.array([[[0.5, 0], [0.5, 1]], [[0, 0.5], [1, 0.5]],
                     [[0.5 + EPS - 0.5 / t, 0.0], [0.5 + EPS + 0.5 / t, 1.0]]])


def test_without_snapping_the_short_edge_is_there_and_listed():
    m = build(square(), traces=_near_concurrent_traces(), rounding_m=ROUNDING, snap_edges=False)
    assert _edges(m).min() == pytest.approx(EPS, rel=1e-6)
    assert m.quality.tiny_edges["count"] > 0 and m.quality.edges_snapped is None


def test_short_edges_collapse_and_the_model_stays_valid():
    m = build(square(), traces=_near_concurrent_traces(), rounding_m=ROUNDING)
    inv = check_model(m)
    assert inv["ok"] and inv["n_concave"] == 0
    assert _edges(m).min() >= 2 * ROUNDING
    report = m.quality.edges_snapped
    assert report["count"] >= 1 and report["not_snapped"] == 0
    assert m.quality.tiny_edges["count"] == 0
    first = report["changes"][0]
    assert first["edge_m"] == pytest.approx(EPS, rel=1e-6)
    # every node moved by less than the edge it collapsed
    for change in report["changes"]:
        for xy in change["from_xy_m"]:
            assert math.dist(xy, change["to_xy_m"]) <= change["edge_m"] + 1e-12
    # the traces keep their label: every interior contact is still a trace contact
    interior = m.contact_blocks[:, 1] >= 0
    assert (m.contact_kind[interior] == KIND_TRACE).all()


def test_a_node_near_a_domain_corner_moves_onto_the_corner_and_the_outline_is_unchanged():
    traces = np.array([[[EPS, 0.0], [0.6, 1.0]], [[0.0, 0.5], [1.0, 0.5]]])
    m = build(square(), traces=traces, rounding_m=ROUNDING)
    assert check_model(m)["ok"]
    change = m.quality.edges_snapped["changes"][0]
    assert change["to_xy_m"] == [0.0, 0.0]
    assert _edges(m).min() >= 2 * ROUNDING
    # the blocks still cover the unit square exactly
    union = shapely.union_all(m.to_shapely())
    assert union.symmetric_difference(shapely.Polygon(square())).area <= 1e-12


def test_excavation_stage_area_is_exact_after_snapping():
    # a 36-gon of radius r has area (n/2) r² sin(2π/n); joints at 0.05 m pass near its vertices
    m = build(square(), [JointSet(0, 0.05, origin_xy_m=(0, 0.0003)),
                         JointSet(90, 0.05, origin_xy_m=(0.0007, 0))],
              excavations=[circle((0.5, 0.5), 0.2, "tunnel", 36)], rounding_m=0.0025)
    assert check_model(m)["ok"]
    assert m.quality.edges_snapped["count"] > 0
    exact = 36 / 2 * 0.2 ** 2 * math.sin(2 * math.pi / 36)
    assert m.area_m2[m.region == 1].sum() == pytest.approx(exact, rel=1e-9)
    assert m.contact_length_m[m.contact_kind == KIND_EXCAVATION].sum() == pytest.approx(
        36 * 2 * 0.2 * math.sin(math.pi / 36), rel=1e-9)


@pytest.mark.parametrize("pattern, seed", [("voronoi", 2), ("triangular", 3)])
def test_cracked_models_have_no_edge_below_the_minimum_unless_listed(pattern, seed):
    m = build(square(10.0), [JointSet(30, 1.7), JointSet(100, 2.3)],
              excavations=[circle((5, 5), 1.5)], cracks=Cracks(0.5, pattern=pattern), seed=seed)
    assert check_model(m)["ok"]
    min_edge = m.quality.tolerances.min_edge_m
    n_short = int((_edges(m) < min_edge).sum())
    # the report counts short edges per block (a shared edge twice), and every one left is an edge
    # the snapping rule refused (listed as not_snapped)
    assert n_short == m.quality.tiny_edges["count"]
    assert n_short <= 2 * m.quality.edges_snapped["not_snapped"]


def test_a_vertex_off_its_line_by_round_off_is_not_reflex_but_a_real_notch_is():
    from rockmass.blockgen.convex import reflex_vertices
    from rockmass.blockgen.tolerances import model_tolerances

    tol = model_tolerances(141.0, 1.0)
    assert tol.reflex_m == 8 * tol.grid_m

    def ring(h):  # CCW unit square with a vertex h inside the bottom edge, between 1 mm edges
        return np.array([[0, 0], [0.001, h], [0.002, 0], [1, 0], [1, 1], [0, 1]], float)

    # 2 grid cells inside: the turn's sine (≈ 2h / 1 mm ≈ 5e-7) exceeds reflex_sin, the height does not
    assert len(reflex_vertices(ring(2 * tol.grid_m), tol.reflex_sin)) == 1
    assert len(reflex_vertices(ring(2 * tol.grid_m), tol.reflex_sin, tol.reflex_m)) == 0
    assert reflex_vertices(ring(20 * tol.grid_m), tol.reflex_sin, tol.reflex_m).tolist() == [1]
    # pushed outwards the vertex itself is convex (its neighbours are then the notch)
    assert 1 not in reflex_vertices(ring(-20 * tol.grid_m), tol.reflex_sin, tol.reflex_m)


def test_unique_rows_matches_numpy_unique():
    from rockmass.blockgen.network import unique_rows

    rng = np.random.default_rng(11)  # fixed seed: rows with many repeats and negative values
    a = rng.integers(-3, 3, (500, 4))
    uniq, inv, counts = unique_rows(a)
    ref = np.unique(a, axis=0, return_inverse=True, return_counts=True)
    assert np.array_equal(uniq, ref[0]) and np.array_equal(inv, ref[1].ravel())
    assert np.array_equal(counts, ref[2])
    assert np.array_equal(uniq[inv], a)



NEEDLE_CASE = """
[dfn]
seed = 5904729961632443646
realizations = 1
[dfn.domain]
min_m = [0.0, 0.0, 0.0]
max_m = [60.0, 60.0, 40.0]
[[dfn.sets]]
name = "J1"
orientation = {distribution = "fisher", dip_deg = 50.0, dip_direction_deg = 270.0, kappa = 20.0}
size = {distribution = "power_law", r_min_m = 3.53, r_max_m = 40.0, alpha = 2.5}
intensity = {measure = "P32", value = 0.6666666666666666}
[[dfn.sets]]
name = "J2"
orientation = {distribution = "fisher", dip_deg = 80.0, dip_direction_deg = 10.0, kappa = 20.0}
size = {distribution = "power_law", r_min_m = 2.51, r_max_m = 40.0, alpha = 2.5}
intensity = {measure = "P32", value = 0.6666666666666666}
[[dfn.sets]]
name = "J3"
orientation = {distribution = "fisher", dip_deg = 70.0, dip_direction_deg = 150.0, kappa = 20.0}
size = {distribution = "power_law", r_min_m = 2.84, r_max_m = 40.0, alpha = 2.5}
intensity = {measure = "P32", value = 0.6666666666666666}
[[dfn.sections]]
name = "drift face"
point_m = [30.0, 30.0, 0.0]
dip_deg = 90.0
dip_direction_deg = 0.0
window_uv_m = [[-20.0, 5.0], [20.0, 5.0], [20.0, 35.0], [-20.0, 35.0]]
[blocks]
seed = 5904729961632443646
rounding_m = 0.05
min_edge_m = 0.1
dangling = "glued"
[blocks.dfn_section]
section = "drift face"
realization = 0
[[blocks.excavations]]
shape = "horseshoe"
name = "drift"
center_xy_m = [0.0, 15.0]
span_m = 6.0
wall_height_m = 3.0
"""


def test_snapping_leaves_no_needle_block_on_a_dfn_section(tmp_path):
    """Seed-001 sets at P32 = 2 on a drift section (a case of samples/study_dfn_seed001.toml with
    min_edge_m = 0.1): a collapse used to turn a thin triangle (mean width 2A/P = 0.017 m) into a
    needle of width 7.6e-13 m, which drove the DEM time step to 1e-10 s. The rule now refuses it:
    every block keeps a mean width above 1 mm (measured: 0.021 m, the same thinnest block as
    without snapping)."""
    from rockmass.blockgen import read_json
    from rockmass.cli import main

    config = tmp_path / "case.toml"
    config.write_text(NEEDLE_CASE)
    assert main(["blocks", str(config), "--out", str(tmp_path / "out")]) == 0
    model = read_json(tmp_path / "out" / "blocks.json")
    perimeter = np.array([shapely.Polygon(model.xy_m[a:b]).length
                          for a, b in zip(model.offsets[:-1], model.offsets[1:])])
    width = 2 * model.area_m2 / perimeter
    assert width.min() > 1e-3, width.min()

