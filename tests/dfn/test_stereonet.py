"""Equal-area stereonet: projection by hand, cones, and the written figure."""

import math

import numpy as np
import pytest

from rockmass.dfn.fisher import fit_fisher, sample_fisher
from rockmass.dfn.orientation import pole_from_dip, vector_from_trend_plunge
from rockmass.dfn.stereonet import equal_area_xy, plot_stereonet, small_circle


def test_projection_puts_vertical_at_centre_and_horizontal_on_the_primitive():
    xy = equal_area_xy([[0, 0, -1], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    np.testing.assert_allclose(xy, [[0, 0], [1, 0], [0, 1], [0, 0]], atol=1e-15)


@pytest.mark.parametrize("trend, plunge", [(0.0, 45.0), (135.0, 10.0), (250.0, 80.0)])
def test_radius_is_root_two_sin_half_the_angle_from_vertical(trend, plunge):
    xy = equal_area_xy(vector_from_trend_plunge(trend, plunge))
    radius = math.sqrt(2.0) * math.sin(math.radians(90.0 - plunge) / 2.0)
    assert np.hypot(*xy) == pytest.approx(radius, rel=1e-12)
    assert math.degrees(math.atan2(xy[0], xy[1])) % 360.0 == pytest.approx(trend % 360.0)  # North up


def test_upper_hemisphere_vectors_plot_as_their_opposites():
    v = np.array([0.3, -0.4, 0.5])
    np.testing.assert_allclose(equal_area_xy(v), equal_area_xy(-v))


def test_cone_about_the_vertical_is_a_circle_of_the_equal_area_radius():
    xy = small_circle([0.0, 0.0, -1.0], 30.0)
    assert np.all(np.isfinite(xy))
    np.testing.assert_allclose(np.hypot(*xy.T), math.sqrt(2.0) * math.sin(math.radians(15.0)), rtol=1e-12)


def test_cone_crossing_the_primitive_is_broken_not_drawn_across():
    xy = small_circle(pole_from_dip(85.0, 0.0), 20.0)
    breaks = np.flatnonzero(np.isnan(xy[:, 0]))
    assert breaks.size == 2
    finite = xy[np.isfinite(xy[:, 0])]
    assert np.all(np.hypot(*finite.T) <= 1.0 + 1e-12)


def test_stereonet_writes_a_png(tmp_path):
    rng = np.random.default_rng(3)  # fixed seed
    poles = np.vstack([sample_fisher(rng, pole_from_dip(50, 270), 30.0, 20),
                       sample_fisher(rng, pole_from_dip(80, 10), 30.0, 20)])
    fits = [fit_fisher(poles[:20]), fit_fisher(poles[20:])]
    path = tmp_path / "net.png"
    plot_stereonet(poles, path, membership=np.repeat([0, 1], 20), set_fits=fits,
                   line_direction=vector_from_trend_plunge(135.0, 10.0), title="test")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_density_of_no_pole_is_refused():
    from rockmass.dfn.stereonet import plot_pole_density

    with pytest.raises(ValueError, match="no pole"):
        plot_pole_density(np.zeros((0, 3)))
