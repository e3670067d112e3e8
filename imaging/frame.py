"""Conversions between image pixels and the face frame — the only place they happen.

Image coordinates are ``rc_px``: (row, column), row 0 at the top, integer values at pixel centres
(OpenCV and scikit-image agree on this). The face frame is ``uv_m``: u to the right, v up, in metres,
origin at the image's bottom-left *corner* (docs/imaging.md §1, eq. (1.1)). With ``m_per_px``
metres per pixel and an image ``height_px`` rows high:

    u = (col + 0.5) * m_per_px
    v = (height_px - row - 0.5) * m_per_px

so the centre of the bottom-left pixel is at (m_per_px / 2, m_per_px / 2).
"""

from __future__ import annotations

import numpy as np

__all__ = ["rc_to_uv", "uv_to_rc", "check_scale"]


def check_scale(m_per_px: float, name: str = "m_per_px") -> float:
    """Return ``m_per_px`` as a float if it is finite and > 0, else raise naming it."""
    value = float(m_per_px)
    if not (np.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} must be a finite scale > 0 (metres per pixel), got {m_per_px!r}")
    return value


def rc_to_uv(rc_px, height_px: int, m_per_px: float) -> np.ndarray:
    """Pixel (row, col) positions ``(n, 2)`` to face-frame (u, v) metres ``(n, 2) float64``.

    Examples
    --------
    >>> rc_to_uv([[9, 0]], height_px=10, m_per_px=0.01).tolist()
    [[0.005, 0.005]]
    """
    rc = np.asarray(rc_px, dtype=np.float64).reshape(-1, 2)
    s = check_scale(m_per_px)
    return np.column_stack([(rc[:, 1] + 0.5) * s, (height_px - rc[:, 0] - 0.5) * s])


def uv_to_rc(uv_m, height_px: int, m_per_px: float) -> np.ndarray:
    """Face-frame (u, v) metres ``(n, 2)`` to pixel (row, col) positions ``(n, 2) float64``.

    The inverse of :func:`rc_to_uv`.

    Examples
    --------
    >>> uv_to_rc([[0.005, 0.005]], height_px=10, m_per_px=0.01).round(12).tolist()
    [[9.0, 0.0]]
    """
    uv = np.asarray(uv_m, dtype=np.float64).reshape(-1, 2)
    s = check_scale(m_per_px)
    return np.column_stack([height_px - uv[:, 1] / s - 0.5, uv[:, 0] / s - 0.5])
