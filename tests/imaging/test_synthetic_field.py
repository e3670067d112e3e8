"""Field-like synthetic faces: reproducible, truth on the dark joint cores, truth inside the image."""

import numpy as np
import pytest

from rockmass.imaging.synthetic_field import FieldStyle, centre_line_mask, field_face

SMALL = dict(shape_px=(160, 200), m_per_px=0.01)


def test_same_seed_gives_the_same_field_face():
    a, b, c = field_face(seed=4, **SMALL), field_face(seed=4, **SMALL), field_face(seed=5, **SMALL)
    assert np.array_equal(a.image, b.image) and np.array_equal(a.truth.xy_m, b.truth.xy_m)
    assert not np.array_equal(a.image, c.image)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_truth_centre_lines_lie_on_dark_joint_cores(seed):
    # cores darken the rock by 25-75 %; without clutter or steps, the centre line is darker than
    # the rock beside it (8 px away, outside the widest core's half width of 6 px)
    style = FieldStyle(minor_cracks=(0, 0), rubble=(0, 0), plates=(0, 0), veins=(0, 0),
                       crevice_fields=(0, 0), step_share=0.0, shadow_share=0.0, core_width_px=(2, 6))
    face = field_face(seed=seed, style=style, **SMALL)
    lines = centre_line_mask(face)
    import cv2

    near = cv2.dilate(lines.astype(np.uint8), np.ones((17, 17), np.uint8)).astype(bool)
    beside = near & ~cv2.dilate(lines.astype(np.uint8), np.ones((11, 11), np.uint8)).astype(bool)
    assert face.image[lines].mean() < 0.85 * face.image[beside].mean()


def test_truth_lies_inside_the_image_window():
    face = field_face(seed=7, **SMALL)
    h, w = face.image.shape
    xy = face.truth.xy_m
    assert face.truth.n_traces >= 1
    assert xy[:, 0].min() >= -1e-9 and xy[:, 0].max() <= w * 0.01 + 1e-9
    assert xy[:, 1].min() >= -1e-9 and xy[:, 1].max() <= h * 0.01 + 1e-9


def test_tiny_field_face_is_refused():
    with pytest.raises(ValueError, match="shape_px"):
        field_face(seed=0, shape_px=(20, 200))
