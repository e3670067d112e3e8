"""Tiny trace networks for the GIS and fractopo interop tests, with node and branch counts worked out
by hand (tests/dfn/test_gis_io.py, tests/pipeline/test_traces_gpkg.py).

``hash_and_t``, in the 10 m square window (0, 0)-(10, 10)::

    y=9.5        |T                  traces: H1 y=3 and H2 y=7 (x 1..9), V1 x=3 and V2 x=7 (y 1..9),
    y=7   --+----+----+--            T x=5 from H2 (y=7) up to y=9.5, and C y=5 from x=8.5 out of
          V1|    |    |V2  C         the window to x=11 (the window's edge at x=10 censors it).
    y=5     |         |  --:--
    y=3   --+---------+--
              H1

Nodes: X = 4 (the corners of the "#"), Y = 1 (T's lower end on H2), I = 8 (ends of the "#") + 1
(T's upper end) + 1 (C's inner end) = 10, E = 1 (C at the window's edge).
Branches: H1, V1 and V2 are cut at two crossings: I-C, C-C, C-I each; H2 at two crossings and T's
abutment: I-C, C-C, C-C, C-I; T is one C-I branch; C one I-E branch (to the edge). So "C - C" = 3 +
2 = 5, "C - I" = 6 + 2 + 1 = 9, "I - E" = 1: 15 branches, 4 x 8 + 2.5 + 1.5 = 36 m long.
"""

from rockmass.dfn import TraceMap

SQUARE_10 = [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)]
HASH_AND_T_SEGMENTS = [[1, 3, 9, 3], [1, 7, 9, 7], [3, 1, 3, 9], [7, 1, 7, 9], [5, 7, 5, 9.5], [8.5, 5, 11, 5]]
HASH_AND_T_NODES = {"X": 4, "Y": 1, "I": 10, "E": 1}
HASH_AND_T_BRANCHES = {"C - C": 5, "C - I": 9, "C - E": 0, "I - I": 0, "I - E": 1, "E - E": 0}
HASH_AND_T_LENGTH_IN_WINDOW_M = 36.0


def hash_and_t(frame: str = "map", crs: str | None = "EPSG:3067") -> TraceMap:
    """The "#" of four traces plus a T and a censored trace (module docstring), with a set attribute."""
    return TraceMap.from_segments(HASH_AND_T_SEGMENTS, {"set": [0, 0, 1, 1, 1, 0], "name": list("HHVVTC")},
                                  window=SQUARE_10, frame=frame, crs=crs)
