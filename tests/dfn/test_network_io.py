"""fractures.csv round trip and fractures.vtu polygons."""

import meshio
import numpy as np
import pytest

from rockmass.dfn.network import DiskNetwork
from rockmass.dfn.network_io import disk_polygons, read_fractures_csv, write_fractures_csv, write_fractures_vtu


@pytest.fixture
def network():
    rng = np.random.default_rng(3)  # seed 3 (fixed): arbitrary floats, including awkward ones
    n = 50
    centre = rng.normal(size=(n, 3)) * 1e3
    centre[0] = [1e-300, -0.1, 1 / 3]
    normal = rng.normal(size=(n, 3))
    return DiskNetwork(centre, normal, rng.uniform(0.01, 5, n), rng.integers(0, 4, n), [-5e3] * 3 + [5e3] * 3)


def test_csv_round_trip_is_exact(network, tmp_path):
    path = tmp_path / "fractures.csv"
    write_fractures_csv(network, path)
    assert path.read_text().splitlines()[0] == "set,cx,cy,cz,nx,ny,nz,radius"
    back = read_fractures_csv(path, network.domain_m)
    for key in ("centre_m", "normal", "radius_m", "set_id", "domain_m"):
        assert np.array_equal(getattr(back, key), getattr(network, key)), key


def test_csv_of_empty_network_round_trips(tmp_path):
    empty = DiskNetwork(np.zeros((0, 3)), np.zeros((0, 3)), [], np.zeros(0, int), [0, 0, 0, 1, 1, 1])
    write_fractures_csv(empty, tmp_path / "f.csv")
    assert read_fractures_csv(tmp_path / "f.csv").n_fractures == 0


@pytest.mark.parametrize("text, match", [
    ("set,x,y\n", "line 1: header"),
    ("set,cx,cy,cz,nx,ny,nz,radius\n0,1,2,3,0,0,1\n", "line 2: expected 8 values"),
    ("set,cx,cy,cz,nx,ny,nz,radius\n0,1,2,3,0,0,1,0.5\n0,1,2,nan,0,0,1,0.5\n", "line 3: .*finite"),
    ("set,cx,cy,cz,nx,ny,nz,radius\n0,1,2,3,0,0,1,-1\n", "radius_m"),
])
def test_bad_csv_raises_naming_file_and_line(tmp_path, text, match):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(ValueError, match=match):
        read_fractures_csv(path)


def test_vtu_is_readable_with_one_polygon_per_disk(network, tmp_path):
    path = tmp_path / "fractures.vtu"
    write_fractures_vtu(network, path, n_vertices=12)
    mesh = meshio.read(path)
    assert [block.type for block in mesh.cells] == ["polygon"]
    assert mesh.cells[0].data.shape == (network.n_fractures, 12)
    assert mesh.cell_data["set"][0].tolist() == network.set_id.tolist()
    assert mesh.cell_data["id"][0].tolist() == list(range(network.n_fractures))
    vertices = mesh.points[mesh.cells[0].data]                    # (n, 12, 3)
    offset = vertices - network.centre_m[:, None, :]
    assert np.allclose(np.linalg.norm(offset, axis=2), network.radius_m[:, None], rtol=1e-9)
    assert np.allclose(offset @ network.normal.T * np.eye(network.n_fractures)[:, None, :], 0.0, atol=1e-9)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fractures.vtu"]  # no temporary left


def test_polygon_area_approaches_disk_area():
    net = DiskNetwork([[0, 0, 0]], [[0.2, 0.3, 0.9]], [2.0], [0], [-5] * 3 + [5] * 3)
    poly = disk_polygons(net, 360)[0]
    area = 0.5 * np.linalg.norm(np.cross(poly, np.roll(poly, -1, axis=0)).sum(axis=0))
    assert area == pytest.approx(np.pi * 4, rel=1e-4)


def test_vtu_with_vertex_counts_per_set_has_one_block_per_count(network, tmp_path):
    path = tmp_path / "f.vtu"
    write_fractures_vtu(network, path, n_vertices=[6, 12, 6, 20])
    mesh = meshio.read(path)
    assert [b.data.shape[1] for b in mesh.cells] == [6, 12, 20]
    ids = np.concatenate(mesh.cell_data["id"])
    assert sorted(ids.tolist()) == list(range(network.n_fractures))
    assert np.array_equal(np.concatenate(mesh.cell_data["set"]), network.set_id[ids])


# -- issue 19, item 6: fractures.vtu worth opening in ParaView ------------------------------------

def _polygon_area(vertices):
    """Area of a planar polygon (vector area), independent of the writer."""
    return 0.5 * np.linalg.norm(np.cross(vertices, np.roll(vertices, -1, axis=0)).sum(axis=0))


def _cells(mesh):
    """(vertices of each polygon, {name: value per polygon}) over every cell block of a mesh."""
    polygons = [mesh.points[row] for block in mesh.cells for row in block.data]
    data = {name: np.concatenate(values) for name, values in mesh.cell_data.items()}
    return polygons, data


@pytest.mark.parametrize("normal, dip, dip_direction", [
    ((np.sqrt(6) / 4, -np.sqrt(6) / 4, 0.5), 60.0, 135.0),   # upper normal leans SE: dips 60° to SE
    ((0.0, 1.0, 1.0), 45.0, 0.0),                             # leans North: dips 45° due North
    ((-1.0, 0.0, np.sqrt(3.0)), 30.0, 270.0),                 # leans West: dips 30° due West
    ((0.0, 0.0, 1.0), 0.0, 0.0),                              # horizontal: dip direction 0 by rule
])
def test_vtu_cell_data_give_dip_and_dip_direction_clockwise_from_north(tmp_path, normal, dip, dip_direction):
    """A disk's upper normal leans the way the plane dips (x East, y North, z Up): the cell data
    read back give the dip and the dip direction clockwise from North (+y), with radius, set, id."""
    net = DiskNetwork([[0, 0, 0]], [normal], [1.5], [2], [-5] * 3 + [5] * 3)
    write_fractures_vtu(net, tmp_path / "f.vtu", n_vertices=12)
    _, data = _cells(meshio.read(tmp_path / "f.vtu"))
    assert data["dip_deg"] == pytest.approx([dip], abs=1e-12)
    assert data["dip_direction_deg"] == pytest.approx([dip_direction], abs=1e-12)
    assert data["radius_m"].tolist() == [1.5] and data["set"].tolist() == [2] and data["id"].tolist() == [0]
    assert data["clipped"].tolist() == [0]


def test_vtu_disk_half_outside_the_box_keeps_half_its_area(tmp_path):
    """A disk centred on the face x = 0 of the box, its plane across that face, keeps the half
    inside: half the area of its inscribed 64-gon, which is π r² / 2 within the polygon factor
    1 − (m/2π) sin(2π/m) = 0.16 %; every vertex inside the box, the cut edge on the face."""
    m, r = 64, 2.0
    normal = np.array([0.0, 0.6, 0.8])                        # the disk's plane contains the x axis
    net = DiskNetwork([[0.0, 5.0, 5.0]], [normal], [r], [0], [0, 0, 0, 10, 10, 10])
    assert write_fractures_vtu(net, tmp_path / "f.vtu", n_vertices=m) == \
        {"polygons": 1, "clipped": 1, "outside": 0}
    (polygon,), data = _cells(meshio.read(tmp_path / "f.vtu"))
    whole = 0.5 * m * r ** 2 * np.sin(2 * np.pi / m)          # area of the inscribed m-gon
    assert _polygon_area(polygon) == pytest.approx(whole / 2, rel=1e-12)
    assert _polygon_area(polygon) == pytest.approx(np.pi * r ** 2 / 2, rel=(2 * np.pi / m) ** 2 / 6)
    assert (polygon[:, 0] >= 0).all() and np.isclose(polygon[:, 0], 0.0, atol=1e-12).sum() == 2
    assert np.allclose((polygon - net.centre_m[0]) @ normal, 0.0, atol=1e-12)   # still in its plane
    assert data["clipped"].tolist() == [1] and data["radius_m"].tolist() == [r]   # the whole disk's radius


def test_vtu_disk_at_a_corner_keeps_the_quarter_and_one_outside_is_dropped(tmp_path):
    """A horizontal disk centred on a vertical edge of the box keeps a quarter (two cuts); a disk
    wholly outside is left out and counted; a disk inside stays whole."""
    m, r = 64, 1.0
    net = DiskNetwork([[0, 0, 1], [5, 5, 5], [20, 5, 5]], [[0, 0, 1]] * 3, [r, r, r], [0, 1, 0],
                      [0, 0, 0, 10, 10, 10])
    assert write_fractures_vtu(net, tmp_path / "f.vtu", n_vertices=m) == \
        {"polygons": 2, "clipped": 1, "outside": 1}
    polygons, data = _cells(meshio.read(tmp_path / "f.vtu"))
    areas = dict(zip(data["id"].tolist(), map(_polygon_area, polygons)))
    whole = 0.5 * m * r ** 2 * np.sin(2 * np.pi / m)
    assert sorted(areas) == [0, 1]
    assert areas[0] == pytest.approx(whole / 4, rel=1e-12) and areas[1] == pytest.approx(whole, rel=1e-12)


def test_vtu_clipped_area_matches_the_network_clipped_area(network, tmp_path):
    """Over a random network in a box that cuts many disks, each written polygon's area times the
    polygon-to-disk factor is the disk's area in the box of DiskNetwork.clipped_area_m2 (the P32
    code, a separate kernel)."""
    m = 48
    box = DiskNetwork(network.centre_m, network.normal, network.radius_m * 400, network.set_id,
                      [-1.5e3] * 3 + [1.5e3] * 3)
    report = write_fractures_vtu(box, tmp_path / "f.vtu", n_vertices=m)
    polygons, data = _cells(meshio.read(tmp_path / "f.vtu"))
    expected = box.clipped_area_m2(n_vertices=m)
    assert report["clipped"] >= 10 and report["outside"] >= 5
    assert report["polygons"] + report["outside"] == box.n_fractures
    assert sorted(data["id"].tolist()) == np.flatnonzero(expected > 0).tolist()
    factor = np.pi / (0.5 * m * np.sin(2 * np.pi / m))
    areas = np.array([_polygon_area(p) for p in polygons])
    assert areas * np.where(data["clipped"] == 1, factor, 1.0) == pytest.approx(
        np.where(data["clipped"] == 1, expected[data["id"]], areas), rel=1e-9)
    lo, hi = box.domain_m
    assert all(((p >= lo - 1e-9) & (p <= hi + 1e-9)).all() for p in polygons)


def test_vtu_without_clipping_keeps_every_whole_polygon(tmp_path):
    net = DiskNetwork([[0, 0, 1], [20, 5, 5]], [[0, 0, 1]] * 2, [1.0, 1.0], [0, 0], [0, 0, 0, 10, 10, 10])
    assert write_fractures_vtu(net, tmp_path / "f.vtu", n_vertices=8, clip=False) == \
        {"polygons": 2, "clipped": 0, "outside": 0}
    mesh = meshio.read(tmp_path / "f.vtu")
    assert mesh.cells[0].data.shape == (2, 8)


def test_section_traces_vtu_lies_on_the_plane_in_world_coordinates(tmp_path):
    """A vertical North–South disk (normal East) cut by the horizontal plane z = 1 and by the
    vertical plane y = 0 (facing North): each trace is the chord of the disk on the plane, with
    the length 2 √(r² − d²) (d the distance of the plane from the centre), set and id."""
    from rockmass.dfn.network_io import write_section_traces_vtu

    r = 2.0
    net = DiskNetwork([[0, 0, 0], [9, 9, 9]], [[1, 0, 0], [0, 0, 1]], [r, 0.5], [4, 1], [-10] * 3 + [10] * 3)
    window = [(-5, -5), (5, -5), (5, 5), (-5, 5)]
    sections = [([0, 0, 1.0], [0, 0, 1], window), ([0, 0, 0], [0, 1, 0], window)]
    assert write_section_traces_vtu(net, sections, tmp_path / "s.vtu") == {"traces": [1, 1]}
    mesh = meshio.read(tmp_path / "s.vtu")
    data = {name: values[0] for name, values in mesh.cell_data.items()}
    assert data["section"].tolist() == [0, 1] and data["set"].tolist() == [4, 4] and data["id"].tolist() == [0, 0]
    assert data["length_m"] == pytest.approx([2 * np.sqrt(r ** 2 - 1.0), 2 * r], rel=1e-12)
    ends = mesh.points[mesh.cells[0].data]                                    # (2 lines, 2 ends, 3)
    assert np.allclose(ends[0, :, 0], 0) and np.allclose(ends[0, :, 2], 1.0)       # x = 0 on z = 1
    assert sorted(ends[0, :, 1].round(12).tolist()) == pytest.approx([-np.sqrt(3), np.sqrt(3)])
    assert np.allclose(ends[1, :, :2], 0) and sorted(ends[1, :, 2].round(12).tolist()) == [-r, r]
    assert np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1) == pytest.approx(data["length_m"], rel=1e-12)
