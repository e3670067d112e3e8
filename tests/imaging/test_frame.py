"""Pixel <-> face-frame conversions."""

import numpy as np
import pytest

from rockmass.imaging import rc_to_uv, uv_to_rc


def test_round_trip_is_exact_to_rounding():
    rng = np.random.default_rng(31)
    rc = rng.uniform(-5, 500, size=(100, 2))
    back = uv_to_rc(rc_to_uv(rc, 480, 0.0125), 480, 0.0125)
    assert np.allclose(back, rc, atol=1e-9)


def test_bottom_left_pixel_centre_is_half_a_pixel_from_the_origin():
    assert rc_to_uv([[99, 0]], 100, 0.02).tolist() == [[0.01, 0.01]]


def test_v_points_up_and_u_right():
    uv = rc_to_uv([[0, 0], [99, 0], [99, 49]], 100, 1.0)
    assert uv[0, 1] > uv[1, 1]  # row 0 (top) has the largest v
    assert uv[2, 0] > uv[1, 0]  # larger column, larger u


@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan, np.inf])
def test_scale_must_be_positive_and_finite(bad):
    with pytest.raises(ValueError, match="m_per_px"):
        rc_to_uv([[0, 0]], 10, bad)
