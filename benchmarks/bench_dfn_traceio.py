"""Trace-map I/O: read and write time against round-trip error, GeoJSON and CSV.

    python benchmarks/bench_dfn_traceio.py

Random polyline maps of 10^3, 10^4 and 10^5 traces (5 vertices each) are written and read back in
each format; the error column is the largest coordinate difference after the round trip (the
writers print floats with repr, so it must be exactly 0). Rows also go to
benchmarks/results/bench_dfn_traceio.json.
"""

from __future__ import annotations

import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from _common import header, save, table
from rockmass.dfn import TraceMap, read_traces, write_traces


def random_map(n_traces: int, seed: int) -> TraceMap:
    rng = np.random.default_rng(seed)
    start = rng.uniform(0, 100, size=(n_traces, 1, 2))
    steps = rng.normal(0, 0.5, size=(n_traces, 4, 2))
    vertices = np.concatenate([start, start + np.cumsum(steps, axis=1)], axis=1)
    return TraceMap.from_polylines(list(vertices), attributes={"set": rng.integers(1, 4, n_traces)},
                                   window=np.array([[-5, -5], [105, -5], [105, 105], [-5, 105.0]]))


def main() -> None:
    print(header("trace-map I/O: run time and round-trip error (5 vertices per trace)"))
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in (1_000, 10_000, 100_000):
            trace_map = random_map(n, seed=n)
            for suffix in (".geojson", ".csv"):
                path = Path(tmp) / f"map{suffix}"
                t0 = time.perf_counter()
                with warnings.catch_warnings():  # CSV drops the window, as documented
                    warnings.simplefilter("ignore", UserWarning)
                    write_traces(trace_map, path)
                t1 = time.perf_counter()
                back = read_traces(path)
                t2 = time.perf_counter()
                same_shape = back.xy_m.shape == trace_map.xy_m.shape
                error = float(np.max(np.abs(back.xy_m - trace_map.xy_m))) if same_shape else np.inf
                rows.append(dict(traces=n, format=suffix[1:], write_s=t1 - t0, read_s=t2 - t1,
                                 MB=path.stat().st_size / 1e6, max_coord_error=error,
                                 offsets_equal=bool(np.array_equal(back.offsets, trace_map.offsets))))
    print(table(rows, [("traces", "d"), ("format", "s"), ("write_s", ".3f"), ("read_s", ".3f"),
                       ("MB", ".1f"), ("max_coord_error", ".1e"), ("offsets_equal", "")]))
    print(f"\nrows written to {save('bench_dfn_traceio', {'rows': rows})}")


if __name__ == "__main__":
    main()
