"""Trace files: exact round trips, hand-written inputs, the documented rules, errors, atomic writes."""

import csv
import json
import os
import warnings

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from rockmass.dfn import TraceMap, read_csv, read_geojson, read_traces, write_csv, write_geojson, write_traces
from rockmass.dfn import csv_io, geojson_io
from rockmass.dfn.tracemap import MAX_COORDINATE_M

from ._fixtures import CATALOGUE, assert_same_map, rich_map

CASES = list(CATALOGUE)


def _write(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def _no_window_warning(trace_map, write, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", ".*CSV does not store the sampling window", UserWarning)
        write(trace_map, *args, **kwargs)


# -- round trips ---------------------------------------------------------------------------------


@pytest.mark.parametrize("name", CASES)
def test_geojson_round_trip_is_exact_for_the_catalogue(tmp_path, name):
    tm = CATALOGUE[name].build()
    write_traces(tm, tmp_path / "t.geojson")
    assert_same_map(tm, read_traces(tmp_path / "t.geojson"))


@pytest.mark.parametrize("name", CASES)
def test_csv_polylines_round_trip_is_exact_for_the_catalogue(tmp_path, name):
    tm = CATALOGUE[name].build()
    _no_window_warning(tm, write_traces, tmp_path / "t.csv")
    assert_same_map(tm, read_traces(tmp_path / "t.csv"), window=False)


def test_geojson_round_trip_keeps_every_attribute_type_window_frame_and_crs(tmp_path):
    tm = rich_map()
    write_geojson(tm, tmp_path / "rich.json")
    back = read_geojson(tmp_path / "rich.json")
    assert_same_map(tm, back)
    assert [back.attributes[k].dtype.kind for k in back.attributes] == ["U", "i", "f", "b", "U"]


def test_geojson_file_round_trips_byte_for_byte(tmp_path):
    write_geojson(rich_map(), tmp_path / "a.geojson")
    write_geojson(read_geojson(tmp_path / "a.geojson"), tmp_path / "b.geojson")
    assert (tmp_path / "a.geojson").read_bytes() == (tmp_path / "b.geojson").read_bytes()


@pytest.mark.parametrize("layout", ["polylines", "segments"])
def test_csv_round_trip_keeps_every_attribute_type_frame_and_crs(tmp_path, layout):
    tm = rich_map()
    if layout == "segments":
        tm = tm.subset(tm.offsets[1:] - tm.offsets[:-1] == 2)
    _no_window_warning(tm, write_csv, tmp_path / "rich.csv", layout=layout)
    assert_same_map(tm, read_csv(tmp_path / "rich.csv"), window=False)


# every finite coordinate a trace map holds (beyond ±MAX_COORDINATE_M is refused as a unit slip)
floats = st.floats(min_value=-MAX_COORDINATE_M, max_value=MAX_COORDINATE_M)
polylines_strategy = st.lists(st.lists(st.tuples(floats, floats), min_size=2, max_size=5), min_size=1, max_size=5)
text = st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="\x00"), max_size=8)


@st.composite
def trace_maps(draw, two_vertex=False):
    """Random traces with a float (NaN allowed), an int, a bool and a (non-numeric) str column."""
    if two_vertex:
        polylines = draw(st.lists(st.lists(st.tuples(floats, floats), min_size=2, max_size=2), min_size=1, max_size=5))
    else:
        polylines = draw(polylines_strategy)
    n = len(polylines)
    column = lambda values: draw(st.lists(values, min_size=n, max_size=n))  # noqa: E731
    attributes = {
        "dip_deg": column(st.floats(allow_infinity=False)),
        "set": column(st.integers(-(2**63), 2**63 - 1)),
        "open": column(st.booleans()),
        "note": ["s:" + t for t in column(text)],
    }
    return TraceMap.from_polylines(polylines, attributes, frame="face", crs="EPSG:2056")


@settings(max_examples=40, deadline=None)
@given(trace_maps())
def test_geojson_round_trip_is_exact_for_random_maps(tmp_path_factory, tm):
    path = tmp_path_factory.mktemp("geojson") / "random.geojson"
    write_geojson(tm, path)
    assert_same_map(tm, read_geojson(path))


@settings(max_examples=40, deadline=None)
@given(trace_maps())
def test_csv_polylines_round_trip_is_exact_for_random_maps(tmp_path_factory, tm):
    path = tmp_path_factory.mktemp("csv") / "random.csv"
    write_csv(tm, path)
    assert_same_map(tm, read_csv(path), window=False)


@settings(max_examples=40, deadline=None)
@given(trace_maps(two_vertex=True))
def test_csv_segments_round_trip_is_exact_for_random_maps(tmp_path_factory, tm):
    path = tmp_path_factory.mktemp("csv") / "random.csv"
    write_csv(tm, path, layout="segments")
    assert_same_map(tm, read_csv(path), window=False)


def test_written_geojson_is_standard_json_read_alike_by_shapely(tmp_path):
    tm = rich_map()
    write_geojson(tm, tmp_path / "t.geojson")
    raw = (tmp_path / "t.geojson").read_text(encoding="utf-8")

    def refuse(token):
        raise AssertionError(f"non-standard JSON token {token}")

    doc = json.loads(raw, parse_constant=refuse)
    assert doc["crs"] == {"type": "name", "properties": {"name": "EPSG:32633"}} and doc["frame"] == "utm33n"
    assert doc["features"][1]["properties"]["aperture_mm"] is None  # NaN written as null
    geometries = list(shapely.from_geojson(raw).geoms)  # an independent reader of the same file
    for i, line in enumerate(geometries[: tm.n_traces]):
        assert np.array_equal(shapely.get_coordinates(line), tm.polyline(i))
    assert np.array_equal(shapely.get_coordinates(geometries[-1].exterior)[:-1], tm.window_xy_m)


def test_trace_id_starting_with_a_hash_is_not_read_as_a_comment(tmp_path):
    tm = TraceMap.from_polylines([[(0, 0), (1, 1)], [(2, 2), (3, 3)]], {"id": ["#1", "# 2"]})
    write_csv(tm, tmp_path / "t.csv")
    assert_same_map(tm, read_csv(tmp_path / "t.csv"))


# -- hand-written files: the documented reading rules -------------------------------------------

HAND_GEOJSON = """{"type": "FeatureCollection",
 "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32633"}},
 "features": [
  {"type": "Feature", "properties": {"id": "T1", "set": 1, "aperture_mm": 0.5, "note": "open"},
   "geometry": {"type": "LineString", "coordinates": [[0, 0, 100.5], [3, 4, 101.0]]}},
  {"type": "Feature", "properties": {"id": "T2", "set": 2, "note": null},
   "geometry": {"type": "LineString", "coordinates": [[1, 1], [1, 2], [2, 2]]}},
  {"type": "Feature", "id": "T3", "properties": {"set": "B", "aperture_mm": 1},
   "geometry": {"type": "LineString", "coordinates": [[5, 5], [6, 5]]}},
  {"type": "Feature", "properties": {"name": "bench 3"},
   "geometry": {"type": "Polygon", "coordinates": [[[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]]]}}
 ]}"""


def test_hand_written_geojson_reads_as_documented(tmp_path):
    tm = read_geojson(_write(tmp_path, "faces.geojson", HAND_GEOJSON))
    assert tm.xy_m.tolist() == [[0, 0], [3, 4], [1, 1], [1, 2], [2, 2], [5, 5], [6, 5]]  # z dropped
    assert tm.offsets.tolist() == [0, 2, 5, 7]
    assert tm.attributes["id"].tolist() == ["T1", "T2", "T3"]  # T3 from the feature's own id
    assert tm.attributes["set"].tolist() == ["1", "2", "B"]  # mixed types -> str
    assert np.array_equal(tm.attributes["aperture_mm"], [0.5, np.nan, 1.0], equal_nan=True)  # gap -> NaN
    assert tm.attributes["note"].tolist() == ["open", "", ""]  # null / absent string -> ''
    assert tm.window_xy_m.tolist() == [[0, 0], [10, 0], [10, 10], [0, 10]]
    # issue 19: a file with a projected CRS and no frame member is a map (easting, northing)
    assert (tm.crs, tm.frame) == ("urn:ogc:def:crs:EPSG::32633", "map")


@pytest.mark.parametrize(
    ("member", "crs"),
    [('"EPSG:32633"', "EPSG:32633"), ('{"type": "EPSG", "properties": {"code": 2056}}', "EPSG:2056"), ("null", None)],
)
def test_plain_and_legacy_crs_members_are_read(tmp_path, member, crs):
    text = '{"type": "FeatureCollection", "crs": %s, "frame": "map", "features": []}' % member
    tm = read_geojson(_write(tmp_path, "c.geojson", text))
    assert (tm.crs, tm.frame, tm.n_traces) == (crs, "map", 0)


def test_bare_geometry_and_single_feature_are_read(tmp_path):
    bare = read_geojson(_write(tmp_path, "a.json", '{"type": "LineString", "coordinates": [[0, 0], [3, 4]]}'))
    assert bare.lengths_m().tolist() == [5.0]
    single = read_geojson(
        _write(tmp_path, "b.json", '{"type": "Feature", "properties": {"id": 7}, "geometry": '
               '{"type": "LineString", "coordinates": [[0, 0], [0, 2]]}}')
    )
    assert single.attributes["id"].tolist() == [7]


def _multi(coords, props='{"id": 7, "set": 1}'):
    return (
        '{"type": "FeatureCollection", "features": ['
        '{"type": "Feature", "properties": {"id": 8, "set": 2}, "geometry": '
        '{"type": "LineString", "coordinates": [[0, 9], [1, 9]]}},'
        '{"type": "Feature", "properties": %s, "geometry": {"type": "MultiLineString", "coordinates": %s}}]}'
        % (props, coords)
    )


def test_multilinestring_whose_parts_join_is_merged_into_one_trace(tmp_path):
    # the second part is reversed; end to end they form (0,0)-(1,0)-(2,0)
    tm = read_geojson(_write(tmp_path, "m.geojson", _multi("[[[1, 0], [2, 0]], [[1, 0], [0, 0]]]")))
    assert tm.n_traces == 2 and "part" not in tm.attributes
    assert tm.lengths_m().tolist() == [1.0, 2.0]
    merged = tm.polyline(1)
    assert merged.shape == (3, 2) and {tuple(merged[0]), tuple(merged[-1])} == {(0.0, 0.0), (2.0, 0.0)}
    assert tm.attributes["id"].tolist() == [8, 7]


def test_multilinestring_whose_parts_do_not_join_is_split_with_a_part_attribute(tmp_path):
    tm = read_geojson(_write(tmp_path, "m.geojson", _multi("[[[0, 0], [1, 0]], [[5, 0], [5, 3]]]")))
    assert tm.attributes["id"].tolist() == [8, 7, 7]
    assert tm.attributes["set"].tolist() == [2, 1, 1]
    assert tm.attributes["part"].tolist() == [-1, 0, 1]  # -1: the trace came whole from its feature
    assert tm.lengths_m().tolist() == [1.0, 1.0, 3.0]


def test_split_multilinestring_with_its_own_part_property_is_rejected(tmp_path):
    path = _write(tmp_path, "m.geojson", _multi("[[[0, 0], [1, 0]], [[5, 0], [5, 3]]]", '{"id": 7, "part": 2}'))
    with pytest.raises(ValueError, match=r"feature 1 \(id=7\): properties already have a 'part' field"):
        read_geojson(path)


def test_role_window_on_a_closed_linestring_is_the_window(tmp_path):
    text = ('{"type": "Feature", "properties": {"role": "window"}, "geometry": {"type": "LineString", '
            '"coordinates": [[0, 0], [2, 0], [2, 2], [0, 0]]}}')
    tm = read_geojson(_write(tmp_path, "w.geojson", text))
    assert tm.n_traces == 0 and tm.window_xy_m.tolist() == [[0, 0], [2, 0], [2, 2]]


CSV_POLYLINES = """# digitised on photo IMG_0412
# frame: face
Trace_ID , X , Y ,set,note

T1,0,0,1,calcite
T1,3,4,1,calcite
T2,1,1,2,
T2,1,2,2,
T2,2,2,2,
"""


def test_hand_written_csv_polylines_read_as_documented(tmp_path):
    tm = read_csv(_write(tmp_path, "p.csv", CSV_POLYLINES))
    assert tm.xy_m.tolist() == [[0, 0], [3, 4], [1, 1], [1, 2], [2, 2]]
    assert tm.offsets.tolist() == [0, 2, 5]
    assert tm.attributes["id"].tolist() == ["T1", "T2"]
    assert tm.attributes["set"].tolist() == [1, 2] and tm.attributes["set"].dtype == np.int64
    assert tm.attributes["note"].tolist() == ["calcite", ""]
    assert tm.lengths_m().tolist() == [5.0, 2.0] and tm.frame == "face"


def test_hand_written_csv_segments_read_as_documented(tmp_path):
    text = "x0,y0,x1,y1,ID,aperture_mm,open\n0,0,3,4,10,0.5,TRUE\n1,1,1,3,11,,false\n"
    tm = read_csv(_write(tmp_path, "s.csv", text))
    assert tm.segments().tolist() == [[0, 0, 3, 4], [1, 1, 1, 3]]
    assert tm.attributes["id"].tolist() == [10, 11]
    assert np.array_equal(tm.attributes["aperture_mm"], [0.5, np.nan], equal_nan=True)  # blank -> NaN
    assert tm.attributes["open"].tolist() == [True, False]


# -- errors name the file, the feature or line, and the field ------------------------------------


@pytest.mark.parametrize("literal", ["NaN", "Infinity", "-Infinity"])
def test_non_finite_geojson_coordinate_names_the_feature(tmp_path, literal):
    text = (
        '{"type": "FeatureCollection", "features": ['
        '{"type": "Feature", "properties": {"id": "T1"}, "geometry": '
        '{"type": "LineString", "coordinates": [[0, 0], [1, 1]]}},'
        '{"type": "Feature", "properties": {"id": "T2"}, "geometry": {"type": "LineString", '
        '"coordinates": [[0, 0], [1, 1], [%s, 2]]}}]}' % literal
    )
    message = r"faces\.geojson: feature 1 \(id=T2\): coordinates contain NaN/Infinity at positions \[2\]"
    with pytest.raises(ValueError, match=message):
        read_geojson(_write(tmp_path, "faces.geojson", text))


def test_one_vertex_geojson_trace_names_the_feature(tmp_path):
    text = '{"type": "Feature", "properties": {"id": "A"}, "geometry": {"type": "LineString", "coordinates": [[0, 0]]}}'
    with pytest.raises(ValueError, match=r"feature 0 \(id=A\): coordinates has 1 position\(s\); a trace needs"):
        read_geojson(_write(tmp_path, "one.geojson", text))


def test_two_window_polygons_are_rejected(tmp_path):
    square = (
        '{"type": "Feature", "properties": null, '
        '"geometry": {"type": "Polygon", "coordinates": [[[0,0],[1,0],[1,1],[0,0]]]}}'
    )
    text = '{"type": "FeatureCollection", "features": [%s, %s]}' % (square, square)
    with pytest.raises(ValueError, match=r"w\.geojson: feature 1: a second window polygon \(feature 0 is already"):
        read_geojson(_write(tmp_path, "w.geojson", text))


def test_point_feature_is_rejected_naming_index_and_type(tmp_path):
    text = ('{"type": "FeatureCollection", "features": [{"type": "Feature", "id": 5, "properties": {}, '
            '"geometry": {"type": "Point", "coordinates": [0, 0]}}]}')
    with pytest.raises(ValueError, match=r"feature 0 \(id=5\): geometry type 'Point' is not a trace"):
        read_geojson(_write(tmp_path, "p.geojson", text))


def test_null_geometry_is_rejected(tmp_path):
    text = '{"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {}, "geometry": null}]}'
    with pytest.raises(ValueError, match=r"feature 0: geometry is null"):
        read_geojson(_write(tmp_path, "n.geojson", text))


def test_string_coordinate_names_the_position(tmp_path):
    text = '{"type": "LineString", "coordinates": [[0, 0], [1, "2"]]}'
    with pytest.raises(ValueError, match=r"feature 0: coordinates\[1\]: expected a position"):
        read_geojson(_write(tmp_path, "s.geojson", text))


def test_invalid_json_names_the_line_and_column(tmp_path):
    with pytest.raises(ValueError, match=r"bad\.geojson: invalid JSON at line 2, column 15"):
        read_geojson(_write(tmp_path, "bad.geojson", '{"type": "FeatureCollection",\n "features": [}'))


def test_frame_argument_conflicting_with_the_file_is_rejected(tmp_path):
    path = _write(tmp_path, "f.geojson", '{"type": "FeatureCollection", "frame": "face", "features": []}')
    with pytest.raises(ValueError, match=r"frame: the file's frame is 'face' but frame='utm' was asked for"):
        read_traces(path, frame="utm")
    named = _write(tmp_path, "n.csv", "# frame: face\nx0,y0,x1,y1\n0,0,1,1\n")
    with pytest.raises(ValueError, match=r"n\.csv: frame: the file's frame is 'face' but frame='utm' was asked for"):
        read_traces(named, frame="utm")
    assert read_traces(named, frame="face").frame == "face"
    unnamed = _write(tmp_path, "u.csv", "x0,y0,x1,y1\n0,0,1,1\n")
    assert read_traces(unnamed, frame="utm").frame == "utm"


@pytest.mark.parametrize(
    ("value", "message"),
    [("abc", r"'abc' is not a number"), ("", "empty value; expected a number"), ("nan", r"'nan' is not finite")],
)
def test_bad_csv_coordinate_names_the_line_and_column(tmp_path, value, message):
    text = f"# frame: face\ntrace_id,x,y\n\n1,0,0\n1,1,{value}\n"
    with pytest.raises(ValueError, match=rf"bad\.csv: line 5, column 'y': {message}"):
        read_csv(_write(tmp_path, "bad.csv", text))


def test_wrong_csv_header_lists_both_accepted_headers(tmp_path):
    message = r"h\.csv: line 1: header 'x,y,z' matches neither layout; .*x0,y0,x1,y1 .*trace_id,x,y"
    with pytest.raises(ValueError, match=message):
        read_csv(_write(tmp_path, "h.csv", "x,y,z\n1,2,3\n"))


def test_reappearing_trace_id_names_the_row(tmp_path):
    text = "trace_id,x,y\nA,0,0\nA,1,0\nB,0,1\nB,1,1\nA,2,2\n"
    message = r"r\.csv: line 6: trace_id 'A' reappears after other traces \(its rows started on line 2\)"
    with pytest.raises(ValueError, match=message):
        read_csv(_write(tmp_path, "r.csv", text))


def test_attribute_varying_within_a_trace_names_the_column_and_trace(tmp_path):
    text = "trace_id,x,y,set\nA,0,0,1\nA,1,0,2\n"
    with pytest.raises(ValueError, match=r"line 3, column 'set': '2' differs from '1' on line 2 of trace 'A'"):
        read_csv(_write(tmp_path, "v.csv", text))


def test_one_row_csv_trace_is_rejected_with_its_id(tmp_path):
    with pytest.raises(ValueError, match=r"line 4: trace_id 'B' has 1 vertex"):
        read_csv(_write(tmp_path, "o.csv", "trace_id,x,y\nA,0,0\nA,1,0\nB,0,1\n"))


def test_short_csv_row_names_the_line(tmp_path):
    with pytest.raises(ValueError, match=r"line 3: 3 fields, but the header has 4"):
        read_csv(_write(tmp_path, "f.csv", "x0,y0,x1,y1\n0,0,1,1\n0,0,1\n"))


def test_segments_layout_rejects_traces_with_more_than_two_vertices(tmp_path):
    tm = CATALOGUE["string_ids"].build()
    with pytest.raises(ValueError, match=r"1 trace has more: ids \['T1'\] \(indices \[0\]\); use layout='polylines'"):
        write_csv(tm, tmp_path / "s.csv", layout="segments")
    assert not (tmp_path / "s.csv").exists()


def test_polylines_layout_rejects_repeated_ids(tmp_path):
    tm = TraceMap.from_polylines([[(0, 0), (1, 1)]] * 3, {"id": [4, 5, 4]})
    with pytest.raises(ValueError, match=r"ids must be unique; repeated ids \[4\]"):
        write_csv(tm, tmp_path / "r.csv")


def test_attribute_named_like_a_layout_column_is_rejected(tmp_path):
    tm = TraceMap.from_polylines([[(0, 0), (1, 1)]], {"X": [1.0]})
    with pytest.raises(ValueError, match=r"attribute name 'X' cannot be a CSV column"):
        write_csv(tm, tmp_path / "x.csv")


def test_csv_writer_warns_that_the_window_is_not_stored(tmp_path):
    with pytest.warns(UserWarning, match="CSV does not store the sampling window"):
        write_csv(CATALOGUE["crossing_pair"].build(), tmp_path / "w.csv")


def test_geojson_writer_rejects_infinite_attributes(tmp_path):
    tm = TraceMap.from_polylines([[(0, 0), (1, 1)]] * 2, {"k": [1.0, np.inf]})
    with pytest.raises(ValueError, match=r"attribute 'k' is infinite for traces ids \[1\]"):
        write_geojson(tm, tmp_path / "k.geojson")


@pytest.mark.parametrize("function", [read_traces, lambda path: write_traces(CATALOGUE["empty"].build(), path)])
def test_unknown_suffix_is_rejected_with_the_accepted_suffixes(tmp_path, function):
    message = (r"traces\.kml: .*'\.kml'; accepted suffixes: \.geojson or \.json \(GeoJSON\), \.csv \(CSV\), "
               r"\.gpkg \(GeoPackage\), \.shp \(Shapefile\)")
    with pytest.raises(ValueError, match=message):
        function(tmp_path / "traces.kml")


def test_missing_file_raises_oserror(tmp_path):
    with pytest.raises(FileNotFoundError):
        read_traces(tmp_path / "absent.geojson")


def test_suffix_is_matched_case_insensitively(tmp_path):
    write_traces(CATALOGUE["single_trace"].build(), tmp_path / "T.GeoJSON")
    assert read_traces(tmp_path / "T.GeoJSON").lengths_m().tolist() == [5.0]


# -- atomic writes -------------------------------------------------------------------------------


@pytest.mark.parametrize("suffix", [".geojson", ".csv"])
def test_write_leaves_only_the_destination_behind(tmp_path, suffix):
    write_traces(rich_map().with_window(None), tmp_path / f"t{suffix}")
    assert [p.name for p in tmp_path.iterdir()] == [f"t{suffix}"]


def test_written_file_has_the_permissions_of_a_normally_created_file(tmp_path):
    (tmp_path / "plain.txt").write_text("x")
    write_traces(CATALOGUE["single_trace"].build(), tmp_path / "t.geojson")
    assert os.stat(tmp_path / "t.geojson").st_mode == os.stat(tmp_path / "plain.txt").st_mode


def test_failed_geojson_write_keeps_the_old_file_and_removes_the_temporary(tmp_path, monkeypatch):
    path = tmp_path / "t.geojson"
    write_geojson(CATALOGUE["single_trace"].build(), path)
    before = path.read_bytes()
    calls = []

    def dump_then_fail(feature):
        calls.append(feature)
        if len(calls) == 2:
            raise RuntimeError("disk full")
        return json.dumps(feature)

    monkeypatch.setattr(geojson_io, "_dump", dump_then_fail)
    with pytest.raises(RuntimeError, match="disk full"):
        write_geojson(CATALOGUE["parallel_traces"].build(), path)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["t.geojson"]


def test_failed_csv_write_creates_nothing(tmp_path, monkeypatch):
    real_writer = csv.writer

    class FailingWriter:
        def __init__(self, handle, **kwargs):
            self.inner, self.rows = real_writer(handle, **kwargs), 0

        def writerow(self, row):
            self.rows += 1
            if self.rows == 3:
                raise RuntimeError("killed")
            self.inner.writerow(row)

    monkeypatch.setattr(csv_io.csv, "writer", FailingWriter)
    with pytest.raises(RuntimeError, match="killed"):
        write_csv(CATALOGUE["parallel_traces"].build(), tmp_path / "t.csv")
    assert list(tmp_path.iterdir()) == []


def test_writers_do_not_modify_the_map(tmp_path):
    tm = rich_map()
    snapshot = TraceMap(tm.xy_m.copy(), tm.offsets.copy(), {k: v.copy() for k, v in tm.attributes.items()},
                        tm.window_xy_m.copy(), tm.frame, tm.crs)
    write_geojson(tm, tmp_path / "t.geojson")
    _no_window_warning(tm, write_csv, tmp_path / "t.csv")
    assert_same_map(tm, snapshot)


def test_zero_area_window_names_the_feature(tmp_path):
    text = '{"type": "Polygon", "coordinates": [[[0, 0], [1, 1], [2, 2], [0, 0]]]}'
    with pytest.raises(ValueError, match=r"z\.geojson: feature 0: window_xy_m encloses zero area"):
        read_geojson(_write(tmp_path, "z.geojson", text))


@pytest.mark.parametrize("layout", ["segments", "polylines"])
def test_csv_value_with_a_line_break_before_a_hash_round_trips(tmp_path, layout):
    """Regression (found by hypothesis): a quoted value "s:\r#" spans two physical lines, and the
    second one starts with '#'; it must not be read as a comment line."""
    tm = TraceMap.from_polylines([np.zeros((2, 2)), np.ones((2, 2))],
                                 attributes={"note": np.array(["s:\r#", "s:"])})
    path = tmp_path / "notes.csv"
    write_csv(tm, path, layout=layout)
    back = read_csv(path)
    assert back.n_traces == 2
    assert back.attributes["note"].tolist() == ["s:\r#", "s:"]
    assert np.array_equal(back.xy_m, tm.xy_m)
