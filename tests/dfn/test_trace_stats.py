"""The JSON-ready trace-map summary: fractopo names and units, hand-checked values, None with reasons."""

import json
import math

import numpy as np
import pytest
import shapely

from rockmass.dfn import TraceMap
from rockmass.dfn.mauldon import circle_window, mauldon_circle
from rockmass.dfn.trace_stats import trace_map_statistics

from ._fixtures import CATALOGUE, SQUARE_10, TOPOLOGY_CASES, intensity_square

FRACTOPO_PARAMETERS = {
    "Number of Traces": "-",
    "Area": "m²",
    "Areal Frequency P20": "1/m²",
    "Fracture Intensity P21": "m/m²",
    "Trace Mean Length": "m",
    "Trace Min Length": "m",
    "Trace Max Length": "m",
    "Dimensionless Intensity P22": "-",
    "Number of Branches": "-",
    "Connections per Trace": "-",
    "Connections per Branch": "-",
    "Connection Frequency": "1/m²",
    "Fracture Intensity (Mauldon)": "m/m²",
    "Fracture Density (Mauldon)": "1/m²",
    "Trace Mean Length (Mauldon)": "m",
}


def grid_map():
    """Five horizontal traces 2 m apart and four vertical ones 2.5 m apart, all edge to edge in the square."""
    rows = [[0, y, 10, y] for y in (1, 3, 5, 7, 9)] + [[x, 0, x, 10] for x in (2, 4, 6, 8)]
    return TraceMap.from_segments(rows, window=SQUARE_10)


def circle_map():
    """A 64-gon window of radius 5 and three traces: through it (n 2), centre outwards (n 1, m 1), inside (m 2)."""
    return TraceMap.from_segments(
        [[-3, -10, -3, 10], [0, 0, 8, 0], [1, 1, 2, 3]], window=shapely.Point(0, 0).buffer(5.0)
    )


def walk(value):
    """Every leaf of a nested dict / list."""
    if isinstance(value, dict):
        for item in value.values():
            yield from walk(item)
    elif isinstance(value, list):
        for item in value:
            yield from walk(item)
    else:
        yield value



@pytest.mark.parametrize("make", [intensity_square, grid_map, circle_map, CATALOGUE["single_trace"].build])
def test_summary_is_strict_json_with_no_nan(make):
    tm = make()
    # issue 19: the single-trace catalogue map has no window, so its area is chosen explicitly
    result = trace_map_statistics(tm, window=None if tm.window_xy_m is not None else "bbox").to_dict()
    text = json.dumps(result, allow_nan=False)
    assert json.loads(text) == result
    assert not any(isinstance(v, float) and not math.isfinite(v) for v in walk(result))


def test_fractopo_parameters_are_present_with_their_units():
    result = trace_map_statistics(intensity_square()).to_dict()
    for name, unit in FRACTOPO_PARAMETERS.items():
        assert result[name]["unit"] == unit, name
        assert "reason" in result[name] or result[name]["value"] is not None, name


def test_hand_counted_square_gives_exact_intensities():
    result = trace_map_statistics(intensity_square()).to_dict()
    assert result["Number of Traces"]["value"] == 4
    assert result["Area"]["value"] == 100.0
    assert result["Fracture Intensity P21"]["value"] == pytest.approx(0.19, rel=1e-12)
    assert result["Areal Frequency P20"]["value"] == pytest.approx(0.035, rel=1e-12)
    assert result["Trace Mean Length"]["value"] == pytest.approx(4.75, rel=1e-12)
    assert (result["Trace Min Length"]["value"], result["Trace Max Length"]["value"]) == pytest.approx((3.0, 6.0))
    assert result["traces"]["length"] == pytest.approx([5.0, 6.0, 3.0, 5.0], rel=1e-12)
    assert result["traces"]["censored"] == [False, False, False, True]


def test_edge_censored_network_gives_hand_counted_topology():
    case = TOPOLOGY_CASES["edge_censored"]
    result = trace_map_statistics(case.build(), snap_tolerance_m=case.tolerance_m).to_dict()
    assert result["Node Counts"] == {"I": 1, "Y": 0, "X": 1, "E": 3}
    assert result["Number of Branches"]["value"] == 2.5  # (1 + 4) / 2
    assert result["Connections per Trace"]["value"] == 4.0  # 2 x 1 / ((1 + 0) / 2)
    assert result["Fracture Intensity P21"]["value"] == pytest.approx(0.18)  # (10 + 8) / 100
    assert result["Number of Censored Traces"]["value"] == 2
    assert result["traces"]["end_class"] == [["E", "E"], ["I", "E"]]


def test_square_window_leaves_mauldon_undefined_with_a_reason_when_asked_to():
    result = trace_map_statistics(intensity_square(), mauldon_in_window=False).to_dict()
    for name in ("Fracture Intensity (Mauldon)", "Fracture Density (Mauldon)", "Trace Mean Length (Mauldon)"):
        assert result[name]["value"] is None and "not a circle" in result[name]["reason"]
    assert result["window"]["is_circle"] is False and result["window"]["mauldon_circles"] is None


def test_square_window_gets_hand_counted_mauldon_values_on_its_inscribed_circle():
    # circle of radius 4.5 (0.9 x the inscribed 5) at (5, 5); the traces give
    # n = 1 + 0 + 0 + 1 = 2 crossings and m = 1 + 2 + 2 + 1 = 6 ends inside
    result = trace_map_statistics(intensity_square()).to_dict()
    circles = result["window"]["mauldon_circles"]
    assert circles["count"] == 1 and circles["radius"] == pytest.approx(4.5)
    np.testing.assert_allclose(circles["centres_xy"], [[5.0, 5.0]])
    assert result["Fracture Intensity (Mauldon)"]["value"] == pytest.approx(2 / (4 * 4.5))
    assert result["Fracture Density (Mauldon)"]["value"] == pytest.approx(6 / (2 * math.pi * 4.5**2))
    assert result["Trace Mean Length (Mauldon)"]["value"] == pytest.approx(math.pi * 4.5 / 2 * 2 / 6)
    json.dumps(result, allow_nan=False)


def test_circular_window_gives_hand_counted_mauldon_values():
    # n = 2 + 1 + 0 = 3 crossings, m = 0 + 1 + 2 = 3 ends inside, r = 5
    result = trace_map_statistics(circle_map()).to_dict()
    assert result["window"]["is_circle"] and result["window"]["radius"] == pytest.approx(5.0)
    assert result["Fracture Intensity (Mauldon)"]["value"] == pytest.approx(3 / 20)
    assert result["Fracture Density (Mauldon)"]["value"] == pytest.approx(3 / (2 * math.pi * 25))
    assert result["Trace Mean Length (Mauldon)"]["value"] == pytest.approx(math.pi * 5 / 2)


def test_circular_window_mauldon_agrees_with_the_direct_estimator():
    tm = circle_map()
    c = circle_window(tm.window_xy_m)
    direct = mauldon_circle(tm, c.centre_xy_m, c.radius_m)
    result = trace_map_statistics(tm).to_dict()
    assert result["Fracture Intensity (Mauldon)"]["value"] == direct.p21_per_m


def test_grid_gives_two_sets_with_their_spacings():
    result = trace_map_statistics(grid_map()).to_dict()
    sets = result["sets"]
    assert [s["Mean Angle"]["value"] for s in sets] == pytest.approx([0.0, 90.0], abs=1e-9)
    assert [s["Number of Traces"]["value"] for s in sets] == [5, 4]
    assert [s["Fracture Intensity P21"]["value"] for s in sets] == pytest.approx([0.5, 0.4])
    assert [s["Mean Spacing"]["value"] for s in sets] == pytest.approx([2.0, 2.5])
    assert [s["Scanline P10"]["value"] for s in sets] == pytest.approx([0.5, 0.4])
    assert all(s["Concentration Capped"] and s["Circular Spread"]["value"] == 0.0 for s in sets)
    assert result["set_selection"]["method"] == "bic" and set(result["set_selection"]["bic"]) == {"1", "2"}
    assert result["traces"]["set"] == [0] * 5 + [1] * 4


def test_fully_censored_grid_has_no_connections_per_trace_and_says_why():
    result = trace_map_statistics(grid_map()).to_dict()
    assert result["Node Counts"] == {"I": 0, "Y": 0, "X": 20, "E": 18}
    assert result["Number of Branches"]["value"] == 40.0
    entry = result["Connections per Trace"]
    assert entry["value"] is None and "censored" in entry["reason"]


def test_given_number_of_sets_is_used():
    result = trace_map_statistics(grid_map(), n_sets=1).to_dict()
    assert len(result["sets"]) == 1 and result["set_selection"]["method"] == "given"


def test_too_many_sets_is_a_clear_error():
    with pytest.raises(ValueError, match="n_sets=3"):
        trace_map_statistics(grid_map(), n_sets=3)


def test_pixel_maps_are_labelled_in_pixels():
    result = trace_map_statistics(intensity_square(), length_unit="px").to_dict()
    assert result["Fracture Intensity P21"]["unit"] == "px/px²"
    assert result["Areal Frequency P20"]["unit"] == "1/px²"
    assert result["traces"]["unit"] == "px"


def test_traces_outside_the_window_are_left_out_and_counted():
    tm = TraceMap.from_segments([[1, 1, 4, 5], [20, 20, 30, 30]], {"id": ["in", "out"]}, window=SQUARE_10)
    result = trace_map_statistics(tm).to_dict()
    assert result["Number of Traces"]["value"] == 1
    assert result["traces"]["id"] == ["in"]
    assert result["diagnostics"]["traces_outside_window"] == 1


def test_window_source_and_default_snap_tolerance_are_reported():
    tm = TraceMap.from_segments([[0, 0, 10, 10], [0, 10, 10, 0]])  # no window: the 10 m bounding box
    result = trace_map_statistics(tm, window="bbox").to_dict()  # issue 19: chosen explicitly
    assert result["window"]["source"] == "bounding_box"
    assert result["settings"]["snap_tolerance"]["value"] == pytest.approx(1e-4 * math.sqrt(200))


def test_explicit_window_argument_wins():
    result = trace_map_statistics(intensity_square(), window=[(0, 0), (20, 0), (20, 20), (0, 20)]).to_dict()
    assert result["window"]["source"] == "argument" and result["Area"]["value"] == 400.0


def test_midpoint_rule_passes_through():
    result = trace_map_statistics(intensity_square(), p20_rule="midpoints").to_dict()
    assert result["Areal Frequency P20"]["value"] == pytest.approx(0.04)
    assert result["settings"]["p20_rule"] == "midpoints"


def test_zero_length_traces_are_reported_and_get_no_set():
    result = trace_map_statistics(CATALOGUE["zero_length_trace"].build(), window=SQUARE_10).to_dict()
    assert result["diagnostics"]["zero_length_traces"] == 1
    assert result["traces"]["set"][0] == -1 and result["traces"]["angle_deg"][0] is None


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"p20_rule": "centres"}, ValueError, "p20_rule"),
        ({"snap_tolerance_m": -1.0}, ValueError, "snap_tolerance_m"),
        ({"scanline_spacing_m": 0.0}, ValueError, "scanline_spacing_m"),
        ({"resolution_deg": -1.0}, ValueError, "resolution_deg"),
        ({"length_unit": ""}, TypeError, "length_unit"),
        ({"circle_rel_tolerance": 2.0}, ValueError, "rel_tolerance"),
    ],
)
def test_bad_arguments_are_rejected_by_name(kwargs, error, match):
    with pytest.raises(error, match=match):
        trace_map_statistics(intensity_square(), **kwargs)


def test_empty_map_raises():
    with pytest.raises(ValueError, match="0 traces"):
        trace_map_statistics(CATALOGUE["empty"].build())


def test_map_missing_the_window_raises():
    with pytest.raises(ValueError, match="reaches the window"):
        trace_map_statistics(TraceMap.from_segments([[20, 20, 30, 30]], window=SQUARE_10))


def test_window_argument_is_not_modified():
    window = np.array(SQUARE_10, dtype=float)
    before = window.copy()
    trace_map_statistics(intensity_square(), window=window)
    assert np.array_equal(window, before)


@pytest.mark.parametrize("make", [grid_map, intensity_square])
def test_set_intensities_add_up_to_the_whole_map(make):
    result = trace_map_statistics(make()).to_dict()
    assert sum(s["Fracture Intensity P21"]["value"] for s in result["sets"]) == pytest.approx(
        result["Fracture Intensity P21"]["value"], rel=1e-12
    )
    assert sum(s["Areal Frequency P20"]["value"] for s in result["sets"]) == pytest.approx(
        result["Areal Frequency P20"]["value"], rel=1e-12
    )
    assert sum(s["Number of Traces"]["value"] for s in result["sets"]) == result["Number of Traces"]["value"]
