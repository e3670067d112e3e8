"""A map of every joint (docs/imaging.md §8.4): ``rockmass extract --joints all``, the settings
``EVERY_JOINT`` behind it and ``samples/extract_fine_joints.toml``, their TOML form.

Oracles: on a synthetic face, whose truth counts every line drawn (hairlines too), the settings
find clearly more of the truth than the network with the default trace filters, at a precision
still above 0.9; the flag's run equals the library call with the same settings; the sample file
holds the same settings."""

import json
from pathlib import Path

import pytest

from rockmass.cli import main
from rockmass.config import load_config
from rockmass.dfn import read_traces
from rockmass.imaging import save_synthetic_face
from rockmass.imaging.extract import EVERY_JOINT, ExtractParams, extract
from rockmass.imaging.metrics import trace_accuracy
from rockmass.imaging.synthetic import synthetic_face

SAMPLE = Path(__file__).resolve().parents[2] / "samples" / "extract_fine_joints.toml"


@pytest.fixture(scope="module")
def face_png(tmp_path_factory):
    face = synthetic_face("moderate", seed=2, shape_px=(400, 600), m_per_px=0.008)
    return save_synthetic_face(face, tmp_path_factory.mktemp("face"))["image"], face


def test_the_settings_turn_the_trace_filters_off_on_the_network():
    params = ExtractParams(**EVERY_JOINT)
    assert (params.detector, params.pixel_model) == ("learned", "cnn")
    assert params.min_trace_contrast == float("-inf") and params.min_trace_width == 0.0
    assert params.min_trace_length_px == 20.0


def test_the_sample_config_holds_the_same_settings():
    assert load_config(SAMPLE).imaging.params == dict(EVERY_JOINT)


@pytest.mark.parametrize("seed", [2, 3])
def test_every_joint_finds_the_fine_joints_the_default_filters_drop(seed):
    face = synthetic_face("moderate", seed=seed, shape_px=(400, 600), m_per_px=0.008)
    filtered = ExtractParams(detector="learned", pixel_model="cnn")
    a_all, a_filtered = (trace_accuracy(extract(face.image, m_per_px=0.008, params=p).traces,
                                        face.truth, m_per_px=0.008)
                         for p in (ExtractParams(**EVERY_JOINT), filtered))
    assert a_all.recall >= a_filtered.recall + 0.1
    assert abs(a_all.p21_rel_error) < abs(a_filtered.p21_rel_error)
    assert a_all.precision >= 0.9 and a_all.f1 >= 0.9


def test_the_flag_maps_what_the_settings_map_and_says_so(face_png, tmp_path, capsys):
    path, face = face_png
    out = tmp_path / "out"
    assert main(["extract", str(path), "--m-per-px", "0.008", "--out", str(out),
                 "--joints", "all"]) == 0
    assert "joints: every joint the photo shows" in capsys.readouterr().out
    params = json.loads((out / "manifest.json").read_text())["config"]["imaging"]["params"]
    assert params["pixel_model"] == "cnn" and params["min_trace_contrast"] == "-inf"
    expected = extract(face.image, m_per_px=0.008, params=ExtractParams(**EVERY_JOINT)).traces
    got = read_traces(out / "traces.geojson")
    assert got.n_traces == expected.n_traces > 0
    assert got.total_length_m() == pytest.approx(expected.total_length_m(), rel=1e-6)


def test_the_flag_goes_over_the_config_file(face_png, tmp_path):
    # as every flag: the file asks for the ridge filter on bright joints and a 50 px floor,
    # --joints all wins
    path, _ = face_png
    config = tmp_path / "c.toml"
    config.write_text('[imaging.params]\ndetector = "ridge"\nline_polarity = "bright"\n'
                      'min_trace_length_px = 50.0\n')
    out = tmp_path / "out"
    assert main(["extract", str(path), "--m-per-px", "0.008", "--out", str(out), "--config",
                 str(config), "--joints", "all"]) == 0
    params = json.loads((out / "manifest.json").read_text())["config"]["imaging"]["params"]
    assert params["detector"] == "learned" and params["line_polarity"] == "dark"
    assert params["min_trace_length_px"] == 20.0


@pytest.mark.parametrize("flags, named", [(["--detector", "ridge"], "--detector"),
                                          (["--pixel-model", "mlp"], "--pixel-model"),
                                          (["--bright-lines"], "--bright-lines")])
def test_the_flag_beside_another_detector_exits_2_and_writes_nothing(face_png, tmp_path, capsys,
                                                                      flags, named):
    path, _ = face_png
    code = main(["extract", str(path), "--m-per-px", "0.008", "--out", str(tmp_path / "o"),
                 "--joints", "all", *flags])
    assert code == 2
    err = capsys.readouterr().err
    assert "--joints all" in err and named in err
    assert not (tmp_path / "o").exists()


def test_major_is_the_default_map(face_png, tmp_path):
    path, _ = face_png
    runs = []
    for extra in ([], ["--joints", "major"]):
        out = tmp_path / f"o{len(runs)}"
        assert main(["extract", str(path), "--m-per-px", "0.008", "--out", str(out), *extra]) == 0
        runs.append(json.loads((out / "manifest.json").read_text())["config"]["imaging"]["params"])
    assert runs[0] == runs[1] == {}
