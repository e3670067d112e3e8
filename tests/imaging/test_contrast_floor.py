"""The learned detector on faces of low contrast (docs/imaging.md §3.1).

Oracles: flattening a photo's grey levels towards their median (the same face in flatter light)
leaves its joints where they were, so the detector, whose input is stretched back to the spread of
the faces it knows, should find most of what it finds on the original photo; and on faces whose
joints are faint against ordinary texture ("hard" faces), a contrast floor at a share of the
face's own contrast keeps joints that a fixed floor of "a quarter darker than the face" drops.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rockmass.imaging.extract import ExtractParams, contrast_floor, extract
from rockmass.imaging.learned import MAX_STRETCH, MIN_SPREAD, stretch_flat_face
from rockmass.imaging.metrics import trace_accuracy
from rockmass.imaging.synthetic import in_flat_light, synthetic_face
from rockmass.imaging.vectorize import face_levels, face_sample


def test_face_contrast_is_the_darkest_percentile_below_the_median():
    img = np.full((20, 20), 0.8)
    img[:2] = 0.2  # a tenth of the face at 0.2: its 5th percentile
    assert face_levels(img).contrast == pytest.approx(1 - 0.2 / 0.8)
    assert face_levels(img, percentile=50).contrast == pytest.approx(0.0)
    mask = np.zeros_like(img, dtype=bool)
    mask[5:] = True  # the dark rows left out: a uniform face
    assert face_levels(img, mask=mask).contrast == pytest.approx(0.0)
    assert face_levels(np.zeros((0, 0))).contrast == 0.0
    assert face_levels(np.zeros((4, 4))).contrast == 0.0  # no positive median: no contrast


def test_face_sample_is_a_regular_grid_inside_the_mask():
    img = np.arange(100.0).reshape(10, 10)
    assert face_sample(img).size == 100
    assert face_sample(img, max_pixels=25).tolist() == img[::2, ::2].ravel().tolist()
    mask = img < 50
    assert face_sample(img, mask=mask, max_pixels=25).max() < 50
    with pytest.raises(ValueError, match="max_pixels"):
        face_sample(img, max_pixels=0)


def test_face_contrast_does_not_change_with_the_grey_scale():
    rng = np.random.default_rng(1)
    img = rng.uniform(0.2, 1.0, (50, 50))
    assert face_levels(3.7 * img).contrast == pytest.approx(face_levels(img).contrast)


def test_floor_is_the_fixed_one_lowered_on_a_flat_face():
    learned = ExtractParams(detector="learned")
    assert contrast_floor(learned, 0.1) == pytest.approx(0.8 * 0.1)  # a faint face
    assert contrast_floor(learned, 0.8) == pytest.approx(0.25)  # the fixed floor is the lower
    assert contrast_floor(learned, None) == pytest.approx(0.25)
    fixed = ExtractParams(detector="learned", face_contrast_share=math.inf)
    assert contrast_floor(fixed, 0.1) == pytest.approx(0.25)
    assert contrast_floor(ExtractParams(detector="ridge"), 0.1) is None
    off = ExtractParams(detector="learned", min_trace_contrast=-math.inf)
    assert contrast_floor(off, 0.1) == -math.inf


@pytest.mark.parametrize("value", [-0.1, "0.6", math.nan, True])
def test_bad_share_is_refused_by_name(value):
    with pytest.raises(ValueError, match="face_contrast_share"):
        ExtractParams(face_contrast_share=value)


def test_faint_joints_on_ordinary_rock_are_kept():
    """"hard" faces: joints 0.13-0.2 darker than the face in ordinary texture. A fixed floor of
    0.25 drops nearly all; the floor at a share of the face's own contrast keeps a quarter of the
    joints' length, nearly all of it right."""
    face = synthetic_face("hard", seed=1, shape_px=(1000, 1500), m_per_px=0.008)

    def scores(**settings):
        result = extract(face.image, m_per_px=face.m_per_px,
                         params=ExtractParams(detector="learned", **settings))
        accuracy = trace_accuracy(result.traces, face.truth, m_per_px=face.m_per_px)
        return accuracy.recall, accuracy.precision, result.face_contrast

    recall, precision, record = scores()
    assert recall > 0.2 and precision > 0.95
    assert record["stretch"] == 1.0  # ordinary texture: the input is not stretched
    assert record["contrast_floor"] == pytest.approx(0.8 * record["face_contrast"])
    assert record["contrast_floor"] < 0.25
    fixed_recall, _, record = scores(face_contrast_share=math.inf)
    assert fixed_recall < 0.05 and record["contrast_floor"] == 0.25


@pytest.mark.parametrize("factor", [0.0, 1.5, math.nan])
def test_flat_light_factor_is_checked(factor):
    face = synthetic_face("easy", seed=1, shape_px=(40, 60), m_per_px=0.05)
    with pytest.raises(ValueError, match="factor"):
        in_flat_light(face, factor)


def test_a_flat_face_is_stretched_back_to_the_model_range():
    rng = np.random.default_rng(2)
    face = (1.0 + 0.12 * rng.standard_normal((80, 80))).astype(np.float32)
    stretched = []
    for factor in (0.5, 0.25):
        dim = (1.0 + factor * (face - 1.0)).astype(np.float32)
        out, gain, spread = stretch_flat_face(dim)
        assert spread == pytest.approx(0.12 * factor, rel=0.05)
        assert gain == pytest.approx(MIN_SPREAD / (0.12 * factor), rel=0.05)
        median = np.median(out)
        spread = 1.4826 * np.median(np.abs(out - median)) / median
        assert spread == pytest.approx(MIN_SPREAD, rel=1e-3)
        stretched.append(out / median - 1.0)
    # the relative differences from the median are the same, however flat the light was
    assert np.allclose(stretched[0], stretched[1], atol=1e-5)
    assert stretch_flat_face(face)[1] == 1.0  # contrasted enough: unchanged
    assert stretch_flat_face(np.full((8, 8), 0.7, np.float32))[1] == 1.0  # no spread: unchanged
    tiny = (1.0 + 1e-4 * rng.standard_normal((40, 40))).astype(np.float32)
    assert stretch_flat_face(tiny)[1] == MAX_STRETCH
    dim = (1.0 + 0.2 * (face - 1.0)).astype(np.float32)  # spread 0.024: stretched about 3 times
    dim[:4] = 0.1  # a line 0.9 darker than the face: stretched below 0, clipped at 0
    before = dim.copy()
    out, gain, _ = stretch_flat_face(dim)
    assert gain > 2 and out.min() == 0.0 and np.array_equal(dim, before)  # the input is unchanged
    with pytest.raises(ValueError, match="max_stretch"):
        stretch_flat_face(dim, max_stretch=0.5)


def test_moderate_face_in_flat_light_keeps_its_joints():
    face = synthetic_face("moderate", seed=5, shape_px=(500, 750), m_per_px=0.016)

    def recall(image, **settings):
        result = extract(image, m_per_px=face.m_per_px,
                         params=ExtractParams(detector="learned", **settings))
        return trace_accuracy(result.traces, face.truth, m_per_px=face.m_per_px).recall, result

    dim = in_flat_light(face, 0.3).image
    (flat_recall, result), (recall_as_is, _) = recall(dim), recall(face.image)
    assert flat_recall >= 0.8 * recall_as_is > 0.3
    assert result.face_contrast["stretch"] > 2.0
    assert any("stretched" in note for note in result.warnings)
    # the input not stretched, the probabilities no longer reach the seeds: the stretch does it
    assert recall(dim, min_face_spread=0.0)[0] < 0.3 * recall_as_is


def test_stretch_setting_defaults_to_the_model_range_and_is_checked():
    assert ExtractParams().min_face_spread == MIN_SPREAD
    for value in (-0.1, 1.0, math.inf, "0.1", False):
        with pytest.raises(ValueError, match="min_face_spread"):
            ExtractParams(min_face_spread=value)


def test_a_stretch_other_than_the_models_training_is_reported(tmp_path):
    """A model file records the stretch its training faces went through (``info["input"]``); a
    run that stretches a flat face by another factor, or with a model that records none, says so
    and records both factors."""
    from rockmass.imaging.learned import PixelModel, load_model

    shipped = load_model()
    assert shipped.input_stretch == (MIN_SPREAD, MAX_STRETCH)

    def model_with(name, entry):
        info = {k: v for k, v in shipped.info.items() if k != "input"}
        info.update({} if entry is None else {"input": entry})
        return str(PixelModel(shipped.stages, shipped.feature_names, info).save(tmp_path / name))

    face = synthetic_face("moderate", seed=5, shape_px=(250, 375), m_per_px=0.032)
    dim = in_flat_light(face, 0.3).image

    def run(model, image=dim, **settings):
        result = extract(image, m_per_px=face.m_per_px,
                         params=ExtractParams(detector="learned", pixel_model=model, **settings))
        return result, [note for note in result.warnings if "pixel model" in note]

    result, notes = run(None)
    record = result.face_contrast
    assert 1.0 < record["stretch"] < 5.0 and record["model_stretch"] == record["stretch"]
    assert not notes
    assert result.summary()["detector_model"]["input_stretch"] == {
        "min_face_spread": MIN_SPREAD, "max_stretch": MAX_STRETCH}
    wider = model_with("wider.npz", {"min_face_spread": 2 * MIN_SPREAD, "max_stretch": MAX_STRETCH})
    result, notes = run(wider)
    assert result.face_contrast["model_stretch"] == pytest.approx(2 * record["stretch"])
    assert len(notes) == 1 and "min_face_spread" in notes[0]
    assert not run(wider, min_face_spread=2 * MIN_SPREAD)[1]  # the run follows the model: silent
    unrecorded = model_with("unrecorded.npz", None)
    result, notes = run(unrecorded)
    assert result.face_contrast["model_stretch"] is None
    assert len(notes) == 1 and "does not record" in notes[0]
    assert result.summary()["detector_model"]["input_stretch"] is None
    assert not run(unrecorded, image=face.image)[1]  # a face not stretched: nothing to say
