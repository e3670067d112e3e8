"""``rockmass blocks3d``: outputs that agree with each other and with closed forms, bad input exits 2
and writes nothing."""

import csv
import json
import math

import pytest

from rockmass.cli import main

CONFIG = """
[blocks3d]
box_min_m = [0.0, 0.0, 0.0]
box_max_m = [4.0, 4.0, 4.0]

[[blocks3d.sets]]
dip_deg = 0.0
dip_direction_deg = 0.0
spacing_m = 1.0
origin_m = [0.0, 0.0, 0.5]

[[blocks3d.sets]]
dip_deg = 90.0
dip_direction_deg = 0.0
spacing_m = 1.0
origin_m = [0.0, 0.5, 0.0]

[[blocks3d.sets]]
dip_deg = 90.0
dip_direction_deg = 90.0
spacing_m = 1.0
origin_m = [0.5, 0.0, 0.0]

[[blocks3d.tunnels]]
shape = "rectangle"
centre_m = [2.0, 0.0, 1.5]
width_m = 1.0
height_m = 1.0
"""


def test_outputs_of_a_cube_of_blocks_around_a_square_tunnel(tmp_path, capsys):
    config = tmp_path / "c.toml"
    config.write_text(CONFIG)
    out = tmp_path / "out"
    assert main(["blocks3d", str(config), "--out", str(out), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert sorted(p.name for p in out.iterdir()) == ["blocks.csv", "blocks3d.vtu", "keyblocks.csv",
                                                       "keyblocks.png", "manifest.json", "summary.json"]
    assert json.loads((out / "summary.json").read_text()) == doc
    # planes at 0.5, 1.5, 2.5, 3.5 on each axis: 5³ cells; the 1 m square tunnel (x 1.5–2.5,
    # z 1.5–2.5) is exactly the row of 5 cells along y, excavated whole
    assert doc["blocks"] == 125 - 5
    assert doc["excavated_volume_m3"] == pytest.approx(4.0)
    assert doc["volume_balance"] < 1e-12
    rows = list(csv.DictReader((out / "blocks.csv").open()))
    assert len(rows) == doc["blocks"]
    assert sum(float(r["volume_m3"]) for r in rows) == pytest.approx(64.0 - 4.0)
    keyblocks = list(csv.DictReader((out / "keyblocks.csv").open()))
    assert len(keyblocks) == doc["keyblocks"]["with_free_face"]
    # the cube of rock right above the roof has vertical sides: it falls (FS 0); the one below the
    # invert rests on its base: stable
    roof = [k for k in keyblocks if float(k["apex_height_m"]) == pytest.approx(1.0) and k["mode"] == "fall"]
    assert roof and all(float(k["factor_of_safety"]) == 0.0 for k in roof)
    assert doc["keyblocks"]["modes"].get("stable", 0) >= 1
    assert all(k["factor_of_safety"] == "inf" or math.isfinite(float(k["factor_of_safety"])) for k in keyblocks)
    # volumes of the cells: 1 m³ inside, 0.5 / 0.25 / 0.125 m³ along the faces, edges and corners
    volumes = doc["block_volume_m3"]
    assert volumes["count"] == doc["blocks"]
    assert volumes["quantiles"]["0.1"] == pytest.approx(0.25) and volumes["quantiles"]["0.9"] == pytest.approx(1.0)
    logs = [math.log(float(r["volume_m3"])) for r in rows]
    assert volumes["log_mean"] == pytest.approx(sum(logs) / len(logs))
    assert doc["piece_quality"]["tiny"] == 0 and doc["piece_quality"]["slivers"] == 0


@pytest.mark.parametrize("edit, field", [
    (("spacing_m = 1.0\norigin_m = [0.0, 0.5, 0.0]", "spacing_m = -1.0\norigin_m = [0.0, 0.5, 0.0]"),
     "blocks3d.sets[1].spacing_m"),
    (("height_m = 1.0", "heigth_m = 1.0"), "blocks3d.tunnels[0].heigth_m"),
    (("box_max_m = [4.0, 4.0, 4.0]", "box_max_m = [4.0, 0.0, 4.0]"), "blocks3d.box_max_m"),
    (("box_max_m = [4.0, 4.0, 4.0]", "box_max_m = [4.0, 4.0, 4.0]\ndfn_realization = 0"),
     "blocks3d.dfn_realization"),
])
def test_bad_config_exits_2_naming_the_key_and_writes_nothing(tmp_path, capsys, edit, field):
    config = tmp_path / "c.toml"
    config.write_text(CONFIG.replace(*edit))
    out = tmp_path / "out"
    assert main(["blocks3d", str(config), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "c.toml" in err and field in err
    assert not out.exists()


DFN_CONFIG = """
[dfn]
seed = 5
realizations = 1

[dfn.domain]
min_m = [0.0, 0.0, 0.0]
max_m = [6.0, 6.0, 6.0]

[[dfn.sets]]
name = "flat"
orientation = { distribution = "fisher", dip_deg = 10.0, dip_direction_deg = 90.0, kappa = 30.0 }
size = { distribution = "power_law", r_min_m = 1.0, r_max_m = 10.0, alpha = 2.5 }
intensity = { measure = "P32", value = 0.5 }

[[dfn.sets]]
name = "steep"
orientation = { distribution = "fisher", dip_deg = 80.0, dip_direction_deg = 0.0, kappa = 30.0 }
size = { distribution = "power_law", r_min_m = 1.0, r_max_m = 10.0, alpha = 2.5 }
intensity = { measure = "P32", value = 0.5 }

[blocks3d]
box_min_m = [0.0, 0.0, 0.0]
box_max_m = [6.0, 6.0, 6.0]
dfn_realization = REALIZATION

[[blocks3d.tunnels]]
shape = "circle"
centre_m = [3.0, 0.0, 3.0]
radius_m = 1.0
"""


def test_realizations_are_the_same_alone_or_in_a_batch(tmp_path, capsys):
    batch, alone = tmp_path / "batch.toml", tmp_path / "alone.toml"
    batch.write_text(DFN_CONFIG.replace("REALIZATION", "2"))
    alone.write_text(DFN_CONFIG.replace("REALIZATION", "3"))
    assert main(["blocks3d", str(batch), "--out", str(tmp_path / "b"), "--realizations", "3"]) == 0
    assert main(["blocks3d", str(alone), "--out", str(tmp_path / "a")]) == 0
    capsys.readouterr()
    assert sorted(p.name for p in (tmp_path / "b").iterdir()) == [
        "manifest.json", "realization_0002", "realization_0003", "realization_0004",
        "realizations.csv", "summary.json"]
    for name in ("blocks.csv", "keyblocks.csv", "summary.json"):
        assert (tmp_path / "b" / "realization_0003" / name).read_text() == (tmp_path / "a" / name).read_text()
    doc = json.loads((tmp_path / "b" / "summary.json").read_text())
    rows = list(csv.DictReader((tmp_path / "b" / "realizations.csv").open()))
    assert [int(r["realization"]) for r in rows] == [2, 3, 4]
    blocks = [d["blocks"] for d in doc["realizations"]]
    assert [int(r["blocks"]) for r in rows] == blocks
    assert doc["across"]["blocks"]["mean"] == pytest.approx(sum(blocks) / 3)
    assert doc["across"]["blocks"]["min"] == min(blocks) and doc["across"]["blocks"]["max"] == max(blocks)


def test_several_realizations_need_a_dfn(tmp_path, capsys):
    config = tmp_path / "c.toml"
    config.write_text(CONFIG)
    assert main(["blocks3d", str(config), "--out", str(tmp_path / "out"), "--realizations", "2"]) == 2
    assert "blocks3d.dfn_realization" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
