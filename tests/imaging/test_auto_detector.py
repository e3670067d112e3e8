"""``detector = "auto"``: both detectors run, the ridge traces are kept on clean photos (docs/imaging.md
§3.3). The answers here are independent of the benchmark that chose ``auto_agreement``: the
agreement of drawn lines whose overlap is known, and the traces of the detector kept compared
with a run of that detector alone."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rockmass.cli import main
from rockmass.imaging import save_synthetic_face, synthetic_face
from rockmass.imaging.extract import AUTO, ExtractParams, detector_agreement, extract
from rockmass.imaging.synthetic_field import field_face


def _line(row, c0=5.0, c1=195.0):
    return np.array([[row, c0], [row, c1]], dtype=float)


def test_agreement_is_the_share_of_ridge_length_near_learned_traces():
    shape = (60, 200)
    # two ridge lines of equal length, one retraced 3 px away by the learned detector: half agree
    assert detector_agreement([_line(10), _line(40)], [_line(13)], shape) == pytest.approx(0.5, abs=0.01)
    # the radius decides: 3 px off is outside 2 px
    assert detector_agreement([_line(10)], [_line(13)], shape, radius_px=2.0) == 0.0
    # a learned trace covering a third of a ridge line (plus the radius at its end)
    part = detector_agreement([_line(20, 0.0, 179.0)], [_line(20, 0.0, 59.0)], shape)
    assert part == pytest.approx(65 / 180, abs=0.01)
    assert detector_agreement([], [_line(10)], shape) == 0.0  # nothing to confirm


def test_auto_keeps_the_ridge_traces_of_a_clean_face_exactly():
    face = synthetic_face("easy", seed=21, shape_px=(400, 600), m_per_px=0.02)
    auto = extract(face.image, m_per_px=0.02)
    ridge = extract(face.image, m_per_px=0.02, params=ExtractParams(detector="ridge"))
    choice = auto.detector_choice
    assert auto.params.detector == AUTO and choice["kept"] == "ridge"
    assert choice["agreement"] > choice["auto_agreement"] == 0.55
    assert auto.traces.n_traces == ridge.traces.n_traces == choice["traces"]["ridge"]
    for i in range(ridge.traces.n_traces):
        np.testing.assert_array_equal(auto.traces.polyline(i), ridge.traces.polyline(i))
    np.testing.assert_array_equal(auto.traces.attributes["joint_score"],
                                  ridge.traces.attributes["joint_score"])
    assert auto.detector_model is not None  # the learned detector ran: its model is named
    assert ridge.detector_model is None and ridge.detector_choice is None


def test_auto_keeps_the_learned_traces_of_a_cluttered_face_and_a_threshold_of_one_always_does():
    face = field_face(seed=1)  # rubble, plates, minor cracks: the ridge filter draws them all
    auto = extract(face.image, m_per_px=face.m_per_px)
    learned = extract(face.image, m_per_px=face.m_per_px, params=ExtractParams(detector="learned"))
    assert auto.detector_choice["kept"] == "learned"
    assert auto.detector_choice["agreement"] <= 0.55
    assert auto.traces.n_traces == learned.traces.n_traces
    for i in range(learned.traces.n_traces):
        np.testing.assert_array_equal(auto.traces.polyline(i), learned.traces.polyline(i))
    clean = synthetic_face("easy", seed=21, shape_px=(400, 600), m_per_px=0.02)
    never = extract(clean.image, m_per_px=0.02, params=ExtractParams(auto_agreement=1.0))
    assert never.detector_choice["kept"] == "learned"


def test_auto_reports_each_step_once_in_chain_order():
    face = synthetic_face("easy", seed=3, shape_px=(200, 300), m_per_px=0.02)
    steps = []
    result = extract(face.image, m_per_px=0.02, progress=steps.append)
    assert len(steps) == len(set(steps)) and steps == list(result.timings_s)


def test_the_last_step_is_reported_once_a_detector_is_kept(monkeypatch):
    # "vectorize" (the last step of the bar) runs in each detection task and again after the
    # side tasks: the bar must not reach its end before the two detectors are compared
    import importlib

    module = importlib.import_module("rockmass.imaging.extract")
    events = []
    compare = module.detector_agreement
    monkeypatch.setattr(module, "detector_agreement",
                        lambda *a, **k: events.append("agreement") or compare(*a, **k))
    face = synthetic_face("easy", seed=3, shape_px=(200, 300), m_per_px=0.02)
    extract(face.image, m_per_px=0.02, progress=events.append)
    assert events.count("vectorize") == 1
    assert events.index("agreement") < events.index("vectorize")


@pytest.mark.parametrize("kwargs, message", [
    (dict(detector="auto", line_polarity="bright"), "needs params.detector = 'ridge'"),
    (dict(auto_agreement=1.5), "auto_agreement must be a share in 0-1"),
    (dict(auto_agreement=float("nan")), "auto_agreement must be a share in 0-1"),
    (dict(detector="automatic"), "params.detector must be one of auto, ridge, learned"),
])
def test_bad_auto_settings_are_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ExtractParams(**kwargs)


def test_auto_settings_resolve_only_per_detector():
    params = ExtractParams()
    with pytest.raises(ValueError, match="auto detector has no settings of its own"):
        params.resolved("min_trace_length_px")
    with pytest.raises(ValueError, match="for_detector"):
        params.on_grid(2.0)
    assert params.for_detector("learned").resolved("min_trace_length_px") == 70.0
    assert params.for_detector("ridge").on_grid(2.0).min_trace_length_px == 40.0
    assert ExtractParams(pixel_model="own.npz").for_detector("ridge").pixel_model is None


def test_cli_summary_names_the_detector_kept(tmp_path, capsys):
    face = synthetic_face("easy", seed=4, shape_px=(300, 450), m_per_px=0.02)
    photo = save_synthetic_face(face, tmp_path / "face")["image"]
    assert main(["extract", str(photo), "--m-per-px", "0.02", "--out", str(tmp_path / "out"),
                 "--detector", "auto"]) == 0
    assert "detector: auto kept the ridge detector's traces (agreement" in capsys.readouterr().out
    extraction = json.loads((tmp_path / "out" / "summary.json").read_text())["extraction"]
    assert extraction["params"]["detector"] == "auto"
    assert extraction["detector_choice"]["kept"] == "ridge"
    assert extraction["detector_choice"]["traces"]["ridge"] == extraction["n_traces"]
