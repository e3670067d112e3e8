"""Frames of trace maps (issue 19): areas never silent, CRS read / refused / written, azimuths."""

import json
import math

import numpy as np
import pytest
import shapely

from rockmass.dfn import TraceMap, read_traces, sampling_window, trace_map_statistics, write_traces
from rockmass.dfn.frames import angle_convention, check_crs, crs_kind, local_crs_wkt, to_convention
from rockmass.dfn.orientation import dip_text


def _geojson(path, coordinates, crs=None, frame=None, window=None):
    """A FeatureCollection of LineStrings (and a window Polygon), with optional crs / frame members."""
    doc = {"type": "FeatureCollection"}
    if crs is not None:
        doc["crs"] = crs
    if frame is not None:
        doc["frame"] = frame
    doc["features"] = [{"type": "Feature", "properties": {"id": i},
                        "geometry": {"type": "LineString", "coordinates": line}}
                       for i, line in enumerate(coordinates)]
    if window is not None:
        doc["features"].append({"type": "Feature", "properties": {},
                                "geometry": {"type": "Polygon", "coordinates": [window + window[:1]]}})
    path.write_text(json.dumps(doc))
    return path


# a 100 m outcrop near Helsinki in longitude / latitude (about 1e-3 degrees across)
LONLAT = [[[24.9400, 60.1700], [24.9410, 60.1705]], [[24.9402, 60.1706], [24.9409, 60.1701]]]
METRES = [[[0.0, 0.0], [8.0, 6.0]], [[1.0, 5.0], [7.0, 1.0]]]


# -- coordinate reference systems ---------------------------------------------------------------


@pytest.mark.parametrize("crs", [
    {"type": "name", "properties": {"name": "urn:ogc:def:crs:OGC:1.3:CRS84"}},
    {"type": "name", "properties": {"name": "EPSG:4326"}},
    {"type": "EPSG", "properties": {"code": 4326}},
    "OGC:CRS84",
])
def test_geographic_crs_is_refused_naming_the_file_and_how_to_reproject(tmp_path, crs):
    path = _geojson(tmp_path / "lonlat.geojson", LONLAT, crs=crs)
    with pytest.raises(ValueError, match=r"lonlat\.geojson: crs .* is geographic.*reproject"):
        read_traces(path)


def test_geojson_without_crs_in_degrees_is_refused_by_the_rfc7946_default(tmp_path):
    # issue 19: such a file was measured as metres, P21 = 5.7e4 m/m², exit 0
    path = _geojson(tmp_path / "rfc.geojson", LONLAT)
    with pytest.raises(ValueError, match=r"rfc\.geojson: the file names no crs.*RFC 7946.*\"frame\""):
        read_traces(path)


def test_geojson_without_crs_in_metres_is_a_face_map(tmp_path):
    tm = read_traces(_geojson(tmp_path / "face.geojson", METRES))
    assert (tm.frame, tm.crs) == ("face", None)


def test_naming_the_frame_reads_small_coordinates_as_metres(tmp_path):
    tm = read_traces(_geojson(tmp_path / "small.geojson", [[[0.0, 0.0], [0.01, 0.02]]], frame="face"))
    assert tm.lengths_m()[0] == pytest.approx(math.hypot(0.01, 0.02))


def test_projected_crs_is_kept_and_the_file_is_a_map(tmp_path):
    crs = {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::3067"}}
    tm = read_traces(_geojson(tmp_path / "utm.geojson", [[[385000.0, 6671000.0], [385010.0, 6671005.0]]], crs=crs))
    assert (tm.frame, tm.crs) == ("map", "urn:ogc:def:crs:EPSG::3067")


@pytest.mark.parametrize("xy, refused", [(LONLAT[0], True), ([[385000.0, 6671000.0], [385010.0, 6671005.0]], False)])
def test_an_unlisted_code_of_the_geographic_block_is_decided_by_the_coordinates(xy, refused):
    assert crs_kind("EPSG:4301") in ("geographic?", "geographic")
    if refused:
        with pytest.raises(ValueError, match="geographic"):
            check_crs("EPSG:4301", xy, "x.geojson")
    elif crs_kind("EPSG:4301") == "geographic?":  # without pyproj: metres decide
        assert check_crs("EPSG:4301", xy, "x.geojson") == "geographic?"


def test_csv_with_a_geographic_crs_comment_is_refused(tmp_path):
    path = tmp_path / "lonlat.csv"
    path.write_text("# crs: EPSG:4326\nx0,y0,x1,y1\n24.94,60.17,24.941,60.1705\n")
    with pytest.raises(ValueError, match=r"lonlat\.csv: crs 'EPSG:4326' is geographic"):
        read_traces(path)


def test_face_map_is_written_with_a_local_crs_and_reads_back_without_one(tmp_path):
    tm = TraceMap.from_polylines([np.array(line) for line in METRES], frame="face")
    path = tmp_path / "face.geojson"
    write_traces(tm, path)
    doc = json.loads(path.read_text())
    name = doc["crs"]["properties"]["name"]
    assert name == local_crs_wkt("face") and name.startswith('LOCAL_CS["rockmass face frame')
    assert crs_kind(name) == "local"  # a GIS reads a local engineering CRS, not WGS 84
    assert (doc["frame"], doc["angle_convention"]) == ("face", "face")  # what angle_deg attributes mean
    back = read_traces(path)
    assert (back.frame, back.crs) == ("face", None)
    assert np.array_equal(back.xy_m, tm.xy_m)


def test_projected_crs_is_written_back(tmp_path):
    tm = TraceMap.from_polylines([np.array(line) for line in METRES], frame="map", crs="EPSG:32633")
    path = tmp_path / "map.geojson"
    write_traces(tm, path)
    doc = json.loads(path.read_text())
    assert (doc["crs"]["properties"]["name"], doc["angle_convention"]) == ("EPSG:32633", "azimuth")
    assert read_traces(path).crs == "EPSG:32633"


# -- areas ---------------------------------------------------------------------------------------


def test_statistics_of_a_map_without_window_need_an_explicit_area():
    tm = TraceMap.from_segments([[0, 0, 10, 10], [0, 10, 10, 0]])
    with pytest.raises(ValueError, match="no sampling window.*'bbox'.*'hull'"):
        trace_map_statistics(tm)


def test_bbox_and_hull_are_explicit_choices_named_in_the_result():
    tm = TraceMap.from_segments([[0, 0, 4, 0], [0, 0, 0, 3], [4, 0, 0, 3]])  # a 3-4-5 triangle
    box = trace_map_statistics(tm, window="bbox").to_dict()
    hull = trace_map_statistics(tm, window="hull").to_dict()
    assert (box["window"]["source"], box["Area"]["value"]) == ("bounding_box", 12.0)
    assert (hull["window"]["source"], hull["Area"]["value"]) == ("convex_hull", 6.0)
    assert hull["Fracture Intensity P21"]["value"] == pytest.approx(12.0 / 6.0)


def test_hull_of_collinear_traces_is_refused():
    with pytest.raises(ValueError, match="convex hull has zero area"):
        sampling_window(TraceMap.from_segments([[0, 0, 1, 1], [2, 2, 3, 3]]), "hull")


# -- angles --------------------------------------------------------------------------------------


def _fractopo_azimuth(x0, y0, x1, y1):
    """fractopo's determine_azimuth(line, halved=True), written out: 90 - atan2(dy, dx), in [0, 180)."""
    azimuth = (90.0 - math.degrees(math.atan2(y1 - y0, x1 - x0))) % 360.0
    return azimuth - 180.0 if azimuth >= 180.0 else azimuth


@pytest.mark.parametrize("dx, dy", [(1, 1), (0, 1), (1, 0), (-1, -1), (1, -2), (-3, 1), (2, 7)])
def test_map_azimuth_is_clockwise_from_north_as_fractopo(dx, dy):
    tm = TraceMap.from_segments([[0, 0, dx, dy]], frame="map")
    theta = math.degrees(math.atan2(dy, dx)) % 180.0
    assert to_convention([theta], angle_convention(tm.frame))[0] == pytest.approx(_fractopo_azimuth(0, 0, dx, dy),
                                                                              abs=1e-9)


def _parallel_traces(angle_ccw_deg, frame, n=8):
    t = math.radians(angle_ccw_deg)
    d = np.array([math.cos(t), math.sin(t)]) * 4.0
    lines = [np.array([[5.0, 1.0 + k], [5.0, 1.0 + k] + d]) for k in range(n)]
    return TraceMap.from_polylines(lines, frame=frame, window=[(0, -5), (15, -5), (15, 15), (0, 15)])


def test_map_statistics_give_azimuths_and_face_statistics_counter_clockwise_angles():
    # traces 20° counter-clockwise from East: azimuth 070° on a map (issue 19: fractopo 69.5°,
    # rockmass 20.2° on one public map)
    on_map = trace_map_statistics(_parallel_traces(20.0, "map")).to_dict()
    on_face = trace_map_statistics(_parallel_traces(20.0, "face")).to_dict()
    assert on_map["angle_convention"] == "azimuth" and "clockwise from North" in on_map["angle_convention_text"]
    assert on_face["angle_convention"] == "face" and "counter-clockwise" in on_face["angle_convention_text"]
    assert on_map["sets"][0]["Mean Angle"]["value"] == pytest.approx(70.0, abs=1e-6)
    assert on_face["sets"][0]["Mean Angle"]["value"] == pytest.approx(20.0, abs=1e-6)
    assert on_map["traces"]["angle_deg"] == pytest.approx([70.0] * 8, abs=1e-6)
    assert on_map["sets"][0]["Scanline Angle"]["value"] == pytest.approx(160.0, abs=1e-6)  # normal to the set
    assert on_map["sets"][0]["Fracture Intensity P21"] == on_face["sets"][0]["Fracture Intensity P21"]


def test_dip_text_is_whole_degrees_with_three_digit_dip_direction():
    assert (dip_text(68.97, 29.02), dip_text(62.1, 202.46), dip_text(5.4, 359.7)) == ("69/029", "62/202", "05/000")


def test_hull_polygon_is_the_shapely_convex_hull():
    tm = TraceMap.from_segments([[0, 0, 3, 1], [1, 4, 2, -1]])
    expected = shapely.convex_hull(shapely.multipoints(tm.xy_m))
    assert sampling_window(tm, "hull").polygon.equals(expected)
