"""Vertices where a block's boundary runs straight on (T-junctions, snapped round-off).

Blocks cut from traces keep a vertex wherever a neighbour's corner meets an edge. The contact
model must see such a boundary as one face: two blocks at rest that share it touch along all of
it with no overlap. The oracle is the geometry itself (shapely: the length of the shared boundary,
no area in common). The two blocks are taken, coordinates exact, from a 10⁴-block random trace map
(benchmarks/bench_blockgen.py) where they stopped the first step with a false 5.7 mm overlap.
"""

import numpy as np
import pytest
import shapely

from rockmass.blockgen.model import KIND_JOINT, BlockModel
from rockmass.solver import Coulomb, Fix, Material, Settings, Stage
from rockmass.solver.engine import ring_neighbours, rounded_corners, strip_collinear
from rockmass.solver.runner import run

LOWER = [(44.93890629534144, 99.75688016973436), (44.85547294013668, 99.8882720322581),
         (44.848991618840955, 99.89847889589146), (44.48187573766336, 100.47661745082587),
         (44.2114289640449, 100.10240248846821), (44.37852676631883, 99.06782375101466),
         (45.0580412998097, 99.56926491565537)]
UPPER = [(45.187121674302034, 101.92683258152101), (44.343175815884024, 100.6950437745545),
         (44.48187573766336, 100.47661745082587), (44.848991618840955, 99.89847889589146),
         (44.85547294013668, 99.8882720322581), (44.87810755090322, 99.89414745336398),
         (45.99897418706678, 100.1850984909106), (46.954666890902445, 100.43317419837695),
         (45.65536894008983, 102.26687869569287), (45.53575738030486, 102.43568697792944)]


def _pair_model() -> BlockModel:
    xy = np.array(LOWER + UPPER)
    domain = np.array([[40, 95], [50, 95], [50, 105], [40, 105.0]])
    return BlockModel(xy, [0, len(LOWER), len(xy)], [0, 0], ("rock",), [[0, 1]], [0.697],
                      [KIND_JOINT], [0], ("j",), domain)


@pytest.mark.parametrize("rounding", [0.005, 0.001])
def test_blocks_sharing_a_boundary_with_straight_on_vertices_touch_along_it_at_rest(rounding):
    lower, upper = shapely.Polygon(LOWER), shapely.Polygon(UPPER)
    assert lower.intersection(upper).area < 1e-9  # they do not overlap
    shared = lower.boundary.intersection(upper.boundary).length
    settings = Settings(joints={"default": Coulomb(20e9, 10e9, 40.0)},
                        material=Material(2700.0, 20e9, 12e9), gravity_m_s2=(0.0, 0.0),
                        stages=(Stage("rest", max_steps=1, tolerance=1e-30),),
                        fixes=(Fix("blocks:0"),), rounding_m=rounding)
    result = run(_pair_model(), settings)
    assert result.stages[0].status != "overlap"
    contacts = result.contacts
    assert np.max(np.abs(contacts["overlap_m"])) < 1e-9
    assert np.sum(contacts["length_m"]) == pytest.approx(shared, rel=1e-6)


def test_strip_collinear_drops_a_vertex_within_the_tolerance_and_keeps_corners():
    # a 1 m square whose right edge has a vertex 1e-7 m off the straight line
    xy = np.array([(0, 0), (1, 0), (1 + 1e-7, 0.5), (1, 1), (0, 1.0)])
    offsets = np.array([0, 5])
    kept, off = strip_collinear(xy, offsets, tol_m=1e-5)
    assert off.tolist() == [0, 4] and (1 + 1e-7, 0.5) not in map(tuple, kept)
    kept, off = strip_collinear(xy, offsets, tol_m=1e-8)  # 1e-7 m is a corner at this tolerance
    assert off.tolist() == [0, 5]


def test_the_inner_polygon_is_inset_at_a_straight_on_vertex():
    # left unstripped, the vertex (1, 0.5) on the right edge gets no arc but its centre is inset
    loc = np.array([(0, 0), (1, 0), (1, 0.5), (1, 1), (0, 1.0)]) - 0.5
    off = np.array([0, 5])
    edge = loc[ring_neighbours(off)[0]] - loc
    normal = np.column_stack([edge[:, 1], -edge[:, 0]]) / np.hypot(*edge.T)[:, None]
    centre, tangent, radius = rounded_corners(loc, off, normal, 0.01)
    np.testing.assert_allclose(centre[2], loc[2] - 0.01 * np.array([1.0, 0.0]), atol=1e-15)
    assert tangent[2] == 0.0 and radius[0] == 0.01
    np.testing.assert_allclose(centre[1], loc[1] + 0.01 * np.array([-1.0, 1.0]), atol=1e-15)


def test_the_pairs_straight_on_vertices_escaped_the_old_turn_rule_but_not_the_chord_rule():
    # the shared vertices turn by just over 1e-9 (the rule before: kept as corners) while lying
    # 1e-11 m off the chord between their neighbours (the rule now, 0.01 d: dropped)
    shared = [(LOWER, 1), (LOWER, 2), (UPPER, 3)]
    for poly, i in shared:
        p = np.array(poly)
        e0, e1 = p[i] - p[i - 1], p[(i + 1) % len(p)] - p[i]
        cross = abs(e0[0] * e1[1] - e0[1] * e1[0])
        assert cross / (np.hypot(*e0) * np.hypot(*e1)) > 1e-9
        assert cross / np.hypot(*(e0 + e1)) < 1e-10
    xy, off = strip_collinear(np.array(LOWER + UPPER), np.array([0, len(LOWER), len(LOWER) + len(UPPER)]),
                              tol_m=0.01 * 0.005)
    kept = {id(LOWER): {tuple(v) for v in xy[off[0]:off[1]]},
            id(UPPER): {tuple(v) for v in xy[off[1]:off[2]]}}
    assert not any(poly[i] in kept[id(poly)] for poly, i in shared)
