"""Bad input stops with a clear message naming the field; never NaN, never a silent answer."""

import numpy as np
import pytest

from rockmass.fractal import box_count, fit_loglog


def test_empty_image_is_refused():
    with pytest.raises(ValueError, match="empty"):
        box_count(np.zeros((360, 360), dtype=np.uint8))


def test_no_traces_is_refused():
    with pytest.raises(ValueError, match="no traces"):
        box_count(np.empty((0, 4)))


def test_nan_coordinates_name_the_rows():
    seg = np.array([[0, 0, 1, 1], [0, 1, np.nan, 0], [0, 0, 2, np.inf]], dtype=float)
    with pytest.raises(ValueError, match=r"rows \[1, 2\]"):
        box_count(seg)


def test_grid_too_small_for_the_range():
    with pytest.raises(ValueError, match="only 2 box sizes"):
        box_count(np.array([[0.0, 0.0, 1.0, 1.0]]), grid=16, fit_range_px=(5, 16))


def test_non_binary_image_without_threshold():
    img = np.arange(100, dtype=np.uint8).reshape(10, 10)
    with pytest.raises(ValueError, match="threshold"):
        box_count(img)


def test_raster_sizes_must_divide_the_grid():
    with pytest.raises(ValueError, match=r"divide the grid \(360\).*7\.0"):
        box_count(np.array([[0.0, 0.0, 1.0, 1.0]]), sizes_px=[1, 2, 7])


@pytest.mark.parametrize("kwargs, field", [({"method": "fractal"}, "method"),
                                           ({"line_rule": "wu"}, "line_rule"),
                                           ({"n_offsets": 0}, "n_offsets"),
                                           ({"grid": 2}, "grid"),
                                           ({"skeletonize": "maybe"}, "skeletonize")])
def test_invalid_options_name_the_field(kwargs, field):
    data = np.array([[0.0, 0.0, 1.0, 1.0]])
    if field == "skeletonize":
        data = np.eye(8, dtype=np.uint8)
    with pytest.raises((ValueError, TypeError), match=field):
        box_count(data, **kwargs)


def test_vector_method_refuses_an_image():
    with pytest.raises(ValueError, match="vector"):
        box_count(np.eye(360, dtype=np.uint8), method="vector")


def test_coincident_points_have_no_extent():
    with pytest.raises(ValueError, match="no extent|no traces"):
        box_count(np.array([[1.0, 1.0, 1.0, 1.0]]))


def test_constant_counts_fit_without_nan():
    fit = fit_loglog([1, 2, 4], [1, 1, 1])
    assert fit.dimension == 0.0 and fit.r2 == 1.0 and fit.stderr == 0.0


def test_fit_refuses_zero_counts():
    with pytest.raises(ValueError, match="> 0"):
        fit_loglog([1, 2, 4], [4, 0, 1])


def test_mask_outside_the_traces_is_refused():
    with pytest.raises(ValueError, match="no trace"):
        box_count(np.array([[0.0, 0.0, 1.0, 1.0]]),
                  mask=np.array([[5.0, 5.0], [6.0, 5.0], [6.0, 6.0]]))


def test_vector_sizes_that_would_exhaust_memory_are_refused():
    seg = np.array([[0, 0, 1, 1.0], [0, 1, 1, 0.0]])
    with pytest.raises(ValueError, match="sizes_px"):
        box_count(seg, method="vector", sizes_px=[1e-6, 1e-5, 1e-4], fit_range_px=(1e-6, 1e-4))


@pytest.mark.parametrize("kwargs, match", [({"sizes_px": []}, "sizes_px"),
                                           ({"fit_range_px": (1, 2, 90)}, "fit range"),
                                           ({"threshold": "5"}, "threshold")])
def test_malformed_arguments_have_clear_messages(kwargs, match):
    data = np.eye(60, dtype=np.uint8) if "threshold" in kwargs else np.array([[0, 0, 1, 1.0]])
    with pytest.raises((ValueError, TypeError), match=match):
        box_count(data, **kwargs)


@pytest.mark.parametrize("scale", [1e160, 1e-200])
def test_unrepresentable_extents_stop_with_a_message(scale):
    seg = np.array([[0, 0, 1, 1.0], [0, 1, 1, 0.0], [0.2, 0.1, 0.9, 0.4]]) * scale
    with pytest.raises(ValueError, match="rescale"):
        box_count(seg)
