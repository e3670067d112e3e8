"""The learned detector: shipped model, file round trip, forward pass, known lines, confidence."""

import importlib.resources

import cv2
import numpy as np
import pytest

from rockmass.imaging.extract import ExtractParams, extract
from rockmass.imaging.features import CONTEXT_NAMES, FEATURE_NAMES, line_support
from rockmass.imaging.learned import PixelModel, Stage, joint_probability, load_model, model_input
from rockmass.imaging.reuse import shared_work
from rockmass.imaging.train_pixel_model import face_samples, fit_mlp
from rockmass.imaging.vectorize import mean_along


def _line_face(row=60, width=4, shape=(120, 200), seed=3):
    """Textured rock (grey ~150, noise sd 6, seed fixed) with one dark horizontal joint at ``row``."""
    rng = np.random.default_rng(seed)
    image = 150 + 6 * cv2.GaussianBlur(rng.standard_normal(shape).astype(np.float32), (0, 0), 1.0)
    cv2.line(image, (0, row), (shape[1] - 1, row), 70.0, width, cv2.LINE_AA)
    return np.clip(image, 0, 255).astype(np.uint8)


def _naive_forward(stage, x):
    """Eq. (3.2) one row at a time, with explicit sums (an independent implementation)."""
    out = []
    for row in x:
        z = [min(max((v - m) / s, -6.0), 6.0) for v, m, s in zip(row, stage.mean, stage.std)]
        for k, (w, b) in enumerate(zip(stage.weights, stage.biases)):
            z = [sum(z[i] * w[i, j] for i in range(len(z))) + b[j] for j in range(w.shape[1])]
            if k < len(stage.weights) - 1:
                z = [max(v, 0.0) for v in z]
        out.append(1.0 / (1.0 + np.exp(-z[0])))
    return np.array(out)


def _random_stage(rng, n_in, hidden=(5, 3)):
    sizes = (n_in, *hidden, 1)
    return Stage(mean=rng.normal(size=n_in).astype(np.float32),
                 std=rng.uniform(0.5, 2, n_in).astype(np.float32),
                 weights=tuple(rng.normal(size=(a, b)).astype(np.float32)
                               for a, b in zip(sizes[:-1], sizes[1:])),
                 biases=tuple(rng.normal(size=b).astype(np.float32) for b in sizes[1:]))


def test_shipped_model_is_package_data_and_loads():
    resource = importlib.resources.files("rockmass.imaging").joinpath("models/joint_pixel_mlp.npz")
    assert resource.is_file()
    model = load_model()
    assert model.feature_names[:len(FEATURE_NAMES)] == FEATURE_NAMES
    assert model.stages[0].mean.size == len(FEATURE_NAMES)
    assert "synthetic" in model.info["data"]  # trained on synthetic faces only


def test_stage_forward_pass_matches_a_naive_loop():
    rng = np.random.default_rng(0)  # fixed: random weights and inputs
    stage = _random_stage(rng, 4)
    x = rng.normal(size=(40, 4)).astype(np.float32) * 8
    assert (np.abs((x - stage.mean) / stage.std) > 6).sum() >= 10  # the ±6 sd clip is exercised
    expected = _naive_forward(stage, x)
    assert np.allclose(stage.predict(x.T), expected, atol=1e-5)
    assert np.allclose(stage.predict(x.T, block=16), expected, atol=1e-5)  # blocks of 16, 16, 8


def test_forward_pass_of_any_depth_and_widths_matches_the_naive_loop():
    # the kernel takes outputs four at a time: widths of 9, 4 and 6 take both of its paths
    rng = np.random.default_rng(6)
    stage = _random_stage(rng, 7, hidden=(9, 4, 6))
    x = rng.normal(size=(1037, 7)).astype(np.float32)
    expected = _naive_forward(stage, x)
    for block in (1, 5, 512, 4096):
        assert np.allclose(stage.predict(x.T, block=block), expected, atol=1e-5)
    with pytest.raises(ValueError, match="block"):
        stage.predict(x.T, block=0)


def test_forward_pass_keeps_its_digits_for_inputs_far_from_zero():
    """Features whose mean is 10⁴ standard deviations from zero (a grey level in raw units, say):
    the folded first layer must not cancel the digits that distinguish one input from another."""
    rng = np.random.default_rng(4)
    stage = _random_stage(rng, 3)
    stage = Stage(mean=np.full(3, 1e4, np.float32), std=np.ones(3, np.float32),
                  weights=stage.weights, biases=stage.biases)
    x = (1e4 + rng.normal(size=(30, 3)) * 3).astype(np.float32)
    assert np.allclose(stage.predict(x.T), _naive_forward(stage, x), atol=1e-5)


def test_a_stage_with_a_zero_standard_deviation_is_refused():
    rng = np.random.default_rng(5)
    stage = _random_stage(rng, 2)
    with pytest.raises(ValueError, match="standard deviations"):
        Stage(mean=stage.mean, std=np.array([1.0, 0.0], np.float32), weights=stage.weights,
              biases=stage.biases)


def test_model_file_round_trip_keeps_every_prediction(tmp_path):
    rng = np.random.default_rng(1)
    n1, n2 = len(FEATURE_NAMES), len(FEATURE_NAMES) + len(CONTEXT_NAMES)
    model = PixelModel(stages=(_random_stage(rng, n1), _random_stage(rng, n2)),
                       feature_names=FEATURE_NAMES + CONTEXT_NAMES, info={"seed": 1})
    path = model.save(tmp_path / "m.npz")
    loaded = load_model(path)
    features = rng.normal(size=(n1, 24, 24)).astype(np.float32)
    assert loaded.info == {"seed": 1} and len(loaded.stages) == 2
    assert np.array_equal(loaded.probability(features), model.probability(features))


def test_model_with_other_features_is_refused(tmp_path):
    rng = np.random.default_rng(2)
    model = PixelModel(stages=(_random_stage(rng, 3),), feature_names=("a", "b", "c"))
    with pytest.raises(ValueError, match="features"):
        load_model(model.save(tmp_path / "other.npz"))


def test_probability_peaks_on_a_dark_line_of_known_position():
    image = _line_face(row=60)
    p = joint_probability(model_input(image.astype(np.float32) / 255.0))
    profile = p[:, 40:160].mean(axis=1)
    assert abs(int(profile.argmax()) - 60) <= 1
    assert profile[60] > 0.9 and np.median(profile) < 0.2


def test_learned_detector_traces_a_dark_line_at_its_known_position():
    image = _line_face(row=60)
    traces = extract(image, m_per_px=1.0, params=ExtractParams(detector="learned")).traces
    assert traces.n_traces >= 1
    longest = int(np.argmax(traces.lengths_m()))
    rows = 120 - 0.5 - traces.polyline(longest)[:, 1]  # v up from the bottom edge -> row
    assert np.all(np.abs(rows - 60) <= 2.0)
    assert traces.lengths_m()[longest] >= 0.8 * 200
    confidence = traces.attributes["confidence"]
    assert np.all((confidence >= 0) & (confidence <= 1)) and confidence[longest] > 0.9


def test_unknown_detector_and_bad_probabilities_are_refused():
    with pytest.raises(ValueError, match="detector"):
        ExtractParams(detector="sobel")
    with pytest.raises(ValueError, match="prob_high"):
        ExtractParams(prob_low=0.9, prob_high=0.5)


def test_mean_along_weights_each_stretch_by_its_length():
    image = np.zeros((10, 41))
    image[5, :10] = 1.0  # columns 0-9: nearest-pixel sampling sees the first 9.5 px of 40
    assert mean_along([np.array([[5.0, 0.0], [5.0, 40.0]])], image)[0] == pytest.approx(9.5 / 40, abs=0.01)


def test_line_support_is_largest_along_the_line():
    values = np.zeros((61, 61), np.float32)
    values[30, :] = 1.0
    top, excess = line_support(values, 21)
    assert top[30, 30] == pytest.approx(1.0, abs=0.02)
    assert excess[30, 30] > 0.7  # only the horizontal direction sees the whole line
    dot = np.zeros((61, 61), np.float32)
    dot[30, 30] = 1.0
    assert line_support(dot, 21)[0][30, 30] < 0.1  # a point is 1 of about 21 samples


def test_smoothed_features_of_a_ramp_match_their_closed_forms_on_both_grids():
    """On a linear ramp I = 1 + a·col + b·row (gradient g = (b, a)), the Gaussian mean is the ramp
    itself, so the contrast is 0; the local standard deviation at σ is |g|·σ; the structure tensor
    is g gᵀ everywhere, so the coherence is |g|² / (|g|² + 1e-6) (its regulariser). σ 3 runs on
    the full grid, σ 4 and more on the coarsened one (COARSE_FROM_SIGMA)."""
    from rockmass.imaging.features import pixel_features

    r, c = np.mgrid[0:240, 0:240].astype(np.float32)
    a, b = 0.01, 0.004
    features = pixel_features(1.0 + a * c + b * r)
    at = {name: float(features[k][120, 120]) for k, name in enumerate(FEATURE_NAMES)}
    g2 = a * a + b * b
    for sigma in (3, 8, 20):
        assert abs(at[f"contrast_{sigma}"]) < 1e-5
    for sigma in (4, 16):
        assert at[f"std_{sigma}"] == pytest.approx(np.sqrt(g2) * sigma, rel=0.01)
    for sigma in (4, 12):
        assert at[f"coherence_{sigma}"] == pytest.approx(g2 / (g2 + 1e-6), rel=1e-3)


def test_fit_mlp_separates_two_linearly_separable_classes():
    rng = np.random.default_rng(4)
    x = rng.normal(size=(3000, 2)).astype(np.float32)
    y = (x[:, 0] + 0.5 * x[:, 1] > 0.3).astype(np.float32)
    mean, std, weights, biases = fit_mlp(x, y, hidden=(8,), epochs=40, batch=256, seed=4)
    stage = Stage(mean=mean, std=std, weights=weights, biases=biases)
    assert np.mean((stage.predict(x.T) > 0.5) == (y > 0.5)) > 0.97


def test_training_samples_keep_ignored_pixels_out_of_the_negatives():
    # a centre line on row 20, an ignored band (a minor crack) on rows 40-44: positives within 1 px
    # of the line, negatives beyond 3 px of it and never in the band; without the band some are
    rng = np.random.default_rng(0)
    features = rng.normal(size=(len(FEATURE_NAMES), 64, 64)).astype(np.float32)
    lines = np.zeros((64, 64), bool)
    lines[20] = True
    ignore = np.zeros((64, 64), bool)
    ignore[40:45] = True
    index, labels = face_samples(features, lines, rng, ignore=ignore, n_positive=50, n_negative=400)
    rows = index // 64
    assert np.all(np.abs(rows[labels == 1] - 20) <= 1)
    assert np.all(np.abs(rows[labels == 0] - 20) > 3)
    assert not np.any((rows[labels == 0] >= 40) & (rows[labels == 0] < 45))
    index, labels = face_samples(features, lines, rng, n_positive=50, n_negative=400)
    assert np.any(((index // 64)[labels == 0] >= 40) & ((index // 64)[labels == 0] < 45))


def test_trace_filters_default_per_detector_and_are_checked():
    learned, ridge = ExtractParams(detector="learned"), ExtractParams(detector="ridge")
    assert ExtractParams().detector == "auto"  # the default, except for bright joints
    assert ExtractParams(line_polarity="bright").detector == "ridge"
    assert ExtractParams(pixel_model="own.npz").detector == "learned"  # and own models
    with pytest.raises(ValueError, match="needs params.detector = 'ridge'"):
        ExtractParams(detector="learned", line_polarity="bright")
    assert [learned.resolved(n) for n in ("fill_holes_px", "min_trace_length_px",
                                          "min_trace_contrast", "min_trace_width")] == [400, 70.0, 0.25, 1.0]
    assert [ridge.resolved(n) for n in ("fill_holes_px", "min_trace_length_px",
                                        "min_trace_contrast", "min_trace_width")] == [0, 20.0, None, None]
    assert ExtractParams(detector="learned", min_trace_contrast=0.1).resolved("min_trace_contrast") == 0.1
    for bad, field in ((dict(min_trace_contrast=1.5), "min_trace_contrast"),
                       (dict(min_trace_contrast=float("nan")), "min_trace_contrast"),
                       (dict(min_trace_width=-1.0), "min_trace_width"),
                       (dict(fill_holes_px=-3), "fill_holes_px"), (dict(fill_holes_px=2.5), "fill_holes_px")):
        with pytest.raises(ValueError, match=field):
            ExtractParams(**bad)


def _two_line_face(faint=0.85, dark=0.45, shape=(160, 240), seed=5):
    """Textured rock with a dark 6 px joint (row 50) and a faint one (row 110): grey ratio to the
    rock ``dark`` and ``faint``."""
    rng = np.random.default_rng(seed)
    image = 150 + 5 * cv2.GaussianBlur(rng.standard_normal(shape).astype(np.float32), (0, 0), 1.0)
    image[47:53] *= dark
    image[108:112] *= faint
    return np.clip(image, 0, 255).astype(np.uint8)


def test_contrast_filter_drops_a_faint_line_and_keeps_the_dark_one():
    image = _two_line_face()
    # this rock is smooth (grey 150 +- 1.4): not stretched, so its lines keep their grey ratios
    loose = ExtractParams(detector="learned", min_trace_contrast=float("-inf"), min_face_spread=0.0)
    kept = extract(image, m_per_px=1.0, params=loose).traces
    contrast = kept.attributes["contrast"]
    rows = [float(np.median(160 - 0.5 - kept.polyline(i)[:, 1])) for i in range(kept.n_traces)]
    faint = [c for r, c in zip(rows, contrast) if abs(r - 109.5) <= 3]
    strong = [c for r, c in zip(rows, contrast) if abs(r - 50) <= 3]
    assert strong and faint, "both lines are traced without the contrast filter"
    assert min(strong) > 0.25 > max(faint)  # the grey ratios 0.45 and 0.85, seen through flattening
    # the fixed floor: the two lines cover 6 % of this face, so the darkest 5 % that give the
    # face's own contrast are the faint line itself, and the default share would lower the floor
    # to keep it (test_contrast_floor.py)
    fixed = ExtractParams(detector="learned", face_contrast_share=float("inf"), min_face_spread=0.0)
    filtered = extract(image, m_per_px=1.0, params=fixed).traces
    rows = [float(np.median(160 - 0.5 - filtered.polyline(i)[:, 1])) for i in range(filtered.n_traces)]
    assert any(abs(r - 50) <= 3 for r in rows) and not any(abs(r - 109.5) <= 3 for r in rows)


def test_shared_work_computes_a_map_once_per_model_and_image_and_changes_nothing(monkeypatch):
    from rockmass.imaging import learned

    rng = np.random.default_rng(3)
    image = (0.6 + 0.05 * rng.normal(size=(160, 200))).astype(np.float32)
    cv2.line(image, (10, 20), (190, 140), 0.3, 3)
    photo = (np.clip(image, 0, 1) * 255).astype(np.uint8)
    settings = [ExtractParams(detector="learned", prob_low=low, min_trace_length_px=floor)
                for low, floor in ((0.8, 70.0), (0.5, 30.0), (0.65, 50.0))]
    alone = [extract(photo, m_per_px=1.0, params=p) for p in settings]
    calls = []
    probability = learned.PixelModel.probability
    monkeypatch.setattr(learned.PixelModel, "probability",
                        lambda self, features: calls.append(features.shape) or
                        probability(self, features))
    with shared_work():
        reused = [extract(photo, m_per_px=1.0, params=p) for p in settings]
        with pytest.raises(RuntimeError, match="do not nest"):
            with shared_work():
                pass
    # one map per grid the learned detector reads (the working grid and the coarser ones)
    assert len(calls) == len(set(calls)) == 1 + len(alone[0].learned_levels["levels"][1:])
    for a, b in zip(alone, reused):
        np.testing.assert_array_equal(a.traces.xy_m, b.traces.xy_m)
        np.testing.assert_array_equal(a.traces.offsets, b.traces.offsets)
    assert alone[0].traces.xy_m.shape != alone[1].traces.xy_m.shape  # the settings do differ here
    n_calls = len(calls)
    extract(photo, m_per_px=1.0, params=settings[0])  # the maps were dropped with the block
    assert len(calls) == 2 * n_calls


def test_shared_work_traces_once_per_joint_mask_and_each_setting_gives_what_it_gives_alone(
        monkeypatch):
    import importlib
    from dataclasses import replace

    extract_module = importlib.import_module("rockmass.imaging.extract")  # not the function
    learned_module = importlib.import_module("rockmass.imaging.learned")
    rng = np.random.default_rng(4)
    image = (0.6 + 0.05 * rng.normal(size=(200, 260))).astype(np.float32)
    for (a, b) in (((10, 20), (250, 150)), ((20, 180), (60, 150)), ((150, 20), (200, 60))):
        cv2.line(image, a, b, 0.3, 3)  # one long joint, two of about 50 and 65 px
    photo = (np.clip(image, 0, 1) * 255).astype(np.uint8)
    settings = [ExtractParams(detector="learned", min_trace_length_px=floor, learned_levels=(),
                              prob_low=low)
                for low in (0.85, 0.5) for floor in (70.0, 50.0, 30.0)]
    alone = [extract(photo, m_per_px=1.0, params=p) for p in settings]
    traced, mapped = [], []
    chains = extract_module._chains_before_floor
    flattened = learned_module.flattened
    monkeypatch.setattr(extract_module, "_chains_before_floor",
                        lambda *args: traced.append(1) or chains(*args))
    monkeypatch.setattr(learned_module, "flattened",
                        lambda *args, **kw: mapped.append(1) or flattened(*args, **kw))
    with shared_work():
        reused = [extract(photo, m_per_px=1.0, params=p) for p in settings]
        again = extract(photo, m_per_px=1.0, params=replace(settings[0], prob_high=0.99))
    assert len(traced) == 3 and len(mapped) == 1  # a joint mask per pair of levels, one map
    for a, b in zip(alone + [extract(photo, m_per_px=1.0, params=replace(settings[0],
                                                                       prob_high=0.99))],
                    reused + [again]):
        np.testing.assert_array_equal(a.traces.xy_m, b.traces.xy_m)
        np.testing.assert_array_equal(a.traces.offsets, b.traces.offsets)
        for name in ("confidence", "contrast", "band_width_px", "joint_score"):
            np.testing.assert_array_equal(a.traces.attributes[name], b.traces.attributes[name])
        assert set(b.timings_s) == set(a.timings_s)
    assert alone[0].traces.n_traces < alone[2].traces.n_traces  # the floors do differ here
    assert alone[2].traces.total_length_m() != alone[5].traces.total_length_m()  # and the levels
