"""TraceMap: hand-checkable geometry, naive-loop oracles, validation messages and immutability."""

import copy
import dataclasses
import doctest
import math
import pickle
import subprocess
import sys

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

import rockmass.dfn
import rockmass.dfn.atomic
import rockmass.dfn.traceio
import rockmass.dfn.tracemap
from rockmass.dfn import TraceMap

from ._fixtures import CATALOGUE, N_GON, assert_same_map, naive_segments

CASES = list(CATALOGUE)

coordinate = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False)
polylines_strategy = st.lists(st.lists(st.tuples(coordinate, coordinate), min_size=2, max_size=6), max_size=6)


# -- hand-checkable geometry --------------------------------------------------------------------


def test_three_four_five_trace_has_length_5():
    assert TraceMap.from_polylines([[(0, 0), (3, 4)]]).lengths_m().tolist() == [5.0]


def test_legs_of_a_three_four_five_triangle_sum_to_12():
    tm = TraceMap.from_polylines([[(0, 0), (3, 0), (3, 4), (0, 0)]])
    assert tm.lengths_m().tolist() == [12.0]


def test_unit_square_polyline_has_length_4():
    tm = TraceMap.from_polylines([[(0, 0), (1, 0), (1, 1), (0, 1), (0, 0)]])
    assert tm.lengths_m().tolist() == [4.0]
    assert tm.total_length_m() == 4.0


def test_regular_polygon_polyline_length_matches_closed_form():
    case = CATALOGUE["many_vertices"]
    assert case.build().lengths_m()[0] == pytest.approx(2 * N_GON * math.sin(math.pi / N_GON), rel=1e-12)


@pytest.mark.parametrize("name", CASES)
def test_lengths_match_hand_values(name):
    case = CATALOGUE[name]
    assert case.build().lengths_m() == pytest.approx(case.lengths_m, rel=1e-12, abs=0.0)


@pytest.mark.parametrize("name", [n for n in CASES if CATALOGUE[n].bounds is not None])
def test_bounds_match_hand_values(name):
    case = CATALOGUE[name]
    assert case.build().bounds() == pytest.approx(case.bounds, abs=1e-12)


def test_bounds_of_an_empty_map_are_an_error():
    with pytest.raises(ValueError, match="empty TraceMap"):
        CATALOGUE["empty"].build().bounds()


def test_sizes_count_traces_vertices_and_segments():
    tm = CATALOGUE["string_ids"].build()
    assert (tm.n_traces, tm.n_vertices, tm.n_segments) == (2, 7, 5)


# -- vectorised methods against naive loops ------------------------------------------------------


@pytest.mark.parametrize("name", CASES)
def test_segments_equal_a_naive_python_loop(name):
    case = CATALOGUE[name]
    tm = case.build()
    rows, owner = naive_segments(case.polylines)
    assert np.array_equal(tm.segments(), np.array(rows, dtype=float).reshape(-1, 4))
    assert np.array_equal(tm.segment_trace_index(), np.array(owner, dtype=np.int64))
    assert tm.segments().shape == (tm.n_segments, 4)


@settings(max_examples=60, deadline=None)
@given(polylines_strategy)
def test_segments_and_lengths_equal_naive_loops_on_random_polylines(polylines):
    tm = TraceMap.from_polylines(polylines)
    rows, owner = naive_segments(polylines)
    assert np.array_equal(tm.segments(), np.array(rows, dtype=float).reshape(-1, 4))
    assert np.array_equal(tm.segment_trace_index(), np.array(owner, dtype=np.int64))
    naive = [math.fsum(math.hypot(x1 - x0, y1 - y0) for (x0, y0), (x1, y1) in zip(p[:-1], p[1:])) for p in polylines]
    assert np.allclose(tm.lengths_m(), naive, rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("name", CASES)
def test_polyline_returns_the_vertices_of_each_trace(name):
    case = CATALOGUE[name]
    tm = case.build()
    for i, line in enumerate(case.polylines):
        assert np.array_equal(tm.polyline(i), np.array(line, dtype=float))
    if tm.n_traces:
        assert np.array_equal(tm.polyline(-1), np.array(case.polylines[-1], dtype=float))
    with pytest.raises(IndexError, match=f"out of range for a map of {tm.n_traces} traces"):
        tm.polyline(tm.n_traces)


@pytest.mark.parametrize("name", CASES)
def test_shapely_lengths_agree_with_lengths_m(name):
    tm = CATALOGUE[name].build()
    lines = tm.to_shapely()
    assert lines.shape == (tm.n_traces,)
    assert np.allclose(shapely.length(lines), tm.lengths_m(), rtol=1e-12, atol=0.0)


@pytest.mark.parametrize("name", CASES)
def test_from_shapely_rebuilds_the_same_map(name):
    tm = CATALOGUE[name].build()
    again = TraceMap.from_shapely(tm.to_shapely(), tm.attributes, window=tm.window_polygon())
    assert_same_map(tm, again)


def test_from_shapely_drops_z_and_rejects_other_geometries():
    tm = TraceMap.from_shapely([shapely.LineString([(0, 0, 9), (3, 4, 9)])])
    assert tm.xy_m.tolist() == [[0.0, 0.0], [3.0, 4.0]]
    with pytest.raises(ValueError, match=r"indices \[1\] are \['Point'\]"):
        TraceMap.from_shapely([shapely.LineString([(0, 0), (1, 1)]), shapely.Point(0, 0)])


def test_from_segments_gives_two_vertex_traces_in_row_order():
    tm = TraceMap.from_segments(np.array([[0.0, 0.0, 3.0, 4.0], [1.0, 1.0, 1.0, 2.0]]))
    assert tm.offsets.tolist() == [0, 2, 4]
    assert tm.xy_m.tolist() == [[0, 0], [3, 4], [1, 1], [1, 2]]
    assert np.array_equal(tm.segments(), [[0, 0, 3, 4], [1, 1, 1, 2]])


# -- degenerate traces, subsets, windows ---------------------------------------------------------


@pytest.mark.parametrize("name", CASES)
def test_degenerate_traces_flags_exactly_the_zero_length_traces(name):
    case = CATALOGUE[name]
    expected = [length == 0.0 for length in case.lengths_m]
    assert case.build().degenerate_traces().tolist() == expected


def test_a_tiny_but_nonzero_trace_is_not_degenerate():
    tm = TraceMap.from_polylines([[(0.0, 0.0), (0.0, 5e-324)]])
    assert tm.degenerate_traces().tolist() == [False]


@pytest.mark.parametrize(
    ("selection", "picked"),
    [([2, 0], [2, 0]), ([True, False, True], [0, 2]), ([-1], [2]), ([], []), (np.array([1, 1]), [1, 1])],
)
def test_subset_equals_a_map_built_from_the_selected_polylines(selection, picked):
    polylines = [[(0, 0), (1, 0)], [(0, 1), (1, 1), (2, 2)], [(5, 5), (6, 6), (7, 5), (8, 6)]]
    window = [(0, 0), (9, 0), (9, 9)]
    tm = TraceMap.from_polylines(polylines, {"set": [10, 20, 30]}, window=window)
    expected = TraceMap.from_polylines(
        [polylines[i] for i in picked],
        {"id": np.array(picked, dtype=np.int64), "set": np.array([10, 20, 30])[picked]},
        window=window,
    )
    assert_same_map(tm.subset(selection), expected)


def test_subset_names_bad_selections():
    tm = CATALOGUE["parallel_traces"].build()
    with pytest.raises(ValueError, match=r"one value per trace \(3\)"):
        tm.subset([True, False])
    with pytest.raises(IndexError, match=r"trace indices \[3\] are out of range for 3 traces"):
        tm.subset([0, 3])


def test_with_window_replaces_only_the_window():
    tm = CATALOGUE["string_ids"].build()
    framed = tm.with_window(shapely.box(0, 0, 10, 10))
    assert shapely.area(framed.window_polygon()) == 100.0
    assert_same_map(tm, framed, window=False)
    assert framed.with_window(None).window_xy_m is None


def test_a_closed_window_ring_is_stored_open():
    tm = TraceMap.from_polylines([], window=[(0, 0), (1, 0), (1, 1), (0, 0)])
    assert tm.window_xy_m.tolist() == [[0, 0], [1, 0], [1, 1]]


# -- validation messages -------------------------------------------------------------------------


def test_non_finite_coordinates_are_reported_by_trace_id():
    polylines = [[(0, 0), (1, 1)]] * 20
    polylines[4] = [(0, 0), (np.nan, 1)]
    polylines[17] = [(np.inf, 0), (1, 1)]
    with pytest.raises(ValueError, match=r"2 traces have non-finite coordinates: ids \[4, 17\]$"):
        TraceMap.from_polylines(polylines)


def test_non_finite_coordinates_name_string_ids_and_indices():
    with pytest.raises(ValueError, match=r"1 trace has non-finite coordinates: ids \['B'\] \(indices \[1\]\)"):
        TraceMap.from_polylines([[(0, 0), (1, 1)], [(0, 0), (1, -np.inf)]], {"id": ["A", "B"]})


def test_one_vertex_trace_is_rejected_with_its_id():
    with pytest.raises(ValueError, match=r"1 trace has fewer than 2 vertices: ids \['T9'\]"):
        TraceMap(np.zeros((3, 2)), [0, 2, 3], {"id": ["T8", "T9"]})


@pytest.mark.parametrize(
    ("offsets", "message"),
    [
        ([1, 4], r"offsets\[0\] must be 0, got 1"),
        ([0, 2], r"offsets\[-1\] must equal the number of vertices in xy_m \(4\), got 2"),
        ([0, 3, 2, 4], r"non-decreasing; they decrease after positions \[1\]"),
        ([], "1-D array of n_traces \\+ 1"),
    ],
)
def test_inconsistent_offsets_are_rejected(offsets, message):
    with pytest.raises(ValueError, match=message):
        TraceMap(np.zeros((4, 2)), np.array(offsets, dtype=np.int64))


def test_float_offsets_and_string_coordinates_are_type_errors():
    with pytest.raises(TypeError, match="offsets must hold integers"):
        TraceMap(np.zeros((2, 2)), np.array([0.0, 2.0]))
    with pytest.raises(TypeError, match="xy_m must hold real numbers"):
        TraceMap(np.array([["0", "0"], ["1", "1"]]), [0, 2])


def test_attribute_of_wrong_length_names_the_column():
    with pytest.raises(ValueError, match=r"attributes\['set'\] has 1 values, expected 2"):
        TraceMap.from_polylines([[(0, 0), (1, 1)]] * 2, {"set": [1]})


def test_attribute_with_non_string_objects_names_the_column_and_items():
    with pytest.raises(TypeError, match=r"attributes\['note'\] is an object array .* indices \[1\]"):
        TraceMap.from_polylines([[(0, 0), (1, 1)]] * 2, {"note": np.array(["a", None], dtype=object)})


def test_float_ids_are_rejected():
    with pytest.raises(TypeError, match=r"attributes\['id'\] must hold integers or strings"):
        TraceMap.from_polylines([[(0, 0), (1, 1)]], {"id": [1.5]})


@pytest.mark.parametrize(
    ("window", "message"),
    [
        ([(0, 0), (1, 1)], "at least 3 distinct ring vertices, got 2"),
        ([(0, 0), (1, 0), (np.nan, 1)], r"non-finite coordinates at vertices \[2\]"),
        ([(0, 0), (1, 1), (2, 2)], "encloses zero area"),
    ],
)
def test_bad_windows_are_rejected(window, message):
    with pytest.raises(ValueError, match=message):
        TraceMap.from_polylines([], window=window)


def test_window_with_a_hole_is_rejected():
    holed = shapely.Polygon([(0, 0), (4, 0), (4, 4), (0, 4)], [[(1, 1), (2, 1), (2, 2)]])
    with pytest.raises(ValueError, match="1 holes; holes are not supported"):
        TraceMap.from_polylines([], window=holed)


def test_frame_must_be_a_non_empty_string():
    with pytest.raises(TypeError, match="frame must be a non-empty string"):
        TraceMap.from_polylines([], frame="")


# -- immutability and inputs ---------------------------------------------------------------------


def test_constructor_does_not_modify_inputs():
    xy = np.array([[0.0, 0.0], [3.0, 4.0], [1.0, 1.0], [1.0, 1.0]])
    offsets = np.array([0, 2, 4], dtype=np.int32)
    attributes = {"set": np.array([1, 2], dtype=np.int32)}
    window = np.array([[0.0, 0.0], [5.0, 0.0], [5.0, 5.0], [0.0, 0.0]])
    before = [a.copy() for a in (xy, offsets, attributes["set"], window)]
    TraceMap(xy, offsets, attributes, window)
    for after, original in zip((xy, offsets, attributes["set"], window), before):
        assert np.array_equal(after, original) and after.dtype == original.dtype and after.flags.writeable
    assert list(attributes) == ["set"]


def test_from_polylines_does_not_modify_inputs():
    polylines = [np.array([[0.0, 0.0], [1.0, 1.0]]), [(2, 2), (3, 3)]]
    attributes = {"id": ["a", "b"]}
    TraceMap.from_polylines(polylines, attributes)
    assert polylines[0].tolist() == [[0, 0], [1, 1]] and polylines[1] == [(2, 2), (3, 3)]
    assert attributes == {"id": ["a", "b"]}


def test_later_changes_to_the_inputs_do_not_reach_the_map():
    xy = np.array([[0.0, 0.0], [3.0, 4.0]])
    tm = TraceMap(xy, [0, 2])
    xy[1] = [6.0, 8.0]
    assert tm.lengths_m().tolist() == [5.0]


def test_arrays_and_attribute_mapping_are_read_only():
    tm = CATALOGUE["crossing_pair"].build()
    for array in (tm.xy_m, tm.offsets, tm.window_xy_m, tm.attributes["id"], tm.polyline(0)):
        with pytest.raises(ValueError, match="read-only"):
            array[0] = 0
    with pytest.raises(TypeError):
        tm.attributes["new"] = np.zeros(2)
    with pytest.raises(dataclasses.FrozenInstanceError):
        tm.frame = "other"


def test_id_column_defaults_to_trace_index_and_comes_first():
    tm = TraceMap.from_polylines([[(0, 0), (1, 1)]] * 3, {"set": [1, 1, 2]})
    assert list(tm.attributes) == ["id", "set"]
    assert tm.attributes["id"].tolist() == [0, 1, 2] and tm.attributes["id"].dtype == np.int64


@pytest.mark.parametrize("name", CASES)
def test_pickle_and_deepcopy_give_an_equal_immutable_map(name):
    tm = CATALOGUE[name].build()
    for clone in (pickle.loads(pickle.dumps(tm)), copy.deepcopy(tm)):
        assert_same_map(tm, clone)
        assert not clone.xy_m.flags.writeable


def test_repr_summarises_instead_of_printing_arrays():
    text = repr(CATALOGUE["many_vertices"].build())
    assert text == (
        f"TraceMap(n_traces=1, n_vertices={N_GON + 1}, frame='face', crs=None, attributes=['id'], window=None)"
    )


# -- package hygiene -----------------------------------------------------------------------------


def test_docstring_examples_run():
    for module in (rockmass.dfn.tracemap, rockmass.dfn.traceio, rockmass.dfn.atomic):
        assert doctest.testmod(module).failed == 0, module.__name__


def test_importing_dfn_or_its_atomic_writes_loads_neither_the_pipeline_nor_heavy_modules():
    # public names load lazily, so the pipeline's rockmass.atomic can build on rockmass.dfn.atomic
    code = (
        "import sys, rockmass.dfn, rockmass.dfn.atomic; "
        "print(sorted(m for m in sys.modules if m.split('.')[0] in "
        "('numpy', 'shapely', 'numba', 'matplotlib', 'cv2', 'skimage', 'scipy') or "
        "(m.startswith('rockmass.') and not m.startswith('rockmass.dfn'))))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_all_is_the_union_of_the_public_modules_all():
    import importlib

    modules = set(rockmass.dfn._SOURCES.values())
    union = set()
    for module in modules:
        union |= set(importlib.import_module(f"rockmass.dfn.{module}").__all__)
    assert set(rockmass.dfn.__all__) == union
    assert {"TraceMap", "read_traces", "write_traces", "trace_map_statistics"} <= union


def test_every_public_name_resolves_and_an_unknown_name_raises_attribute_error():
    import importlib

    for name, module in rockmass.dfn._SOURCES.items():
        defining = importlib.import_module(f"rockmass.dfn.{module}")
        assert getattr(rockmass.dfn, name) is getattr(defining, name)
        assert name in dir(rockmass.dfn)
    with pytest.raises(AttributeError, match="has no attribute 'read_shapefile'"):
        rockmass.dfn.read_shapefile  # noqa: B018
