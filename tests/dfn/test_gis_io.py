"""GeoPackage / Shapefile layers, fractopo's branches and nodes, and fractopo-style validation.

Oracles: node and branch counts worked out by hand (tests/dfn/_gis_fixtures.py), Sanderson & Nixon's
branch count, the clipped trace lengths of :mod:`rockmass.dfn.intensity`, and round trips.
"""

import sys

import numpy as np
import pytest
import shapely

from rockmass.dfn import (TraceMap, branches_and_nodes, clipped_lengths_m, read_traces, trace_map_statistics,
                          trace_topology, validate_traces, write_gis, write_traces)

from ._fixtures import CATALOGUE
from ._gis_fixtures import (HASH_AND_T_BRANCHES, HASH_AND_T_LENGTH_IN_WINDOW_M, HASH_AND_T_NODES,
                            HASH_AND_T_SEGMENTS, hash_and_t)

TAU = 1e-3


# -- branches and nodes (no pyogrio needed) ------------------------------------------------------


def test_hash_and_t_nodes_match_the_hand_count():
    tm = hash_and_t()
    topology = trace_topology(tm, snap_tolerance_m=TAU)
    assert (topology.n_x, topology.n_y, topology.n_i, topology.n_e) == (4, 1, 10, 1)
    assert branches_and_nodes(tm, snap_tolerance_m=TAU).node_counts() == HASH_AND_T_NODES


def test_hash_and_t_branches_match_the_hand_count():
    net = branches_and_nodes(hash_and_t(), snap_tolerance_m=TAU)
    assert net.branch_counts() == HASH_AND_T_BRANCHES
    assert net.n_branches == 15
    assert net.branch_lengths_m().sum() == pytest.approx(HASH_AND_T_LENGTH_IN_WINDOW_M, rel=1e-12)


def test_branches_add_up_to_the_clipped_trace_lengths():
    tm = hash_and_t()
    net = branches_and_nodes(tm, snap_tolerance_m=TAU)
    per_trace = np.bincount(net.branch_trace, weights=net.branch_lengths_m(), minlength=tm.n_traces)
    np.testing.assert_allclose(per_trace, clipped_lengths_m(tm, tm.window_xy_m), rtol=1e-12)


def test_branch_count_is_sanderson_nixon_without_a_window():
    # without C and the window: N_I = 9, N_Y = 1, N_X = 4 -> N_B = (9 + 3 + 16) / 2 = 14 (eq. 3)
    tm = TraceMap.from_segments(HASH_AND_T_SEGMENTS[:5])
    net = branches_and_nodes(tm, snap_tolerance_m=TAU)
    counts = net.node_counts()
    assert counts == {"X": 4, "Y": 1, "I": 9, "E": 0}
    assert net.n_branches == (counts["I"] + 3 * counts["Y"] + 4 * counts["X"]) / 2 == 14


def test_branch_ends_add_up_to_the_node_degrees_on_a_random_clean_map():
    # handshake: every branch has two ends; an I or E node ends 1 branch, a Y node 3, an X node 4
    rng = np.random.default_rng(2)  # seed 2: a fixed map of 300 segments in a 20 m square
    centre, angle = rng.uniform(0, 20, (300, 2)), rng.uniform(0, np.pi, 300)
    half = np.stack([np.cos(angle), np.sin(angle)], axis=1) * rng.uniform(0.25, 1.5, 300)[:, None]
    abutting = [[x, 5, x, 8] for x in (2.5, 7.5, 12.5)]  # Y nodes on the line y = 5
    tm = TraceMap.from_segments(np.vstack([np.hstack([centre - half, centre + half]), [[0.5, 5, 19.5, 5]], abutting]),
                                window=[(0, 0), (20, 0), (20, 20), (0, 20)])
    assert validate_traces(tm, snap_tolerance_m=1e-4).n_flagged == 0  # no near-coincident nodes
    net = branches_and_nodes(tm, snap_tolerance_m=1e-4)
    k = net.node_counts()
    assert k["Y"] >= 3 and k["X"] > 100 and k["E"] > 10
    assert 2 * net.n_branches == k["I"] + 3 * k["Y"] + 4 * k["X"] + k["E"]


@pytest.mark.parametrize("name", sorted(CATALOGUE))
def test_degenerate_maps_give_branches_as_long_as_their_traces(name):
    tm = CATALOGUE[name].build()  # every window of the catalogue holds its traces whole
    net = branches_and_nodes(tm, snap_tolerance_m=TAU)
    assert net.branch_lengths_m().sum() == pytest.approx(tm.total_length_m(), rel=1e-12, abs=1e-12)
    assert validate_traces(tm, snap_tolerance_m=TAU).flags.shape == (tm.n_traces, 9)


def test_trace_crossing_the_whole_window_is_one_e_e_branch():
    tm = TraceMap.from_segments([[-1, 5, 11, 5]], window=[(0, 0), (10, 0), (10, 10), (0, 10)])
    net = branches_and_nodes(tm, snap_tolerance_m=TAU)
    assert net.connection.tolist() == ["E - E"]
    assert net.node_counts() == {"X": 0, "Y": 0, "I": 0, "E": 2}
    assert net.branch_lengths_m().tolist() == [10.0]


def test_branches_do_not_modify_the_input():
    tm = hash_and_t()
    xy = tm.xy_m.copy()
    branches_and_nodes(tm, snap_tolerance_m=TAU)
    np.testing.assert_array_equal(tm.xy_m, xy)


# -- validation (no pyogrio needed) --------------------------------------------------------------


def test_sharp_turn_is_flagged_and_straight_and_gentle_traces_are_not():
    tm = TraceMap.from_polylines([
        [(0, 0), (10, 0)],                    # straight
        [(0, 2), (5, 2), (10, 7)],            # a 45° bend
        [(0, 4), (5, 4), (5, 9)],             # a 90° bend: fractopo's limit, not beyond it
        [(0, 12), (6, 12), (1, 13), (8, 14)],  # doubles back: a turn of about 169°
    ])
    errors = validate_traces(tm, snap_tolerance_m=TAU).errors()
    assert [("SHARP TURNS" in e) for e in errors] == [False, False, False, True]


def test_sharp_turn_limit_is_a_parameter():
    bend = TraceMap.from_polylines([[(0, 2), (5, 2), (10, 7)]])  # 45°
    assert validate_traces(bend, snap_tolerance_m=TAU, sharp_turn_deg=30.0).errors() == [("SHARP TURNS",)]
    with pytest.raises(ValueError, match="sharp_turn_deg"):
        validate_traces(bend, snap_tolerance_m=TAU, sharp_turn_deg=200.0)


def test_hash_and_t_is_clean():
    validation = validate_traces(hash_and_t(), snap_tolerance_m=TAU)
    assert validation.n_flagged == 0
    assert set(validation.counts().values()) == {0}


def test_v_node_and_multi_junction_are_flagged():
    v = TraceMap.from_segments([[0, 0, 1, 1], [1, 1, 2, 0], [5, 0, 5, 3]])
    assert validate_traces(v, snap_tolerance_m=TAU).errors() == [("V NODE",), ("V NODE",), ()]
    # two traces end at the same point of a third: three traces meet
    star = TraceMap.from_segments([[0, 0, 4, 0], [2, 0, 2, 2], [2, 0, 2, -2]])
    assert validate_traces(star, snap_tolerance_m=TAU).counts()["MULTI JUNCTION"] == 3


def test_self_crossing_stacked_and_multiple_crosscuts_are_flagged():
    tm = TraceMap.from_polylines([
        [(0, 0), (4, 0)],
        [(1, -1), (1, 1), (2, -1), (2, 1)],     # crosses trace 0 three times
        [(10, 0), (12, 2), (12, 0), (10, 2)],   # crosses itself
        [(20, 0), (24, 0)], [(21, 0), (23, 0)],  # stacked
    ])
    errors = validate_traces(tm, snap_tolerance_m=TAU).errors()
    assert "MULTIPLE CROSSCUTS" in errors[0] and "MULTIPLE CROSSCUTS" in errors[1]
    assert "CUTS ITSELF" in errors[2]
    assert "STACKED TRACES" in errors[3] and "STACKED TRACES" in errors[4]


def test_underlapping_end_is_flagged_between_tau_and_1_1_tau():
    tau = 0.01
    tm = TraceMap.from_segments([[0, 0, 4, 0], [2, 0.0105, 2, 2], [3, 0.02, 3, 2], [1, 0.005, 1, 2]])
    errors = validate_traces(tm, snap_tolerance_m=tau).errors()
    assert errors[1] == ("UNDERLAPPING SNAP",)  # 1.05 tau short of trace 0
    assert errors[2] == ()  # 2 tau away: an isolated end
    assert errors[3] == ()  # within tau: snapped


def test_statistics_count_the_validation_flags():
    tm = TraceMap.from_polylines([[(0, 1), (9, 1)], [(1, 5), (6, 5), (1, 6), (8, 7)]],
                                 window=[(0, 0), (10, 0), (10, 10), (0, 10)])
    result = trace_map_statistics(tm, n_sets=1).to_dict()
    assert result["validation"]["traces_flagged"] == 1
    assert result["validation"]["errors"]["SHARP TURNS"] == 1
    assert result["traces"]["validation_errors"] == [[], ["SHARP TURNS"]]


# -- GeoPackage and Shapefile (pyogrio) ----------------------------------------------------------


@pytest.fixture
def pyogrio():
    return pytest.importorskip("pyogrio")


def _layer_field(pyogrio, path, layer, field):
    meta, _, _, values = pyogrio.raw.read(str(path), layer=layer)
    return values[list(meta["fields"]).index(field)].tolist()


def test_geopackage_round_trip_keeps_geometry_p21_and_node_counts(pyogrio, tmp_path):
    tm = hash_and_t()
    write_traces(tm, tmp_path / "hash.gpkg")
    back = read_traces(tmp_path / "hash.gpkg")
    np.testing.assert_array_equal(back.xy_m, tm.xy_m)
    np.testing.assert_array_equal(back.offsets, tm.offsets)
    assert back.attributes["set"].tolist() == [0, 0, 1, 1, 1, 0]
    assert back.attributes["name"].tolist() == list("HHVVTC")
    assert shapely.equals(back.window_polygon(), tm.window_polygon())
    before, after = trace_map_statistics(tm).to_dict(), trace_map_statistics(back).to_dict()
    assert after["Fracture Intensity P21"] == before["Fracture Intensity P21"]
    assert after["Node Counts"] == before["Node Counts"] == HASH_AND_T_NODES


def test_geopackage_has_fractopo_layers_and_fields(pyogrio, tmp_path):
    tm = hash_and_t()
    path = tmp_path / "net.gpkg"
    write_gis(tm, path, branches_and_nodes(tm, snap_tolerance_m=TAU))
    assert {n: t for n, t in pyogrio.list_layers(str(path))} == {
        "traces": "LineString", "area": "Polygon", "nodes": "Point", "branches": "LineString"}
    classes = _layer_field(pyogrio, path, "nodes", "Class")
    assert {c: classes.count(c) for c in "XYIE"} == HASH_AND_T_NODES
    connections = _layer_field(pyogrio, path, "branches", "Connection")
    assert {c: connections.count(c) for c in HASH_AND_T_BRANCHES} == HASH_AND_T_BRANCHES
    assert sorted(set(_layer_field(pyogrio, path, "branches", "trace_id"))) == list(range(6))


def test_projected_crs_round_trips_through_geopackage_and_shapefile(pyogrio, tmp_path):
    for name in ("m.gpkg", "m.shp"):
        write_traces(hash_and_t(crs="EPSG:3067"), tmp_path / name)
        back = read_traces(tmp_path / name)
        assert (back.crs, back.frame) == ("EPSG:3067", "map")


def test_face_frame_round_trips_as_a_local_crs(pyogrio, tmp_path):
    write_traces(hash_and_t(frame="face", crs=None), tmp_path / "face.gpkg")
    assert pyogrio.read_info(str(tmp_path / "face.gpkg"), layer="traces")["crs"].startswith('LOCAL_CS["rockmass face')
    back = read_traces(tmp_path / "face.gpkg")
    assert (back.crs, back.frame) == (None, "face")


def test_geographic_crs_is_refused(pyogrio, tmp_path):
    path = tmp_path / "lonlat.gpkg"
    lines = np.array([shapely.LineString([(24.90, 60.10), (24.91, 60.11)])])
    pyogrio.raw.write(str(path), shapely.to_wkb(lines), [], fields=[], layer="traces",
                      geometry_type="LineString", crs="EPSG:4326")
    with pytest.raises(ValueError, match=r"lonlat\.gpkg: crs 'EPSG:4326' is geographic"):
        read_traces(path)


def test_shapefile_layers_are_files_beside_the_traces(pyogrio, tmp_path):
    tm = hash_and_t()
    written = write_gis(tm, tmp_path / "t.shp", branches_and_nodes(tm, snap_tolerance_m=TAU))
    stems = sorted({p.stem for p in written})
    assert stems == ["t", "t_area", "t_branches", "t_nodes"]
    assert {p.suffix for p in written} == {".shp", ".shx", ".dbf", ".prj", ".cpg"}
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in written)  # no debris
    area = read_traces(tmp_path / "t_area.shp")
    assert area.n_traces == 0 and shapely.equals(area.window_polygon(), tm.window_polygon())


def test_shapefile_cuts_field_names_to_ten_characters_as_fractopo(pyogrio, tmp_path):
    tm = TraceMap.from_segments([[0, 0, 1, 1]], {"VALIDATION_ERRORS": ["('V NODE',)"]})
    write_gis(tm, tmp_path / "v.shp")
    assert _layer_field(pyogrio, tmp_path / "v.shp", "v", "VALIDATION") == ["('V NODE',)"]
    clash = TraceMap.from_segments([[0, 0, 1, 1]], {"length_in_area": [1.0], "length_in_a": [2.0]})
    with pytest.raises(ValueError, match="10 characters"):
        write_gis(clash, tmp_path / "c.shp")


def test_missing_pyogrio_says_how_to_install(tmp_path, monkeypatch):
    (tmp_path / "t.gpkg").write_bytes(b"")
    monkeypatch.setitem(sys.modules, "pyogrio", None)  # import pyogrio -> ImportError
    with pytest.raises(ImportError, match=r"pip install 'rockmass\[gis\]'"):
        read_traces(tmp_path / "t.gpkg")
    with pytest.raises(ImportError, match=r"rockmass\[gis\]"):
        write_traces(hash_and_t(), tmp_path / "u.gpkg")


def _two_line_layers(pyogrio, path):
    for layer, xy in (("faults", [(0, 0), (1, 1)]), ("joints", [(0, 1), (1, 0)])):
        pyogrio.raw.write(str(path), shapely.to_wkb(np.array([shapely.LineString(xy)])), [], fields=[],
                          layer=layer, geometry_type="LineString", crs="EPSG:3067")


def test_ambiguous_line_layers_are_named_in_the_error(pyogrio, tmp_path):
    path = tmp_path / "two.gpkg"
    _two_line_layers(pyogrio, path)
    with pytest.raises(ValueError, match=r"two\.gpkg: 2 layers could hold the traces: 'faults', 'joints'.*layer=NAME"):
        read_traces(path)
    assert read_traces(path, layer="joints").polyline(0).tolist() == [[0.0, 1.0], [1.0, 0.0]]
    with pytest.raises(ValueError, match=r"layer 'veins' is not in the file; its layers: 'faults' \(LineString\)"):
        read_traces(path, layer="veins")


def test_point_in_a_traces_layer_names_file_layer_and_feature(pyogrio, tmp_path):
    path = tmp_path / "mixed.gpkg"
    geometries = np.array([shapely.LineString([(0, 0), (1, 1)]), shapely.Point(2, 2)])
    pyogrio.raw.write(str(path), shapely.to_wkb(geometries), [], fields=[], layer="traces",
                      geometry_type="Unknown", crs="EPSG:3067")
    with pytest.raises(ValueError, match=r"mixed\.gpkg: layer 'traces': feature 1 \(fid 2\): geometry 'Point' is not a trace"):
        read_traces(path, layer="traces")


def test_two_area_polygons_are_refused(pyogrio, tmp_path):
    path = tmp_path / "areas.gpkg"
    write_traces(TraceMap.from_segments([[1, 1, 2, 2]], crs="EPSG:3067", frame="map"), path)
    boxes = np.array([shapely.box(0, 0, 5, 5), shapely.box(6, 0, 9, 5)])
    pyogrio.raw.write(str(path), shapely.to_wkb(boxes), [], fields=[], layer="area", geometry_type="Polygon",
                      crs="EPSG:3067")
    with pytest.raises(ValueError, match=r"layer 'area' holds 2 polygons; a trace map has one sampling window"):
        read_traces(path)


def test_unjoined_multilinestring_is_split_and_flagged(pyogrio, tmp_path):
    path = tmp_path / "multi.gpkg"
    multi = shapely.MultiLineString([[(0, 0), (1, 0)], [(3, 0), (4, 0)]])
    joined = shapely.MultiLineString([[(0, 2), (1, 2)], [(1, 2), (2, 3)]])
    pyogrio.raw.write(str(path), shapely.to_wkb(np.array([multi, joined])), [], fields=[], layer="traces",
                      geometry_type="MultiLineString", crs="EPSG:3067")
    tm = read_traces(path)
    assert tm.n_traces == 3 and tm.attributes["part"].tolist() == [0, 1, -1]
    errors = validate_traces(tm, snap_tolerance_m=TAU).errors()
    assert [("GEOM TYPE MULTILINESTRING" in e) for e in errors] == [True, True, False]


def test_failed_geopackage_write_keeps_the_previous_file(pyogrio, tmp_path, monkeypatch):
    path = tmp_path / "keep.gpkg"
    write_traces(hash_and_t(), path)
    before = path.read_bytes()
    real = pyogrio.raw.write

    def fail_on_area(*args, **kwargs):
        if kwargs.get("layer") == "area":
            raise OSError("disk full")
        return real(*args, **kwargs)

    monkeypatch.setattr(pyogrio.raw, "write", fail_on_area)
    with pytest.raises(OSError, match="disk full"):
        write_traces(hash_and_t(), path)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["keep.gpkg"]


def test_a_layer_gdal_cannot_read_is_bad_input_naming_the_file(pyogrio, tmp_path, monkeypatch):
    """GDAL's layer, field and geometry errors (RuntimeErrors: exit 1) become a ValueError (exit 2)
    that names the file."""
    path = tmp_path / "hash.gpkg"
    write_traces(hash_and_t(), path)

    def broken(*args, **kwargs):
        raise pyogrio.errors.DataLayerError("simulated damaged table")

    monkeypatch.setattr(pyogrio.raw, "read", broken)
    with pytest.raises(ValueError, match=r"hash\.gpkg: a layer GDAL cannot read"):
        read_traces(path)


def test_shapefile_rewrite_without_area_or_topology_drops_their_old_layers(pyogrio, tmp_path):
    tm = hash_and_t()
    path = tmp_path / "net.shp"
    write_gis(tm, path, branches_and_nodes(tm, snap_tolerance_m=TAU))
    assert (tmp_path / "net_branches.shp").is_file() and (tmp_path / "net_area.shp").is_file()
    bare = TraceMap.from_segments(HASH_AND_T_SEGMENTS, frame="map", crs="EPSG:3067")
    write_gis(bare, path)
    assert sorted(p.stem for p in tmp_path.glob("*.shp")) == ["net"]
