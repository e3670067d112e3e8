"""Scale-aware extraction: the joint width and pixel settings keep their size on the face.

The oracle is the face itself: one synthetic face, its joints drawn with widths in metres, seen at
two resolutions (the finer one area-averaged down, as a camera with fewer pixels sees it) must give
the same traces in metres, within what the coarser grid can resolve.
"""

import importlib
import json
from dataclasses import replace

import cv2
import numpy as np
import pytest

from rockmass.accuracy import trace_accuracy
from rockmass.cli import main
from rockmass.imaging import save_synthetic_face
from rockmass.imaging.extract import (DEFAULT_JOINT_WIDTH_PX, PIXEL_AREAS, PIXEL_LENGTHS,
                                      ExtractParams, extract, grid_scale, joint_width_on_grid)
from rockmass.imaging.synthetic import DIFFICULTIES, synthetic_face

#: the module (``rockmass.imaging.extract`` the name is also the function, re-exported)
extract_module = importlib.import_module("rockmass.imaging.extract")


@pytest.fixture(scope="module")
def face_two_resolutions():
    """A 6 m x 4 m moderate face at 1.5 MP (joints 2-8 px, i.e. 8-32 mm) and at 0.375 MP."""
    h, w = 1000, 1500
    m_per_px = 6.0 / w
    style = replace(DIFFICULTIES["moderate"], width_px=(2, 8), jpeg_quality=100)
    face = synthetic_face("moderate", seed=3, shape_px=(h, w), m_per_px=m_per_px, style=style)
    coarse = cv2.resize(face.image, (w // 2, h // 2), interpolation=cv2.INTER_AREA)
    return {"fine": (face.image, m_per_px), "coarse": (coarse, 2 * m_per_px)}, face.truth


def _errors(images, truth) -> dict:
    """(dP21, dP20) in % per resolution, every photo at full resolution."""
    out = {}
    for name, (image, m_per_px) in images.items():
        result = extract(image, m_per_px=m_per_px,
                         params=ExtractParams(max_megapixels=1000, detector="ridge"))
        acc = trace_accuracy(result.traces, truth, m_per_px=0.008, buffer_px=2)
        out[name] = (100 * acc.p21_rel_error, 100 * acc.p20_rel_error, acc.f1)
    return out


def test_pixel_settings_scaled_to_the_grid_keep_the_traces_the_same_at_any_resolution(
        face_two_resolutions, monkeypatch):
    images, truth = face_two_resolutions
    # the coarse photo is the reference grid: the fine one is 2x finer per side
    monkeypatch.setattr(extract_module, "REFERENCE_MEGAPIXELS", 0.375)
    scaled = _errors(images, truth)
    assert abs(scaled["fine"][0] - scaled["coarse"][0]) < 3.0  # dP21, percentage points
    assert abs(scaled["fine"][1] - scaled["coarse"][1]) < 5.0  # dP20
    assert min(scaled["fine"][2], scaled["coarse"][2]) > 0.9
    # the same settings in pixels of whatever grid: the trace count drifts (the test can fail)
    monkeypatch.setattr(extract_module, "REFERENCE_MEGAPIXELS", float("inf"))
    fixed = _errors(images, truth)
    assert abs(fixed["fine"][1] - fixed["coarse"][1]) > 15.0


def test_the_default_joint_width_is_three_pixels_of_the_working_grid():
    face = synthetic_face("easy", seed=5, shape_px=(600, 900), m_per_px=0.01)
    params = ExtractParams(max_megapixels=0.135, detector="ridge")
    result = extract(face.image, m_per_px=0.01, params=params)
    factor = result.scale.work_factor
    assert factor == pytest.approx(0.5, rel=0.01)
    assert result.joint_width_px == pytest.approx(DEFAULT_JOINT_WIDTH_PX / factor)
    assert result.joint_width_source == "default"
    given = extract(face.image, m_per_px=0.01, joint_width_px=3.0, params=params)
    assert (given.joint_width_px, given.joint_width_source) == (3.0, "joint_width_px")


def test_the_learned_detector_caps_a_wide_joint_width_and_says_so():
    # its probability bands do not widen with the joints, so a width filter in a wide given joint
    # width removed nearly every trace of a large photo (benchmarks/bench_imaging_real.py section 5)
    face = synthetic_face("easy", seed=5, shape_px=(300, 450), m_per_px=0.02)
    learned = ExtractParams(detector="learned", learned_levels=())  # the working grid alone
    plain = extract(face.image, m_per_px=0.02, params=learned)
    wide = extract(face.image, m_per_px=0.02, joint_width_px=12.0, params=learned)
    assert (wide.joint_width_px, wide.joint_width_source) == (plain.joint_width_px,
                                                              "joint_width_px, capped")
    assert any("joint width given (12 px, 12 px of the working grid) is wider" in w
               for w in wide.warnings)
    assert wide.traces.n_traces == plain.traces.n_traces > 0
    for i in range(plain.traces.n_traces):
        np.testing.assert_array_equal(wide.traces.polyline(i), plain.traces.polyline(i))
    narrow = extract(face.image, m_per_px=0.02, joint_width_px=2.0, params=learned)  # used
    assert (narrow.joint_width_px, narrow.joint_width_source) == (2.0, "joint_width_px")
    assert not any("wider" in w for w in narrow.warnings)


def test_a_joint_width_in_metres_is_divided_by_the_scale():
    face = synthetic_face("easy", seed=5, shape_px=(300, 450), m_per_px=0.02)
    result = extract(face.image, m_per_px=0.02, joint_width_m=0.08,
                     params=ExtractParams(detector="ridge"))
    assert result.joint_width_px == pytest.approx(4.0)
    assert result.joint_width_source == "joint_width_m"
    assert result.summary()["joint_width_source"] == "joint_width_m"


@pytest.mark.parametrize("kwargs, message", [
    ({"m_per_px": 0.02, "joint_width_px": 3.0, "joint_width_m": 0.05}, "either joint_width_px or"),
    ({"joint_width_m": 0.05}, "joint_width_m needs a scale"),
    ({"m_per_px": 0.02, "joint_width_m": float("nan")}, "joint_width_m must be a finite width"),
    ({"m_per_px": 0.02, "joint_width_m": -1.0}, "joint_width_m must be a finite width"),
    ({"m_per_px": 0.02, "joint_width_m": 100.0}, "joint_width_m = 100 m"),
])
def test_bad_joint_widths_are_refused_naming_the_field(kwargs, message):
    image = synthetic_face("easy", seed=5, shape_px=(64, 64), m_per_px=0.02).image
    with pytest.raises(ValueError, match=message):
        extract(image, **kwargs)


def test_on_grid_scales_lengths_by_s_and_areas_by_s_squared():
    base = ExtractParams(detector="learned")
    scaled = base.on_grid(1.5)
    for name in PIXEL_LENGTHS:
        assert getattr(scaled, name) == pytest.approx(1.5 * base.resolved(name)
                                                      if name == "min_trace_length_px"
                                                      else 1.5 * getattr(base, name))
    assert scaled.min_object_px == round(2.25 * base.min_object_px)
    assert scaled.fill_holes_px == round(2.25 * base.resolved("fill_holes_px"))
    assert set(PIXEL_AREAS) == {"min_object_px", "fill_holes_px"}
    assert scaled.min_sigma_px == base.min_sigma_px  # the finest scale a grid resolves
    assert base.on_grid(1.0) is base
    with pytest.raises(ValueError, match="grid scale"):
        base.on_grid(0.0)


def test_grid_scale_and_width_on_grid_closed_forms():
    assert grid_scale(1.0) == 1.0 and grid_scale(4.0) == 1.0
    assert grid_scale(36.0) == pytest.approx(3.0)
    assert joint_width_on_grid(None, None, work_factor=0.5, m_per_px=0.01, scale=2.0) == (6.0, "default")
    assert joint_width_on_grid(8.0, None, work_factor=0.5, m_per_px=None, scale=1.0) == (
        4.0, "joint_width_px")
    assert joint_width_on_grid(None, 0.03, work_factor=0.5, m_per_px=0.01, scale=1.0) == (
        pytest.approx(1.5), "joint_width_m")


@pytest.fixture(scope="module")
def small_face_png(tmp_path_factory):
    face = synthetic_face("easy", seed=11, shape_px=(300, 450), m_per_px=0.02)
    return save_synthetic_face(face, tmp_path_factory.mktemp("face"))["image"]


def test_cli_joint_width_in_metres_reaches_the_summary(small_face_png, tmp_path, capsys):
    assert main(["extract", str(small_face_png), "--m-per-px", "0.02", "--joint-width-m", "0.1",
                 "--detector", "ridge", "--out", str(tmp_path / "out"), "--json"]) == 0
    extraction = json.loads(capsys.readouterr().out)["extraction"]
    assert extraction["joint_width_px"] == pytest.approx(5.0)
    assert extraction["joint_width_source"] == "joint_width_m"


def test_cli_flag_replaces_the_config_files_width(small_face_png, tmp_path, capsys):
    config = tmp_path / "c.toml"
    config.write_text("[imaging]\nm_per_px = 0.02\njoint_width_px = 4.0\n")
    assert main(["extract", str(small_face_png), "--config", str(config), "--joint-width-m", "0.1",
                 "--detector", "ridge", "--out", str(tmp_path / "out"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["extraction"]["joint_width_px"] == pytest.approx(5.0)


def test_a_config_with_both_widths_exits_2_naming_the_key(small_face_png, tmp_path, capsys):
    config = tmp_path / "c.toml"
    config.write_text("[imaging]\nm_per_px = 0.02\njoint_width_px = 4.0\njoint_width_m = 0.1\n")
    out = tmp_path / "out"
    assert main(["extract", str(small_face_png), "--config", str(config), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert str(config) in err and "imaging.joint_width_m" in err
    assert not out.exists()


def test_both_width_flags_are_refused(small_face_png, tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["extract", str(small_face_png), "--joint-width", "3", "--joint-width-m", "0.1",
              "--out", str(tmp_path / "out")])
    assert stop.value.code == 2
