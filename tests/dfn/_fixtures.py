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


# -- trace-map statistics: hand-drawn networks whose answers are counted by eye -------------------

SQUARE_10 = [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)]  # 10 m x 10 m window, area 100 m²


@dataclass(frozen=True)
class TopologyCase:
    """Straight traces (rows x0, y0, x1, y1), a window, a snap tolerance, and node counts by eye."""

    name: str
    segments: list
    counts: dict  # {"I": .., "Y": .., "X": .., "E": ..}
    connections: list  # per trace: X nodes on it + its Y ends + Y ends abutting it
    tolerance_m: float = 0.01
    window: list | None = None

    def build(self) -> TraceMap:
        return TraceMap.from_segments(self.segments, window=self.window)


TOPOLOGY_CASES = {
    case.name: case
    for case in [
        # two traces crossing at the origin: 4 tips, 1 crossing
        TopologyCase("x", [[-1, 0, 1, 0], [0, -1, 0, 1]], {"I": 4, "Y": 0, "X": 1, "E": 0}, [1, 1]),
        # a T: the stem (0, 0)-(0, 1) ends on the bar's interior
        TopologyCase("t", [[-1, 0, 1, 0], [0, 0, 0, 1]], {"I": 3, "Y": 1, "X": 0, "E": 0}, [1, 1]),
        # one isolated trace
        TopologyCase("isolated", [[0, 0, 2, 1]], {"I": 2, "Y": 0, "X": 0, "E": 0}, [0]),
        # a "+" of two crossing traces, and a third trace abutting the vertical arm from the right
        TopologyCase(
            "plus_with_abutting_arm",
            [[-1, 0, 1, 0], [0, -1, 0, 1], [0, 0.5, 2, 0.5]],
            {"I": 5, "Y": 1, "X": 1, "E": 0},
            [1, 2, 1],
        ),
        # a "+" drawn as a through bar and two half-stems that both end on it: two Y nodes, no X
        TopologyCase(
            "plus_of_two_abutting_halves",
            [[-1, 0, 1, 0], [0, 0, 0, 1], [0, -1, 0, 0]],
            {"I": 4, "Y": 2, "X": 0, "E": 0},
            [2, 1, 1],
        ),
        # in the 10 m square: a trace edge to edge (2 E), and one from inside (I at y = 2) to the top
        # edge (E) crossing it at (5, 5)
        TopologyCase(
            "edge_censored",
            [[0, 5, 10, 5], [5, 2, 5, 10]],
            {"I": 1, "Y": 0, "X": 1, "E": 3},
            [1, 1],
            window=SQUARE_10,
        ),
        # a stem stopping 0.05 m short of the bar: an I node at tolerance 0.01 ...
        TopologyCase("gap_below_tolerance", [[-1, 0, 1, 0], [0, 0.05, 0, 1]], {"I": 4, "Y": 0, "X": 0, "E": 0}, [0, 0]),
        # ... and a Y node at tolerance 0.1
        TopologyCase(
            "gap_within_tolerance", [[-1, 0, 1, 0], [0, 0.05, 0, 1]], {"I": 3, "Y": 1, "X": 0, "E": 0}, [1, 1], 0.1
        ),
        # a stem overshooting the bar by 0.05 m: a crossing at tolerance 0.01, an abutment at 0.1
        TopologyCase(
            "overshoot_below_tolerance", [[-1, 0, 1, 0], [0, -0.05, 0, 1]], {"I": 4, "Y": 0, "X": 1, "E": 0}, [1, 1]
        ),
        TopologyCase(
            "overshoot_within_tolerance",
            [[-1, 0, 1, 0], [0, -0.05, 0, 1]],
            {"I": 3, "Y": 1, "X": 0, "E": 0},
            [1, 1],
            0.1,
        ),
        # two collinear traces meeting end to end: four I nodes (two of them flagged as end contacts)
        TopologyCase("end_to_end", [[0, 0, 1, 0], [1, 0, 2, 0]], {"I": 4, "Y": 0, "X": 0, "E": 0}, [0, 0]),
    ]
}


def intensity_square() -> TraceMap:
    """Four traces in the 10 m square whose clipped lengths are 5, 6, 3 and 5 m (sum 19 m).

    Trace ends strictly inside: 2 + 2 + 2 + 1 = 7 (the last trace leaves through the right edge at
    (10, 5)). Arc-length midpoints (2.5, 3), (5, 8), (6, 2.5) and (10, 5): all in the closed window.
    """
    return TraceMap.from_segments(
        [[1, 1, 4, 5], [2, 8, 8, 8], [6, 1, 6, 4], [5, 5, 15, 5]],  # 3-4-5; 6 m; 3 m; 10 m, 5 m inside
        window=SQUARE_10,
    )


def poisson_segments(rng, *, intensity_per_m2, length_m, region_radius_m) -> np.ndarray:
    """Rows x0, y0, x1, y1 of a Poisson process of segments of one length, isotropic, centred on (0, 0).

    Centres are uniform in a disc of radius ``region_radius_m`` (their number is Poisson with mean
    intensity x area), so inside any window that stays ``length_m / 2`` away from the disc's edge the
    network is stationary with P20 = intensity_per_m2 and P21 = intensity_per_m2 * length_m.
    """
    count = rng.poisson(intensity_per_m2 * math.pi * region_radius_m**2)
    radius = region_radius_m * np.sqrt(rng.random(count))
    phi = rng.uniform(0.0, 2.0 * math.pi, count)
    theta = rng.uniform(0.0, math.pi, count)
    centre = np.column_stack([radius * np.cos(phi), radius * np.sin(phi)])
    half = 0.5 * length_m * np.column_stack([np.cos(theta), np.sin(theta)])
    return np.hstack([centre - half, centre + half])
