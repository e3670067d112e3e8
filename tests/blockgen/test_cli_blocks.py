"""``rockmass blocks CONFIG --out DIR`` and the ``[blocks]`` config section."""

import json
from pathlib import Path

import pytest

from rockmass.blockgen import check_model, read_json
from rockmass.cli import main

SAMPLES = Path(__file__).resolve().parents[2] / "samples"


@pytest.mark.parametrize("name", ["blocks_shaketable.toml", "blocks_cavern.toml",
                                  "blocks_dfn_horseshoe.toml"])
def test_sample_configs_build_models_that_pass_the_invariants(name, tmp_path, capsys):
    assert main(["blocks", str(SAMPLES / name), "--out", str(tmp_path)]) == 0
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["blocks.json", "blocks.png", "blocks.vtu", "manifest.json"]
    model = read_json(tmp_path / "blocks.json")
    assert check_model(model)["ok"]
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert manifest["extra"]["invariants"]["ok"] if "extra" in manifest else True
    assert "blocks" in capsys.readouterr().out


def test_cavern_sample_has_three_stages_in_order(tmp_path):
    assert main(["blocks", str(SAMPLES / "blocks_cavern.toml"), "--out", str(tmp_path)]) == 0
    model = read_json(tmp_path / "blocks.json")
    assert model.region_names == ("rock", "arch", "bench 1", "bench 2")
    # bench areas are rectangles 24 x 15
    for stage in (2, 3):
        assert model.area_m2[model.region == stage].sum() == pytest.approx(360.0, rel=1e-9)


def _write(tmp_path, text):
    path = tmp_path / "c.toml"
    path.write_text(text)
    return path


_BASE = """[blocks]
[blocks.domain]
width_m = 1.0
height_m = 1.0
[[blocks.sets]]
angle_deg = 0
spacing_m = {spacing}
"""


@pytest.mark.parametrize("spacing, field", [("0.0", "blocks.sets[0].spacing_m"),
                                            ("-1", "blocks.sets[0].spacing_m"),
                                            ('"a"', "blocks.sets[0].spacing_m")])
def test_bad_config_exits_2_naming_the_file_and_field(tmp_path, capsys, spacing, field):
    path = _write(tmp_path, _BASE.format(spacing=spacing))
    out = tmp_path / "out"
    assert main(["blocks", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert str(path) in err and field in err
    assert not out.exists()


def test_excavation_outside_the_domain_exits_2(tmp_path, capsys):
    text = _BASE.format(spacing="0.1") + """[[blocks.excavations]]
shape = "circle"
name = "t"
center_xy_m = [2.0, 2.0]
radius_m = 0.1
"""
    path = _write(tmp_path, text)
    assert main(["blocks", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "blocks.excavations[0]" in err and "outside the domain" in err
    assert not (tmp_path / "out").exists()


def test_unknown_key_is_refused(tmp_path, capsys):
    path = _write(tmp_path, _BASE.format(spacing="0.1") + "spacinng = 3\n")
    assert main(["blocks", str(path), "--out", str(tmp_path / "out")]) == 2
    assert "unknown key" in capsys.readouterr().err


def test_dfn_sample_labels_contacts_by_trace(tmp_path):
    assert main(["blocks", str(SAMPLES / "blocks_dfn_horseshoe.toml"), "--out", str(tmp_path)]) == 0
    model = read_json(tmp_path / "blocks.json")
    kinds = set(model.contact_kind.tolist())
    assert {1, 2, 3, 4} <= kinds  # trace, glued (extended dangling ends), excavation, domain
    assert model.quality["dangling"]["n_extended"] > 0
