"""3D blocks by exact plane cutting: counts and volumes from closed forms, disks that do or do not cut
a block through, and convexity of every piece."""

import math

import numpy as np
import pytest

from rockmass.blockgen.blocks3d import Planes, cut_box, persistent_set_planes
from rockmass.blockgen.polyhedra import box_polyhedron, split

UNIT = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]])


def _orthogonal_sets(box, spacing, origin=(0.0, 0.0, 0.0)):
    return [persistent_set_planes(box, axis, spacing, origin_m=origin, label=i)
            for i, axis in enumerate(np.eye(3))]


def _disk(normal, centre, radius, label=0):
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    c = np.asarray(centre, float)
    return Planes(n[None], np.array([n @ c]), np.array([label]), c[None], np.array([radius]))


def _assert_convex(piece, tol=1e-9):
    vertices = piece.vertices_m()
    for face in piece.faces:
        outward = np.cross(face[1] - face[0], face[2] - face[0])
        outward /= np.linalg.norm(outward)
        assert ((vertices - face[0]) @ outward <= tol).all()


@pytest.mark.parametrize("spacing, n_per_axis", [(0.5, 2), (0.25, 4), (0.2, 5)])
def test_cube_cut_by_three_orthogonal_sets_gives_cubes_of_side_s(spacing, n_per_axis):
    blocks = cut_box(UNIT, *_orthogonal_sets(UNIT, spacing))
    assert blocks.n_blocks == len(blocks.pieces) == n_per_axis ** 3
    np.testing.assert_allclose(blocks.volume_m3, spacing ** 3, rtol=1e-12)
    assert abs(blocks.volume_m3.sum() - 1.0) < 1e-9
    # every internal face shared by two cubes, wholly fractured
    assert len(blocks.links) == 3 * (n_per_axis - 1) * n_per_axis ** 2
    np.testing.assert_allclose(blocks.link_area_m2, spacing ** 2, rtol=1e-9)
    np.testing.assert_allclose(blocks.link_real_area_m2, blocks.link_area_m2, rtol=1e-12)


def test_oblique_sets_conserve_volume_and_give_convex_pieces():
    box = np.array([[-1.0, 2.0, 0.5], [2.0, 4.5, 3.0]])
    rng = np.random.default_rng(5)
    normals = rng.normal(size=(3, 3))
    sets = [persistent_set_planes(box, n, s, origin_m=rng.uniform(0, 1, 3), label=i)
            for i, (n, s) in enumerate(zip(normals, (0.4, 0.55, 0.7)))]
    blocks = cut_box(box, *sets)
    assert len(blocks.pieces) > 50
    assert abs(blocks.volume_m3.sum() / np.prod(box[1] - box[0]) - 1.0) < 1e-9
    assert (blocks.volume_m3 > 0).all()
    for piece in blocks.pieces:
        _assert_convex(piece)
    # pieces cut only by persistent planes are all separate blocks
    assert blocks.n_blocks == len(blocks.pieces)


def test_disk_inside_a_block_leaves_one_block_with_a_real_face_of_the_disk_area():
    radius = 0.3
    blocks = cut_box(UNIT, _disk([0, 0, 1], [0.5, 0.5, 0.5], radius))
    assert len(blocks.pieces) == 2
    assert blocks.n_blocks == 1
    assert len(blocks.links) == 1
    assert blocks.link_area_m2[0] == pytest.approx(1.0, rel=1e-12)
    # the 256-gon of the disk: relative area error (2π/256)²/6 ≈ 1e-4
    assert blocks.link_real_area_m2[0] == pytest.approx(math.pi * radius ** 2, rel=2e-4)


def test_disk_covering_the_section_separates_the_block():
    blocks = cut_box(UNIT, _disk([0, 0, 1], [0.5, 0.5, 0.4], 0.75))  # 0.75 > √2/2: covers the square
    assert len(blocks.pieces) == 2 and blocks.n_blocks == 2
    np.testing.assert_allclose(sorted(blocks.block_volumes_m3()), [0.4, 0.6], rtol=1e-12)


def test_disk_that_misses_a_block_does_not_cut_it():
    # two halves by a persistent plane x = 0.5; a small disk at z = 0.5 inside the left half only
    sets = [persistent_set_planes(UNIT, [1, 0, 0], 0.5, label=0)]
    blocks = cut_box(UNIT, *sets, _disk([0, 0, 1], [0.25, 0.5, 0.5], 0.1, label=1))
    assert len(blocks.pieces) == 3
    assert blocks.n_blocks == 2
    np.testing.assert_allclose(sorted(blocks.block_volumes_m3()), [0.5, 0.5], rtol=1e-12)


def test_poisson_orthogonal_sets_give_the_product_of_interval_counts():
    """With Poisson plane positions (P10 = λ on each axis) the box falls into Π(1 + N_i) blocks,
    N_i the planes crossing axis i; E[count] = Π(1 + λL)."""
    rng = np.random.default_rng(11)
    lam, counts, expected = 3.0, [], []
    for _ in range(12):
        sets, n_planes = [], []
        for i, axis in enumerate(np.eye(3)):
            offsets = np.sort(rng.uniform(0.0, 1.0, rng.poisson(lam)))
            n_planes.append(len(offsets))
            m = len(offsets)
            sets.append(Planes(np.tile(axis, (m, 1)), offsets, np.full(m, i), np.zeros((m, 3)),
                               np.full(m, np.inf)))
        blocks = cut_box(UNIT, *sets)
        counts.append(blocks.n_blocks)
        expected.append(math.prod(1 + n for n in n_planes))
        assert abs(blocks.volume_m3.sum() - 1.0) < 1e-9
    assert counts == expected


def test_a_plane_through_a_face_or_an_edge_does_not_make_an_empty_piece():
    cube = box_polyhedron(UNIT)
    below, above, cap = split(cube, [0, 0, 1], 1.0, 0, 1e-12)     # along the top face
    assert above is None and cap is None and below is cube
    below, above, cap = split(cube, np.array([1, 1, 0]) / math.sqrt(2), 0.0, 0, 1e-12)  # edge
    assert below is None and above is cube
    below, above, cap = split(cube, np.array([1, 1, 0]) / math.sqrt(2), math.sqrt(2) / 2, 0, 1e-12)
    assert below.volume_m3() == pytest.approx(0.5) and above.volume_m3() == pytest.approx(0.5)
    _assert_convex(below)
    _assert_convex(above)


def test_a_tunnel_through_a_cube_of_blocks_removes_its_volume_and_leaves_a_free_surface():
    from rockmass.blockgen.openings3d import Tunnel, circle_section

    box = np.array([[0.0, 0.0, 0.0], [2.0, 2.0, 2.0]])
    section = circle_section(0.5, 16)
    tunnel = Tunnel(section, centre_m=(1.0, 0.0, 1.0), trend_deg=0.0)   # along +y
    blocks = cut_box(box, *_orthogonal_sets(box, 0.5, origin=(0.1, 0.1, 0.1)), tunnels=(tunnel,))
    x, y = section.T
    section_area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    rock = ~blocks.excavated
    assert abs(blocks.volume_m3[rock].sum() - (8.0 - 2.0 * section_area)) < 1e-9 * 8.0
    assert abs(blocks.volume_m3[~blocks.excavated].sum() + blocks.volume_m3[blocks.excavated].sum() - 8.0) < 1e-9
    # wall cuts between rock pieces are glued back: the in-situ blocks are the 5 x 5 x 5 cells of the
    # offset sets (planes at 0.1, 0.6, 1.1, 1.6), none of which lies wholly inside the tunnel (the
    # nearest cell corner is 0.57 m from the axis) or falls apart around it
    assert (blocks.block_id[blocks.excavated] == -1).all()
    assert blocks.n_blocks == 125
    for piece in blocks.pieces:
        _assert_convex(piece)


def test_block_shapes_of_boxes_and_of_a_block_glued_from_two_pieces():
    from rockmass.blockgen.block_shapes import block_shapes

    shapes = block_shapes(cut_box([[0, 0, 0], [1, 2, 3]]))
    # a 1 x 2 x 3 box: variances L²/12 along its edges, so semi-axes √(5/12)·(3, 2, 1)
    np.testing.assert_allclose(shapes.semi_axes_m[0], np.sqrt(5 / 12) * np.array([3, 2, 1]), rtol=1e-12)
    assert shapes.surface_area_m2[0] == pytest.approx(22.0)
    cube = block_shapes(cut_box(UNIT))
    assert cube.sphericity[0] == pytest.approx((math.pi / 6) ** (1 / 3), rel=1e-12)   # 0.806
    # a disk inside the cube splits it into two pieces glued outside the disk: still one unit cube
    glued = block_shapes(cut_box(UNIT, _disk([0.3, 0.2, 1.0], [0.5, 0.5, 0.45], 0.2)))
    assert len(glued.volume_m3) == 1
    assert glued.volume_m3[0] == pytest.approx(1.0, rel=1e-12)
    assert glued.surface_area_m2[0] == pytest.approx(6.0, rel=1e-12)
    np.testing.assert_allclose(glued.centroid_m[0], 0.5, rtol=1e-12)
    np.testing.assert_allclose(glued.semi_axes_m[0], math.sqrt(5 / 12), rtol=1e-9)


def test_a_dfn_realization_cut_around_two_crossing_tunnels_conserves_volume():
    from rockmass.blockgen.blocks3d import disk_planes
    from rockmass.blockgen.keyblocks import MODES, keyblocks
    from rockmass.blockgen.openings3d import Tunnel, horseshoe_section
    from rockmass.dfn import FisherOrientation, FractureSetSpec, IntensityP32, generate
    from rockmass.dfn.sizes import PowerLawSize

    sets = [FractureSetSpec(FisherOrientation(d, dd, 20.0), PowerLawSize(r, 10.0, 2.5), IntensityP32(0.25))
            for d, dd, r in ((50, 270, 1.8), (80, 10, 1.3), (70, 150, 1.4))]   # Kiran & Juneja 2022 orientations
    box = np.array([[0.0, 0.0, 0.0], [10.0, 10.0, 8.0]])
    network = generate(sets, box, seed=3)
    tunnels = (Tunnel(horseshoe_section(3.0, 1.5), centre_m=(5.0, 0.0, 3.0), trend_deg=0.0),
               Tunnel(horseshoe_section(3.0, 1.5), centre_m=(0.0, 5.0, 3.0), trend_deg=90.0))
    blocks = cut_box(box, disk_planes(network), tunnels=tunnels)
    assert abs(blocks.volume_m3.sum() / 800.0 - 1.0) < 1e-9
    assert (blocks.volume_m3 > 0).all()
    excavated = blocks.volume_m3[blocks.excavated].sum()
    # the two horseshoe prisms (area 3·1.5 + π·1.5²/2 with a 12-edge roof) overlap in a small cell
    assert 60.0 < excavated < 2 * 10.0 * (4.5 + math.pi * 1.5 ** 2 / 2)
    assert np.isclose(blocks.block_volumes_m3().sum(), 800.0 - excavated, rtol=1e-9)
    results = keyblocks(blocks, {i: (30.0, 0.0) for i in range(len(network.radius_m))})
    assert results and all(r.mode in MODES and r.factor_of_safety >= 0 for r in results)
    for piece in blocks.pieces:
        _assert_convex(piece, tol=1e-8)


def test_piece_volumes_centroids_and_inertia_agree_with_trimesh():
    import trimesh

    box = np.array([[0.0, 0.0, 0.0], [2.0, 1.5, 1.0]])
    rng = np.random.default_rng(8)
    sets = [persistent_set_planes(box, n, 0.6, origin_m=rng.uniform(0, 1, 3), label=i)
            for i, n in enumerate(rng.normal(size=(3, 3)))]
    blocks = cut_box(box, *sets)
    for piece in blocks.pieces[::7]:
        triangles = np.concatenate([np.stack([np.broadcast_to(f[0], (len(f) - 2, 3)), f[1:-1], f[2:]], axis=1)
                                    for f in piece.faces])
        mesh = trimesh.Trimesh(**trimesh.triangles.to_kwargs(triangles))
        volume, first, second = piece.moments()
        assert volume == pytest.approx(mesh.volume, rel=1e-9)
        np.testing.assert_allclose(first / volume, mesh.center_mass, atol=1e-12)
        centroid = first / volume
        covariance = second - volume * np.outer(centroid, centroid)     # ∫(x − x̄)(x − x̄)ᵀ dV
        inertia = np.trace(covariance) * np.eye(3) - covariance          # density 1
        np.testing.assert_allclose(inertia, mesh.moment_inertia, atol=1e-12 + 1e-9 * np.abs(inertia).max())


def test_vtu_holds_every_face_with_its_block_and_keyblock_data(tmp_path):
    import meshio

    from rockmass.blockgen.blocks3d_io import write_blocks3d_vtu
    from rockmass.blockgen.keyblocks import MODES, keyblocks
    from rockmass.blockgen.openings3d import Tunnel, circle_section
    from rockmass.blockgen.polyhedra import polygon_area_3d

    box = np.array([[0.0, 0.0, 0.0], [2.0, 2.0, 2.0]])
    tunnel = Tunnel(circle_section(0.5, 12), centre_m=(1.0, 0.0, 1.0))
    blocks = cut_box(box, *_orthogonal_sets(box, 0.5, origin=(0.1, 0.1, 0.1)), tunnels=(tunnel,))
    table = keyblocks(blocks, {0: (30.0, 0.0), 1: (30.0, 0.0), 2: (30.0, 0.0)})
    path = write_blocks3d_vtu(blocks, tmp_path / "blocks3d.vtu", table)
    mesh = meshio.read(path)
    n_faces = sum(len(p.faces) for p in blocks.pieces)
    assert sum(len(c.data) for c in mesh.cells) == n_faces
    data = {k: np.concatenate(v) for k, v in mesh.cell_data.items()}
    area = np.concatenate([[polygon_area_3d(mesh.points[row]) for row in c.data] for c in mesh.cells])
    # the faces of each piece enclose it: their areas add up to the piece's surface
    for p in (0, len(blocks.pieces) // 2, len(blocks.pieces) - 1):
        assert area[data["piece"] == p].sum() == pytest.approx(blocks.pieces[p].surface_area_m2(), rel=1e-9)
    analysed = {k.block: MODES.index(k.mode) for k in table}
    for b, m in analysed.items():
        assert set(data["keyblock_mode"][data["block"] == b]) == {m}
    assert (data["block"][data["excavated"] == 1] == -1).all()


def test_a_thin_slab_is_reported_as_a_sliver_and_tiny_piece():
    from rockmass.blockgen.block_shapes import piece_quality

    planes = Planes(np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]]), np.array([0.5, 0.501]), np.array([0, 1]),
                    np.zeros((2, 3)), np.full(2, np.inf))
    blocks = cut_box(UNIT, planes)
    quality = piece_quality(blocks, tiny_fraction=1e-2)
    # the 1 x 1 x 0.001 slab: volume 1e-3 < 1e-2 of the cube, and its thickness semi-axis is
    # 0.001/1 of its width one (< 0.01); the two halves are neither
    assert (quality.tiny, quality.slivers) == (1, 1)
    assert quality.smallest_m3 == pytest.approx(1e-3, rel=1e-9)


def test_block_meshes_for_trimesh_and_export(tmp_path):
    import trimesh

    from rockmass.blockgen.block_shapes import block_shapes
    from rockmass.blockgen.blocks3d_io import block_mesh, export_blocks

    box = np.array([[0.0, 0.0, 0.0], [2.0, 1.5, 1.0]])
    blocks = cut_box(box, *_orthogonal_sets(box, 0.6, origin=(0.1, 0.2, 0.3)),
                     _disk([0.2, 0.1, 1.0], [1.0, 0.7, 0.55], 0.3, label=3))
    shapes = block_shapes(blocks)
    for b in range(blocks.n_blocks):
        mesh = block_mesh(blocks, b)
        assert mesh.volume == pytest.approx(shapes.volume_m3[b], rel=1e-9)
        np.testing.assert_allclose(mesh.center_mass, shapes.centroid_m[b], atol=1e-9)
    path = export_blocks(blocks, tmp_path / "blocks.ply")
    assert trimesh.load(path).volume == pytest.approx(np.prod(box[1] - box[0]), rel=1e-6)
