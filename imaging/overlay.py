"""The extraction overlay: traces coloured by joint set, drawn over the photograph.

The sampling window (a ROI, or the face-mask outline of docs/imaging.md §2.1) is drawn as a dashed
yellow line when it is not the photo's edge.

When the traces carry a ``joint_score`` (:func:`rockmass.imaging.extract`, docs/imaging.md §7.1),
or else a ``confidence`` attribute (§7), each is drawn with opacity 0.25 + 0.75 · that value, so
doubtful traces fade.

matplotlib is imported inside the function (Agg backend). Large photographs are shown area-averaged
down to at most ``max_side_px`` pixels on their longer side (1100: the figure's width at its 110
dpi, so nothing visible is lost); the traces keep their coordinates.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..dfn.plots import _figure, _segment_colours, _set_legend
from .frame import uv_to_rc

__all__ = ["plot_overlay"]

#: Margin round the photo and height of the title band above it, inches.
_MARGIN_IN, _TITLE_IN = 0.05, 0.4
#: A photo band lower than this holds no legend column (ten sets at 8 pt), inches; the legend's
#: single row below it then takes a band of this height.
_LEGEND_COLUMN_IN, _LEGEND_ROW_IN = 2.2, 0.35


def _shade_key(trace_map) -> str | None:
    """The attribute the traces' opacity follows: ``joint_score``, else ``confidence``, else none."""
    return next((k for k in ("joint_score", "confidence") if k in trace_map.attributes), None)


def plot_overlay(image, trace_map, path, *, m_per_px: float, set_ids=None, title: str | None = None,
                 max_side_px: int = 1100) -> None:
    """Write the photograph (grey) with the traces on top, coloured by set (grey: unassigned).

    Parameters
    ----------
    image : (H, W) or (H, W, 3|4) array
        The photograph the traces were extracted from (input pixels).
    trace_map : TraceMap
        Traces in the face frame of that image.
    path : path-like
        Output file (format from the suffix).
    m_per_px : float
        The scale the traces are in (1.0 for traces in pixels).
    set_ids : (n_traces,) array of int, optional
        Joint set of each trace, -1 for none.
    """
    from matplotlib.collections import LineCollection

    import cv2

    img = np.asarray(image)
    if img.dtype not in (np.uint8, np.uint16, np.float32, np.float64):
        img = img.astype(np.float32)  # what cv2.resize takes
    h, w = img.shape[:2]
    factor = min(1.0, max_side_px / max(h, w))
    shown = img if factor == 1.0 else cv2.resize(  # area average: no aliasing, a fraction of the cost
        img, (max(round(w * factor), 1), max(round(h * factor), 1)), interpolation=cv2.INTER_AREA)
    if shown.ndim == 3:
        shown = shown[..., :3].mean(axis=2)
    # the axes placed by hand, the photo's shape with a narrow margin and a band for the title:
    # the layout engine would draw the whole figure twice (once to measure it), 0.1 s of a 12 MP
    # photo's ``rockmass extract``
    width_in = 10.0
    photo_w_in = width_in - 2 * _MARGIN_IN
    photo_h_in = photo_w_in * h / w
    # a photo band too low for the legend's column (a panorama): the legend goes in one row
    # below the photo, in a band of its own
    legend_below = set_ids is not None and photo_h_in < _LEGEND_COLUMN_IN
    bottom_in = _MARGIN_IN + (_LEGEND_ROW_IN if legend_below else 0.0)
    height_in = photo_h_in + bottom_in + _MARGIN_IN + _TITLE_IN
    fig = _figure((width_in, height_in), layout=None)
    ax = fig.add_axes((_MARGIN_IN / width_in, bottom_in / height_in, photo_w_in / width_in,
                       photo_h_in / height_in))
    ax.imshow(shown, cmap="gray", extent=(-0.5, w - 0.5, h - 0.5, -0.5), interpolation="antialiased")
    segments, shade_key = trace_map.segments(), _shade_key(trace_map)
    if segments.shape[0]:
        a = uv_to_rc(segments[:, :2], h, m_per_px)
        b = uv_to_rc(segments[:, 2:], h, m_per_px)
        lines = np.stack([a[:, ::-1], b[:, ::-1]], axis=1)  # (x=col, y=row) for matplotlib
        colours = _segment_colours(trace_map, set_ids, "0.7")
        if shade_key is not None:
            alpha = np.clip(np.asarray(trace_map.attributes[shade_key], dtype=float), 0.0, 1.0)
            colours[:, 3] = 0.25 + 0.75 * np.nan_to_num(alpha)[trace_map.segment_trace_index()]
        ax.add_collection(LineCollection(lines, colors=colours, linewidths=1.2))
    window = trace_map.window_xy_m
    if window is not None:  # a ROI or face-mask outline: drawn dashed unless it is the photo's edge
        ring = uv_to_rc(np.vstack([window, window[:1]]), h, m_per_px)
        x, y = ring[:, 1], ring[:, 0]
        area = 0.5 * abs(np.dot(x[:-1], y[1:]) - np.dot(x[1:], y[:-1]))
        if area < 0.995 * h * w:
            ax.plot(x, y, color="#ffd400", linewidth=1.0, linestyle="--", label="_window")
    _set_legend(ax, set_ids, **(dict(bbox_to_anchor=(1.0, 0.0), ncols=10) if legend_below else {}))
    ax.set_xlim(-0.5, w - 0.5)
    ax.set_ylim(h - 0.5, -0.5)
    ax.set_axis_off()
    shading = f", opacity = {shade_key.replace('_', ' ')}" if shade_key else ""
    ax.set_title(title or f"{trace_map.n_traces} traces{shading}", fontsize=10)
    # a PNG (the format of a path without suffix too) at zlib level 3 rather than Pillow's 6: less
    # compression work for a slightly larger file
    png = Path(path).suffix.lower() in ("", ".png")
    fig.savefig(path, dpi=110, **({"pil_kwargs": {"compress_level": 3}} if png else {}))
