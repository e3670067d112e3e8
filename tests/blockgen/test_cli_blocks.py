"""``rockmass blocks CONFIG --out DIR`` and the ``[blocks]`` config section."""

import json
from pathlib import Path

import numpy as np
import pytest

from rockmass.blockgen import check_model, read_json
from rockmass.cli import main

SAMPLES = Path(__file__).resolve().parents[2] / "samples"


@pytest.mark.parametrize("name", ["blocks_shaketable.toml", "blocks_cavern.toml",
                                  "blocks_dfn_horseshoe.toml", "blocks_cavern_cracks.toml",
                                  "blocks_dfn_section.toml"])
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
    assert model.quality.dangling["n_extended"] > 0


def test_cracks_sample_has_glued_crack_contacts_only_near_the_cavern(tmp_path, capsys):
    from rockmass.blockgen import SOURCE_CRACK
    from rockmass.blockgen.model import KIND_GLUED

    assert main(["blocks", str(SAMPLES / "blocks_cavern_cracks.toml"), "--out", str(tmp_path)]) == 0
    assert "potential cracks" in capsys.readouterr().out
    model = read_json(tmp_path / "blocks.json")
    crack = model.contact_source == SOURCE_CRACK
    assert crack.sum() > 500 and (model.contact_kind[crack] == KIND_GLUED).all()
    # every cracked block lies in a joint block (parallelogram of heights 6 and 8 m at 60°: sides
    # 8/sin 60° and 6/sin 60°, diagonal < 16.2 m) within within_m = 20 m of the excavation (inside
    # the 24 x 36 m box x in [-12, 12], y in [-20, 16])
    c = model.centroid_xy_m[model.contact_blocks[crack].ravel()]
    dx = np.maximum(np.abs(c[:, 0]) - 12, 0)
    dy = np.maximum(np.maximum(c[:, 1] - 16, -20 - c[:, 1]), 0)
    assert (np.hypot(dx, dy) < 20 + 16.2).all()


@pytest.mark.parametrize("line, field", [("size_m = 0.0", "blocks.cracks.size_m"),
                                         ("size_m = 1.0\njitter = 0.7", "blocks.cracks.jitter"),
                                         ("size_m = 1.0\npattern = \"hex\"", "blocks.cracks.pattern"),
                                         ("size_m = 1.0\nwithin_m = 1.0", "blocks.cracks")])
def test_bad_crack_section_exits_2_naming_the_field(tmp_path, capsys, line, field):
    path = _write(tmp_path, _BASE.format(spacing="0.25") + "[blocks.cracks]\n" + line + "\n")
    assert main(["blocks", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert f"{field}:" in err
    assert not (tmp_path / "out").exists()


def test_dfn_section_sample_cuts_the_window_by_the_section_traces(tmp_path):
    from rockmass.blockgen.model import KIND_TRACE
    from rockmass.config import load_config
    from rockmass.dfn.orientation import normal_from_dip
    from rockmass.dfn.section import generate_section

    assert main(["blocks", str(SAMPLES / "blocks_dfn_section.toml"), "--out", str(tmp_path)]) == 0
    model = read_json(tmp_path / "blocks.json")
    # the domain is the 40 m x 30 m section window
    assert model.quality.area_balance["domain_m2"] == pytest.approx(1200.0, rel=1e-12)
    assert (model.contact_kind == KIND_TRACE).sum() > 100
    # the traces are the section of the file's [dfn] sets with its seed, realization 0
    doc = load_config(SAMPLES / "blocks_dfn_section.toml")
    sec = doc.dfn.sections[0]
    traces = generate_section([s.to_spec() for s in doc.dfn.sets], sec.point_m,
                              normal_from_dip(sec.dip_deg, sec.dip_direction_deg), sec.window_uv_m,
                              seed=doc.dfn.seed, realization=0)
    assert model.quality.n_traces_used == traces.n_traces


_SECTION = """
[blocks]
[blocks.dfn_section]
section = "{name}"
realization = {realization}
"""
_DFN = (SAMPLES / "blocks_dfn_section.toml").read_text().split("\n[blocks]\n")[0]


@pytest.mark.parametrize("text, field", [
    (_SECTION.format(name="drift face", realization=0), "blocks.dfn_section"),
    (_DFN + _SECTION.format(name="nope", realization=0), "blocks.dfn_section.section"),
    (_DFN + _SECTION.format(name="drift face", realization=1), "blocks.dfn_section.realization"),
    ("[blocks]\n[[blocks.sets]]\nangle_deg = 0\nspacing_m = 1.0\n", "blocks.domain")],
    ids=["no dfn", "unknown section", "realization", "no domain"])
def test_bad_dfn_section_exits_2_naming_the_field(tmp_path, capsys, text, field):
    path = _write(tmp_path, text)
    assert main(["blocks", str(path), "--out", str(tmp_path / "out")]) == 2
    assert f"{field}:" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
