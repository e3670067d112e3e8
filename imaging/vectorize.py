"""Pixel chains to trace polylines in metres: simplification, face frame, per-trace attributes.

docs/imaging.md §7: an 8-connected pixel chain over-estimates length by up to 8 % at 22.5°, so
lengths are measured on Douglas–Peucker-simplified polylines [1]_; all pixel -> metre conversion
goes through :mod:`rockmass.imaging.frame`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .frame import check_scale, rc_to_uv

__all__ = ["simplify_polylines", "axial_angle_deg", "image_window_uv_m", "mean_along", "trace_contrast",
           "FaceLevels", "face_levels", "face_sample", "band_width_px", "to_trace_map"]


def simplify_polylines(polylines_rc_px, tolerance_px: float) -> list[np.ndarray]:
    """Douglas–Peucker simplification of pixel polylines (shapely ``simplify``, topology kept).

    Parameters
    ----------
    polylines_rc_px : sequence of (k, 2) array_like
        Pixel (row, col) chains, k >= 2.
    tolerance_px : float
        Largest distance of a dropped vertex from the simplified line, pixels (>= 0; 0 keeps all).

    Returns
    -------
    list of (m, 2) float64 ndarray
        End points are always kept, so m >= 2.

    References
    ----------
    .. [1] Douglas, D. H., Peucker, T. K. (1973). Algorithms for the reduction of the number of
       points required to represent a digitized line or its caricature. Cartographica 10(2),
       112-122.
    """
    import shapely

    if not (np.isfinite(tolerance_px) and tolerance_px >= 0):
        raise ValueError(f"tolerance_px must be a finite distance >= 0 (pixels), got {tolerance_px!r}")
    lines = [np.asarray(p, dtype=np.float64) for p in polylines_rc_px]
    if not lines:
        return []
    geoms = shapely.linestrings(lines) if len({len(p) for p in lines}) == 1 else np.array(
        [shapely.LineString(p) for p in lines], dtype=object)
    simple = shapely.simplify(geoms, tolerance_px, preserve_topology=True)
    return [np.asarray(shapely.get_coordinates(g)) for g in np.atleast_1d(simple)]


def axial_angle_deg(trace_map) -> np.ndarray:
    r"""Orientation of each trace, 0–180° counter-clockwise from +x (u on a face), length-weighted.

    The angle every trace-map statistic uses, :func:`rockmass.dfn.sets2d.trace_angles_deg` with
    ``method="segments"``: :math:`\theta = \tfrac12 \arg \sum_j \ell_j e^{2 i \phi_j}` over the pieces
    j of the trace (length :math:`\ell_j`, direction :math:`\phi_j`), so a straight trace gets its
    direction and a wiggly one its overall trend.

    Parameters
    ----------
    trace_map : TraceMap

    Returns
    -------
    (n_traces,) float64 ndarray
        Degrees in [0, 180); NaN only for a trace without a direction (zero length).

    Examples
    --------
    >>> from rockmass.dfn import TraceMap
    >>> axial_angle_deg(TraceMap.from_segments([[0, 0, 1, 1], [0, 0, -1, 0]])).tolist()
    [45.0, 0.0]
    """
    from ..dfn.sets2d import trace_angles_deg

    return trace_angles_deg(trace_map, method="segments")


def image_window_uv_m(shape_px, m_per_px: float) -> np.ndarray:
    """(4, 2) ring of the image rectangle in metres on the face frame (bottom-left origin)."""
    h, w = (int(v) for v in shape_px)
    s = check_scale(m_per_px)
    return np.array([[0.0, 0.0], [w * s, 0.0], [w * s, h * s], [0.0, h * s]])


def mean_along(polylines_rc_px, image, *, step_px: float = 0.5) -> np.ndarray:
    r"""Mean of an image along each pixel polyline (nearest pixel, points every ``step_px``).

    Parameters
    ----------
    polylines_rc_px : sequence of (k, 2) array_like
        Pixel (row, col) polylines on the image's grid.
    image : (H, W) array_like
        E.g. the joint probability map; not modified.
    step_px : float, default 0.5

    Returns
    -------
    (n,) float64 ndarray
        :math:`\frac{1}{m}\sum_j I(\mathrm{round}(p_j))` over m points :math:`p_j` evenly spaced
        along each polyline (its vertices included), so every stretch counts by its length; NaN for
        an empty image.

    Examples
    --------
    >>> img = np.zeros((5, 10)); img[2, :5] = 1.0
    >>> mean_along([[(2, 0), (2, 9)]], img).round(1).tolist()
    [0.5]
    """
    values = np.asarray(image)  # sampled, then made float64: no float64 copy of the whole image
    h, w = values.shape
    out = np.full(len(polylines_rc_px), np.nan)
    for i, line in enumerate(polylines_rc_px):
        rc = np.asarray(line, dtype=np.float64)
        seg = np.hypot(*np.diff(rc, axis=0).T)
        arc = np.concatenate([[0.0], np.cumsum(seg)])
        t = np.linspace(0.0, arc[-1], max(int(np.ceil(arc[-1] / step_px)), 1) + 1)
        r = np.clip(np.round(np.interp(t, arc, rc[:, 0])).astype(np.int64), 0, h - 1)
        c = np.clip(np.round(np.interp(t, arc, rc[:, 1])).astype(np.int64), 0, w - 1)
        out[i] = values[r, c].astype(np.float64).mean() if values.size else np.nan
    return out


def trace_contrast(polylines_rc_px, flat, *, mask=None) -> np.ndarray:
    r"""How much darker than the face each trace is: :math:`1 - \bar I / \operatorname{med}(I)`,
    with :math:`\bar I` the mean of the flattened image along the trace (:func:`mean_along`) and
    the median over the image (over ``mask`` when given; the whole image when it leaves no pixel).

    0.25 means a quarter darker than the typical face; negative values are brighter than it.

    Examples
    --------
    >>> img = np.ones((5, 10)); img[2] = 0.6
    >>> trace_contrast([[(2, 0), (2, 9)], [(0, 0), (0, 9)]], img).round(2).tolist()
    [0.4, 0.0]
    """
    values = np.asarray(flat, dtype=np.float64)
    reference = float(np.median(_face_values(values, mask))) if values.size else 0.0
    if not reference > 0:
        return np.zeros(len(polylines_rc_px))
    return 1.0 - mean_along(polylines_rc_px, values) / reference


def _face_values(values: np.ndarray, mask) -> np.ndarray:
    """The pixels of ``values`` inside ``mask`` (all of them when it is None or leaves none)."""
    if mask is None:
        return values.ravel()
    inside = values[np.asarray(mask, dtype=bool)]
    return inside if inside.size else values.ravel()


def face_sample(image, *, mask=None, max_pixels: int = 1_000_000) -> np.ndarray:
    """The pixels of a 2-D ``image`` inside ``mask`` on a regular grid of every k-th row and
    column, k the smallest step leaving at most ``max_pixels`` (k = 1 for smaller images): enough
    for percentiles of the face (a 4 MP face gives a quarter of its pixels).

    Examples
    --------
    >>> face_sample(np.arange(16.0).reshape(4, 4), max_pixels=4).tolist()
    [0.0, 2.0, 8.0, 10.0]
    """
    if not max_pixels >= 1:
        raise ValueError(f"max_pixels must be >= 1, got {max_pixels!r}")
    values = np.asarray(image)
    step = max(1, int(np.ceil(np.sqrt(values.size / max_pixels)))) if values.ndim == 2 else 1
    grid = values[::step, ::step] if step > 1 else values
    return _face_values(grid, None if mask is None else np.asarray(mask, dtype=bool)[::step, ::step])


class FaceLevels(NamedTuple):
    """What :func:`face_levels` reads from a flattened face."""

    median: float
    spread: float
    contrast: float


def face_levels(flat, *, mask=None, percentile: float = 5.0) -> FaceLevels:
    r"""The flattened face's median m, relative spread and own contrast, from one
    :func:`face_sample` (over ``mask`` when given):

    - the spread :math:`s = 1.4826\,\mathrm{MAD}(I) / m`, a robust standard deviation over the
      median (how flat the face is: ``ExtractParams.min_face_spread``);
    - the contrast :math:`C = \max(0,\ 1 - q_p(I) / m)`, with :math:`q_p` the ``percentile``: the
      :func:`trace_contrast` of a line as dark as the face's darkest ``p`` %. A photo in flat
      light, or of pale rock, has a small C: all its joints are faint in absolute terms, and a
      contrast floor set on photos of ordinary contrast would drop every one of them
      (``ExtractParams.face_contrast_share``, docs/imaging.md §3.1).

    s and C are 0 for an empty image or a median that is not positive.

    Examples
    --------
    >>> img = np.ones((10, 10)); img[0] = 0.4  # a tenth of the face at 0.4
    >>> round(face_levels(img).contrast, 3)
    0.6
    >>> img = np.ones((40, 40), np.float32); img[::2] = 1.2
    >>> [round(v, 3) for v in face_levels(img)[:2]]
    [1.1, 0.135]
    >>> face_levels(np.full((4, 4), 0.8))
    FaceLevels(median=0.8, spread=0.0, contrast=0.0)
    """
    sample = face_sample(flat, mask=mask).astype(np.float64, copy=False)
    if not sample.size:
        return FaceLevels(0.0, 0.0, 0.0)
    median = float(np.median(sample))
    if not median > 0:
        return FaceLevels(median, 0.0, 0.0)
    spread = 1.4826 * float(np.median(np.abs(sample - median))) / median
    contrast = max(1.0 - float(np.percentile(sample, percentile)) / median, 0.0)
    return FaceLevels(median, spread, contrast)


def band_width_px(polylines_rc_px, binary) -> np.ndarray:
    """Mean width (pixels) of the binary mask along each trace: twice the Euclidean distance from
    the trace's pixels to the nearest pixel outside the mask, averaged along it (:func:`mean_along`).

    Examples
    --------
    >>> b = np.zeros((11, 20), bool); b[3:8] = True
    >>> band_width_px([[(5, 2), (5, 17)]], b).round(1).tolist()
    [6.0]
    """
    import cv2

    inside = np.asarray(binary, dtype=bool)
    half = cv2.distanceTransform(inside.view(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    return 2.0 * mean_along(polylines_rc_px, half)


def to_trace_map(polylines_rc_px, *, height_px: int, m_per_px: float, window_uv_m=None,
                 tolerance_px: float = 1.0, frame: str = "face", attributes=None):
    """Build a :class:`rockmass.dfn.TraceMap` (metres, face frame) from pixel trace polylines.

    Parameters
    ----------
    polylines_rc_px : sequence of (k, 2) array_like
        Traces in pixel (row, col) of an image ``height_px`` rows high.
    height_px : int
        Image height (the face frame's v axis points up from the bottom row).
    m_per_px : float
        Scale, > 0 (1.0 for a map in pixels).
    window_uv_m : (k, 2) array_like, optional
        Sampling window in metres (the ROI); default the image rectangle is not known here, so
        None leaves the map without a window.
    tolerance_px : float, default 1.0
        Douglas–Peucker tolerance, pixels.
    frame : str, default "face"
    attributes : mapping of str to (n,) array_like, optional
        More per-trace attributes (e.g. ``confidence``), one value per polyline.

    Returns
    -------
    TraceMap
        Attributes ``length_m`` (simplified polyline length), ``angle_deg`` (see
        :func:`axial_angle_deg`) and those given.
    """
    from ..dfn import TraceMap

    scale = check_scale(m_per_px)
    simple = simplify_polylines(polylines_rc_px, tolerance_px)
    uv = [rc_to_uv(p, height_px, scale) for p in simple]
    trace_map = TraceMap.from_polylines(uv, window=window_uv_m, frame=frame)
    return TraceMap.from_polylines(
        uv, {"length_m": trace_map.lengths_m(), "angle_deg": axial_angle_deg(trace_map),
             **dict(attributes or {})},
        window=window_uv_m, frame=frame)
