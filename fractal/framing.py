"""The square frame a trace network is counted in, and the conversion of traces into it.

Box counting needs a square: Jiang et al. (§4.1; docs/fractal.md §1) draw each network into a 360 x 360 cell
square. The frame is either the network's bounding square or a square built on a window given by the
user; a non-square window, and an optional face polygon, become a *face mask* so that boxes outside
the face are not counted (see :mod:`rockmass.fractal.boxcount`).

Segments are ``(n, 4) float64`` arrays of ``x0, y0, x1, y1`` in the map's units (metres).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Frame", "as_segments", "as_ring", "frame_for", "clip_segments_to_ring"]


@dataclass(frozen=True)
class Frame:
    """A square of side ``side_m`` with its lower-left corner at ``(x0_m, y0_m)``.

    The raster grid divides it into ``grid`` x ``grid`` pixels; pixel column ``i`` covers
    ``x0_m + [i, i+1) * side_m / grid`` and the grid's row 0 is the *top* of the square, as in an image.
    """

    x0_m: float
    y0_m: float
    side_m: float

    def to_units(self, segments_m: np.ndarray, units_per_side: float) -> np.ndarray:
        """Segments relative to the lower-left corner, scaled so the side is ``units_per_side``."""
        scale = units_per_side / self.side_m
        out = np.empty_like(segments_m)
        out[:, 0::2] = (segments_m[:, 0::2] - self.x0_m) * scale
        out[:, 1::2] = (segments_m[:, 1::2] - self.y0_m) * scale
        # points on the far edge may round a hair past it; the edge belongs to the last box anyway
        np.clip(out, 0.0, units_per_side, out=out)
        return out

    def square_ring(self) -> np.ndarray:
        """The frame's square as a ring ``(4, 2)`` in metres, counter-clockwise."""
        x0, y0, s = self.x0_m, self.y0_m, self.side_m
        return np.array([[x0, y0], [x0 + s, y0], [x0 + s, y0 + s], [x0, y0 + s]])

    def ring_to_units(self, ring_m: np.ndarray, units_per_side: float) -> np.ndarray:
        """A polygon ring relative to the lower-left corner in the same scaled units."""
        scale = units_per_side / self.side_m
        return np.ascontiguousarray(
            (ring_m - np.array([self.x0_m, self.y0_m])) * scale, dtype=np.float64)


def as_segments(data, name: str = "traces") -> np.ndarray:
    """Segments ``(n, 4) float64`` from an array or from any object with a ``segments()`` method.

    Zero-length segments are kept here (callers drop them and say so). Raises ``ValueError`` naming
    the first offending rows when coordinates are not finite.
    """
    if hasattr(data, "segments") and callable(data.segments):
        data = data.segments()
    seg = np.asarray(data, dtype=np.float64)
    if seg.ndim != 2 or seg.shape[1] != 4:
        raise ValueError(
            f"{name} must be segments of shape (n, 4) with columns x0, y0, x1, y1, got shape {seg.shape}")
    bad = np.flatnonzero(~np.isfinite(seg).all(axis=1))
    if bad.size:
        raise ValueError(
            f"{name}: {bad.size} segments have NaN or infinite coordinates: rows {bad[:10].tolist()}"
            + (" ..." if bad.size > 10 else ""))
    return np.ascontiguousarray(seg)


def _ring_area(ring) -> float:
    """Area of the polygon with the open ring ``(k, 2)`` (m² for a ring in metres).

    fractal imports no other rockmass stage, so it cannot call rockmass.dfn.polygon_area; shapely
    (already the clipping engine of this module) measures the ring instead of a second copy of the
    shoelace formula (docs/fractal.md §3).
    """
    import shapely

    return float(shapely.area(shapely.polygons(np.asarray(ring, dtype=np.float64))))


def as_ring(polygon, name: str = "mask") -> np.ndarray:
    """The exterior ring ``(k, 2) float64`` of a polygon given as coordinates or a shapely Polygon.

    A closing vertex equal to the first is dropped. Raises ``ValueError`` for fewer than 3 distinct
    vertices, non-finite coordinates or zero area.
    """
    if hasattr(polygon, "exterior"):
        if len(getattr(polygon, "interiors", ())) > 0:
            raise ValueError(f"{name}: polygons with holes are not supported (the hole would count "
                             "as face); give the outer ring and drop the traces inside the hole")
        polygon = np.asarray(polygon.exterior.coords)
    ring = np.asarray(polygon, dtype=np.float64)
    if ring.ndim != 2 or ring.shape[1] != 2:
        raise ValueError(f"{name} must be polygon vertices of shape (k, 2), got shape {ring.shape}")
    if not np.isfinite(ring).all():
        raise ValueError(f"{name}: polygon vertices must be finite")
    if ring.shape[0] > 1 and np.array_equal(ring[0], ring[-1]):
        ring = ring[:-1]
    if ring.shape[0] < 3:
        raise ValueError(f"{name}: a polygon needs at least 3 vertices, got {ring.shape[0]}")
    if not _ring_area(ring) > 0.0:
        raise ValueError(f"{name}: polygon has zero area")
    return np.ascontiguousarray(ring)


def frame_for(segments_m: np.ndarray, window=None) -> tuple[Frame, np.ndarray | None]:
    """The counting frame, and the window's ring when it must act as a face mask.

    Parameters
    ----------
    segments_m : (n, 4) float64
        The traces.
    window : (xmin, ymin, xmax, ymax) or None
        None frames the network's bounding square: side = the larger extent, centred on the
        network's bounding box (the spare room of the shorter axis split evenly, so no edge of the
        network is put on a grid line by construction; measured on a level-7 Koch curve: anchored
        at the lower-left D = 1.304, centred 1.274, exact 1.262). A window
        frames the square of side ``max(width, height)`` anchored at ``(xmin, ymin)``; a non-square
        window is returned as a ring so the part of the square outside it is masked.

    Returns
    -------
    frame : Frame
    window_ring : (4, 2) float64 or None
    """
    if window is None:
        xs = segments_m[:, 0::2]
        ys = segments_m[:, 1::2]
        xmin, xmax, ymin, ymax = xs.min(), xs.max(), ys.min(), ys.max()
        side = max(xmax - xmin, ymax - ymin)
        if not side > 0.0:
            raise ValueError("traces: all trace vertices coincide; the network has no extent to count")
        x0 = xmin - 0.5 * (side - (xmax - xmin))
        y0 = ymin - 0.5 * (side - (ymax - ymin))
        return Frame(float(x0), float(y0), float(side)), None
    w = np.asarray(window, dtype=np.float64).ravel()
    if w.size != 4 or not np.isfinite(w).all() or not (w[2] > w[0] and w[3] > w[1]):
        raise ValueError(f"window must be (xmin, ymin, xmax, ymax) with xmax > xmin and ymax > ymin, "
                         f"got {np.asarray(window).tolist()}")
    width, height = w[2] - w[0], w[3] - w[1]
    frame = Frame(float(w[0]), float(w[1]), float(max(width, height)))
    if width == height:
        return frame, None
    ring = np.array([[w[0], w[1]], [w[2], w[1]], [w[2], w[3]], [w[0], w[3]]])
    return frame, ring


def clip_segments_to_ring(segments_m: np.ndarray, ring_m: np.ndarray) -> np.ndarray:
    """The parts of the segments inside the polygon ``ring_m`` (shapely intersection).

    Returns ``(m, 4) float64`` segments; pieces that touch the polygon in a point are dropped.
    """
    import shapely

    if segments_m.shape[0] == 0:
        return segments_m
    polygon = shapely.Polygon(ring_m)
    if not polygon.is_valid:
        polygon = shapely.make_valid(polygon)
    lines = shapely.linestrings(segments_m.reshape(-1, 2, 2))
    clipped = shapely.intersection(lines, polygon)
    parts = shapely.get_parts(clipped)
    parts = parts[shapely.get_type_id(parts) == 1]  # LineString pieces only (points are touches)
    if parts.size == 0:
        return np.empty((0, 4))
    coords, index = shapely.get_coordinates(parts, return_index=True)
    same = index[1:] == index[:-1]
    return np.ascontiguousarray(np.hstack([coords[:-1][same], coords[1:][same]]))
