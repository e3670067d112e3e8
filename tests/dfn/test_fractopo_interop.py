"""Interop with fractopo itself (issue 19): a map rockmass writes as a GeoPackage, read by fractopo's
``Network``, has rockmass's P21, node counts and branch counts, and fractopo's validation flags the
traces rockmass flags. Runs where fractopo is installed (``pip install 'rockmass[fractopo]'``);
the hand-counted network is tests/dfn/_gis_fixtures.py's."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from rockmass.dfn import (TraceMap, branches_and_nodes, trace_map_statistics, validate_traces,
                          write_gis)

from ._gis_fixtures import HASH_AND_T_BRANCHES, HASH_AND_T_NODES, hash_and_t

fractopo = pytest.importorskip("fractopo")
gpd = pytest.importorskip("geopandas")
pytest.importorskip("pyogrio")

SNAP_M = 0.001


def _fractopo_network(path):
    from fractopo import Network

    traces, area = gpd.read_file(path, layer="traces"), gpd.read_file(path, layer="area")
    return Network(traces, area, name="rockmass", truncate_traces=True,
                   circular_target_area=False, determine_branches_nodes=True,
                   snap_threshold=SNAP_M)


def test_fractopo_reads_our_geopackage_with_our_p21_nodes_and_branches(tmp_path):
    tm = hash_and_t()
    path = tmp_path / "hash.gpkg"
    write_gis(tm, path, branches_and_nodes(tm, snap_tolerance_m=SNAP_M))
    net = _fractopo_network(path)
    ours = trace_map_statistics(tm).to_dict()
    assert net.parameters["Fracture Intensity P21"] == pytest.approx(
        ours["Fracture Intensity P21"]["value"], rel=1e-9)
    assert dict(Counter(net.node_types)) == {k: v for k, v in HASH_AND_T_NODES.items() if v}
    assert dict(Counter(net.branch_types)) == {k: v for k, v in HASH_AND_T_BRANCHES.items() if v}


def test_fractopo_flags_what_we_flag(tmp_path):
    """A sharp turn, a V node and clean traces: the same labels, trace by trace."""
    from fractopo.tval.trace_validation import Validation

    xy = [np.array([[1.0, 1.0], [5.0, 1.0], [2.0, 2.0]]),        # a sharp turn
          np.array([[1.0, 6.0], [4.0, 8.0]]), np.array([[4.0, 8.0], [7.0, 6.0]]),  # a V node
          np.array([[1.0, 4.0], [9.0, 4.5]])]                     # clean
    tm = TraceMap.from_polylines(xy, window=[(0, 0), (10, 0), (10, 10), (0, 10)], frame="map",
                                 crs="EPSG:3067")
    path = tmp_path / "flags.gpkg"
    write_gis(tm, path)
    traces, area = gpd.read_file(path, layer="traces"), gpd.read_file(path, layer="area")
    checked = Validation(traces.drop(columns=["VALIDATION_ERRORS"], errors="ignore"), area,
                         name="x", allow_fix=False, SNAP_THRESHOLD=SNAP_M).run_validation()
    theirs = [set(v) for v in checked[Validation.ERROR_COLUMN]]
    ours = [set(e) for e in validate_traces(tm, snap_tolerance_m=SNAP_M).errors()]
    assert ours == theirs
    assert {"SHARP TURNS"} <= ours[0] and {"V NODE"} <= ours[1] and ours[3] == set()
