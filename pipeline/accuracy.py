"""Accuracy of extracted traces against ground truth, box-counting dimension included.

:func:`rockmass.imaging.metrics.trace_accuracy` scores an extraction (buffered F1, P21, P20, set
orientations, node counts) and takes the box-counting dimensions as numbers, because imaging does
not import fractal (docs/design.md §1). This module is the glue that measures them with
:func:`rockmass.fractal.box_count` and hands them over.
"""

from __future__ import annotations

__all__ = ["trace_accuracy"]


def trace_accuracy(extracted, truth, *, m_per_px: float, **options):
    """:func:`rockmass.imaging.metrics.trace_accuracy` with D_box measured on both maps.

    Parameters
    ----------
    extracted, truth : TraceMap
        Same frame and units; the truth's window is the sampling window.
    m_per_px : float
        Image scale.
    **options
        ``buffer_px``, ``n_sets``, ``snap_px``, ``shape_px`` of the imaging function.

    Returns
    -------
    rockmass.imaging.metrics.Accuracy
        With ``d_box_true`` and ``d_box_extracted`` from :func:`rockmass.fractal.box_count` with its
        defaults (raster on the 360 grid; each map's own window as the face mask);
        ``d_box_extracted`` is NaN when nothing was extracted.
    """
    from .fractal import box_count
    from .imaging.metrics import trace_accuracy as score

    d_true = box_count(truth).dimension
    d_ext = box_count(extracted).dimension if extracted.n_traces else float("nan")
    return score(extracted, truth, m_per_px=m_per_px, d_box_true=d_true, d_box_extracted=d_ext,
                 **options)
