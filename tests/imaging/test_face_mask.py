"""The face mask (imaging/face_mask.py): synthetic scenes whose rock region is known by construction."""

import cv2
import numpy as np
import pytest

from rockmass.imaging import extract
from rockmass.imaging.extract import ExtractParams
from rockmass.imaging.face_mask import FaceMaskParams, face_mask, face_mask_cues
from rockmass.imaging.frame import uv_to_rc

SHAPE = (300, 450)
SKY_ROWS = 70           # rows [0, 70): saturated white "sky"
PANEL_COL = 270         # columns [270, 450) below the sky: flat grey "shotcrete"
ROCK_LINE_COL = 120     # a dark vertical joint on the rock
PANEL_LINE_COL = 360    # the same dark line on the shotcrete


def _rock_texture(shape, seed):
    """Rough rock: grey-brown noise at two scales, 0.2-0.7 (seed fixed: the scene is the fixture)."""
    rng = np.random.default_rng(seed)
    fine = cv2.GaussianBlur(rng.normal(0, 1, shape).astype(np.float32), (0, 0), 1.2)
    coarse = cv2.GaussianBlur(rng.normal(0, 1, shape).astype(np.float32), (0, 0), 6.0)
    grey = 0.45 + 0.12 * fine / fine.std() + 0.08 * coarse / coarse.std()
    return np.clip(grey, 0.2, 0.7)


def _scene(lines=False, seed=3):
    """RGB uint8 scene: rock (lower left), shotcrete panel (lower right), sky band (top); and the
    known rock region as a bool mask."""
    grey = _rock_texture(SHAPE, seed)
    rng = np.random.default_rng(seed + 1)
    rgb = np.stack([grey * 1.04, grey, grey * 0.92], axis=2)
    rock = np.zeros(SHAPE, dtype=bool)
    rock[SKY_ROWS:, :PANEL_COL] = True
    rgb[SKY_ROWS:, PANEL_COL:] = 0.58 + rng.normal(0, 0.004, (SHAPE[0] - SKY_ROWS, SHAPE[1] - PANEL_COL, 1))
    rgb[:SKY_ROWS] = 1.0
    if lines:
        for col in (ROCK_LINE_COL, PANEL_LINE_COL):
            rgb[SKY_ROWS + 30:SHAPE[0] - 30, col - 1:col + 2] = 0.08
    return np.round(np.clip(rgb, 0, 1) * 255).astype(np.uint8), rock


def _iou(a, b):
    return (a & b).sum() / (a | b).sum()


def test_rock_region_is_kept_and_panel_and_sky_are_left_out():
    image, rock = _scene()
    mask = face_mask(image)
    assert _iou(mask, rock) >= 0.9
    assert not mask[:SKY_ROWS].any()
    assert mask[SKY_ROWS:, PANEL_COL:].mean() < 0.001  # a corner pixel or two where all three meet


def test_cues_name_what_they_left_out():
    image, _ = _scene()
    cues = face_mask_cues(image)
    assert cues.cues["bright"][:SKY_ROWS - 5].all()
    assert cues.cues["smooth"][SKY_ROWS + 10:-10, PANEL_COL + 10:-10].all()
    assert not cues.cues["smooth"][SKY_ROWS + 10:-10, 10:PANEL_COL - 10].any()
    expected_outside = 1 - (SHAPE[0] - SKY_ROWS) * PANEL_COL / (SHAPE[0] * SHAPE[1])
    assert cues.excluded_fraction["total"] == pytest.approx(expected_outside, abs=0.05)


def test_border_band_is_left_out_of_an_all_rock_photo():
    grey = _rock_texture(SHAPE, seed=5)
    band = round(FaceMaskParams().border_frac * min(SHAPE))
    for mode in ("full", "border"):
        mask = face_mask(grey, mode=mode)
        assert not mask[:band].any() and not mask[-band:].any()
        assert not mask[:, :band].any() and not mask[:, -band:].any()
        assert mask[band:-band, band:-band].all()


def test_border_mode_ignores_panel_and_sky():
    image, _ = _scene()
    mask = face_mask(image, mode="border")
    assert mask[SKY_ROWS // 2, SHAPE[1] // 2] and mask[200, PANEL_COL + 50]


def test_strongly_coloured_machinery_is_left_out():
    grey = _rock_texture(SHAPE, seed=6)
    image = np.stack([grey, grey, grey], axis=2)
    image[150:260, 300:420] = (0.95, 0.75, 0.05)  # a yellow machine
    mask = face_mask(image)
    assert not mask[150:260, 300:420].any()
    assert mask[50:250, 20:250].all()


def test_grey_photo_gets_no_colour_cue_and_the_mask_has_the_shape_asked_for():
    grey = _rock_texture((600, 900), seed=7)  # 0.54 MP: computed on a down-sampled copy
    cues = face_mask_cues(grey, shape_px=(150, 225))
    assert cues.mask.shape == (150, 225)
    assert not cues.cues["coloured"].any()
    assert face_mask(grey).shape == (600, 900)


def test_flat_photo_falls_back_to_the_inside_of_the_border_band():
    mask = face_mask(np.full((100, 120), 0.4))
    assert mask[5:-5, 5:-5].all() and not mask[0].any()


def test_input_not_modified():
    image, _ = _scene()
    copy = image.copy()
    face_mask(image)
    assert np.array_equal(image, copy)


@pytest.mark.parametrize("kwargs, name", [(dict(border_frac=0.6), "border_frac"),
                                          (dict(smooth_ratio=-1.0), "smooth_ratio"),
                                          (dict(work_megapixels=0.0), "work_megapixels")])
def test_bad_params_raise_naming_the_field(kwargs, name):
    with pytest.raises(ValueError, match=name):
        FaceMaskParams(**kwargs)


def test_bad_mode_raises_naming_the_choices():
    with pytest.raises(ValueError, match="face_mask must be one of border, full, off"):
        ExtractParams(face_mask="auto")
    with pytest.raises(ValueError, match="mode"):
        face_mask(np.zeros((50, 50)), mode="off")


def _polylines_rc(result):
    """Each trace as (n, 2) pixel (row, col) vertices."""
    return [uv_to_rc(result.traces.polyline(i), SHAPE[0], 1.0) for i in range(result.traces.n_traces)]


def _long_vertical_near(result, col):
    """Traces at least 100 px long lying within 4 px of column ``col``."""
    return [r for r in _polylines_rc(result) if np.abs(r[:, 1] - col).max() <= 4 and np.ptp(r[:, 0]) >= 100]


def test_line_on_shotcrete_is_dropped_and_line_on_rock_is_kept():
    image, _ = _scene(lines=True)
    masked = extract(image, m_per_px=1.0, params=ExtractParams(face_mask="full"))
    assert _long_vertical_near(masked, ROCK_LINE_COL)
    rc = np.vstack(_polylines_rc(masked))
    assert not (rc[:, 1] > PANEL_COL).any()  # nothing at all on the panel
    info = masked.summary()["face_mask"]
    assert info["used"] and info["source"] == "face mask" and info["window"] == "face outline"
    outside_rock = 1 - (SHAPE[0] - SKY_ROWS) * PANEL_COL / (SHAPE[0] * SHAPE[1])
    assert outside_rock < info["masked_fraction"] < outside_rock + 0.06  # + border band and margin
    # the sampling window is the rock region (about 230 x 270 px), not the photo
    window = masked.traces.window_xy_m
    area = 0.5 * abs(np.dot(window[:, 0], np.roll(window[:, 1], -1))
                     - np.dot(window[:, 1], np.roll(window[:, 0], -1)))
    assert area == pytest.approx((SHAPE[0] - SKY_ROWS) * PANEL_COL, rel=0.05)


def test_without_the_mask_the_line_on_shotcrete_is_a_trace():
    image, _ = _scene(lines=True)
    unmasked = extract(image, m_per_px=1.0, params=ExtractParams(face_mask="off"))
    assert _long_vertical_near(unmasked, PANEL_LINE_COL)
    assert unmasked.summary()["face_mask"] == {"used": False, "source": "none", "mode": "off",
                                               "masked_fraction": 0.0, "window": "image"}


def test_roi_overrides_the_face_mask():
    image, _ = _scene(lines=True)
    panel = [[SKY_ROWS + 5, PANEL_COL + 5], [SKY_ROWS + 5, SHAPE[1] - 5],
             [SHAPE[0] - 5, SHAPE[1] - 5], [SHAPE[0] - 5, PANEL_COL + 5]]
    result = extract(image, m_per_px=1.0, roi=panel, params=ExtractParams(face_mask="full"))
    assert _long_vertical_near(result, PANEL_LINE_COL)
    info = result.summary()["face_mask"]
    assert info["source"] == "roi" and info["window"] == "roi" and "excluded_fraction" not in info


@pytest.mark.parametrize("detector", ["ridge", "learned"])
def test_trace_crossing_the_border_band_still_reaches_the_border(detector):
    image = _rock_texture(SHAPE, seed=8)
    image[:, 200:203] = 0.05  # a dark joint from top to bottom
    result = extract(image, m_per_px=1.0, params=ExtractParams(detector=detector))  # default band
    assert result.summary()["face_mask"]["mode"] == "border"
    found = _long_vertical_near(result, 201)
    # one trace, not two overlapping ones (a texture spur beside the line once took its
    # continuation with the learned detector; tests/imaging/test_skeleton_graph.py)
    assert len(found) == 1
    assert found and min(r[:, 0].min() for r in found) < 0.5
    assert max(r[:, 0].max() for r in found) > SHAPE[0] - 1.5
