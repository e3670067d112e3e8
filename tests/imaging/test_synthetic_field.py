"""Field-like synthetic faces: reproducible, truth on the dark joint cores, truth inside the image,
half-casts straight and unlabelled, no truth under shotcrete."""

from dataclasses import replace

import numpy as np
import pytest

from rockmass.imaging.synthetic_field import (CREVICE_STYLE, TUNNEL_STYLE, FieldStyle,
                                              centre_line_mask, field_face, half_cast_axes,
                                              minor_crack_mask, shotcrete_area, shotcrete_mask)

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


@pytest.mark.parametrize("seed", [1, 2])
def test_minor_crack_mask_marks_the_drawn_cracks(seed):
    # the same quiet face drawn with and without minor cracks: the pixels the cracks darkened must
    # be those the mask redraws (a mask redrawn from a wrong stream would miss them)
    quiet = FieldStyle(major_joints=(0, 0), rubble=(0, 0), plates=(0, 0), veins=(0, 0),
                       crevice_fields=(0, 0), relief=(0.0, 0.0), oriented_texture=(0.0, 0.0),
                       minor_cracks=(40, 40))
    face = field_face(seed=seed, style=quiet, **SMALL)
    bare = field_face(seed=seed, style=replace(quiet, minor_cracks=(0, 0)), **SMALL)
    darkened = bare.image.astype(float) - face.image
    strokes = minor_crack_mask(face, margin_px=0)
    assert 0.005 < strokes.mean() < 0.2
    assert darkened[strokes].mean() > darkened[~strokes].mean() + 5.0
    assert (darkened > 8).sum() > 100
    assert minor_crack_mask(face)[darkened > 8].mean() > 0.95  # within the 2 px margin
    assert not minor_crack_mask(bare).any()


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


# quiet faces: one joint, no clutter, light noise, little blur, JPEG at 95 - the new elements stand out
QUIET = dict(minor_cracks=(0, 0), rubble=(0, 0), plates=(0, 0), veins=(0, 0), crevice_fields=(0, 0),
             major_joints=(1, 1), blur_px=(0.5, 0.5), noise=(1.5, 1.5), jpeg_quality=(95, 95))
NO_EXTRAS = dict(half_cast_families=(0, 0), shotcrete_share=0.0)


def test_half_casts_change_the_image_but_not_the_truth():
    # half-casts and shotcrete have their own random streams: switching them on leaves every other
    # element (and the truth) as it was
    with_casts = FieldStyle(half_cast_families=(2, 2), half_casts_per_family=(4, 4), shotcrete_share=0.0)
    a = field_face(seed=11, style=with_casts, **SMALL)
    b = field_face(seed=11, style=FieldStyle(**NO_EXTRAS), **SMALL)
    assert np.array_equal(a.truth.xy_m, b.truth.xy_m)
    assert not np.array_equal(a.image, b.image)
    assert len(half_cast_axes(a)) == 2 and half_cast_axes(b) == []


def test_half_cast_grooves_are_straight_and_parallel():
    import cv2

    style = FieldStyle(half_cast_families=(1, 1), half_casts_per_family=(5, 5), half_cast_fan_share=0.0,
                       half_cast_crack_share=0.0, half_cast_spacing_m=(0.3, 0.4), shotcrete_share=0.0,
                       **QUIET)
    face = field_face(seed=3, style=style, shape_px=(200, 300), m_per_px=0.005)
    plain = field_face(seed=3, style=replace(style, half_cast_families=(0, 0)), shape_px=(200, 300),
                       m_per_px=0.005)
    dark = (face.image.astype(int) - plain.image.astype(int)) < -20  # the grooves' shaded sides
    n, labels, stats, _ = cv2.connectedComponentsWithStats(dark.astype(np.uint8), connectivity=8)
    angles = []
    for k in range(1, n):
        if stats[k, cv2.CC_STAT_AREA] < 80:
            continue
        rc = np.argwhere(labels == k).astype(float)
        rc -= rc.mean(axis=0)
        _, _, vt = np.linalg.svd(rc, full_matrices=False)
        t, s = rc @ vt[0], rc @ vt[1]  # along and across the fitted line, px
        bins = np.round(t / 5).astype(int)  # the band's middle every 5 px along it
        middle = np.array([s[bins == b].mean() for b in np.unique(bins) if (bins == b).sum() >= 5])
        assert len(middle) >= 8 and np.sqrt(np.mean(middle ** 2)) < 0.5  # straight to half a pixel
        angles.append(np.degrees(np.arctan2(vt[0, 0], vt[0, 1])) % 180)
    assert len(angles) >= 2
    spread = np.ptp(np.unwrap(np.radians(angles) * 2) / 2)
    assert np.degrees(spread) < 2.0
    # and where the axes say they are
    axes = half_cast_axes(face)[0]
    direction = np.degrees(np.arctan2(*(axes[0, 1] - axes[0, 0]))) % 180
    assert abs((angles[0] - direction + 90) % 180 - 90) < 2.0


def test_shotcrete_hides_the_joints_under_it():
    import cv2
    import shapely

    style = FieldStyle(shotcrete_share=1.0, shotcrete_cover=(0.3, 0.3), half_cast_families=(0, 0))
    hidden_length = 0.0
    for seed in (1, 2, 3):
        face = field_face(seed=seed, style=style, **SMALL)
        bare = field_face(seed=seed, style=FieldStyle(**NO_EXTRAS), **SMALL)
        mask, area = shotcrete_mask(face), shotcrete_area(face)
        assert abs(mask.mean() - 0.3) < 0.01
        assert abs(area.area / (face.image.size * 0.01 ** 2) - 0.3) < 0.02
        lines = shapely.union_all(face.truth.to_shapely())
        assert lines.intersection(area).length < 1e-6  # no truth under the shotcrete
        hidden_length += bare.truth.total_length_m() - face.truth.total_length_m()
        # shotcrete is smoother than rock: local (7 x 7) standard deviation, away from its rim
        img = face.image.astype(np.float64)
        mean = cv2.blur(img, (7, 7))
        local_std = np.sqrt(np.maximum(cv2.blur(img * img, (7, 7)) - mean * mean, 0))
        kernel = np.ones((9, 9), np.uint8)
        inside = cv2.erode(mask.astype(np.uint8), kernel).astype(bool)
        outside = cv2.erode((~mask).astype(np.uint8), kernel).astype(bool)
        assert np.median(local_std[inside]) < 0.7 * np.median(local_std[outside])
    assert hidden_length > 0.1  # some joints did run where the shotcrete is


def test_the_tunnel_style_draws_some_faces_without_the_new_elements_and_the_default_none():
    style = TUNNEL_STYLE
    assert style.half_cast_families[0] == 0 and style.shotcrete_cover[0] == 0.0
    bare = sum(not half_cast_axes(f) and not shotcrete_mask(f).any()
               for f in (field_face(seed=s, shape_px=(40, 40), style=style) for s in range(12)))
    assert 0 < bare < 12
    assert all(not half_cast_axes(f) and not shotcrete_mask(f).any()
               for f in (field_face(seed=s, shape_px=(40, 40)) for s in range(12)))


def test_wide_crevices_widen_some_joints_and_leave_the_rest_of_the_face_as_it_was():
    # the crevices have a random stream of their own: the truth keeps its lines, only the widths
    # of the joints drawn as crevices change; the default style draws none
    faces = [(field_face(seed=s, **SMALL), field_face(seed=s, style=CREVICE_STYLE, **SMALL))
             for s in range(8)]
    assert FieldStyle().crevice_share == 0.0 and 0 < CREVICE_STYLE.crevice_share < 1
    widened = 0
    for plain, wide in faces:
        assert np.array_equal(plain.truth.xy_m, wide.truth.xy_m)
        a, b = plain.truth.attributes["width_px"], wide.truth.attributes["width_px"]
        changed = a != b
        widened += int(changed.sum())
        assert np.all(b[changed] >= CREVICE_STYLE.crevice_width_px[0] - 0.5)
        assert np.array_equal(plain.image, wide.image) == (not changed.any())
    assert widened > 0


def test_a_wide_crevice_is_a_dark_band_labelled_at_its_centre_line():
    import cv2

    style = replace(FieldStyle(**QUIET), step_share=0.0, shadow_share=0.0, crevice_share=1.0,
                    crevice_width_px=(24.0, 24.0), crevice_depth=(0.8, 0.8))
    face = field_face(seed=3, style=style, **SMALL)
    lines = centre_line_mask(face).astype(np.uint8)

    def ring(inner, outer):  # pixels between inner and outer px from the centre line
        near = cv2.dilate(lines, np.ones((2 * outer + 1,) * 2, np.uint8)).astype(bool)
        return near & ~cv2.dilate(lines, np.ones((2 * inner + 1,) * 2, np.uint8)).astype(bool)

    centre, inside, rock = (face.image[lines > 0].mean(), face.image[ring(5, 7)].mean(),
                            face.image[ring(20, 26)].mean())
    assert centre < 0.5 * rock and inside < 0.6 * rock  # dark across its width, not on a line
    assert centre <= inside + 5  # no lighter middle: the label is not on an edge


# the same face photographed with k times the pixels across (FieldStyle.feature_scale)
@pytest.mark.parametrize("style", [FieldStyle(), TUNNEL_STYLE], ids=["field", "tunnel"])
@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("k, base_shape, shape", [
    (2.0, (160, 200), (320, 400)), (1.7, (160, 200), (272, 340)),
    (np.sqrt(8.0), (160, 200), (453, 566))])
def test_feature_scale_draws_the_same_joints_in_metres_at_k_times_the_pixels(seed, k, base_shape,
                                                                              shape, style):
    # vertex for vertex when the larger face spans exactly k times the reference shape and no
    # shotcrete cuts the joints; else (k = sqrt 8: the image edge moves by the rounding of the
    # shape, and with it the clipping; a cut end follows the enlarged shotcrete edge) the same
    # lines to within one reference pixel
    import shapely

    base = field_face(seed=seed, shape_px=base_shape, m_per_px=0.01, style=style)
    big = field_face(seed=seed, shape_px=shape, m_per_px=0.01 / k,
                     style=replace(style, feature_scale=k))
    assert big.truth.n_traces == base.truth.n_traces
    lines = [shapely.MultiLineString([f.truth.polyline(i) for i in range(f.truth.n_traces)])
             for f in (base, big)]
    assert lines[0].hausdorff_distance(lines[1]) <= 0.01
    assert lines[1].length == pytest.approx(lines[0].length, rel=0.02)
    if np.allclose(np.multiply(k, base_shape), shape, atol=1e-9) and not shotcrete_mask(base).any():
        np.testing.assert_array_equal(big.truth.offsets, base.truth.offsets)
        np.testing.assert_allclose(big.truth.xy_m, base.truth.xy_m, atol=1e-9)
        # core widths in pixels: k times (each rounded to a whole pixel)
        widths, big_widths = base.truth.attributes["width_px"], big.truth.attributes["width_px"]
        assert np.all(np.abs(big_widths - k * widths) <= 0.5 + 0.5 * k)


@pytest.mark.parametrize("seed", [1, 2])
def test_feature_scale_counts_are_those_of_the_reference_face(seed):
    # 200 x 400 px is half of 400 x 400: five joints give a count of 2.5, which rounds to 2; the
    # larger face's rounded shape (566 x 1131 px, a little more than sqrt 8 times) holds a little
    # more area, so a count taken from it would round to 3
    style = FieldStyle(major_joints=(5, 5))
    base = field_face(seed=seed, shape_px=(200, 400), m_per_px=0.01, style=style)
    big = field_face(seed=seed, shape_px=(566, 1131), m_per_px=0.01 / np.sqrt(8.0),
                     style=replace(style, feature_scale=np.sqrt(8.0)))
    assert big.truth.n_traces == base.truth.n_traces
    np.testing.assert_array_equal(big.truth.offsets, base.truth.offsets)


@pytest.mark.parametrize("k", [2.0, 3.0])
def test_feature_scale_makes_a_joint_k_times_wider_in_pixels(k):
    # one quiet joint of a 4 px core, with and without its darkening: the darkened area in pixels
    # grows as k^2 on a face k times larger (k times longer, k times wider)
    quiet = FieldStyle(**{**QUIET, "noise": (0.0, 0.0)}, core_width_px=(4.0, 4.0),
                       shadow_share=0.0, step_share=0.0, relief=(0.0, 0.0),
                       oriented_texture=(0.0, 0.0))

    def darkened_px(scale):
        shape = (round(160 * scale), round(200 * scale))
        style = replace(quiet, feature_scale=scale)
        face = field_face(seed=3, shape_px=shape, m_per_px=0.01 / scale, style=style)
        bare = field_face(seed=3, shape_px=shape, m_per_px=0.01 / scale,
                          style=replace(style, core_depth=(0.0, 0.0)))
        return ((bare.image.astype(float) - face.image) > 10).sum()

    ratio = darkened_px(k) / darkened_px(1.0)
    assert ratio == pytest.approx(k * k, rel=0.2)


def test_feature_scale_minor_crack_mask_follows_the_scale():
    quiet = FieldStyle(major_joints=(0, 0), rubble=(0, 0), plates=(0, 0), veins=(0, 0),
                       crevice_fields=(0, 0), relief=(0.0, 0.0), oriented_texture=(0.0, 0.0),
                       minor_cracks=(40, 40), feature_scale=2.0)
    shape = dict(shape_px=(320, 400), m_per_px=0.005)
    face = field_face(seed=1, style=quiet, **shape)
    bare = field_face(seed=1, style=replace(quiet, minor_cracks=(0, 0)), **shape)
    darkened = bare.image.astype(float) - face.image
    assert (darkened > 8).sum() > 400
    assert minor_crack_mask(face)[darkened > 8].mean() > 0.95


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), float("inf")])
def test_feature_scale_must_be_finite_and_positive(bad):
    with pytest.raises(ValueError, match="feature_scale"):
        field_face(seed=0, style=FieldStyle(feature_scale=bad), **SMALL)


@pytest.mark.parametrize("style", [FieldStyle(), TUNNEL_STYLE], ids=["field", "tunnel"])
def test_a_face_at_feature_scale_k_averaged_down_k_times_is_the_reference_face(style):
    # the same face with k times the pixels: area-averaged back to the reference grid it must be
    # the face of k = 1 up to the camera's per-pixel noise, JPEG and the interpolation (a face
    # whose rock or clutter were drawn anew correlates at about 0.2-0.8)
    import cv2

    reference = field_face(seed=3, shape_px=(150, 225), m_per_px=0.008, style=style)
    for k in (2.0, 3.0):
        face = field_face(seed=3, shape_px=(round(150 * k), round(225 * k)), m_per_px=0.008 / k,
                          style=replace(style, feature_scale=k))
        averaged = cv2.resize(face.image, (225, 150), interpolation=cv2.INTER_AREA)
        assert np.corrcoef(reference.image.ravel(), averaged.ravel())[0, 1] > 0.97
        cover = cv2.resize(shotcrete_mask(face).astype(np.float32), (225, 150),
                           interpolation=cv2.INTER_AREA) > 0.5
        drawn = shotcrete_mask(reference)
        if drawn.any():  # the same lobes, not only the same share (which the quantile fixes)
            assert (cover & drawn).sum() / (cover | drawn).sum() > 0.95
