"""Trace maps whose answers can be worked out by hand, and the dfn catalogue of degenerate inputs.

Each :class:`Case` keeps the plain Python polylines it was built from, so tests can compute their
oracles (segments, lengths, bounds) with naive loops that never touch the code under test.
"""

import math
from dataclasses import dataclass

import numpy as np

from rockmass.dfn import TraceMap

N_GON = 1000  # vertices of the "many vertices" polyline (a closed regular polygon of radius 1)


@dataclass(frozen=True)
class Case:
    """A trace map, the polylines it was built from, and its hand-computed lengths and bounds."""

    name: str
    polylines: list
    lengths_m: list
    bounds: tuple | None
    attributes: dict | None = None
    window: list | None = None

    def build(self) -> TraceMap:
        return TraceMap.from_polylines(self.polylines, self.attributes, window=self.window)


def _regular_polygon(n: int) -> list:
    ring = [(math.cos(2 * math.pi * k / n), math.sin(2 * math.pi * k / n)) for k in range(n)]
    return ring + ring[:1]


CATALOGUE = {
    case.name: case
    for case in [
        Case("empty", [], [], None),
        Case("single_trace", [[(0.0, 0.0), (3.0, 4.0)]], [5.0], (0.0, 0.0, 3.0, 4.0)),  # 3-4-5 triangle
        Case(
            "zero_length_trace",
            [[(2.0, 1.0), (2.0, 1.0), (2.0, 1.0)], [(0.0, 0.0), (1.0, 0.0)]],
            [0.0, 1.0],
            (0.0, 0.0, 2.0, 1.0),
        ),
        Case(
            "parallel_traces",
            [[(0.0, y), (2.0, y)] for y in (0.0, 1.0, 2.0)],
            [2.0, 2.0, 2.0],
            (0.0, 0.0, 2.0, 2.0),
        ),
        Case(
            "crossing_pair",
            [[(-1.0, 0.0), (1.0, 0.0)], [(0.0, -1.0), (0.0, 1.0)]],
            [2.0, 2.0],
            (-1.0, -1.0, 1.0, 1.0),
            window=[(-2.0, -2.0), (2.0, -2.0), (2.0, 2.0), (-2.0, 2.0)],
        ),
        Case(
            "many_vertices",
            [_regular_polygon(N_GON)],
            [2 * N_GON * math.sin(math.pi / N_GON)],  # perimeter of a regular n-gon inscribed in r = 1
            (-1.0, -1.0, 1.0, 1.0),
        ),
        Case(
            "string_ids",
            [[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (0.0, 0.0)], [(5.0, 5.0), (5.0, 7.0)]],
            [4.0, 2.0],  # a unit square walked round, and a 2 m vertical trace
            (0.0, 0.0, 5.0, 7.0),
            attributes={"id": ["T1", "T2"], "set": [1, 2]},
        ),
    ]
}


def rich_map() -> TraceMap:
    """Every attribute type, a missing float, string ids, a window, a map frame and a CRS."""
    return TraceMap.from_polylines(
        [
            [(500000.125, 4649776.25), (500003.5, 4649780.0)],
            [(0.1, 0.2), (0.30000000000000004, 1e-300), (-2.5e-7, 7.0)],
            [(1.0, 1.0), (1.0, 1.0)],
        ],
        {
            "id": ["F1", "F2", "F3"],
            "set": np.array([1, 2, 1], dtype=np.int64),
            "aperture_mm": np.array([0.5, np.nan, 1.0 / 3.0]),
            "open": np.array([True, False, True]),
            "note": np.array(["calcite, 'filled'", "", 'ü "quoted"'], dtype=str),
        },
        window=[(0.0, 0.0), (600000.0, 0.0), (600000.0, 5e6), (0.0, 5e6)],
        frame="utm33n",
        crs="EPSG:32633",
    )


def naive_segments(polylines) -> tuple[list, list]:
    """Rows x0, y0, x1, y1 of every straight piece, and the trace of each, by plain loops."""
    rows, owner = [], []
    for i, line in enumerate(polylines):
        for (x0, y0), (x1, y1) in zip(line[:-1], line[1:]):
            rows.append([x0, y0, x1, y1])
            owner.append(i)
    return rows, owner


def assert_same_map(a: TraceMap, b: TraceMap, *, window: bool = True) -> None:
    """Exact equality of coordinates, offsets, attributes (names, kinds, values), frame and CRS."""
    assert np.array_equal(a.xy_m, b.xy_m)
    assert np.array_equal(a.offsets, b.offsets)
    assert list(a.attributes) == list(b.attributes)
    for key in a.attributes:
        x, y = a.attributes[key], b.attributes[key]
        assert x.dtype.kind == y.dtype.kind, key
        assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), key
    if window:
        assert (a.window_xy_m is None) == (b.window_xy_m is None)
        if a.window_xy_m is not None:
            assert np.array_equal(a.window_xy_m, b.window_xy_m)
    assert a.frame == b.frame
    assert a.crs == b.crs
