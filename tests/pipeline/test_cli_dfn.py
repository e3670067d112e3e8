"""``rockmass dfn``: files per realization, seeding rule across runs, exit 2 on bad config."""

import json
from pathlib import Path

import meshio
import numpy as np
import pytest

from rockmass.cli import main
from rockmass.config import load_config
from rockmass.dfn.network_io import read_fractures_csv
from rockmass.dfn_config import DFNDocument

SAMPLE = Path(__file__).resolve().parents[2] / "samples" / "dfn_seed001.toml"

CONFIG = """
[dfn]
seed = 5
realizations = 3

[dfn.domain]
min_m = [0, 0, 0]
max_m = [12, 10, 8]

[[dfn.sets]]
name = "J1"
orientation = { distribution = "fisher", dip_deg = 50, dip_direction_deg = 270, kappa = 20 }
size = { distribution = "power_law", r_min_m = 0.5, r_max_m = 4.0, alpha = 2.5 }
intensity = { measure = "P32", value = 0.5 }

[[dfn.sets]]
name = "J2"
orientation = { distribution = "uniform" }
size = { distribution = "constant", radius_m = 1.0 }
intensity = { measure = "P10", value = 0.2, trend_deg = 90, plunge_deg = 0 }
n_vertices = 8
"""


@pytest.fixture
def config(tmp_path):
    path = tmp_path / "site.toml"
    path.write_text(CONFIG)
    return path


def test_writes_every_file_with_achieved_p32_at_target(config, tmp_path):
    out = tmp_path / "out"
    assert main(["dfn", str(config), "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["manifest.json", "realization_0000", "realization_0001",
                                                     "realization_0002"]
    folder = out / "realization_0001"
    assert sorted(p.name for p in folder.iterdir()) == ["fractures.csv", "fractures.vtu", "summary.json"]
    summary = json.loads((folder / "summary.json").read_text())
    volume = 12 * 10 * 8
    for s, r_max in zip(summary["sets"], (4.0, 1.0)):
        assert 0 <= s["achieved_p32"] - s["target_p32"] <= np.pi * r_max ** 2 / volume
    assert summary["sets"][1]["target_p32"] == pytest.approx(0.4, rel=1e-9)  # P10 · C13 = 0.2 · 2
    net = read_fractures_csv(folder / "fractures.csv", summary["domain_m"])
    assert net.n_fractures == summary["total"]["count"] == sum(s["count"] for s in summary["sets"])
    assert net.p32() == pytest.approx(summary["total"]["achieved_p32"], rel=1e-12)
    mesh = meshio.read(folder / "fractures.vtu")
    sizes = np.concatenate([np.full(len(block.data), block.data.shape[1]) for block in mesh.cells])
    data = {name: np.concatenate(values) for name, values in mesh.cell_data.items()}
    whole = data["clipped"] == 0     # J2: 8-gons, J1: 16-gons; cut by the domain: up to 6 vertices more
    assert sizes[whole].tolist() == np.where(data["set"][whole] == 1, 8, 16).tolist()
    assert (sizes[~whole] <= np.where(data["set"][~whole] == 1, 14, 22)).all()
    report = summary["fractures_vtu"]
    assert report == {"polygons": len(sizes), "clipped": int((~whole).sum()), "outside": net.n_fractures - len(sizes)}
    assert report["clipped"] > 0 and sorted(data["id"].tolist()) == sorted(set(data["id"].tolist()))
    assert np.array_equal(data["radius_m"], net.radius_m[data["id"]])
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["seeds"]["root"] == 5 and manifest["seeds"]["realizations"] == [0, 1, 2]
    assert manifest["config"]["dfn"]["sets"][0]["name"] == "J1"


def test_realization_alone_equals_realization_of_a_batch(config, tmp_path):
    assert main(["dfn", str(config), "--out", str(tmp_path / "batch")]) == 0
    assert main(["dfn", str(config), "--out", str(tmp_path / "alone"), "--first", "2", "--realizations", "1"]) == 0
    a = (tmp_path / "batch" / "realization_0002" / "fractures.csv").read_bytes()
    b = (tmp_path / "alone" / "realization_0002" / "fractures.csv").read_bytes()
    assert a == b
    assert main(["dfn", str(config), "--out", str(tmp_path / "seed9"), "--seed", "9", "--realizations", "1"]) == 0
    assert (tmp_path / "seed9" / "realization_0000" / "fractures.csv").read_bytes() != \
        (tmp_path / "batch" / "realization_0000" / "fractures.csv").read_bytes()


@pytest.mark.parametrize("old, new, fragment", [
    ("kappa = 20", "kappa = -1", "dfn.sets[0].orientation.kappa"),
    ("dip_deg = 50", "dip_deg = 95", "dfn.sets[0].orientation.dip_deg"),
    ("r_min_m = 0.5", "r_min_m = 5.0", "dfn.sets[0].size.r_min_m"),
    ("measure = \"P32\", value = 0.5", "measure = \"P32\", value = 0.0", "dfn.sets[0].intensity.value"),
    ("max_m = [12, 10, 8]", "max_m = [12, 10, -1]", "dfn.domain.max_m"),
    ("seed = 5", "seed = 5\nseeed = 3", "dfn.seeed"),
    ("value = 0.5", "value = nan", "dfn.sets[0].intensity.value"),
    ("realizations = 3", "realizations = 1\nmax_fractures = 10", "sets[0] (J1)"),
])
def test_bad_config_exits_2_naming_the_field(config, tmp_path, capsys, old, new, fragment):
    config.write_text(CONFIG.replace(old, new, 1))
    out = tmp_path / "out"
    assert main(["dfn", str(config), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert str(config) in err and fragment in err
    assert not out.exists()


def test_bad_flag_exits_2(config, tmp_path, capsys):
    assert main(["dfn", str(config), "--out", str(tmp_path / "o"), "--seed", "-3"]) == 2
    assert "--seed" in capsys.readouterr().err


def test_realizations_flag_is_capped_like_the_config(config, tmp_path, capsys):
    """--realizations 1000000000 was accepted (the config caps dfn.realizations at 10 000) and
    generated until the memory ran out; now it stops at once with exit 2 naming the flag."""
    out = tmp_path / "o"
    assert main(["dfn", str(config), "--out", str(out), "--realizations", "1000000000"]) == 2
    err = capsys.readouterr().err
    assert "--realizations" in err and "10000" in err
    assert not out.exists()


def test_sample_config_of_seed_001_is_valid_and_generates(tmp_path):
    document = load_config(SAMPLE, model=DFNDocument)
    assert [s.orientation.dip_deg for s in document.dfn.sets] == [50.0, 80.0, 70.0]
    assert sum(s.intensity.value for s in document.dfn.sets) == pytest.approx(1.0)
    assert main(["dfn", str(SAMPLE), "--out", str(tmp_path / "o"), "--realizations", "1"]) == 0
    summary = json.loads((tmp_path / "o" / "realization_0000" / "summary.json").read_text())
    assert summary["total"]["achieved_p32"] >= 1.0


def test_sections_are_written_as_traces_in_world_coordinates(config, tmp_path):
    """With [[dfn.sections]], each realization also writes sections.vtu: the traces that
    summary.json counts, one line per trace on the section plane, with set, disk id and length."""
    from rockmass.dfn.orientation import normal_from_dip

    config.write_text(CONFIG + """
[[dfn.sections]]
name = "wall"
point_m = [6, 5, 4]
dip_deg = 90
dip_direction_deg = 180
window_uv_m = [[-5, -3], [5, -3], [5, 3], [-5, 3]]

[[dfn.sections]]
point_m = [6, 5, 4]
dip_deg = 0
dip_direction_deg = 0
window_uv_m = [[-6, -5], [6, -5], [6, 5], [-6, 5]]
""")
    out = tmp_path / "out"
    assert main(["dfn", str(config), "--out", str(out), "--realizations", "1"]) == 0
    folder = out / "realization_0000"
    assert sorted(p.name for p in folder.iterdir()) == ["fractures.csv", "fractures.vtu", "sections.vtu",
                                                        "summary.json"]
    summary = json.loads((folder / "summary.json").read_text())
    net = read_fractures_csv(folder / "fractures.csv", summary["domain_m"])
    mesh = meshio.read(folder / "sections.vtu")
    data = {name: values[0] for name, values in mesh.cell_data.items()}
    for k, (dip, dip_direction) in enumerate([(90, 180), (0, 0)]):
        mine = data["section"] == k
        assert mine.sum() == summary["sections"][k]["traces"] > 0
        assert data["length_m"][mine].sum() / summary["sections"][k]["area_m2"] == \
            pytest.approx(summary["sections"][k]["p21"], rel=1e-12)
        ends = mesh.points[mesh.cells[0].data[mine]]                            # (traces, 2, 3)
        plane = normal_from_dip(dip, dip_direction)
        assert np.allclose((ends - [6, 5, 4]) @ plane, 0.0, atol=1e-9)          # on the section plane
        ids = data["id"][mine]
        for e in (ends[:, 0], ends[:, 1]):                                      # on its own disk
            assert np.allclose(np.einsum("ij,ij->i", e - net.centre_m[ids], net.normal[ids]), 0.0, atol=1e-9)
            assert (np.linalg.norm(e - net.centre_m[ids], axis=1) <= net.radius_m[ids] + 1e-9).all()
        assert np.array_equal(data["set"][mine], net.set_id[ids])
