"""``rockmass traces`` with GeoPackage / Shapefile input and ``--gis`` layers (issue 19, item 4).

Oracles: the hand-counted network of tests/dfn/_gis_fixtures.py, and the same map read from GeoJSON.
"""

import json
import subprocess
import sys

import pytest

from rockmass.cli import main
from rockmass.dfn import TraceMap, write_traces

from ..dfn._gis_fixtures import HASH_AND_T_BRANCHES, HASH_AND_T_NODES, SQUARE_10, hash_and_t

pyogrio = pytest.importorskip("pyogrio")


def _field(path, layer, field):
    meta, _, _, values = pyogrio.raw.read(str(path), layer=layer)
    return values[list(meta["fields"]).index(field)].tolist()


def _summary(capsys):
    return json.loads(capsys.readouterr().out)


def test_gpkg_input_gives_the_statistics_of_the_same_geojson(tmp_path, capsys):
    write_traces(hash_and_t(), tmp_path / "hash.gpkg")
    write_traces(hash_and_t(), tmp_path / "hash.geojson")
    assert main(["traces", str(tmp_path / "hash.gpkg"), "--json"]) == 0
    from_gpkg = _summary(capsys)
    assert main(["traces", str(tmp_path / "hash.geojson"), "--json"]) == 0
    from_geojson = _summary(capsys)
    assert from_gpkg["Fracture Intensity P21"] == from_geojson["Fracture Intensity P21"]
    assert from_gpkg["Fracture Intensity P21"]["value"] == pytest.approx(0.36, rel=1e-12)  # 36 m / 100 m²
    assert from_gpkg["Node Counts"] == from_geojson["Node Counts"] == HASH_AND_T_NODES
    assert from_gpkg["crs"] == "EPSG:3067" and from_gpkg["angle_convention"] == "azimuth"


def test_gis_gpkg_writes_traces_area_nodes_and_branches(tmp_path, capsys):
    write_traces(hash_and_t(), tmp_path / "hash.geojson")
    out = tmp_path / "out"
    assert main(["traces", str(tmp_path / "hash.geojson"), "--gis", "gpkg", "--out", str(out), "--json"]) == 0
    summary = _summary(capsys)
    gpkg = out / "traces.gpkg"
    assert [n for n, _ in pyogrio.list_layers(str(gpkg))] == ["traces", "area", "nodes", "branches"]
    classes = _field(gpkg, "nodes", "Class")
    assert {c: classes.count(c) for c in "XYIE"} == summary["Node Counts"] == HASH_AND_T_NODES
    connections = _field(gpkg, "branches", "Connection")
    assert {c: connections.count(c) for c in HASH_AND_T_BRANCHES} == HASH_AND_T_BRANCHES
    assert _field(gpkg, "traces", "azimuth") == [90.0, 90.0, 0.0, 0.0, 0.0, 90.0]
    assert _field(gpkg, "traces", "VALIDATION_ERRORS") == ["()"] * 6
    assert _field(gpkg, "traces", "length_in_area") == [8.0, 8.0, 8.0, 8.0, 2.5, 1.5]
    assert summary["validation"]["traces_flagged"] == 0
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["config"]["gis"] == "gpkg"


def test_written_geopackage_reads_back_with_the_same_p21_and_nodes(tmp_path, capsys):
    write_traces(hash_and_t(), tmp_path / "hash.geojson")
    out = tmp_path / "out"
    assert main(["traces", str(tmp_path / "hash.geojson"), "--gis", "gpkg", "--out", str(out), "--json"]) == 0
    first = _summary(capsys)
    assert main(["traces", str(out / "traces.gpkg"), "--json"]) == 0  # two line layers: 'traces' is taken
    second = _summary(capsys)
    for key in ("Fracture Intensity P21", "Node Counts", "Number of Branches"):
        assert second[key] == first[key]


def test_gis_shp_writes_one_shapefile_per_layer(tmp_path, capsys):
    write_traces(hash_and_t(), tmp_path / "hash.geojson")
    out = tmp_path / "out"
    assert main(["traces", str(tmp_path / "hash.geojson"), "--gis", "shp", "--out", str(out)]) == 0
    for stem in ("traces", "traces_area", "traces_nodes", "traces_branches"):
        for suffix in (".shp", ".shx", ".dbf", ".prj"):
            assert (out / (stem + suffix)).is_file()
    assert "VALIDATION" in pyogrio.read_info(str(out / "traces.shp"))["fields"].tolist()


def test_a_rerun_without_gis_drops_the_layers_of_the_earlier_run(tmp_path, capsys):
    """The folder never holds GIS layers of another map (or format) beside a new summary."""
    write_traces(hash_and_t(), tmp_path / "hash.geojson")
    out = tmp_path / "out"
    assert main(["traces", str(tmp_path / "hash.geojson"), "--gis", "shp", "--out", str(out)]) == 0
    assert main(["traces", str(tmp_path / "hash.geojson"), "--gis", "gpkg", "--out", str(out)]) == 0
    assert not list(out.glob("traces*.shp")) and (out / "traces.gpkg").is_file()
    (out / "notes.txt").write_text("mine")  # a file of the user's stays
    assert main(["traces", str(tmp_path / "hash.geojson"), "--out", str(out)]) == 0
    assert not (out / "traces.gpkg").exists() and (out / "notes.txt").read_text() == "mine"


def test_area_from_a_geopackage_polygon_file(tmp_path, capsys):
    traces = TraceMap.from_segments([[1, 3, 9, 3], [3, 1, 3, 9]], frame="map", crs="EPSG:3067")
    write_traces(traces, tmp_path / "t.gpkg")
    write_traces(TraceMap.from_polylines([], window=SQUARE_10, frame="map", crs="EPSG:3067"), tmp_path / "a.gpkg")
    assert main(["traces", str(tmp_path / "t.gpkg"), "--area", str(tmp_path / "a.gpkg"), "--json"]) == 0
    summary = _summary(capsys)
    assert summary["Area"]["value"] == 100.0
    assert summary["Fracture Intensity P21"]["value"] == pytest.approx(0.16, rel=1e-12)


def test_ambiguous_layers_exit_2_and_layer_picks_one(tmp_path, capsys):
    import numpy as np
    import shapely

    path = tmp_path / "two.gpkg"
    for layer, xy in (("faults", [(0, 0), (4, 4)]), ("joints", [(0, 4), (4, 0)])):
        pyogrio.raw.write(str(path), shapely.to_wkb(np.array([shapely.LineString(xy)])), [], fields=[],
                          layer=layer, geometry_type="LineString", crs="EPSG:3067")
    assert main(["traces", str(path), "--area", "bbox"]) == 2
    err = capsys.readouterr().err
    assert "two.gpkg" in err and "'faults', 'joints'" in err and "--layer NAME" in err
    assert main(["traces", str(path), "--layer", "joints", "--area", "bbox", "--json"]) == 0
    assert _summary(capsys)["Number of Traces"]["value"] == 1


def test_missing_pyogrio_exits_2_with_the_pip_hint(tmp_path, capsys, monkeypatch):
    write_traces(hash_and_t(), tmp_path / "hash.gpkg")
    write_traces(hash_and_t(), tmp_path / "hash.geojson")
    monkeypatch.setitem(sys.modules, "pyogrio", None)
    assert main(["traces", str(tmp_path / "hash.gpkg")]) == 2
    assert "pip install 'rockmass[gis]'" in capsys.readouterr().err
    out = tmp_path / "out"
    assert main(["traces", str(tmp_path / "hash.geojson"), "--gis", "gpkg", "--out", str(out)]) == 2
    assert "pip install 'rockmass[gis]'" in capsys.readouterr().err
    assert not out.exists()  # refused before any work


def test_unreadable_gpkg_and_layer_of_a_geojson_exit_2(tmp_path, capsys):
    (tmp_path / "bad.gpkg").write_text("not a geopackage")
    assert main(["traces", str(tmp_path / "bad.gpkg")]) == 2
    assert "bad.gpkg: not a readable GeoPackage or Shapefile" in capsys.readouterr().err
    write_traces(hash_and_t(), tmp_path / "hash.geojson")
    assert main(["traces", str(tmp_path / "hash.geojson"), "--layer", "traces"]) == 2
    assert "hash.geojson: a layer ('traces'; --layer" in capsys.readouterr().err


def test_gis_without_out_exits_2(tmp_path, capsys):
    write_traces(hash_and_t(), tmp_path / "hash.geojson")
    assert main(["traces", str(tmp_path / "hash.geojson"), "--gis", "gpkg"]) == 2
    assert "--out" in capsys.readouterr().err


def test_cli_start_up_does_not_import_pyogrio():
    code = "import sys, rockmass.cli; rockmass.cli.build_parser(); print('pyogrio' in sys.modules)"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "False"
