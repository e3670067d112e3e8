"""Accuracy of extracted traces against ground truth, at the level users care about.

docs/imaging.md §8: buffered trace F1 (k ≈ 3 px), relative errors of P21 and P20 over the window, the
error of each joint set's mean orientation, the error of the box-counting dimension, and node-count
errors (I, Y, X nodes).

Joint sets come from :mod:`rockmass.dfn.sets2d` (the set fitting every trace map gets), with the
number of sets fixed to the truth's, so the set orientations compared are those a user sees.

The box-counting dimensions are numbers the caller measures and passes in (imaging does not import
:mod:`rockmass.fractal`: it depends on dfn only); :func:`rockmass.accuracy.trace_accuracy` measures
them with :func:`rockmass.fractal.box_count` and calls :func:`trace_accuracy`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .frame import check_scale, uv_to_rc

__all__ = ["Accuracy", "trace_accuracy", "buffered_match", "raster_match", "raster_counts",
           "matched_pixels", "pixels_within", "summarise_counts", "image_f1", "render_chains", "render_traces",
           "count_nodes", "set_mean_angles"]


@dataclass(frozen=True)
class Accuracy:
    """Accuracy of an extracted trace map against the truth (see :func:`trace_accuracy`).

    Attributes
    ----------
    precision, recall, f1 : float
        Buffered length-based scores, 0–1.
    p21_rel_error, p20_rel_error : float
        (extracted − true) / true, as fractions (0.1 = 10 % too high).
    set_angles_true_deg, set_angles_extracted_deg : tuple of float
        Mean angle of each true set and of the extracted set matched to it (0–180°).
    set_angle_errors_deg : tuple of float
        Axial difference per set, 0–90°.
    d_box_true, d_box_extracted, d_box_error : float
        Box-counting dimensions as given to :func:`trace_accuracy`, and extracted − true; NaN
        when not given.
    nodes_true, nodes_extracted : dict
        Counts of I, Y, X and E (window-edge) nodes.
    node_count_error : float
        Σ|Δ| over I, Y and X divided by the true Σ.
    """

    precision: float
    recall: float
    f1: float
    p21_rel_error: float
    p20_rel_error: float
    set_angles_true_deg: tuple[float, ...]
    set_angles_extracted_deg: tuple[float, ...]
    set_angle_errors_deg: tuple[float, ...]
    d_box_true: float
    d_box_extracted: float
    d_box_error: float
    nodes_true: dict
    nodes_extracted: dict
    node_count_error: float

    @property
    def max_set_angle_error_deg(self) -> float:
        """Largest set angle error (NaN when no set was matched)."""
        return max(self.set_angle_errors_deg) if self.set_angle_errors_deg else float("nan")


def render_traces(trace_map, shape_px, m_per_px) -> np.ndarray:
    """The traces drawn as 1-px 8-connected lines on a (rows, cols) grid: a bool mask."""
    h = int(shape_px[0])
    return render_chains((uv_to_rc(trace_map.polyline(i), h, m_per_px)
                          for i in range(trace_map.n_traces)), shape_px)


def render_chains(chains_rc, shape_px) -> np.ndarray:
    """Polylines in (row, col) pixels drawn as 1-px 8-connected lines on a (rows, cols) grid (to
    1/16 px): a bool mask."""
    import cv2

    canvas = np.zeros(tuple(int(v) for v in shape_px), dtype=np.uint8)
    for rc in chains_rc:
        xy = np.round(np.asarray(rc, dtype=float)[:, ::-1] * 16).astype(np.int32)
        cv2.polylines(canvas, [xy], False, 1, thickness=1, lineType=cv2.LINE_8, shift=4)
    return canvas.astype(bool)


def _distance_to(mask: np.ndarray) -> np.ndarray:
    """Euclidean distance (pixels) from every pixel to the nearest True pixel of ``mask``."""
    import cv2

    background = np.where(mask, 0, 255).astype(np.uint8)
    return cv2.distanceTransform(background, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)


def _render_distance(trace_map, shape_px, m_per_px) -> np.ndarray:
    """Distance (pixels) from every pixel of the grid to the nearest trace (1-px raster)."""
    return _distance_to(render_traces(trace_map, shape_px, m_per_px))


def raster_match(extracted, truth, *, tolerance_px: float = 5.0) -> tuple[float, float, float]:
    r"""Pixel precision, recall and F1 of two thin-line masks at a distance tolerance.

    Parameters
    ----------
    extracted, truth : (H, W) bool array_like
        One-pixel-wide lines (skeletons, or traces drawn by :func:`render_traces`); not modified.
    tolerance_px : float, default 5.0
        A pixel of one mask is matched when a pixel of the other lies within this Euclidean
        distance (pixels).

    Returns
    -------
    (precision, recall, f1) : tuple of float
        precision = share of extracted pixels within the tolerance of a true pixel, recall = share
        of true pixels within the tolerance of an extracted pixel (docs/imaging.md §8, eqs.
        (8.5)-(8.6)), F1 their harmonic mean. NaN for a precision (recall) with no extracted
        (true) pixels; F1 = 0 when both are 0 or undefined.

    Notes
    -----
    The tolerance-F1 of edge and crack detection benchmarks, without one-to-one matching: the score
    the hand-traced rock-face labels are judged with (labels skeletonised, 5 px tolerance).

    Examples
    --------
    >>> a = np.zeros((20, 20), bool); a[10, 2:18] = True
    >>> b = np.zeros((20, 20), bool); b[13, 2:18] = True
    >>> raster_match(a, b, tolerance_px=5.0), raster_match(a, b, tolerance_px=2.0)[2]
    ((1.0, 1.0, 1.0), 0.0)
    """
    matched_pred, n_pred, matched_true, n_true = raster_counts(extracted, truth, tolerance_px=tolerance_px)
    precision = matched_pred / n_pred if n_pred else float("nan")
    recall = matched_true / n_true if n_true else float("nan")
    if not (precision + recall > 0):
        return precision, recall, 0.0
    return precision, recall, 2 * precision * recall / (precision + recall)


def raster_counts(extracted, truth, *, tolerance_px: float = 5.0) -> tuple[int, int, int, int]:
    """The pixel counts behind :func:`raster_match`, for scores pooled over many images.

    Returns
    -------
    (matched_extracted, extracted, matched_true, true) : tuple of int
        Extracted pixels within the tolerance of a true pixel, extracted pixels, true pixels within
        the tolerance of an extracted pixel, true pixels.
    """
    pred, true = _checked_masks(extracted, truth, tolerance_px, "extracted and truth")
    pred_near, true_near = _near(pred, true, tolerance_px), _near(true, pred, tolerance_px)
    return int(pred_near.sum()), int(pred.sum()), int(true_near.sum()), int(true.sum())


def matched_pixels(extracted, truth, *, tolerance_px: float = 5.0) -> tuple[np.ndarray, np.ndarray]:
    """The pixels :func:`raster_counts` counts as matched, as masks: (extracted pixels within the
    tolerance of a true pixel, true pixels within the tolerance of an extracted pixel).

    Examples
    --------
    >>> a = np.zeros((9, 30), bool); a[4, 0:20] = True
    >>> b = np.zeros((9, 30), bool); b[6, 10:30] = True
    >>> near_a, near_b = matched_pixels(a, b, tolerance_px=3.0)
    >>> int(near_a.sum()), int(near_b.sum()), int(np.flatnonzero(near_b[6]).min())
    (12, 12, 10)
    """
    pred, true = _checked_masks(extracted, truth, tolerance_px, "extracted and truth")
    return _near(pred, true, tolerance_px), _near(true, pred, tolerance_px)


def summarise_counts(counts) -> dict:
    """Scores of a set of labelled images from their :func:`raster_counts` (matched drawn, drawn,
    matched true, true pixels per image).

    Returns
    -------
    dict
        ``F1``, ``P``, ``R``: the means over the images of the F1, precision and recall of
        :func:`raster_match` (F1 = 0 for an image with nothing drawn; an image without drawn
        or true pixels leaves its precision or recall out of the mean, NaN when no image has
        any); ``F1_pooled``: the F1 of
        the pixels pooled over all images; ``dP21_pct``: drawn / true line length - 1 over all
        images, in % (the length of 1-px lines is their pixel count, to a constant factor that
        cancels).

    Examples
    --------
    >>> s = summarise_counts([(8, 10, 8, 8), (0, 0, 0, 4)])
    >>> round(s["F1"], 3), round(s["P"], 3), s["R"], s["dP21_pct"]
    (0.444, 0.8, 0.5, -16.666666666666664)
    """
    c = np.array(counts, dtype=float).reshape(-1, 4)
    p, r, f = _image_scores(c)
    pp, pr = c[:, 0].sum() / max(c[:, 1].sum(), 1), c[:, 2].sum() / max(c[:, 3].sum(), 1)
    return dict(F1=float(np.mean(f)), P=_mean_defined(p), R=_mean_defined(r),
                F1_pooled=float(2 * pp * pr / max(pp + pr, 1e-12)),
                dP21_pct=float(100 * (c[:, 1].sum() / max(c[:, 3].sum(), 1) - 1)))


def image_f1(counts) -> np.ndarray:
    """The F1 of each image from its :func:`raster_counts` (rows of four), 0 for an image with
    nothing drawn: the values :func:`summarise_counts` averages.

    Examples
    --------
    >>> image_f1([(8, 10, 8, 8), (0, 0, 0, 4)]).round(3).tolist()
    [0.889, 0.0]
    """
    return _image_scores(np.array(counts, dtype=float).reshape(-1, 4))[2]


def _image_scores(c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-image precision, recall (NaN when undefined) and F1 (0 then) of (n, 4) counts."""
    with np.errstate(invalid="ignore", divide="ignore"):
        p, r = c[:, 0] / c[:, 1], c[:, 2] / c[:, 3]
        f = np.where(p + r > 0, 2 * p * r / (p + r), 0.0)
    return p, r, f


def _mean_defined(values: np.ndarray) -> float:
    """The mean of the values that are not NaN; NaN (without a warning) when none is."""
    defined = values[~np.isnan(values)]
    return float(defined.mean()) if defined.size else float("nan")


def pixels_within(mask, reference, tolerance_px: float) -> tuple[int, int]:
    """(pixels of ``mask`` within ``tolerance_px`` of a pixel of ``reference``, pixels of ``mask``).

    ``mask`` and ``reference`` are 2-D masks of one shape (any nonzero value is True); one distance
    transform, of ``reference``. A ``reference`` without pixels matches none.

    Examples
    --------
    >>> a = np.zeros((5, 9), bool); a[2, 1:8] = True
    >>> b = np.zeros((5, 9), bool); b[4, 1:4] = True
    >>> pixels_within(a, b, 2.0), pixels_within(a, b, 3.0), pixels_within(b, a, 2.0)
    ((3, 7), (5, 7), (3, 3))
    """
    mask, reference = _checked_masks(mask, reference, tolerance_px, "mask and reference")
    return int(_near(mask, reference, tolerance_px).sum()), int(mask.sum())


def _checked_masks(a, b, tolerance_px, names: str):
    """``a`` and ``b`` as bool arrays, after checking they are 2-D of one shape and the tolerance
    a finite distance >= 0 (ValueError naming ``names`` otherwise)."""
    a, b = np.asarray(a, dtype=bool), np.asarray(b, dtype=bool)
    if a.shape != b.shape or a.ndim != 2:
        raise ValueError(f"{names} must be 2-D masks of one shape, got {a.shape} and {b.shape}")
    if not (np.isfinite(tolerance_px) and tolerance_px >= 0):
        raise ValueError(f"tolerance_px must be a finite distance >= 0, got {tolerance_px!r}")
    return a, b


def _near(mask, reference, tolerance_px) -> np.ndarray:
    """The pixels of ``mask`` within ``tolerance_px`` of a pixel of ``reference`` (bool mask)."""
    if not reference.any():
        return np.zeros_like(mask)
    return mask & (_distance_to(reference) <= tolerance_px)


def _sample(trace_map, height_px, m_per_px, step_px=0.5):
    """Points every ``step_px`` along all traces (pixel rc), the length (px) each stands for and the
    segment (row of ``trace_map.segments()``) each lies on."""
    seg = trace_map.segments()
    a = uv_to_rc(seg[:, :2], height_px, m_per_px)
    b = uv_to_rc(seg[:, 2:], height_px, m_per_px)
    length = np.hypot(*(b - a).T)
    n = np.maximum(np.ceil(length / step_px).astype(np.int64), 1)
    index = np.repeat(np.arange(seg.shape[0]), n)
    t = (np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n) + 0.5) / np.repeat(n, n)
    points = a[index] + t[:, None] * (b - a)[index]
    return points, (length / n)[index], index


def _pixel_of(points, shape_px):
    """The (row, col) pixel each point falls in, clipped to the grid."""
    h, w = shape_px
    return (np.clip(np.round(points[:, 0]).astype(np.int64), 0, h - 1),
            np.clip(np.round(points[:, 1]).astype(np.int64), 0, w - 1))


def buffered_match(extracted, truth, *, m_per_px: float, buffer_px: float = 3.0,
                   shape_px=None, ignore=None) -> tuple[float, float, float]:
    r"""Buffered trace precision, recall and F1.

    Parameters
    ----------
    extracted, truth : TraceMap
        In metres on the face frame (or pixels with ``m_per_px = 1``).
    m_per_px : float
        Scale of the image the buffer is measured on.
    buffer_px : float, default 3.0
        Buffer half-width k, pixels.
    shape_px : (rows, cols), optional
        The image; default the truth window's (or the traces') bounding box from the origin, or
        ``ignore``'s shape when given.
    ignore : (rows, cols) bool array_like, optional
        Pixels where neither map is scored (e.g. fractures a photograph shows that the truth does
        not hold): the length of either map over them counts neither as matched nor as drawn.
        Both maps are still whole when distances are measured.

    Returns
    -------
    (precision, recall, f1) : tuple of float
        precision = extracted length within k px of a true trace / extracted length; recall = true
        length within k px of an extracted trace / true length (lengths outside ``ignore``); F1
        their harmonic mean.

    Notes
    -----
    Distances come from a Euclidean distance transform of each map drawn as 1-px lines, sampled
    every half pixel along the other map; the raster adds at most about half a pixel to a distance.
    """
    scale = check_scale(m_per_px)
    if ignore is not None:
        ignore = np.asarray(ignore, dtype=bool)
        if shape_px is None:
            shape_px = ignore.shape
    if shape_px is None:
        maps = [m for m in (truth, extracted) if m.n_traces]
        corners = [truth.window_xy_m] if truth.window_xy_m is not None else []
        corners += [m.xy_m for m in maps]
        top = np.vstack(corners).max(axis=0) if corners else np.ones(2) * scale
        shape_px = (int(np.ceil(top[1] / scale)) + 1, int(np.ceil(top[0] / scale)) + 1)
    h, w = (int(v) for v in shape_px)
    if ignore is not None and ignore.shape != (h, w):
        raise ValueError(f"ignore must be a mask of the image's shape {(h, w)}, got {ignore.shape}")

    def matched_fraction(a, b):
        if a.n_traces == 0:
            return float("nan")
        points, weight, _ = _sample(a, h, scale)
        r, c = _pixel_of(points, (h, w))
        if ignore is not None:
            kept = ~ignore[r, c]
            r, c, weight = r[kept], c[kept], weight[kept]
        if not weight.sum() > 0:
            return float("nan")
        if b.n_traces == 0:
            return 0.0
        inside = _render_distance(b, (h, w), scale)[r, c] <= buffer_px
        return float(weight[inside].sum() / weight.sum())

    precision = matched_fraction(extracted, truth)
    recall = matched_fraction(truth, extracted)
    if not (precision + recall > 0):
        return precision, recall, 0.0
    return precision, recall, 2 * precision * recall / (precision + recall)


def _axial_difference_deg(a, b):
    """Axial difference of angles in degrees, 0-90 (θ and θ + 180° are the same direction)."""
    return np.abs((np.asarray(a) - np.asarray(b) + 90.0) % 180.0 - 90.0)


def set_mean_angles(trace_map, n_sets: int) -> np.ndarray:
    """Mean angles (0–180°, ascending) of ``n_sets`` joint sets of a trace map.

    The sets are those of :func:`rockmass.dfn.fit_sets_2d` with the number of sets given: a
    length-weighted mixture of von Mises laws on doubled trace angles, fitted by EM. When the map
    has fewer distinct trace directions than ``n_sets``, that many sets are fitted (fewer values
    come back); an empty map, or one without a trace direction, gives an empty array.

    Examples
    --------
    >>> from rockmass.dfn import TraceMap
    >>> tm = TraceMap.from_segments([[0, 0, 2, 0], [0, 1, 2, 1], [0, 0, 0, 3], [1, 0, 1, 3]])
    >>> set_mean_angles(tm, 2).round(6).tolist()
    [0.0, 90.0]
    """
    from ..dfn.sets2d import fit_sets_2d, trace_angles_deg

    if not (isinstance(n_sets, (int, np.integer)) and n_sets >= 1):
        raise ValueError(f"n_sets must be an integer >= 1, got {n_sets!r}")
    if trace_map.n_traces == 0:
        return np.zeros(0)
    angle = trace_angles_deg(trace_map)
    fitted = np.isfinite(angle) & (trace_map.lengths_m() > 0)
    n_distinct = np.unique(np.round(2.0 * angle[fitted], 9) % 360.0).size
    if n_distinct == 0:
        return np.zeros(0)
    sets = fit_sets_2d(trace_map, n_sets=min(int(n_sets), n_distinct))
    return np.sort(sets.mean_angle_deg)


def _labelled_set_means(trace_map, labels) -> np.ndarray:
    r"""Length-weighted axial mean angle of the traces of each label (labels in ascending order).

    A one-set fit of :func:`rockmass.dfn.fit_sets_2d` on each label's traces: with one set, its mean
    is :math:`\tfrac12 \arg \sum_i \ell_i e^{2 i \theta_i}`.
    """
    from ..dfn.sets2d import fit_axial_mixture, trace_angles_deg

    angle, length = trace_angles_deg(trace_map), trace_map.lengths_m()
    return np.array([fit_axial_mixture(angle[labels == k], length[labels == k],
                                       n_sets=1).mean_angle_deg[0] for k in np.unique(labels)])


def count_nodes(trace_map, *, snap_m: float) -> dict:
    """Topological node counts of a trace map: I, Y, X, and E (ends on the window edge).

    Parameters
    ----------
    trace_map : TraceMap
    snap_m : float
        An end within this distance of another trace is a Y node, of the window boundary an E node.

    Returns
    -------
    dict
        ``{"I": ..., "Y": ..., "X": ..., "E": ...}``: isolated ends, abutting ends, crossings
        (intersection points of two traces away from both traces' ends) and window-edge ends.
    """
    import shapely

    geoms = trace_map.to_shapely()
    n = geoms.size
    counts = {"I": 0, "Y": 0, "X": 0, "E": 0}
    if n == 0:
        return counts
    starts = trace_map.xy_m[trace_map.offsets[:-1]]
    stops = trace_map.xy_m[trace_map.offsets[1:] - 1]
    ends = np.vstack([starts, stops])
    owner = np.concatenate([np.arange(n), np.arange(n)])
    points = shapely.points(ends)
    tree = shapely.STRtree(geoms)
    end_idx, geom_idx = tree.query(points, predicate="dwithin", distance=snap_m)
    touching = np.zeros(ends.shape[0], dtype=bool)
    touching[end_idx[geom_idx != owner[end_idx]]] = True
    window = trace_map.window_polygon()
    on_edge = (shapely.dwithin(points, window.exterior, snap_m) if window is not None
               else np.zeros(ends.shape[0], dtype=bool))
    counts["E"] = int(np.count_nonzero(on_edge))
    counts["Y"] = int(np.count_nonzero(touching & ~on_edge))
    counts["I"] = int(np.count_nonzero(~touching & ~on_edge))
    left, right = tree.query(geoms, predicate="intersects")
    keep = left < right
    end_points = shapely.points(ends)
    x_count = 0
    for i, j in zip(left[keep], right[keep]):
        hits = shapely.get_parts(shapely.intersection(geoms[i], geoms[j]))
        for hit in hits:
            if hit.geom_type != "Point":
                continue
            near_end = shapely.dwithin(hit, end_points[[i, j, i + n, j + n]], snap_m).any()
            x_count += not near_end
    counts["X"] = x_count
    return counts


def _window_area(truth, extracted) -> float:
    for m in (truth, extracted):
        polygon = m.window_polygon()
        if polygon is not None:
            return float(polygon.area)
    raise ValueError("truth has no window: P21 and P20 need the sampling window's area")


def _scored_part(trace_map, ignore, m_per_px):
    """The traces of ``trace_map`` with at least half their length outside the ``ignore`` mask, and
    the length of the whole map outside it (metres)."""
    if trace_map.n_traces == 0:
        return trace_map, 0.0
    points, weight, segment = _sample(trace_map, ignore.shape[0], m_per_px)
    outside = np.where(ignore[_pixel_of(points, ignore.shape)], 0.0, weight)
    trace_of_point = trace_map.segment_trace_index()[segment]
    n = trace_map.n_traces
    share = (np.bincount(trace_of_point, outside, minlength=n)
             / np.maximum(np.bincount(trace_of_point, weight, minlength=n), 1e-300))
    return trace_map.subset(share >= 0.5), float(outside.sum()) * m_per_px


def trace_accuracy(extracted, truth, *, m_per_px: float, buffer_px: float = 3.0,
                   n_sets: int | None = None, snap_px: float = 3.0, shape_px=None,
                   d_box_true: float | None = None,
                   d_box_extracted: float | None = None, ignore=None) -> Accuracy:
    """Accuracy of extracted traces against ground truth.

    Parameters
    ----------
    extracted, truth : TraceMap
        Same frame and units; the truth's window is the sampling window.
    m_per_px : float
        Image scale (pixels define the buffer and the snap distance).
    buffer_px : float, default 3.0
        Buffer half-width for precision / recall (see :func:`buffered_match`).
    n_sets : int, optional
        Number of joint sets; default the number of distinct values of the truth's ``set`` attribute
        (the truth's set means are then the length-weighted axial means per set), else 1.
    snap_px : float, default 3.0
        Snap distance for node counts (see :func:`count_nodes`).
    shape_px : (rows, cols), optional
        Image shape (see :func:`buffered_match`).
    d_box_true, d_box_extracted : float, optional
        Box-counting dimensions of the two maps, measured by the caller on the same grid and
        window (:func:`rockmass.accuracy.trace_accuracy` does); default None: not measured (NaN).
    ignore : (rows, cols) bool array_like, optional
        Pixels of the image where neither map is scored (see :func:`buffered_match`); the
        image's shape. The P21 of each map is then its length outside them, and the trace counts,
        set angles and nodes are those of the traces with at least half their length outside (at
        least one true trace must be).

    Returns
    -------
    Accuracy

    Notes
    -----
    P21 = Σ length / window area and P20 = number of traces / window area, both maps over the
    truth's window. Extracted sets are matched to true ones by the assignment that minimises the
    summed axial angle differences (Hungarian method).
    """
    from scipy.optimize import linear_sum_assignment

    scale = check_scale(m_per_px)
    precision, recall, f1 = buffered_match(extracted, truth, m_per_px=scale, buffer_px=buffer_px,
                                           shape_px=shape_px, ignore=ignore)
    area = _window_area(truth, extracted)
    if ignore is None:
        p21_true, p21_ext = truth.total_length_m() / area, extracted.total_length_m() / area
    else:
        ignore = np.asarray(ignore, dtype=bool)
        (truth, true_length), (extracted, ext_length) = (
            _scored_part(m, ignore, scale) for m in (truth, extracted))
        if truth.n_traces == 0:
            raise ValueError("ignore covers the truth: no true trace has half its length outside it, "
                             "so nothing of the truth is left to score")
        p21_true, p21_ext = true_length / area, ext_length / area  # relative errors: area cancels
    p20_true, p20_ext = truth.n_traces / area, extracted.n_traces / area
    if "set" in truth.attributes and n_sets is None:
        true_sets = _labelled_set_means(truth, np.asarray(truth.attributes["set"]))
    else:
        true_sets = set_mean_angles(truth, n_sets or 1)
    ext_sets = set_mean_angles(extracted, true_sets.size) if extracted.n_traces else np.zeros(0)
    if ext_sets.size:
        cost = _axial_difference_deg(true_sets[:, None], ext_sets[None, :])
        rows, cols = linear_sum_assignment(cost)
        order = np.argsort(rows)
        rows, cols = rows[order], cols[order]
        matched = tuple(float(ext_sets[c]) for c in cols)
        errors = tuple(float(cost[r, c]) for r, c in zip(rows, cols))
        true_listed = tuple(float(true_sets[r]) for r in rows)
    else:
        matched, errors, true_listed = (), (), tuple(float(a) for a in true_sets)
    d_true = float("nan") if d_box_true is None else float(d_box_true)
    d_ext = float("nan") if d_box_extracted is None else float(d_box_extracted)
    snap = snap_px * scale
    nodes_true, nodes_ext = count_nodes(truth, snap_m=snap), count_nodes(extracted, snap_m=snap)
    total = sum(nodes_true[k] for k in "IYX")
    node_error = (sum(abs(nodes_ext[k] - nodes_true[k]) for k in "IYX") / total
                  if total else float("nan"))
    return Accuracy(
        precision=precision, recall=recall, f1=f1,
        p21_rel_error=(p21_ext - p21_true) / p21_true if p21_true else float("nan"),
        p20_rel_error=(p20_ext - p20_true) / p20_true if p20_true else float("nan"),
        set_angles_true_deg=true_listed, set_angles_extracted_deg=matched,
        set_angle_errors_deg=errors, d_box_true=float(d_true), d_box_extracted=float(d_ext),
        d_box_error=float(d_ext - d_true), nodes_true=nodes_true, nodes_extracted=nodes_ext,
        node_count_error=float(node_error))
