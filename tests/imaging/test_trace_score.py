"""The per-trace joint score: features by closed form, the shipped weights' directions, the fit
recovering a known model, labels, and the score on extracted traces."""

import numpy as np
import pytest

from rockmass.dfn import TraceMap
from rockmass.imaging.extract import ExtractParams, extract
from rockmass.imaging.synthetic import synthetic_face
from rockmass.imaging.trace_score import (FEATURE_NAMES, LOW_SCORE, joint_score, load, trace_features,
                                          unscored)
from rockmass.imaging.train_trace_score import fit_logistic, main, trace_labels


def test_features_of_a_straight_and_a_bent_trace():
    # a 40 px straight trace and a 3-4-5 zigzag (length 10, chord 6), joint width 2 px, at 0.01 m/px
    traces = TraceMap.from_polylines([[(0, 0), (0.4, 0)], [(0, 0), (0.03, 0.04), (0.06, 0)]],
                                     attributes={"contrast": [0.3, 0.05], "band_width_px": [4.0, 1.0]})
    x = trace_features(traces, m_per_px=0.01, joint_width_px=2.0)
    assert x.shape == (2, len(FEATURE_NAMES))
    np.testing.assert_allclose(x[:, 0], np.log([40 / 2, 10 / 2]))
    np.testing.assert_allclose(x[:, 1], [0.3, 0.05])
    np.testing.assert_allclose(x[:, 2], np.log([4 / 2, 1 / 2]))
    np.testing.assert_allclose(x[:, 3], [1.0, 0.6])


@pytest.mark.parametrize("detector", ["ridge", "learned"])
def test_shipped_weights_rank_longer_and_straighter_traces_higher(detector):
    base = np.array([np.log(20.0), 0.3, 0.0, 0.9])
    longer, straighter = base + [1.0, 0, 0, 0], base + [0, 0, 0, 0.09]
    s = joint_score(np.array([base, longer, straighter]), detector)
    assert np.all((s > 0) & (s < 1))
    assert s[1] > s[0] and s[2] > s[0]
    assert set(load()) == {"ridge", "learned"}


def test_unknown_detector_is_refused():
    with pytest.raises(ValueError, match="no weights for detector 'sobel'"):
        joint_score(np.zeros((1, 4)), "sobel")


def test_fit_recovers_a_known_logistic_model():
    # traces drawn from a logistic model with known coefficients on standardised features: the
    # class-balanced fit changes only the intercept, so the slopes must come back
    rng = np.random.default_rng(3)
    x = rng.normal(size=(40000, 3)) * [1.0, 2.0, 0.5] + [0.0, 1.0, -1.0]
    slopes = np.array([1.5, -0.8, 0.4])
    z = (x - x.mean(axis=0)) / x.std(axis=0)
    y = (rng.random(len(x)) < 1 / (1 + np.exp(-(0.3 + z @ slopes)))).astype(float)
    mean, std, beta = fit_logistic(x, y, np.ones(len(x)), penalty=0.0)
    np.testing.assert_allclose(beta[1:], slopes, atol=0.06)
    np.testing.assert_allclose(mean, x.mean(axis=0))


def test_fit_needs_both_classes():
    with pytest.raises(ValueError, match="joints and non-joints"):
        fit_logistic(np.zeros((5, 2)), np.ones(5), np.ones(5))


def test_labels_mark_the_trace_on_the_truth():
    # truth: row 50 of a 100 x 100 grid at 0.01 m/px (v = 0.5 m); one trace 1 px beside it, one
    # 30 px away; both 80 px long (81 pixels drawn)
    truth = np.zeros((100, 100), bool)
    truth[49, 10:91] = True
    traces = TraceMap.from_polylines([[(0.1, 0.51), (0.9, 0.51)], [(0.1, 0.2), (0.9, 0.2)]])
    labels, pixels = trace_labels(traces, truth, 0.01)
    assert labels.tolist() == [1.0, 0.0] and pixels.tolist() == [81, 81]
    assert trace_labels(traces, truth, 0.01, tolerance_px=35.0)[0].tolist() == [1.0, 1.0]


def test_extracted_traces_carry_a_score_and_a_band_width():
    face = synthetic_face("easy", seed=5, shape_px=(300, 400), m_per_px=0.01)
    traces = extract(face.image, m_per_px=0.01, params=ExtractParams()).traces
    score = np.asarray(traces.attributes["joint_score"])
    assert traces.n_traces > 0 and score.shape == (traces.n_traces,)
    assert np.all((score > 0) & (score < 1))
    assert np.all(np.asarray(traces.attributes["band_width_px"]) > 0)
    # on a clean face most of the trace length is scored a joint
    lengths = traces.lengths_m()
    assert lengths[score >= LOW_SCORE].sum() > 0.8 * lengths.sum()
    with unscored():
        assert "joint_score" not in extract(face.image, m_per_px=0.01).traces.attributes


def test_the_fitting_command_writes_a_model_the_score_reads_and_nothing_else(tmp_path):
    # one training face instead of 24: finite weights other than the shipped ones, the same layout,
    # read back by the score; the file is written whole, under its own name only
    out = tmp_path / "score.npz"
    assert main(["--faces", "1", "--out", str(out)]) == 0
    assert [p.name for p in tmp_path.iterdir()] == ["score.npz"]
    weights, shipped = load(out), load()
    assert set(weights) == set(shipped)
    x = np.array([[np.log(20.0), 0.3, 0.0, 0.9]])
    for detector, (mean, std, beta) in weights.items():
        assert np.all(np.isfinite(beta)) and np.all(std > 0)
        assert not np.allclose(beta, shipped[detector][2])
        z = beta[0] + ((x - mean) / std) @ beta[1:]
        np.testing.assert_allclose(joint_score(x, detector, path=out), 1 / (1 + np.exp(-z)))


def test_a_write_that_fails_halfway_keeps_the_model_file_there_was(tmp_path, monkeypatch):
    # the writer stops after some bytes (a full disk, a kill): the file there was stays whole and
    # no partial file is left (a plain open() would have truncated it)
    out = tmp_path / "score.npz"
    out.write_bytes(b"the previous model")

    def failing_savez(handle, **arrays):
        handle.write(b"half a model")
        raise OSError("disk full")

    monkeypatch.setattr(np, "savez", failing_savez)
    with pytest.raises(OSError, match="disk full"):
        main(["--faces", "1", "--out", str(out)])
    assert out.read_bytes() == b"the previous model"
    assert [p.name for p in tmp_path.iterdir()] == ["score.npz"]
