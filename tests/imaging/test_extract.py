"""extract(): single lines with known answers, scale handling, bad input, synthetic accuracy, brick."""

import warnings

import cv2
import numpy as np
import pytest

from rockmass.accuracy import trace_accuracy
from rockmass.imaging.extract import ExtractParams, extract, scale_from_control_points
from rockmass.imaging.metrics import buffered_match, set_mean_angles
from rockmass.imaging.synthetic import synthetic_face


def _line_image(angle_deg, width=3, shape=(200, 300), half_length=100.0):
    """A dark antialiased line through (row 100, col 150); returns the image and its end points."""
    img = np.full(shape, 180, dtype=np.uint8)
    centre = np.array([150.0, 100.0])  # (x=col, y=row)
    d = half_length * np.array([np.cos(np.radians(angle_deg)), -np.sin(np.radians(angle_deg))])
    p0, p1 = np.round(centre - d).astype(int), np.round(centre + d).astype(int)
    cv2.line(img, tuple(p0), tuple(p1), 60, width, cv2.LINE_AA)
    return img, float(np.hypot(*(p1 - p0)))


@pytest.mark.parametrize("angle", [0.0, 30.0, 90.0, 135.0])
def test_single_line_gives_one_trace_of_its_length_and_angle(angle):
    img, length_px = _line_image(angle)
    traces = extract(img, m_per_px=0.01).traces
    assert traces.n_traces == 1
    # skeleton ends sit within half a width of the drawn (round-capped) ends: 3 px in all
    assert abs(traces.attributes["length_m"][0] / 0.01 - length_px) <= 3.0
    assert abs((traces.attributes["angle_deg"][0] - angle + 90) % 180 - 90) <= 1.0


def test_m_per_px_scales_lengths_linearly():
    img, _ = _line_image(30.0)
    a = extract(img, m_per_px=0.01).traces
    b = extract(img, m_per_px=0.03).traces
    np.testing.assert_allclose(b.lengths_m(), 3 * a.lengths_m(), rtol=1e-12)
    np.testing.assert_allclose(b.xy_m, 3 * a.xy_m, rtol=1e-12)


def test_control_point_scale_equals_direct_scale():
    img, _ = _line_image(30.0)
    cp = {"rc_px": [(10, 10), (10, 110)], "distance_m": 2.0}  # 100 px = 2 m
    via_points = extract(img, control_points=cp)
    direct = extract(img, m_per_px=0.02)
    assert via_points.scale.source == "control_points" and via_points.scale.m_per_px == 0.02
    np.testing.assert_allclose(via_points.traces.xy_m, direct.traces.xy_m)


@pytest.mark.parametrize("distance", [0.0, -1.0, np.nan, np.inf])
def test_bad_control_point_distances_raise_naming_the_field(distance):
    with pytest.raises(ValueError, match="control_points.distance_m"):
        scale_from_control_points(((0, 0), (0, 10), distance))


def test_coincident_control_points_raise():
    with pytest.raises(ValueError, match="control_points.rc_px"):
        scale_from_control_points({"rc_px": [(5, 5), (5, 5)], "distance_m": 1.0})


@pytest.mark.parametrize("image, message", [
    (np.zeros((100, 100), dtype=np.uint8), "blank"),
    (np.full((100, 100), 255, dtype=np.uint8), "blank"),
    (np.zeros((1, 1), dtype=np.uint8), "1 x 1"),
])
def test_degenerate_images_raise_a_clear_message(image, message):
    with pytest.raises(ValueError, match=message):
        extract(image, m_per_px=0.01)


def test_bad_scale_and_roi_outside_raise():
    img, _ = _line_image(30.0)
    with pytest.raises(ValueError, match="m_per_px"):
        extract(img, m_per_px=0.0)
    with pytest.raises(ValueError, match="roi lies outside"):
        extract(img, m_per_px=0.01, roi=[[500, 500], [500, 600], [600, 600]])


def test_no_scale_runs_in_pixels_with_a_warning():
    img, length_px = _line_image(0.0)
    with pytest.warns(UserWarning, match="no scale"):
        result = extract(img)
    assert result.scale.units == "px" and result.scale.source == "none"
    assert any("no scale" in w for w in result.warnings)
    assert abs(result.traces.lengths_m()[0] - length_px) <= 3.0


def test_input_array_not_modified():
    img, _ = _line_image(30.0)
    rgb = np.dstack([img, img, img])
    before = rgb.copy()
    extract(rgb, m_per_px=0.01)
    np.testing.assert_array_equal(rgb, before)


def test_roi_limits_traces_and_becomes_the_window():
    img, _ = _line_image(0.0)  # horizontal line along row 100, cols 50..250
    roi = [[50, 0], [50, 150], [150, 150], [150, 0]]  # left half
    result = extract(img, m_per_px=0.01, roi=roi)
    assert result.traces.n_traces == 1
    assert result.traces.xy_m[:, 0].max() <= 1.51 + 1e-9  # u of col 150.5
    assert abs(result.traces.window_polygon().area - 1.0 * 1.5) < 0.05


def test_file_input_and_debug_images(tmp_path):
    img, _ = _line_image(135.0)
    path = tmp_path / "face.png"
    cv2.imwrite(str(path), img)
    result = extract(path, m_per_px=0.01, debug=True)
    assert result.traces.n_traces == 1
    assert set(result.debug) == {"flattened", "joint_probability", "ridge_response", "binary",
                                 "skeleton", "pruned", "face_mask"}  # "auto": both responses
    assert result.debug["binary"].shape == img.shape
    assert list(result.timings_s)[0] == "read"


def test_large_image_is_down_sampled_and_says_so():
    face = synthetic_face("easy", seed=11, shape_px=(300, 450), m_per_px=0.02)
    result = extract(face.image, m_per_px=0.02, params=ExtractParams(max_megapixels=0.06, detector="ridge"))
    assert result.scale.work_factor < 0.7 and "down-sampled" in result.scale.processing
    precision, recall, f1 = buffered_match(result.traces, face.truth, m_per_px=0.02,
                                           shape_px=face.image.shape)
    assert f1 > 0.6  # coordinates are back on the input grid


def test_easy_synthetic_face_has_f1_at_least_0_9():
    # the ridge filter's target on the plain faces (the learned detector leaves their short and
    # faint joints out, as real labels do: docs/imaging.md §3.1)
    face = synthetic_face("easy", seed=3, shape_px=(300, 450), m_per_px=0.02)
    result = extract(face.image, m_per_px=0.02, params=ExtractParams(detector="ridge"))
    acc = trace_accuracy(result.traces, face.truth, m_per_px=0.02)
    assert acc.f1 >= 0.9


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2])
def test_moderate_synthetic_face_meets_the_targets(seed):
    face = synthetic_face("moderate", seed=seed)
    result = extract(face.image, m_per_px=face.m_per_px, params=ExtractParams(detector="ridge"))
    acc = trace_accuracy(result.traces, face.truth, m_per_px=face.m_per_px)
    assert acc.f1 >= 0.85
    assert abs(acc.p21_rel_error) <= 0.10
    assert acc.max_set_angle_error_deg <= 3.0
    assert abs(acc.d_box_error) <= 0.05


def test_brick_photo_yields_near_vertical_continuous_and_short_cross_joints():
    from skimage import data

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # no scale: pixels
        traces = extract(data.brick(), params=ExtractParams(detector="ridge")).traces
    angles = set_mean_angles(traces, 2)
    vertical = np.argmin(np.abs(angles - 90))
    assert abs(angles[vertical] - 90) <= 10
    assert min(angles[1 - vertical], 180 - angles[1 - vertical]) <= 10
    angle, length = traces.attributes["angle_deg"], traces.attributes["length_m"]
    is_vertical = np.abs(angle - 90) < 45
    assert length[is_vertical].sum() > 3 * length[~is_vertical].sum()  # continuous joints dominate
    assert np.median(length[is_vertical]) > 2 * np.median(length[~is_vertical])  # cross joints short


def _vertical_joints_per_row_by_third(traces, rows):
    """Mean number of distinct near-vertical traces crossed per image row, in each column third."""
    import shapely

    vertical = np.abs(traces.attributes["angle_deg"] - 90) < 30
    geoms = traces.to_shapely()[vertical]
    counts = np.zeros(3)
    for y in rows:
        line = shapely.LineString([(0, y), (512, y)])
        xs = sorted(p.x for g in geoms for p in shapely.get_parts(shapely.intersection(g, line))
                    if p.geom_type == "Point")
        xs = [x for i, x in enumerate(xs) if i == 0 or x - xs[i - 1] > 4]
        for x in xs:
            counts[min(int(x // 171), 2)] += 1
    return counts / len(rows)


def test_brick_bright_joints_are_found_across_the_whole_photo():
    from scipy.ndimage import gaussian_filter
    from scipy.signal import find_peaks
    from skimage import data

    image = data.brick()
    rows = np.linspace(20, 492, 40).astype(int)
    # independent count: bright intensity peaks (mortar) along each row of the lightly smoothed photo
    smooth = gaussian_filter(image.astype(float), 1.5)
    peaks = np.zeros(3)
    for y in rows:
        for x in find_peaks(smooth[y], prominence=25, distance=12)[0]:
            peaks[min(x // 171, 2)] += 1
    peaks /= rows.size
    traces = extract(image, m_per_px=1.0, joint_width_px=8.0,
                     params=ExtractParams(line_polarity="bright")).traces
    # the face frame's v runs up from the bottom edge; the rows are symmetric about the middle, so
    # the same 40 rows are scanned (v = 512 - row - 0.5); with the default 3 px width the right
    # third's recessed joints give two rims each (9.1 crossings per row there)
    found = _vertical_joints_per_row_by_third(traces, 512 - rows - 0.5)
    np.testing.assert_allclose(found, peaks, rtol=0.2)
