"""Trace maps: joint traces as polylines in metres, per-trace attributes and a sampling window.

This module owns :class:`TraceMap`, the one data model that every trace source produces (digitised
GIS or CSV files, photo extraction in :mod:`rockmass.imaging`, virtual sampling of a DFN by a plane)
and every trace consumer reads (box counting, intensity statistics, block generation). Reading and
writing files lives in :mod:`rockmass.dfn.traceio`.

Array layout
------------
The traces are one structure of arrays in the ragged ("GeoArrow") layout that
:func:`shapely.from_ragged_array` reads in a single call::

    xy_m        (n_vertices, 2) float64   vertex coordinates (x, y) in metres, in the frame `frame`
    offsets     (n_traces + 1,) int64     trace i is xy_m[offsets[i]:offsets[i + 1]]
    attributes  {name: (n_traces,) array} per-trace columns; always holds "id"
    window_xy_m (k, 2) float64 or None    open exterior ring of the sampling window polygon

For a face photograph the frame is u to the right, v up, origin at the image's bottom-left
(docs/fractures.md §1.2, docs/imaging.md §1); for a GIS file it is easting / northing in the file's CRS.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np
import shapely

from .polygon import signed_area

__all__ = ["TraceMap"]

#: Longest list of offending items quoted in an error message.
_MAX_LISTED = 10

#: Largest magnitude of a coordinate, metres (10⁹ km: no face or projected map comes near it). A
#: value beyond it is a typo or a unit slip, never a position, and the products of coordinate
#: differences the statistics and the block cutter form (squared lengths, areas) would overflow.
MAX_COORDINATE_M = 1e12


def _beyond_range(xy: np.ndarray) -> np.ndarray:
    """(n,) bool: vertices of ``xy`` (n, 2) with a coordinate beyond ±:data:`MAX_COORDINATE_M`."""
    return (np.abs(xy) > MAX_COORDINATE_M).any(axis=1)


def _plural(count: int, noun: str, verb: str | None = None) -> str:
    """``"1 trace has"`` / ``"3 traces have"``."""
    text = f"{count} {noun if count == 1 else noun + 's'}"
    if verb == "has":
        text += " has" if count == 1 else " have"
    return text


def _describe_traces(indices: Any, ids: np.ndarray) -> str:
    """Name traces in an error message by id, adding their indices when those differ."""
    indices = np.asarray(indices, dtype=np.int64)
    shown = indices[:_MAX_LISTED]
    more = f" and {indices.size - shown.size} more" if indices.size > shown.size else ""
    text = f"ids {ids[shown].tolist()}{more}"
    if not (ids.dtype.kind == "i" and np.array_equal(ids[shown], shown)):
        text += f" (indices {shown.tolist()})"
    return text


def _require_trace_map(value: Any, name: str = "trace_map") -> None:
    """Raise TypeError unless ``value`` is a :class:`TraceMap`."""
    if not isinstance(value, TraceMap):
        raise TypeError(f"{name} must be a rockmass.dfn.TraceMap, got {type(value).__name__}")


def _resolve_frame(file_frame: str | None, frame: str | None, name: str, default: str = "face") -> str:
    """The frame a reader gives its map: the file's, else the ``frame`` argument, else ``default``
    (``"face"``; ``"map"`` for a file with a GIS CRS, :func:`rockmass.dfn.frames.default_frame`).

    A file naming another frame than the one asked for is an error (naming the file ``name``), not a
    silent relabelling.
    """
    if frame is not None and file_frame is not None and frame != file_frame:
        raise ValueError(f"{name}: frame: the file's frame is {file_frame!r} but frame={frame!r} was asked for")
    return file_frame or frame or default


def _as_xy(value: Any, name: str) -> np.ndarray:
    """Copy ``value`` to a C-contiguous (n, 2) float64 array; an empty input gives (0, 2)."""
    try:
        array = np.asarray(value)
    except ValueError as exc:  # ragged nested lists
        raise ValueError(f"{name} must be an (n, 2) array of coordinates: {exc}") from exc
    if array.size == 0 and array.ndim <= 2 and array.shape[0] == 0:
        return np.zeros((0, 2), dtype=np.float64)
    if array.dtype.kind not in "iuf":
        raise TypeError(f"{name} must hold real numbers (coordinates in metres), got dtype {array.dtype}")
    if array.ndim != 2 or array.shape[1] != 2:
        raise ValueError(f"{name} must have shape (n, 2) (columns x, y), got shape {array.shape}")
    return np.array(array, dtype=np.float64, order="C", copy=True)


def _as_offsets(value: Any, n_vertices: int) -> np.ndarray:
    array = np.asarray(value)
    if array.ndim != 1 or array.size == 0:
        raise ValueError(
            f"offsets must be a 1-D array of n_traces + 1 vertex offsets starting at 0, got shape {array.shape}"
        )
    if array.dtype.kind not in "iu":
        raise TypeError(f"offsets must hold integers (vertex indices), got dtype {array.dtype}")
    offsets = np.array(array, dtype=np.int64, copy=True)
    if offsets[0] != 0:
        raise ValueError(f"offsets[0] must be 0, got {offsets[0]}")
    if offsets[-1] != n_vertices:
        raise ValueError(f"offsets[-1] must equal the number of vertices in xy_m ({n_vertices}), got {offsets[-1]}")
    falling = np.flatnonzero(np.diff(offsets) < 0)
    if falling.size:
        raise ValueError(
            f"offsets must be non-decreasing; they decrease after positions {falling[:_MAX_LISTED].tolist()}"
        )
    return offsets


def _as_column(name: Any, values: Any, n_traces: int) -> np.ndarray:
    """Copy one attribute column, checking its name, length and dtype (numeric or str)."""
    if not isinstance(name, str) or not name:
        raise TypeError(f"attribute names must be non-empty strings, got {name!r}")
    array = np.asarray(values)
    if array.ndim != 1:
        raise ValueError(f"attributes[{name!r}] must be 1-D (one value per trace), got shape {array.shape}")
    if array.shape[0] != n_traces:
        raise ValueError(f"attributes[{name!r}] has {array.shape[0]} values, expected {n_traces} (one per trace)")
    kind = array.dtype.kind
    if kind in "biufU":
        return array.copy()
    if kind == "T":  # numpy.dtypes.StringDType
        return array.astype(str)
    if kind == "O":
        odd = [i for i, item in enumerate(array.tolist()) if not isinstance(item, str)]
        if odd:
            raise TypeError(
                f"attributes[{name!r}] is an object array with non-string values at indices "
                f"{odd[:_MAX_LISTED]}; give a numeric or str column (missing values: NaN or '')"
            )
        return array.astype(str)
    raise TypeError(f"attributes[{name!r}] must be numeric (bool, int, float) or str, got dtype {array.dtype}")


def _as_attributes(attributes: Any, n_traces: int) -> dict[str, np.ndarray]:
    if attributes is None:
        attributes = {}
    if not isinstance(attributes, Mapping):
        raise TypeError(
            f"attributes must be a mapping of column name to per-trace array, got {type(attributes).__name__}"
        )
    columns = {name: _as_column(name, values, n_traces) for name, values in attributes.items()}
    ids = columns.pop("id", None)
    if ids is None:
        ids = np.arange(n_traces, dtype=np.int64)
    elif ids.dtype.kind in "iu":
        if ids.dtype.kind == "u" and ids.size and ids.max() > np.iinfo(np.int64).max:
            raise ValueError("attributes['id'] has values beyond the int64 range")
        ids = ids.astype(np.int64)
    elif ids.dtype.kind != "U":
        raise TypeError(f"attributes['id'] must hold integers or strings (trace identifiers), got dtype {ids.dtype}")
    return {"id": ids, **columns}


def _as_window(window: Any) -> np.ndarray | None:
    """Open exterior ring (k >= 3) of the sampling window, from an array or a shapely Polygon."""
    if window is None:
        return None
    if isinstance(window, shapely.Polygon):
        if len(window.interiors):
            raise ValueError(f"window polygon has {len(window.interiors)} holes; holes are not supported")
        window = shapely.get_coordinates(window.exterior)
    ring = _as_xy(window, "window_xy_m")
    if ring.shape[0] >= 2 and np.array_equal(ring[0], ring[-1]):
        ring = ring[:-1]  # store the ring open: the closing vertex is implied
    if ring.shape[0] < 3:
        raise ValueError(f"window_xy_m needs at least 3 distinct ring vertices, got {ring.shape[0]}")
    bad = np.flatnonzero(~np.isfinite(ring).all(axis=1))
    if bad.size:
        raise ValueError(f"window_xy_m has non-finite coordinates at vertices {bad[:_MAX_LISTED].tolist()}")
    far = np.flatnonzero(_beyond_range(ring))
    if far.size:
        raise ValueError(f"window_xy_m has coordinates beyond ±{MAX_COORDINATE_M:.0e} m at vertices "
                         f"{far[:_MAX_LISTED].tolist()}")
    if signed_area(ring) == 0.0:
        raise ValueError("window_xy_m encloses zero area; give the exterior ring of the sampling window")
    return ring


def _read_only(array: np.ndarray) -> np.ndarray:
    array.setflags(write=False)
    return array


@dataclass(frozen=True, eq=False, repr=False)
class TraceMap:
    """Joint traces as polylines in metres, with per-trace attributes and a sampling window.

    Parameters
    ----------
    xy_m : (n_vertices, 2) array_like of float
        Vertex coordinates (x, y) in metres in the frame ``frame``; stored as float64.
    offsets : (n_traces + 1,) array_like of int
        Trace ``i`` has vertices ``xy_m[offsets[i]:offsets[i + 1]]``; ``offsets[0] == 0``,
        non-decreasing, ``offsets[-1] == n_vertices``; every trace has at least 2 vertices.
    attributes : mapping of str to (n_traces,) array_like, optional
        Per-trace columns, numeric (bool, int, float; NaN marks a missing float) or str ('' marks a
        missing string). The ``id`` column (int64 or str) is created as ``0..n_traces-1`` when
        absent and always comes first. Ids name traces in messages; they need not be unique (the
        parts of a split MultiLineString share their feature's id).
    window_xy_m : (k, 2) array_like of float or shapely.Polygon, optional
        Exterior ring of the sampling window polygon, k >= 3, finite, non-zero area; a closed ring
        (last vertex equal to the first) is stored open. Holes are not supported. Default None.
    frame : str, default "face"
        Name of the coordinate frame (u right / v up on a face, or a map frame).
    crs : str, optional
        Coordinate reference system of a map frame (e.g. ``"EPSG:32633"``), carried through GeoJSON.

    Raises
    ------
    ValueError
        Inconsistent offsets, a column of the wrong length, a trace with fewer than 2 vertices or a
        coordinate that is not finite or beyond ±:data:`MAX_COORDINATE_M` (the message names the
        traces by id), or a bad window.
    TypeError
        Non-numeric coordinates or offsets, or an attribute column of an unsupported dtype.

    Notes
    -----
    Validation runs once, here. Every array is copied and made read-only and ``attributes`` is a
    read-only mapping, so the caller's inputs are never modified and the map is immutable; derive
    new maps with :meth:`subset`, :meth:`with_window` or :func:`dataclasses.replace`.
    Zero-length traces (all vertices identical) are kept and reported by :meth:`degenerate_traces`;
    an empty map (0 traces) is a valid object, and callers decide whether it is an error.

    Examples
    --------
    >>> tm = TraceMap.from_polylines([[(0, 0), (3, 4)], [(0, 0), (1, 0), (1, 1), (0, 1), (0, 0)]])
    >>> tm.n_traces, tm.n_segments
    (2, 5)
    >>> tm.lengths_m()
    array([5., 4.])
    >>> tm.offsets
    array([0, 2, 7])
    """

    xy_m: np.ndarray
    offsets: np.ndarray
    attributes: Mapping[str, np.ndarray] = field(default_factory=dict)
    window_xy_m: np.ndarray | None = None
    frame: str = "face"
    crs: str | None = None

    def __post_init__(self) -> None:
        xy = _as_xy(self.xy_m, "xy_m")
        offsets = _as_offsets(self.offsets, xy.shape[0])
        n_traces = offsets.size - 1
        columns = _as_attributes(self.attributes, n_traces)
        ids = columns["id"]
        short = np.flatnonzero(np.diff(offsets) < 2)
        if short.size:
            raise ValueError(
                f"{_plural(short.size, 'trace', 'has')} fewer than 2 vertices: {_describe_traces(short, ids)}"
            )
        for bad_vertex, what in ((~np.isfinite(xy).all(axis=1), "non-finite coordinates"),
                                 (_beyond_range(xy), f"coordinates beyond ±{MAX_COORDINATE_M:.0e} m")):
            if bad_vertex.any():
                bad = np.unique(np.searchsorted(offsets, np.flatnonzero(bad_vertex), side="right") - 1)
                raise ValueError(f"{_plural(bad.size, 'trace', 'has')} {what}: {_describe_traces(bad, ids)}")
        window = _as_window(self.window_xy_m)
        if not isinstance(self.frame, str) or not self.frame.strip():
            raise TypeError(f"frame must be a non-empty string naming the coordinate frame, got {self.frame!r}")
        if self.crs is not None and (not isinstance(self.crs, str) or not self.crs.strip()):
            raise TypeError(f"crs must be None or a non-empty string such as 'EPSG:32633', got {self.crs!r}")
        object.__setattr__(self, "xy_m", _read_only(xy))
        object.__setattr__(self, "offsets", _read_only(offsets))
        object.__setattr__(
            self, "attributes", MappingProxyType({k: _read_only(v) for k, v in columns.items()})
        )
        object.__setattr__(self, "window_xy_m", None if window is None else _read_only(window))

    # -- construction -------------------------------------------------------------------------

    @classmethod
    def from_polylines(
        cls,
        polylines: Iterable[Any],
        attributes: Mapping[str, Any] | None = None,
        *,
        window: Any = None,
        frame: str = "face",
        crs: str | None = None,
    ) -> TraceMap:
        """Build a map from a sequence of (k, 2) vertex arrays, one per trace.

        Parameters
        ----------
        polylines : iterable of (k, 2) array_like of float
            Vertices (x, y) in metres of each trace, k >= 2.
        attributes, window, frame, crs
            As in :class:`TraceMap`.

        Returns
        -------
        TraceMap

        Examples
        --------
        >>> TraceMap.from_polylines([[(0, 0), (1, 0)]], {"set": [2]}).attributes["set"]
        array([2])
        """
        arrays = [_as_xy(line, f"polylines[{i}]") for i, line in enumerate(polylines)]
        counts = np.array([a.shape[0] for a in arrays], dtype=np.int64)
        xy = np.concatenate(arrays) if arrays else np.zeros((0, 2))
        offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        return cls(xy, offsets, attributes, window, frame, crs)

    @classmethod
    def from_segments(
        cls,
        segments: Any,
        attributes: Mapping[str, Any] | None = None,
        *,
        window: Any = None,
        frame: str = "face",
        crs: str | None = None,
    ) -> TraceMap:
        """Build a map of straight traces from an (n, 4) array of rows ``x0, y0, x1, y1``.

        Parameters
        ----------
        segments : (n, 4) array_like of float
            One straight trace per row, end points (x0, y0) and (x1, y1) in metres.
        attributes, window, frame, crs
            As in :class:`TraceMap`.

        Returns
        -------
        TraceMap
            n traces of 2 vertices each, ``offsets = [0, 2, 4, ..., 2n]``.

        Examples
        --------
        >>> TraceMap.from_segments([[0, 0, 3, 4], [1, 1, 1, 2]]).lengths_m()
        array([5., 1.])
        """
        array = np.asarray(segments)
        if array.size == 0 and array.ndim in (1, 2) and array.shape[0] == 0:
            array = np.zeros((0, 4))
        if array.dtype.kind not in "iuf":
            raise TypeError(f"segments must hold real numbers (coordinates in metres), got dtype {array.dtype}")
        if array.ndim != 2 or array.shape[1] != 4:
            raise ValueError(f"segments must have shape (n, 4) (columns x0, y0, x1, y1), got shape {array.shape}")
        n = array.shape[0]
        return cls(array.reshape(2 * n, 2), np.arange(0, 2 * n + 1, 2), attributes, window, frame, crs)

    @classmethod
    def from_shapely(
        cls,
        geometries: Any,
        attributes: Mapping[str, Any] | None = None,
        *,
        window: Any = None,
        frame: str = "face",
        crs: str | None = None,
    ) -> TraceMap:
        """Build a map from an array of shapely LineStrings (z coordinates are dropped).

        Parameters
        ----------
        geometries : array_like of shapely.LineString
            One LineString per trace (a single geometry counts as one trace).
        attributes, window, frame, crs
            As in :class:`TraceMap`; ``window`` may be a shapely Polygon.

        Returns
        -------
        TraceMap

        Raises
        ------
        ValueError
            If any geometry is not a LineString (the message lists their indices and types).
        """
        geoms = np.asarray(geometries, dtype=object).reshape(-1)
        type_ids = shapely.get_type_id(geoms)
        odd = np.flatnonzero(type_ids != shapely.GeometryType.LINESTRING)
        if odd.size:
            kinds = [type(g).__name__ for g in geoms[odd[:_MAX_LISTED]]]
            raise ValueError(
                f"geometries must all be LineStrings; {odd.size} are not: "
                f"indices {odd[:_MAX_LISTED].tolist()} are {kinds}"
            )
        if geoms.size == 0:
            return cls(np.zeros((0, 2)), np.zeros(1, dtype=np.int64), attributes, window, frame, crs)
        _, coords, (offsets,) = shapely.to_ragged_array(geoms, include_z=False)
        return cls(coords, offsets, attributes, window, frame, crs)

    # -- sizes and access ---------------------------------------------------------------------

    @property
    def n_traces(self) -> int:
        """Number of traces."""
        return int(self.offsets.size - 1)

    @property
    def n_vertices(self) -> int:
        """Number of vertices over all traces."""
        return int(self.xy_m.shape[0])

    @property
    def n_segments(self) -> int:
        """Number of straight pieces, ``n_vertices - n_traces``."""
        return self.n_vertices - self.n_traces

    def polyline(self, i: int) -> np.ndarray:
        """Vertices of trace ``i`` as a read-only (k, 2) float64 view (negative ``i`` counts from the end)."""
        n = self.n_traces
        if not -n <= i < n:
            raise IndexError(f"trace index {i} is out of range for a map of {n} traces")
        i %= n
        return self.xy_m[self.offsets[i] : self.offsets[i + 1]]

    # -- geometry -----------------------------------------------------------------------------

    def segments(self) -> np.ndarray:
        """Every straight piece of every trace as rows ``x0, y0, x1, y1``.

        Returns
        -------
        (n_segments, 4) ndarray of float64
            Pieces in trace order, then vertex order; row j belongs to trace
            ``segment_trace_index()[j]``.
        """
        is_start = np.ones(self.n_vertices, dtype=bool)
        is_start[self.offsets[1:] - 1] = False  # the last vertex of a trace starts no piece
        start = np.flatnonzero(is_start)
        return np.hstack([self.xy_m[start], self.xy_m[start + 1]])

    def segment_trace_index(self) -> np.ndarray:
        """(n_segments,) int64: the trace each row of :meth:`segments` belongs to."""
        return np.repeat(np.arange(self.n_traces, dtype=np.int64), np.diff(self.offsets) - 1)

    def lengths_m(self) -> np.ndarray:
        r"""Length of each trace in metres.

        Returns
        -------
        (n_traces,) ndarray of float64
            :math:`L_i = \sum_j \sqrt{(x_{j+1} - x_j)^2 + (y_{j+1} - y_j)^2}` over the pieces of trace i.
        """
        seg = self.segments()
        piece = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
        return np.bincount(self.segment_trace_index(), weights=piece, minlength=self.n_traces)

    def total_length_m(self) -> float:
        """Sum of all trace lengths in metres (0.0 for an empty map)."""
        return float(self.lengths_m().sum())

    def degenerate_traces(self) -> np.ndarray:
        """(n_traces,) bool mask of zero-length traces (all vertices identical, compared exactly).

        Such traces are kept (a digitising slip is the user's to fix, not ours to hide); they have
        no orientation, so statistics that need one should exclude them with this mask.
        """
        seg = self.segments()
        moves = (seg[:, 0] != seg[:, 2]) | (seg[:, 1] != seg[:, 3])
        return np.bincount(self.segment_trace_index(), weights=moves, minlength=self.n_traces) == 0

    def bounds(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` of the trace vertices in metres (the window is not included).

        Raises
        ------
        ValueError
            For an empty map, whose bounds are undefined.
        """
        if self.n_traces == 0:
            raise ValueError("bounds of an empty TraceMap (0 traces) are undefined")
        lo, hi = self.xy_m.min(axis=0), self.xy_m.max(axis=0)
        return (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))

    def to_shapely(self) -> np.ndarray:
        """(n_traces,) object array of shapely LineStrings, built in one call (from_ragged_array)."""
        return shapely.from_ragged_array(shapely.GeometryType.LINESTRING, self.xy_m, (self.offsets,))

    def window_polygon(self) -> shapely.Polygon | None:
        """The sampling window as a shapely Polygon, or None when the map has no window."""
        return None if self.window_xy_m is None else shapely.Polygon(self.window_xy_m)

    # -- derived maps -------------------------------------------------------------------------

    def subset(self, selection: Any) -> TraceMap:
        """A new map with the selected traces (and their attributes), in selection order.

        Parameters
        ----------
        selection : (n_traces,) bool array_like, or array_like of int
            A mask with one value per trace, or trace indices (negative ones count from the end).

        Examples
        --------
        >>> tm = TraceMap.from_segments([[0, 0, 1, 0], [0, 0, 2, 0], [0, 0, 3, 0]])
        >>> tm.subset([2, 0]).lengths_m()
        array([3., 1.])
        """
        n = self.n_traces
        sel = np.asarray(selection)
        if sel.dtype == bool:
            if sel.shape != (n,):
                raise ValueError(f"a boolean selection needs one value per trace ({n}), got shape {sel.shape}")
            index = np.flatnonzero(sel)
        elif sel.size == 0:
            index = np.zeros(0, dtype=np.int64)
        elif sel.dtype.kind in "iu" and sel.ndim <= 1:
            index = sel.astype(np.int64).reshape(-1)
            outside = index[(index < -n) | (index >= n)]
            if outside.size:
                raise IndexError(f"trace indices {outside[:_MAX_LISTED].tolist()} are out of range for {n} traces")
            index = np.where(index < 0, index + n, index)
        else:
            raise TypeError(f"selection must be a bool mask or 1-D integer indices, got dtype {sel.dtype}")
        counts = np.diff(self.offsets)[index]
        offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        vertex = np.repeat(self.offsets[index] - offsets[:-1], counts) + np.arange(offsets[-1])
        columns = {name: column[index] for name, column in self.attributes.items()}
        return type(self)(self.xy_m[vertex], offsets, columns, self.window_xy_m, self.frame, self.crs)

    def with_window(self, window: Any) -> TraceMap:
        """A copy with another sampling window ((k, 2) ring, shapely Polygon, or None to remove it)."""
        return dataclasses.replace(self, window_xy_m=window)

    # -- plumbing -----------------------------------------------------------------------------

    def __reduce__(self):
        # the read-only attribute mapping cannot be pickled; rebuild (and revalidate) instead
        return (
            type(self),
            (self.xy_m, self.offsets, dict(self.attributes), self.window_xy_m, self.frame, self.crs),
        )

    def __repr__(self) -> str:
        window = "None" if self.window_xy_m is None else f"<{self.window_xy_m.shape[0]} vertices>"
        return (
            f"TraceMap(n_traces={self.n_traces}, n_vertices={self.n_vertices}, frame={self.frame!r}, "
            f"crs={self.crs!r}, attributes={list(self.attributes)}, window={window})"
        )
