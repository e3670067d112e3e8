"""Box-counting fractal dimension of trace networks and binary images.

Two methods, one result type:

- ``method="raster"`` (Jiang et al. §4.1; docs/fractal.md §1, §2.1): the traces are drawn into an N x N grid
  (default 360) with 1-pixel lines (:mod:`rockmass.fractal.rasterize`), and occupied boxes are
  counted for box sizes that divide N (all 24 divisors for 360, so no box is partial). A binary
  image is counted on its own pixel grid.
- ``method="vector"``: for each box size the boxes the segments themselves cross are counted (grid
  traversal per segment), at any box size: no line width and no rasterisation error.

D is the slope of log N(delta) against log(1/delta) over the fit range (default: boxes up to a
quarter of the side), reported with R^2, the standard error and 95 % interval of the slope, the local
slopes, and the spread of D over shifted box grids (docs/fractal.md §2.3: report the spread; never take the
minimum over offsets, which inflates D when large boxes are few). Shifted grids are applied
cyclically — the frame is treated as a torus, the partial boxes at one edge joining those at the
other — so every grid has the same (N/s)^2 whole boxes. A plain shift would add a ring of partial
boxes that inflates the counts at large sizes and biases every shifted D low (measured on the
bundled sample: zero offset 1.545, plain shifts 1.447-1.545, cyclic shifts spread on both sides).

Framing and face masks — one rule for traces and images
--------------------------------------------------------
Without a face (no window, no mask) the count runs over the counting square as it is, as Jiang et
al. drew their networks into a square: the traces' bounding square (centred on them), or the image
padded to a square. The empty part of that square (the spare room of a non-square network, an
image's padding) is counted as empty, and the result says how large it was.

With a face — a mask polygon, a trace map's sampling window, a non-square ``window``, or a face mask
image — only boxes that meet the face count, and the count of occupied boxes is rescaled to the
whole square, ``N = N_occupied * N_all / N_face``. A face completely covered by traces then has
D = 2 whatever its outline, and empty corners outside an irregular face do not flatten the curve.
The rescaling assumes the network is spread evenly over its face, as a joint network is; it biases
sets that are not (measured: a level-7 Koch curve in its bounding rectangle 1.387 instead of 1.274
in its square; a straight line across a 10 x 3 window 1.072), so give a face only where the traces
were sampled over that face.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .fit import LineFit, fit_loglog, fit_range_mask, local_slopes, loglog_slopes
from .framing import Frame, as_ring, as_segments, clip_segments_to_ring, frame_for, _ring_area
from .image import _pack_rows, divisors, prepare_binary_image
from .rasterize import (check_grid, check_line_rule, rasterize_polygon,
                        rasterize_segments_in_frame)

__all__ = ["BoxCount", "box_count", "grid_offsets", "METHODS"]

METHODS = ("raster", "vector")
KINDS = ("auto", "traces", "image")
_MAX_VECTOR_CELLS = 200_000_000  # box visits one vector count may make (about 1.6 GB of box ids)
_MAX_MARK_CELLS = 1 << 24  # vector counting uses a mark array up to 16 M boxes, then sort + unique
_PLASTIC = 1.324717957244746  # root of x^3 = x + 1; its R2 sequence spreads points evenly


def grid_offsets(n_offsets: int) -> np.ndarray:
    """Shifts of the box grid as fractions of a box, ``(n_offsets, 2) float64`` in [0, 1).

    The first is (0, 0); the rest follow the R2 low-discrepancy sequence (Roberts 2018,
    alpha = (1/g, 1/g^2), g the plastic number), so any count spreads evenly over the box.

    Examples
    --------
    >>> grid_offsets(3).round(3).tolist()
    [[0.0, 0.0], [0.755, 0.57], [0.51, 0.14]]
    """
    if isinstance(n_offsets, bool) or not isinstance(n_offsets, (int, np.integer)) or n_offsets < 1:
        raise ValueError(f"n_offsets must be an integer >= 1, got {n_offsets!r}")
    alpha = np.array([1.0 / _PLASTIC, 1.0 / _PLASTIC**2])
    k = np.arange(n_offsets, dtype=np.float64)[:, None]
    return np.mod(k * alpha, 1.0)


@dataclass(frozen=True)
class BoxCount:
    """The result of a box count and its dimension fit.

    Sizes are in grid pixels (``sizes_px``; for the vector method, pixels of an N x N grid on the
    same frame) and, for traces, in metres (``sizes_m``). Counts are at zero grid offset.

    Attributes
    ----------
    dimension : float
        Box-counting dimension D (slope over the fit range).
    r2, stderr, ci95, intercept
        Fit statistics (see :class:`rockmass.fractal.fit.LineFit`).
    method : str
        "raster" or "vector".
    grid : int
        Side N of the grid in pixels.
    sizes_px, sizes_m : (n,) float64
        Box sizes; ``sizes_m`` is None for images.
    counts : (n,) int64
        Occupied (raster) or crossed (vector) boxes.
    fit_counts : (n,) float64
        The counts that were fitted: ``counts``, or with a face mask ``counts * n_all / face_counts``.
    face_counts : (n,) int64 or None
        Boxes that meet the face, when there is a mask.
    in_fit : (n,) bool
        Which sizes the fit used; ``fit_range_px`` gives the range.
    local_slopes : (n - 1,) float64
        -d log N / d log delta between consecutive sizes (of ``fit_counts``).
    offset_dimensions : (n_offsets,) float64
        D fitted on each shifted grid (the first is zero offset).
    line_rule : str or None
        Rasterisation rule (raster method on traces).
    skeletonized : bool
        Whether an input image was thinned to 1-pixel lines first.
    frame : dict or None
        ``x0_m``, ``y0_m``, ``side_m`` of the counting square, for traces.
    p21_per_m, area_m2 : float or None
        Trace length per area over the face (or the traces' bounding rectangle) and that area:
        D mostly tracks density on real maps, so the two are reported together.
    notes : tuple of str
        Everything done to the input (clipping, thinning, padding, dropped segments).
    """

    dimension: float
    intercept: float
    r2: float
    stderr: float
    ci95: tuple[float, float]
    method: str
    grid: int
    sizes_px: np.ndarray
    sizes_m: np.ndarray | None
    counts: np.ndarray
    fit_counts: np.ndarray
    face_counts: np.ndarray | None
    in_fit: np.ndarray
    fit_range_px: tuple[float, float]
    local_slopes: np.ndarray
    offset_dimensions: np.ndarray
    line_rule: str | None = None
    skeletonized: bool = False
    frame: dict | None = None
    p21_per_m: float | None = None
    area_m2: float | None = None
    notes: tuple[str, ...] = field(default_factory=tuple)

    @property
    def sizes(self) -> np.ndarray:
        """Box sizes in grid pixels (same as ``sizes_px``)."""
        return self.sizes_px

    @property
    def fit_range(self) -> tuple[float, float]:
        """Smallest and largest box size (grid pixels) in the fit (same as ``fit_range_px``)."""
        return self.fit_range_px

    @property
    def offset_spread(self) -> float:
        """Standard deviation of D over the shifted grids (0 with a single offset)."""
        d = self.offset_dimensions
        return float(d.std(ddof=1)) if d.size > 1 else 0.0

    @property
    def offset_mean(self) -> float:
        """Mean D over the shifted grids: less sensitive to where the network sits on the grid."""
        return float(self.offset_dimensions.mean())

    @property
    def offset_range(self) -> tuple[float, float]:
        """Smallest and largest D over the shifted grids."""
        return float(self.offset_dimensions.min()), float(self.offset_dimensions.max())

    def to_dict(self) -> dict:
        """Plain JSON-ready dict (lists and floats; no NaN is ever produced)."""
        def arr(a):
            return None if a is None else np.asarray(a).tolist()

        return {
            "dimension": self.dimension,
            "ci95": list(self.ci95),
            "stderr": self.stderr,
            "r2": self.r2,
            "intercept": self.intercept,
            "n_fit": int(self.in_fit.sum()),
            "fit_range_px": list(self.fit_range_px),
            "offsets": {
                "n": int(self.offset_dimensions.size),
                "dimensions": arr(self.offset_dimensions),
                "mean": self.offset_mean,
                "std": self.offset_spread,
                "min": self.offset_range[0],
                "max": self.offset_range[1],
            },
            "method": self.method,
            "grid": self.grid,
            "line_rule": self.line_rule,
            "skeletonized": self.skeletonized,
            "sizes_px": arr(self.sizes_px),
            "sizes_m": arr(self.sizes_m),
            "counts": arr(self.counts),
            "fit_counts": arr(self.fit_counts),
            "face_counts": arr(self.face_counts),
            "in_fit": arr(self.in_fit),
            "local_slopes": arr(self.local_slopes),
            "frame": self.frame,
            "p21_per_m": self.p21_per_m,
            "area_m2": self.area_m2,
            "notes": list(self.notes),
        }


def _check_choice(value, choices, name):
    if value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(choices)}, got {value!r}")
    return value


def _given_sizes(sizes_px) -> np.ndarray:
    """Sorted distinct box sizes; raises naming ``sizes_px`` unless finite, > 0 and not empty."""
    s = np.unique(np.asarray(sizes_px, dtype=np.float64).ravel())
    if s.size == 0 or not np.all(np.isfinite(s)) or np.any(s <= 0):
        raise ValueError(f"sizes_px must be a non-empty list of finite box sizes > 0 (pixels), "
                         f"got {np.asarray(sizes_px).tolist()}")
    return s


def _raster_sizes(sizes_px, grid: int) -> np.ndarray:
    if sizes_px is None:
        return divisors(grid)
    s = _given_sizes(sizes_px)
    bad = s[(s != np.round(s)) | (s < 1) | (grid % np.maximum(np.round(s), 1) != 0)]
    if bad.size:
        raise ValueError(f"sizes_px for the raster method must divide the grid ({grid}); "
                         f"these do not: {bad.tolist()} (divisors: {divisors(grid).tolist()})")
    return s.astype(np.int64)


def _vector_sizes(sizes_px, grid: int) -> np.ndarray:
    if sizes_px is None:
        return divisors(grid).astype(np.float64)
    return _given_sizes(sizes_px)


def _raster_shifts(sizes: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Whole-pixel grid shifts ``(n_sizes, n_offsets, 2)`` for images: floor(fraction x size).

    An image's box grid can only move by whole pixels, so a shift is the intended fraction of a box
    only to within one pixel: a 1-px box cannot move, a 2-px box by 0 or 1. The shifted grids are
    then not similar across sizes, and the spread over-states the placement error of straight
    features (measured, a 45° line drawn on the 360 grid: D from 0.836 to 1.000 over 8 grids).
    Traces avoid this: their shifted grids are counted exactly (see :func:`box_count`).
    """
    return np.floor(offsets[None, :, :] * sizes[:, None, None]).astype(np.int64)


def _count_raster_mask(mask: np.ndarray, sizes: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Occupied boxes ``(n_sizes, n_offsets)`` of a square uint8 mask on the grids of ``offsets``."""
    off = _raster_shifts(sizes, offsets)
    return _count_raster_shifts(mask, sizes, off[:, :, 1], off[:, :, 0])


def _count_raster_shifts(mask: np.ndarray, sizes: np.ndarray, off_r, off_c) -> np.ndarray:
    """Occupied boxes ``(n_sizes, n_offsets)`` of a square mask on grids shifted cyclically by
    ``off_r``, ``off_c`` ``(n_sizes, n_offsets)`` whole pixels (0 <= shift < size)."""
    from . import _kernels

    n = mask.shape[0]
    tiled = sizes[sizes <= n // 2]  # sizes with 2 or more boxes a side: their boxes may wrap
    bits = _pack_rows(mask, n + (int(tiled.max()) - 1 if tiled.size else 0))
    counts = np.zeros((sizes.size, off_r.shape[1]), dtype=np.int64)
    sizes = np.ascontiguousarray(sizes, dtype=np.int64)
    _kernels.count_occupied_boxes(bits, sizes, np.argsort(sizes),
                                  np.ascontiguousarray(off_r, dtype=np.int64),
                                  np.ascontiguousarray(off_c, dtype=np.int64), counts)
    return counts


def _raster_box_totals(grid: int, sizes: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Boxes in the grid per size and offset: (grid/s)^2, shifted grids being cyclic."""
    return np.repeat(((grid // sizes) ** 2)[:, None], offsets.shape[0], axis=1)


def _vector_face_counts(ring_m, frame: Frame, sizes_m, offsets) -> np.ndarray:
    """Boxes meeting the face polygon, per size and offset, on the same (cyclic) grids as the count."""
    from . import _kernels

    out = np.zeros((sizes_m.size, offsets.shape[0]), dtype=np.int64)
    rel = ring_m - np.array([frame.x0_m, frame.y0_m])
    for a, d in enumerate(sizes_m):
        whole = frame.side_m / d
        cyclic = abs(whole - round(whole)) <= 1e-9 * whole
        for b, (fx, fy) in enumerate(offsets):
            nbx = max(math.ceil((frame.side_m + fx * d) / d - 1e-9), 1)
            nby = max(math.ceil((frame.side_m + fy * d) / d - 1e-9), 1)
            ring = np.ascontiguousarray((rel + np.array([fx * d, fy * d])) / d)
            marks = np.zeros((nby, nbx), dtype=np.uint8)
            _kernels.mark_polygon_cells(ring, nbx, nby, marks)
            nbx_eff = min(nbx, round(whole)) if cyclic else nbx
            nby_eff = min(nby, round(whole)) if cyclic else nby
            out[a, b] = _kernels.fold_and_count(marks, nbx_eff, nby_eff)
    return out


def _fit_all(sizes_px, counts, face, totals, in_fit):
    """Fit every offset column; return the zero-offset fit, its counts and all offset dimensions."""
    if face is not None:
        if np.any(face == 0):
            raise ValueError("mask: the face polygon meets no box at some sizes; is it inside the frame?")
        fit_counts = counts * (totals / face)
    else:
        fit_counts = counts.astype(np.float64)
    if np.any(fit_counts[in_fit] == 0):
        raise ValueError("no trace inside the face: the count is empty")
    fit = fit_loglog(sizes_px[in_fit], fit_counts[in_fit, 0])
    return fit, fit_counts[:, 0], loglog_slopes(sizes_px[in_fit], fit_counts[in_fit])


def box_count(data, *, kind: str = "auto", grid: int = 360, method: str = "raster", sizes_px=None,
              fit_range_px=None, window=None, mask="auto", n_offsets: int = 8,
              line_rule: str = "supercover", threshold: float | None = None,
              invert: bool = False, skeletonize: str = "auto") -> BoxCount:
    """Box-counting dimension of a trace network or a binary image, with its error model.

    Parameters
    ----------
    data : TraceMap, (n, 4) array_like, or (H, W) array_like
        Traces (any object with a ``segments()`` method, or segments ``x0, y0, x1, y1`` in metres),
        or a 2-D image whose non-zero pixels are traces (see :mod:`rockmass.fractal.image`).
    kind : {"auto", "traces", "image"}, default "auto"
        How to read ``data``. "auto": an object with ``segments()`` is traces; an array with 4
        columns is segments unless it is boolean or uint8 (image dtypes; integer segments such as
        OpenCV's ``HoughLinesP`` output are segments); any other 2-D array is an image. Give
        "traces" or "image" for the rare array that "auto" would read the wrong way.
    grid : int, default 360
        Raster side N for traces; for the vector method, the default box sizes are the divisors of
        N in units of side/N. Ignored for images, which are counted on their own pixel grid.
    method : {"raster", "vector"}, default "raster"
        Raster counting or exact vector counting (traces only).
    sizes_px : array_like, optional
        Box sizes in grid pixels. Raster: must divide the grid (default: all divisors). Vector: any
        sizes > 0 (default: the divisors of ``grid``).
    fit_range_px : (min, max), optional
        Box sizes (pixels, inclusive) used in the fit; default from the smallest to grid/4.
    window : (xmin, ymin, xmax, ymax), optional
        Count on this window (traces are clipped to it) instead of the bounding square.
    mask : "auto", None, (k, 2) array_like or shapely Polygon, default "auto"
        Face outline (traces); only boxes meeting it count, and traces are clipped to it. Without
        a window the frame is the square on the mask's bounding box. "auto" takes the sampling
        window of a trace map (its ``window_xy_m``) when it has one, else no mask; None: no mask.
        For an image, a 2-D array of the image's shape whose non-zero pixels are the face.
    n_offsets : int, default 8
        Number of shifted box grids for the spread of D (1 = zero offset only).
    line_rule : {"supercover", "bresenham"}, default "supercover"
        Rasterisation rule (see :mod:`rockmass.fractal.rasterize`).
    threshold, invert, skeletonize
        Image preparation (see :func:`rockmass.fractal.image.prepare_binary_image`).

    Returns
    -------
    BoxCount

    Raises
    ------
    ValueError
        Empty input, non-finite coordinates, a grid with fewer than 3 sizes in the fit range, a
        non-binary image without a threshold, or an invalid option (the message names it).

    Examples
    --------
    >>> import numpy as np
    >>> r = box_count(np.ones((360, 360), dtype=np.uint8), n_offsets=1)
    >>> round(r.dimension, 12), r.r2
    (2.0, 1.0)
    """
    _check_choice(method, METHODS, "method")
    _check_choice(kind, KINDS, "kind")
    check_line_rule(line_rule)
    offsets = grid_offsets(n_offsets)
    has_segments = hasattr(data, "segments") and callable(data.segments)
    arr = None if has_segments else np.asarray(data)
    if kind == "auto":
        is_traces = has_segments or (arr.ndim == 2 and arr.shape[1] == 4
                                     and arr.dtype not in (np.bool_, np.uint8))
    else:
        is_traces = kind == "traces"
    if isinstance(mask, str):
        if mask != "auto":
            raise ValueError(f"mask must be 'auto', None, a polygon or an image mask, got {mask!r}")
        mask = getattr(data, "window_xy_m", None) if has_segments else None
    if not is_traces:
        if method == "vector":
            raise ValueError("method 'vector' needs traces (segments), not an image")
        return _box_count_image(arr, sizes_px, fit_range_px, mask, offsets, threshold, invert,
                                skeletonize)
    grid = check_grid(grid)
    return _box_count_traces(data if has_segments else arr, grid, method, sizes_px, fit_range_px,
                             window, mask, offsets, line_rule)


def _box_count_image(img, sizes_px, fit_range_px, face_mask, offsets, threshold, invert,
                     skeletonize) -> BoxCount:
    prepared = prepare_binary_image(img, threshold=threshold, invert=invert,
                                    skeletonize=skeletonize)
    mask = prepared.mask
    grid = mask.shape[0]
    sizes = _raster_sizes(sizes_px, grid)
    in_fit = fit_range_mask(sizes, fit_range_px, grid)
    counts = _count_raster_mask(mask, sizes, offsets)
    face = totals = None
    notes = list(prepared.notes)
    if face_mask is not None:
        fm = np.asarray(face_mask)
        if fm.shape != prepared.original_shape:
            raise ValueError(f"mask: an image mask must have the image's shape "
                             f"{prepared.original_shape}, got {fm.shape}")
        face_img = np.zeros_like(mask)
        face_img[:fm.shape[0], :fm.shape[1]] = fm != 0
        outside = int(np.count_nonzero(mask & (face_img == 0)))
        if outside:
            mask = mask & face_img
            counts = _count_raster_mask(mask, sizes, offsets)
            notes.append(f"{outside} trace pixels outside the face mask were ignored")
        face = _count_raster_mask(face_img, sizes, offsets)
        totals = _raster_box_totals(grid, sizes, offsets)
    fit, fit_counts, offset_d = _fit_all(sizes.astype(np.float64), counts, face, totals, in_fit)
    return _result(fit, "raster", grid, sizes.astype(np.float64), None, counts[:, 0], fit_counts,
                   None if face is None else face[:, 0], in_fit, fit_range_px, offset_d,
                   line_rule=None, skeletonized=prepared.skeletonized, notes=notes)


def _box_count_traces(traces, grid, method, sizes_px, fit_range_px, window, mask, offsets,
                      line_rule) -> BoxCount:
    seg = as_segments(traces)
    notes = []
    zero = (seg[:, 0] == seg[:, 2]) & (seg[:, 1] == seg[:, 3])
    if zero.any():
        seg = seg[~zero]
        notes.append(f"{int(zero.sum())} zero-length segments cover no box and were dropped")
    if seg.shape[0] == 0:
        raise ValueError("traces: there are no traces (or only zero-length ones) to count")
    mask_ring = None if mask is None else as_ring(mask)
    if window is None and mask_ring is not None:  # frame the face, not just the traces in it
        window = (*mask_ring.min(axis=0), *mask_ring.max(axis=0))
    frame, window_ring = frame_for(seg, window)
    if not (np.isfinite(frame.side_m * frame.side_m) and frame.side_m * frame.side_m > 0.0):
        raise ValueError(f"traces: an extent of {frame.side_m:g} m is outside the range where "
                         "lengths and areas are representable; rescale the coordinates")
    rings = [r for r in (window_ring, mask_ring) if r is not None]
    if window is not None:
        rings.insert(0, frame.square_ring())
    face_ring = _intersect_rings(rings)
    if face_ring is not None:
        n_before = seg.shape[0]
        seg = clip_segments_to_ring(seg, face_ring)
        if seg.shape[0] == 0:
            raise ValueError("traces: no trace lies inside the window / mask")
        notes.append(f"traces clipped to the face: {n_before} segments in, {seg.shape[0]} pieces kept")
    masked = window_ring is not None or mask is not None
    length = float(np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1]).sum())
    if face_ring is not None:
        area = _ring_area(face_ring)
    else:  # the traces' bounding rectangle (a line network has zero height: use the square)
        width, height = float(np.ptp(seg[:, 0::2])), float(np.ptp(seg[:, 1::2]))
        area = width * height or frame.side_m**2
        empty = 1.0 - area / frame.side_m**2
        if empty > 0.01:
            notes.append(f"no face given: counted over the traces' bounding square, {100 * empty:.0f}% "
                         "of which lies beyond the traces' extent; give a window or mask to count "
                         "only the sampled face")
    if not (np.isfinite(area) and area > 0.0 and np.isfinite(length)):
        raise ValueError(f"traces: the face area ({area:g} m²) is not representable; rescale the "
                         "coordinates")
    frame_info = {"x0_m": frame.x0_m, "y0_m": frame.y0_m, "side_m": frame.side_m}

    if method == "raster":
        sizes = _raster_sizes(sizes_px, grid)
        in_fit = fit_range_mask(sizes, fit_range_px, grid)
        image = rasterize_segments_in_frame(seg, frame, grid, line_rule)
        # Supercover pixels are exactly the cells the segments cross, so the shifted grids are
        # counted on the segments themselves, shifted by exact fractions of each box (the pixel
        # image could only move by whole pixels); Bresenham lines have no such twin.
        exact_shifts = line_rule == "supercover" and offsets.shape[0] > 1
        pixel_offsets = offsets[:1] if exact_shifts else offsets
        counts = _count_raster_mask(image, sizes, pixel_offsets)
        face = totals = None
        if masked:
            face = _count_raster_mask(rasterize_polygon(face_ring, frame, grid), sizes,
                                      pixel_offsets)
            totals = _raster_box_totals(grid, sizes, offsets)
        sizes = sizes.astype(np.float64)
        if exact_shifts:
            sizes_m = sizes * frame.side_m / grid
            shifted, _ = _vector_counts(seg, frame, sizes_m, offsets[1:])
            counts = np.hstack([counts, shifted])
            if masked:
                face = np.hstack([face, _vector_face_counts(face_ring, frame, sizes_m,
                                                            offsets[1:])])
    else:
        sizes = _vector_sizes(sizes_px, grid)
        in_fit = fit_range_mask(sizes, fit_range_px, grid)
        sizes_m = sizes * frame.side_m / grid
        _check_vector_budget(seg, sizes_m)
        counts, totals = _vector_counts(seg, frame, sizes_m, offsets)
        face = _vector_face_counts(face_ring, frame, sizes_m, offsets) if masked else None
        line_rule = None
    fit, fit_counts, offset_d = _fit_all(sizes, counts, face, totals, in_fit)
    return _result(fit, method, grid, sizes, sizes * frame.side_m / grid, counts[:, 0], fit_counts,
                   None if face is None else face[:, 0], in_fit, fit_range_px, offset_d,
                   line_rule=line_rule, frame=frame_info, p21_per_m=length / area, area_m2=area,
                   notes=notes)


def _vector_counts(seg: np.ndarray, frame: Frame, sizes_m: np.ndarray, offsets: np.ndarray):
    """Boxes crossed by the segments and boxes in each grid, ``(n_sizes, n_offsets)`` int64 each."""
    from . import _kernels

    rel = frame.to_units(seg, frame.side_m)  # relative to the corner, in metres
    counts = np.zeros((sizes_m.size, offsets.shape[0]), dtype=np.int64)
    totals = np.zeros_like(counts)
    _kernels.count_crossed_boxes(rel, frame.side_m, np.ascontiguousarray(sizes_m), offsets,
                                 _MAX_MARK_CELLS, counts, totals)
    return counts, totals


def _check_vector_budget(seg: np.ndarray, sizes_m: np.ndarray) -> None:
    """Refuse a vector count whose box visits would exhaust memory (per grid: every shifted grid
    reuses the same buffers); name the sizes that cost most."""
    travel = float(np.sum(np.abs(seg[:, 2] - seg[:, 0]) + np.abs(seg[:, 3] - seg[:, 1])))
    visits = travel / sizes_m.min() + 3 * seg.shape[0]
    if visits > _MAX_VECTOR_CELLS:
        raise ValueError(
            f"sizes_px: boxes of {sizes_m.min():.3g} m would make the vector count visit about "
            f"{visits:.2g} boxes (limit {_MAX_VECTOR_CELLS:.0e}, about 1.6 GB); use larger box sizes")


def _intersect_rings(rings):
    """One face ring from the window square, a non-square window and a mask (shapely)."""
    if not rings:
        return None
    if len(rings) == 1:
        return rings[0]
    import shapely

    face = shapely.Polygon(rings[0])
    for r in rings[1:]:
        face = face.intersection(shapely.make_valid(shapely.Polygon(r)))
    if face.is_empty or face.area == 0.0:
        raise ValueError("mask: the mask polygon does not overlap the counting window")
    if face.geom_type != "Polygon":
        raise ValueError("mask: the mask and window overlap in several pieces; give one polygon")
    return as_ring(face, name="mask")


def _result(fit: LineFit, method, grid, sizes, sizes_m, counts, fit_counts, face, in_fit,
            fit_range_px, offset_d, **kwargs) -> BoxCount:
    lo, hi = (float(sizes[in_fit].min()), float(sizes[in_fit].max()))
    return BoxCount(
        dimension=fit.dimension, intercept=fit.intercept, r2=fit.r2, stderr=fit.stderr,
        ci95=fit.ci95, method=method, grid=grid, sizes_px=sizes, sizes_m=sizes_m, counts=counts,
        fit_counts=fit_counts, face_counts=face, in_fit=in_fit, fit_range_px=(lo, hi),
        local_slopes=local_slopes(sizes, fit_counts), offset_dimensions=offset_d,
        notes=tuple(kwargs.pop("notes", ())), **kwargs)
