"""Orientation conversions: hand-worked cases, round trips, axial conventions and bad input."""

import math

import numpy as np
import pytest

from rockmass.dfn.orientation import (
    angle_between,
    dip_from_normal,
    dip_from_pole_trend_plunge,
    dip_from_strike,
    normal_from_dip,
    pole_from_dip,
    pole_trend_plunge,
    strike_from_dip,
    to_lower_hemisphere,
    trend_plunge_from_vector,
    vector_from_trend_plunge,
)

S = math.sqrt(0.5)


def test_horizontal_plane_pole_points_straight_down():
    np.testing.assert_array_equal(pole_from_dip(0.0, 37.0) + 0.0, [0.0, 0.0, -1.0])
    np.testing.assert_array_equal(normal_from_dip(0.0, 37.0) + 0.0, [0.0, 0.0, 1.0])
    dip, dip_direction = dip_from_normal([0.0, 0.0, 1.0])
    assert (float(dip), float(dip_direction)) == (0.0, 0.0)


@pytest.mark.parametrize(("dip", "dip_direction", "pole"), [
    (90.0, 0.0, (0.0, -1.0, 0.0)),       # vertical, dipping North: pole points South
    (90.0, 90.0, (-1.0, 0.0, 0.0)),      # vertical, dipping East: pole points West
    (45.0, 180.0, (0.0, S, -S)),         # dipping South at 45: pole plunges 45 towards North
    (30.0, 90.0, (-0.5, 0.0, -math.sqrt(3) / 2)),
])
def test_pole_by_hand(dip, dip_direction, pole):
    np.testing.assert_allclose(pole_from_dip(dip, dip_direction), pole, atol=1e-15)


def test_upper_normal_points_down_dip_horizontally_and_is_minus_the_pole():
    normal = normal_from_dip(30.0, 90.0)
    np.testing.assert_allclose(normal, [0.5, 0.0, math.sqrt(3) / 2], atol=1e-15)
    np.testing.assert_array_equal(normal, -pole_from_dip(30.0, 90.0))


def test_dip_and_dip_direction_round_trip_through_the_pole_and_the_normal():
    dip, dip_direction = np.meshgrid(np.linspace(0.5, 89.5, 37), np.arange(0.0, 360.0, 7.5))
    for vectors in (pole_from_dip(dip, dip_direction), normal_from_dip(dip, dip_direction)):
        back_dip, back_direction = dip_from_normal(vectors)
        np.testing.assert_allclose(back_dip, dip, atol=1e-12)
        np.testing.assert_allclose(back_direction, dip_direction, atol=1e-10)


def test_vertical_plane_pole_round_trips_to_its_dip_direction():
    directions = np.arange(0.0, 360.0, 15.0)
    dip, direction = dip_from_normal(pole_from_dip(90.0, directions))
    np.testing.assert_allclose(dip, 90.0, atol=1e-12)
    np.testing.assert_allclose(direction, directions, atol=1e-10)
    # The upper normal of a vertical plane has z = 6e-17 > 0 and folds to the same pole.
    np.testing.assert_allclose(dip_from_normal(normal_from_dip(90.0, directions))[1], directions, atol=1e-10)


def test_exactly_horizontal_normal_is_read_as_a_pole():
    dip, direction = dip_from_normal([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    np.testing.assert_array_equal(dip, [90.0, 90.0])
    np.testing.assert_array_equal(direction, [270.0, 90.0])  # the same plane, both ways


def test_dip_direction_is_taken_mod_360():
    np.testing.assert_allclose(pole_from_dip(40.0, [450.0, -90.0, 720.0]),
                               pole_from_dip(40.0, [90.0, 270.0, 0.0]), atol=1e-15)


def test_dip_direction_output_is_in_0_to_360_even_for_rounding_noise():
    _, direction = dip_from_normal([[-1e-17, -1.0, -1.0], [1e-300, -1.0, -1.0]])
    assert ((direction >= 0.0) & (direction < 360.0)).all()
    np.testing.assert_allclose(direction, [0.0, 0.0], atol=1e-12)


@pytest.mark.parametrize(("strike", "dip_direction"), [
    (0.0, 90.0), (90.0, 180.0), (270.0, 0.0), (350.0, 80.0), (-90.0, 0.0), (315.0, 45.0),
])
def test_strike_and_dip_right_hand_rule_by_hand(strike, dip_direction):
    dip, direction = dip_from_strike(strike, 30.0)
    assert float(dip) == 30.0
    assert float(direction) == pytest.approx(dip_direction, abs=1e-12)
    assert float(strike_from_dip(direction)) == pytest.approx(strike % 360.0, abs=1e-12)


def test_strike_zero_dip_30_dips_east():
    # Looking North along the strike, the plane dips to the right (East): its pole plunges West.
    dip, direction = dip_from_strike(0.0, 30.0)
    np.testing.assert_allclose(pole_from_dip(dip, direction), [-0.5, 0.0, -math.sqrt(3) / 2], atol=1e-15)


@pytest.mark.parametrize(("trend", "plunge", "vector"), [
    (90.0, 0.0, (1.0, 0.0, 0.0)),        # due East, horizontal
    (0.0, 0.0, (0.0, 1.0, 0.0)),         # due North
    (123.0, 90.0, (0.0, 0.0, -1.0)),     # straight down, whatever the trend
    (180.0, 45.0, (0.0, -S, -S)),
    (270.0, -30.0, (-math.sqrt(3) / 2, 0.0, 0.5)),  # upward
])
def test_vector_from_trend_and_plunge_by_hand(trend, plunge, vector):
    np.testing.assert_allclose(vector_from_trend_plunge(trend, plunge), vector, atol=1e-15)


def test_trend_and_plunge_round_trip_through_the_vector():
    trend, plunge = np.meshgrid(np.arange(0.0, 360.0, 10.0), np.linspace(-89.0, 89.0, 31))
    back_trend, back_plunge = trend_plunge_from_vector(vector_from_trend_plunge(trend, plunge))
    np.testing.assert_allclose(back_trend, trend, atol=1e-10)
    np.testing.assert_allclose(back_plunge, plunge, atol=1e-12)


def test_vertical_vector_has_trend_zero():
    trend, plunge = trend_plunge_from_vector([[0.0, 0.0, -2.0], [-0.0, -0.0, 3.0]])
    np.testing.assert_array_equal(trend, [0.0, 0.0])
    np.testing.assert_array_equal(plunge, [90.0, -90.0])


def test_pole_trend_and_plunge_agree_with_the_pole_vector():
    dip, dip_direction = np.meshgrid(np.linspace(0.0, 90.0, 10), np.arange(0.0, 360.0, 30.0))
    trend, plunge = pole_trend_plunge(dip, dip_direction)
    np.testing.assert_allclose(vector_from_trend_plunge(trend, plunge), pole_from_dip(dip, dip_direction),
                               atol=1e-15)
    back_dip, back_direction = dip_from_pole_trend_plunge(trend, plunge)
    np.testing.assert_allclose(back_dip, dip, atol=1e-12)
    np.testing.assert_allclose(back_direction, dip_direction, atol=1e-12)


def test_pole_trend_and_plunge_by_hand():
    trend, plunge = pole_trend_plunge(30.0, 300.0)
    assert (float(trend), float(plunge)) == (120.0, 60.0)


def test_upward_normal_given_as_trend_and_plunge_is_the_same_plane():
    dip, direction = dip_from_pole_trend_plunge(300.0, -60.0)  # upper normal of 30/300
    assert (float(dip), float(direction)) == (30.0, 300.0)


def test_to_lower_hemisphere_flips_only_upward_vectors():
    vectors = np.array([[0.0, 1.0, 2.0], [1.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
    np.testing.assert_array_equal(to_lower_hemisphere(vectors), [[0.0, -1.0, -2.0], [1.0, 0.0, -1.0],
                                                                 [0.0, 1.0, 0.0]])


def test_angle_between_lines_is_axial():
    assert float(angle_between([0, 0, 1], [0, 0, -1])) == 0.0
    assert float(angle_between([0, 0, 1], [0, 0, -1], axial=False)) == 180.0
    assert float(angle_between([1, 0, 0], [0, 1, 0])) == 90.0
    assert float(angle_between([1, 0, 0], [-1, 1, 0])) == pytest.approx(45.0, abs=1e-12)


def test_angle_between_keeps_precision_for_nearly_parallel_lines():
    tiny = 1e-9  # radians: acos(cos(1e-9)) would give 0
    angle = angle_between([1.0, 0.0, 0.0], [math.cos(tiny), math.sin(tiny), 0.0])
    assert float(angle) == pytest.approx(math.degrees(tiny), rel=1e-9)


def test_angle_between_planes_is_the_angle_between_their_poles():
    angle = angle_between(pole_from_dip(30.0, 90.0), normal_from_dip(70.0, 90.0))
    assert float(angle) == pytest.approx(40.0, abs=1e-12)


def test_conversions_broadcast():
    poles = pole_from_dip(np.array([10.0, 20.0, 30.0, 40.0])[:, None], np.array([0.0, 90.0, 180.0]))
    assert poles.shape == (4, 3, 3)
    dip, direction = dip_from_normal(poles)
    assert dip.shape == direction.shape == (4, 3)


def test_inputs_are_not_modified():
    dip = np.array([10.0, 20.0])
    direction = np.array([-10.0, 400.0])
    vectors = np.array([[0.0, 3.0, 4.0], [1.0, 0.0, 0.0]])
    copies = [a.copy() for a in (dip, direction, vectors)]
    pole_from_dip(dip, direction)
    dip_from_strike(direction, dip)
    dip_from_normal(vectors)
    trend_plunge_from_vector(vectors)
    to_lower_hemisphere(vectors)
    angle_between(vectors, vectors[::-1])
    for original, copy in zip((dip, direction, vectors), copies):
        np.testing.assert_array_equal(original, copy)


@pytest.mark.parametrize(("call", "match"), [
    (lambda: pole_from_dip(91.0, 0.0), "dip_deg"),
    (lambda: normal_from_dip(-1.0, 0.0), "dip_deg"),
    (lambda: pole_from_dip(30.0, np.nan), "dip_direction_deg"),
    (lambda: dip_from_strike(np.inf, 30.0), "strike_deg"),
    (lambda: dip_from_strike(10.0, 95.0), "dip_deg"),
    (lambda: vector_from_trend_plunge(0.0, 90.5), "plunge_deg"),
    (lambda: vector_from_trend_plunge(np.nan, 10.0), "trend_deg"),
    (lambda: dip_from_pole_trend_plunge(0.0, -91.0), "plunge_deg"),
    (lambda: dip_from_normal([0.0, 0.0, 0.0]), "non-zero"),
    (lambda: dip_from_normal([1.0, 0.0]), r"shape \(\.\.\., 3\)"),
    (lambda: angle_between([1.0, 0.0, 0.0], [np.nan, 0.0, 0.0]), "v must be finite"),
    (lambda: to_lower_hemisphere([[1.0, 2.0]]), "vectors"),
])
def test_bad_input_names_the_field(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_non_numeric_input_is_a_type_error():
    with pytest.raises(TypeError, match="dip_deg"):
        pole_from_dip("steep", 0.0)
