"""blocks.json round trip, blocks.vtu and blocks.png."""

import numpy as np

from rockmass.blockgen import from_json_dict, plot_blocks, read_json, to_json_dict, write_json, write_vtu

from ._fixtures import orthogonal_grid, shake_table


def test_blocks_json_round_trip_is_exact(tmp_path):
    m = shake_table()
    write_json(m, tmp_path / "a.json")
    m2 = read_json(tmp_path / "a.json")
    write_json(m2, tmp_path / "b.json")
    assert (tmp_path / "a.json").read_bytes() == (tmp_path / "b.json").read_bytes()
    for name in ("xy_m", "offsets", "region", "contact_blocks", "contact_length_m", "contact_kind",
                 "contact_source", "area_m2"):
        np.testing.assert_array_equal(getattr(m, name), getattr(m2, name))
    assert to_json_dict(from_json_dict(to_json_dict(m))) == to_json_dict(m)


def test_vtu_holds_one_cell_per_block_with_ids(tmp_path):
    import meshio

    m = orthogonal_grid()
    write_vtu(m, tmp_path / "blocks.vtu")
    mesh = meshio.read(tmp_path / "blocks.vtu")
    ids = np.concatenate(mesh.cell_data["block_id"])
    assert sorted(ids.tolist()) == list(range(m.n_blocks))
    assert set(np.concatenate(mesh.cell_data["set"]).tolist()) <= {0, 1}


def test_png_is_written(tmp_path):
    plot_blocks(shake_table(), tmp_path / "blocks.png")
    assert (tmp_path / "blocks.png").read_bytes()[:4] == b"\x89PNG"
