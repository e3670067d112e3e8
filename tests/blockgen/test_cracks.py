"""Potential cracks (Jiang et al., expanded DEM; docs/blocks.md §4): convex glued sub-blocks of the intact blocks."""

import math

import numpy as np
import pytest
import shapely

from rockmass.blockgen import (SOURCE_CRACK, Cracks, JointSet, build, check_model, circle,
                               from_json_dict, to_json_dict)
from rockmass.blockgen.model import KIND_GLUED

from ._fixtures import square

SETS = [JointSet(30, 1.7), JointSet(100, 2.3)]


def _jointed(cracks=None, seed=1, **kw):
    return build(square(10.0), SETS, excavations=[circle((5, 5), 1.5, "tunnel")], cracks=cracks,
                 seed=seed, **kw)


def _crack(model):
    return (model.contact_kind == KIND_GLUED) & (model.contact_source == SOURCE_CRACK)


def _parent_of(model, parents):
    """Index of the block of ``parents`` (a crack-free model) holding each block's centroid."""
    tree = shapely.STRtree(parents.to_shapely())
    pts = shapely.points(model.centroid_xy_m)
    i, j = tree.query(pts, predicate="within")
    out = np.full(model.n_blocks, -1)
    out[i] = j
    return out


@pytest.mark.parametrize("pattern", ["voronoi", "triangular"])
def test_invariants_hold_area_is_exact_and_every_block_is_convex(pattern):
    m = _jointed(Cracks(0.5, pattern=pattern))
    inv = check_model(m)
    assert inv["ok"] and inv["n_concave"] == 0
    assert inv["area_balance_rel"] <= 1e-9
    assert _crack(m).sum() > 100


@pytest.mark.parametrize("pattern", ["voronoi", "triangular"])
def test_every_internal_edge_of_a_parent_is_a_glued_crack_and_every_crack_is_internal(pattern):
    plain = _jointed()
    m = _jointed(Cracks(0.5, pattern=pattern))
    parent = _parent_of(m, plain)
    assert (parent >= 0).all()
    a, b = m.contact_blocks.T
    interior = b >= 0
    same = np.zeros(m.n_contacts, bool)
    same[interior] = parent[a[interior]] == parent[b[interior]]
    assert np.array_equal(same, _crack(m))
    # without short-edge snapping (which may move a joint node by < min_edge), the pieces of each
    # parent add up to it exactly
    plain, m = _jointed(snap_edges=False), _jointed(Cracks(0.5, pattern=pattern), snap_edges=False)
    parent = _parent_of(m, plain)
    sums = np.bincount(parent, m.area_m2, plain.n_blocks)
    np.testing.assert_allclose(sums, plain.area_m2, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("pattern", ["voronoi", "triangular"])
def test_same_seed_same_model_other_seed_other_cracks(pattern):
    c = Cracks(0.6, pattern=pattern)
    one, two, other = _jointed(c, 7), _jointed(c, 7), _jointed(c, 8)
    assert to_json_dict(one) == to_json_dict(two)
    assert one.n_blocks != other.n_blocks or not np.array_equal(one.xy_m, other.xy_m)


def test_round_trip_keeps_the_crack_source():
    m = _jointed(Cracks(0.5))
    back = from_json_dict(to_json_dict(m))
    assert np.array_equal(_crack(back), _crack(m))


def test_voronoi_piece_count_and_mean_area_follow_the_target_size():
    # an uncut 10 m square, size 1 m: seed density 1 / m², so about 100 pieces of about 1 m²
    m = build(square(10.0), cracks=Cracks(1.0, jitter=0.3), seed=3)
    assert check_model(m)["ok"]
    assert 90 <= m.n_blocks <= 110
    interior = np.ones(m.n_blocks, bool)
    interior[m.contact_blocks[m.contact_blocks[:, 1] < 0, 0]] = False
    assert np.mean(m.area_m2[interior]) == pytest.approx(1.0, rel=0.1)


def test_regular_hexagons_and_triangles_away_from_the_boundary_have_area_size_squared():
    for pattern, n_sides in (("voronoi", 6), ("triangular", 3)):
        m = build(square(10.0), cracks=Cracks(0.8, pattern=pattern, jitter=0.0, angle_deg=17.0),
                  seed=5)
        boundary = np.zeros(m.n_blocks, bool)
        boundary[m.contact_blocks[m.contact_blocks[:, 1] < 0, 0]] = True
        inner = np.flatnonzero(~boundary & (np.diff(m.offsets) == n_sides))
        assert len(inner) > 50
        # hexagon (√3/2)a² with a = s√(2/√3); triangle (√3/4)t² with t = s√(4/√3): both s²
        np.testing.assert_allclose(m.area_m2[inner], 0.8 ** 2, rtol=1e-9)


def test_within_m_subdivides_only_blocks_near_the_excavation():
    plain = _jointed()
    m = _jointed(Cracks(0.5, within_m=1.0))
    parent = _parent_of(m, plain)
    counts = np.bincount(parent, minlength=plain.n_blocks)
    opening = circle((5, 5), 1.5).polygon()
    far = shapely.distance(plain.to_shapely(), opening) > 1.0 + 1e-9
    assert (counts[far] == 1).all()
    assert (counts[~far & (plain.region == 0)] > 1).any()
    assert (counts[plain.region > 0] == 1).all()  # excavated blocks are left alone by default


def test_zone_limits_the_subdivision_to_blocks_whose_point_lies_inside():
    plain = _jointed()
    zone = [(0, 0), (4, 0), (4, 4), (0, 4)]
    m = _jointed(Cracks(0.5, zone_xy_m=zone))
    counts = np.bincount(_parent_of(m, plain), minlength=plain.n_blocks)
    inside = shapely.contains(shapely.Polygon(zone), shapely.point_on_surface(plain.to_shapely()))
    assert (counts[~inside] == 1).all() and (counts[inside] > 1).any()


def test_no_sliver_is_left_in_the_subdivided_blocks():
    for pattern in ("voronoi", "triangular"):
        m = _jointed(Cracks(0.4, pattern=pattern))
        polys = m.to_shapely()
        width = 2 * shapely.area(polys) / shapely.length(polys)
        cracked = np.unique(m.contact_blocks[_crack(m)].ravel())
        kept = m.quality.cracks.get("slivers_kept", 0)
        n_thin = int((width[cracked] < m.quality.tolerances.sliver_width_m).sum())
        assert n_thin <= kept


@pytest.mark.parametrize("kwargs, field", [({"size_m": 0.0}, "cracks.size_m"),
                                           ({"size_m": 1.0, "pattern": "hex"}, "cracks.pattern"),
                                           ({"size_m": 1.0, "jitter": 0.6}, "cracks.jitter"),
                                           ({"size_m": 1.0, "within_m": -1.0}, "cracks.within_m"),
                                           ({"size_m": math.nan}, "cracks.size_m"),
                                           ({"size_m": 1.0, "zone_xy_m": [(0, 0), (1, 1)]},
                                            "cracks.zone_xy_m")])
def test_bad_crack_settings_name_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field.replace(".", r"\.")):
        Cracks(**kwargs)


def test_within_m_without_excavations_and_cracks_without_convex_are_refused():
    with pytest.raises(ValueError, match=r"cracks\.within_m"):
        build(square(2.0), SETS, cracks=Cracks(0.5, within_m=1.0))
    with pytest.raises(ValueError, match="convex=True"):
        build(square(2.0), SETS, cracks=Cracks(0.5), convex=False)


@pytest.mark.parametrize("pattern", ["voronoi", "triangular"])
def test_local_rebuild_gives_the_blocks_of_a_full_polygonisation(monkeypatch, pattern):
    # two routes, one answer: the builder's local rebuild after merges, cuts and cracks against
    # polygonising the whole network every time (excavation stages inside a cracked zone)
    import rockmass.blockgen.builder as builder
    from rockmass.blockgen import rectangle

    def model():
        return build(square(10.0), SETS, excavations=[circle((5, 5), 1.5, "arch"),
                                                      rectangle((5, 3), 3.0, 1.0, "bench")],
                     cracks=Cracks(0.5, pattern=pattern, within_m=1.5), seed=4)

    local = model()

    def full(noded, faces, region, changed, excavations, grid_m):
        new = builder.polygonize_segments(noded)
        return new, builder._regions(new, excavations)

    monkeypatch.setattr(builder, "_local_faces", full)
    reference = model()
    assert check_model(local)["ok"]
    a = sorted(g.wkb for g in shapely.normalize(local.to_shapely()))
    b = sorted(g.wkb for g in shapely.normalize(reference.to_shapely()))
    assert a == b
    assert np.array_equal(np.sort(local.contact_length_m), np.sort(reference.contact_length_m))
