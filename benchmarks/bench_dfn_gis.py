"""GeoPackage / Shapefile layers and fractopo's topology layers: run time against round-trip error.

    python benchmarks/bench_dfn_gis.py

Random maps of 10^3 and 10^4 straight traces (exponential lengths, mean 1 m, in a 100 m square;
seed = number of traces) go through: fractopo-style validation (`validate_traces`), branches and
nodes (`branches_and_nodes`), then `write_gis` with every layer and `read_traces` back, as GeoPackage
and as Shapefile. Error columns: the largest coordinate difference after the round trip (GDAL stores
float64: exactly 0), and whether P21 and the node counts of the map read back equal the original's.
Needs pyogrio (pip install 'rockmass[gis]'). Rows also go to benchmarks/results/bench_dfn_gis.json.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from _common import header, save, table
from rockmass.dfn import (TraceMap, branches_and_nodes, read_traces, trace_map_statistics, validate_traces,
                          write_gis)

SNAP_M = 0.01


def random_map(n_traces: int, seed: int) -> TraceMap:
    rng = np.random.default_rng(seed)
    centre = rng.uniform(0, 100, (n_traces, 2))
    angle = rng.uniform(0, np.pi, n_traces)
    half = np.stack([np.cos(angle), np.sin(angle)], axis=1) * rng.exponential(0.5, n_traces)[:, None]
    return TraceMap.from_segments(np.hstack([centre - half, centre + half]), {"set": rng.integers(0, 3, n_traces)},
                                  window=[(0, 0), (100, 0), (100, 100), (0, 100)], frame="map", crs="EPSG:3067")


def main() -> None:
    print(header(f"GIS layers: validation, branches and nodes, GeoPackage / Shapefile round trip (snap {SNAP_M} m)"))
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in (1_000, 10_000):
            trace_map = random_map(n, seed=n)
            t0 = time.perf_counter()
            flagged = validate_traces(trace_map, snap_tolerance_m=SNAP_M).n_flagged
            t1 = time.perf_counter()
            network = branches_and_nodes(trace_map, snap_tolerance_m=SNAP_M)
            t2 = time.perf_counter()
            before = trace_map_statistics(trace_map, n_sets=1, snap_tolerance_m=SNAP_M).to_dict()
            for suffix in (".gpkg", ".shp"):
                path = Path(tmp) / f"map{n}{suffix}"
                t3 = time.perf_counter()
                written = write_gis(trace_map, path, network)
                t4 = time.perf_counter()
                back = read_traces(path)
                t5 = time.perf_counter()
                after = trace_map_statistics(back.with_window(trace_map.window_xy_m), n_sets=1,
                                             snap_tolerance_m=SNAP_M).to_dict()
                rows.append(dict(
                    traces=n, format=suffix[1:], flagged=flagged, branches=network.n_branches,
                    validate_s=t1 - t0, branches_s=t2 - t1, write_s=t4 - t3, read_s=t5 - t4,
                    MB=sum(p.stat().st_size for p in written) / 1e6,
                    max_coord_error=float(np.max(np.abs(back.xy_m - trace_map.xy_m))),
                    p21_equal=after["Fracture Intensity P21"] == before["Fracture Intensity P21"],
                    nodes_equal=after["Node Counts"] == before["Node Counts"]))
    print(table(rows, [("traces", "d"), ("format", "s"), ("flagged", "d"), ("branches", "d"),
                       ("validate_s", ".3f"), ("branches_s", ".3f"), ("write_s", ".3f"), ("read_s", ".3f"),
                       ("MB", ".1f"), ("max_coord_error", ".1e"), ("p21_equal", ""), ("nodes_equal", "")]))
    print(f"\nrows written to {save('bench_dfn_gis', {'rows': rows})}")


if __name__ == "__main__":
    main()
