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
