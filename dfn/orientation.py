"""Orientations of planes and lines: dip / dip direction, strike / dip, trend / plunge and unit vectors.

Every function is vectorised (numpy broadcasting over the leading axes) and takes and returns
degrees; vectors are ``(..., 3) float64`` in the world frame of docs/fractures.md §1.1, x = East, y = North,
z = Up.

Conventions
-----------
Plane, dip / dip direction
    dip δ in [0, 90]°, dip direction α any real (taken mod 360, returned in [0, 360)), clockwise from
    North.
Upper normal
    ``normal_from_dip``: n = (sin δ sin α, sin δ cos α, cos δ), the unit normal with n_z >= 0; its
    horizontal part points down the dip.
Pole (the project convention, docs/fractures.md §1.1, eq. (1.1))
    ``pole_from_dip``: p = -n, the lower-hemisphere normal (p_z <= 0), trend α + 180°,
    plunge 90° - δ.
Strike / dip (right-hand rule)
    the dip direction is 90° clockwise of the strike: α = strike + 90° (mod 360).
Line, trend / plunge
    trend τ any real (mod 360), plunge ρ in [-90, 90]°, positive downward:
    v = (cos ρ sin τ, cos ρ cos τ, -sin ρ).

Degenerate directions get fixed values instead of NaN: a vertical vector has trend 0 and a
horizontal plane has dip direction 0. A vector with v_z = 0 exactly lies on the boundary of both
hemispheres: :func:`to_lower_hemisphere` keeps it as given, and :func:`dip_from_normal` reads it as a
(lower-hemisphere) pole, so a vertical plane's pole round-trips to its own dip direction while its
upper normal round-trips to the opposite one (the same plane).

Orientations are axial: a plane's normal n and -n, and a line's v and -v, are the same object.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "angle_between",
    "dip_text",
    "dip_from_normal",
    "dip_from_pole_trend_plunge",
    "dip_from_strike",
    "normal_from_dip",
    "pole_from_dip",
    "pole_trend_plunge",
    "strike_from_dip",
    "to_lower_hemisphere",
    "trend_plunge_from_vector",
    "vector_from_trend_plunge",
]


# -- validation helpers (shared by the other orientation-statistics modules of rockmass.dfn) -------


def _as_float_array(value: ArrayLike, name: str) -> np.ndarray:
    """``value`` as a float64 array (a copy when conversion is needed); every entry must be finite."""
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"{name} must be a number or an array of numbers: {exc}") from exc
    bad = ~np.isfinite(array)
    if bad.any():
        where = np.flatnonzero(bad.ravel())[:10].tolist()
        raise ValueError(f"{name} must be finite, got {int(bad.sum())} NaN or infinite values "
                         f"(flat indices {where})")
    return array


def _as_angle_range(value: ArrayLike, name: str, low: float, high: float, what: str) -> np.ndarray:
    """Finite float64 array with every entry in [low, high] (degrees); the message names ``name``."""
    array = _as_float_array(value, name)
    bad = (array < low) | (array > high)
    if bad.any():
        first = array[bad].ravel()[:10].tolist()
        raise ValueError(f"{name} must be in [{low:g}, {high:g}] degrees ({what}), got {first}")
    return array


def _as_nonnegative(value: ArrayLike, name: str, what: str) -> np.ndarray:
    """Finite float64 array with every entry >= 0; the message names ``name`` and says ``what`` it is."""
    array = _as_float_array(value, name)
    if (array < 0).any():
        raise ValueError(f"{name} must be >= 0 ({what}), got {array[array < 0].ravel()[:10].tolist()}")
    return array


def _as_vectors(value: ArrayLike, name: str) -> np.ndarray:
    """``value`` as a new ``(..., 3)`` float64 array of unit vectors (each row normalised).

    Rows must be finite and of non-zero length; the message names ``name`` and the offending rows.
    """
    array = _as_float_array(value, name)
    if array.ndim == 0 or array.shape[-1] != 3:
        raise ValueError(f"{name} must have shape (..., 3) (x East, y North, z Up), got {array.shape}")
    norm = np.linalg.norm(array, axis=-1, keepdims=True)
    zero = norm[..., 0] == 0
    if zero.any():
        rows = np.flatnonzero(zero.ravel())[:10].tolist()
        raise ValueError(f"{name} must be non-zero vectors, got {int(zero.sum())} zero vectors "
                         f"(rows {rows})")
    return array / norm


def _as_scalar(value: float, name: str, *, low: float | None = None, high: float | None = None,
               low_open: bool = False, what: str = "") -> float:
    """A finite Python float in a range; TypeError for non-scalars, ValueError naming ``name``."""
    array = np.asarray(value)
    if array.ndim != 0 or array.dtype.kind not in "iuf":
        raise TypeError(f"{name} must be a real scalar, got {value!r}")
    number = float(array)
    suffix = f" ({what})" if what else ""
    if not np.isfinite(number):
        raise ValueError(f"{name} must be finite{suffix}, got {number}")
    if low is not None and (number < low or (low_open and number == low)):
        raise ValueError(f"{name} must be {'>' if low_open else '>='} {low:g}{suffix}, got {number}")
    if high is not None and number > high:
        raise ValueError(f"{name} must be <= {high:g}{suffix}, got {number}")
    return number


def _wrap360(degrees: np.ndarray) -> np.ndarray:
    """Angles mod 360 in [0, 360): ``np.mod`` can round a tiny negative angle up to 360.0."""
    wrapped = np.mod(degrees, 360.0)
    return np.where(wrapped >= 360.0, 0.0, wrapped) + 0.0  # + 0.0 turns -0.0 into 0.0


def _azimuth(vectors: np.ndarray) -> np.ndarray:
    """Azimuth (degrees clockwise from North, in [0, 360)) of the horizontal part; 0 when vertical."""
    x, y = vectors[..., 0], vectors[..., 1]
    vertical = (x == 0) & (y == 0)  # arctan2(-0.0, -0.0) would give 180 or -180
    return np.where(vertical, 0.0, _wrap360(np.degrees(np.arctan2(x, y))))


# -- planes --------------------------------------------------------------------------------------


def normal_from_dip(dip_deg: ArrayLike, dip_direction_deg: ArrayLike) -> np.ndarray:
    """Upper unit normal of planes given by dip / dip direction.

    Parameters
    ----------
    dip_deg : float or array_like
        Dip δ in degrees, 0 <= δ <= 90.
    dip_direction_deg : float or array_like
        Dip direction α in degrees clockwise from North, any finite real (taken mod 360). Broadcasts
        with ``dip_deg``.

    Returns
    -------
    (..., 3) ndarray of float64
        n = (sin δ sin α, sin δ cos α, cos δ), n_z >= 0 (x East, y North, z Up).

    See Also
    --------
    pole_from_dip : the lower-hemisphere pole -n.

    Examples
    --------
    >>> normal_from_dip(0.0, 123.0) + 0.0
    array([0., 0., 1.])
    >>> normal_from_dip(90.0, 90.0).round(12)
    array([1., 0., 0.])
    """
    dip = np.radians(_as_angle_range(dip_deg, "dip_deg", 0.0, 90.0, "dip of a plane"))
    azimuth = np.radians(_as_float_array(dip_direction_deg, "dip_direction_deg"))
    dip, azimuth = np.broadcast_arrays(dip, azimuth)
    sin_dip = np.sin(dip)
    return np.stack([sin_dip * np.sin(azimuth), sin_dip * np.cos(azimuth), np.cos(dip)], axis=-1)


def pole_from_dip(dip_deg: ArrayLike, dip_direction_deg: ArrayLike) -> np.ndarray:
    """Lower-hemisphere unit pole of planes given by dip / dip direction (docs/fractures.md §1.1, eq. (1.1)).

    Parameters are those of :func:`normal_from_dip`.

    Returns
    -------
    (..., 3) ndarray of float64
        p = -(sin δ sin α, sin δ cos α, cos δ), p_z <= 0: trend α + 180°, plunge 90° - δ.

    Examples
    --------
    >>> pole_from_dip(0.0, 0.0) + 0.0      # horizontal plane: pole straight down
    array([ 0.,  0., -1.])
    >>> pole_from_dip(90.0, 0.0).round(12) + 0.0   # vertical plane dipping North: pole points South
    array([ 0., -1.,  0.])
    """
    return -normal_from_dip(dip_deg, dip_direction_deg)


def dip_from_normal(vectors: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Dip and dip direction of planes given by a normal of either sign (axial).

    Parameters
    ----------
    vectors : (..., 3) array_like
        Plane normals or poles, any non-zero length (normalised here); n and -n give the same plane.

    Returns
    -------
    dip_deg : ndarray
        Dip in [0, 90] degrees.
    dip_direction_deg : ndarray
        Dip direction in [0, 360) degrees; 0 for a horizontal plane. A normal with n_z = 0 exactly
        (vertical plane) is read as the lower-hemisphere pole, so the dip direction is its trend
        + 180°.

    Notes
    -----
    The dip is computed as atan2(|n_h|, |n_z|) rather than acos(|n_z|), which keeps full precision
    for nearly horizontal planes.

    Examples
    --------
    >>> dip, dip_direction = dip_from_normal([0.0, -0.5, -0.5])
    >>> float(dip), float(dip_direction)
    (45.0, 0.0)
    """
    pole = to_lower_hemisphere(_as_vectors(vectors, "vectors"))
    horizontal = np.hypot(pole[..., 0], pole[..., 1])
    dip = np.degrees(np.arctan2(horizontal, -pole[..., 2]))
    return dip, _wrap360(np.where(horizontal == 0, 0.0, _azimuth(pole) + 180.0))


def dip_from_strike(strike_deg: ArrayLike, dip_deg: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Dip / dip direction from strike / dip by the right-hand rule.

    Parameters
    ----------
    strike_deg : float or array_like
        Strike in degrees clockwise from North, any finite real; the plane dips to the right when
        looking along the strike.
    dip_deg : float or array_like
        Dip in degrees, 0 <= dip <= 90.

    Returns
    -------
    dip_deg, dip_direction_deg : ndarray
        The dip (unchanged) and the dip direction strike + 90° in [0, 360).

    Examples
    --------
    >>> dip, dip_direction = dip_from_strike(0.0, 30.0)
    >>> float(dip), float(dip_direction)
    (30.0, 90.0)
    >>> [float(d) for d in dip_from_strike([300.0, -90.0], 60.0)[1]]
    [30.0, 0.0]
    """
    strike = _as_float_array(strike_deg, "strike_deg")
    dip = _as_angle_range(dip_deg, "dip_deg", 0.0, 90.0, "dip of a plane")
    strike, dip = np.broadcast_arrays(strike, dip)
    return dip.copy(), _wrap360(strike + 90.0)


def strike_from_dip(dip_direction_deg: ArrayLike) -> np.ndarray:
    """Right-hand-rule strike (dip direction - 90°, in [0, 360)) of planes given by dip direction.

    Examples
    --------
    >>> float(strike_from_dip(45.0))
    315.0
    """
    return _wrap360(_as_float_array(dip_direction_deg, "dip_direction_deg") - 90.0)


def pole_trend_plunge(dip_deg: ArrayLike, dip_direction_deg: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Trend and plunge of the lower-hemisphere pole: (dip direction + 180°, 90° - dip).

    Examples
    --------
    >>> trend, plunge = pole_trend_plunge(30.0, 300.0)
    >>> float(trend), float(plunge)
    (120.0, 60.0)
    """
    dip = _as_angle_range(dip_deg, "dip_deg", 0.0, 90.0, "dip of a plane")
    direction = _as_float_array(dip_direction_deg, "dip_direction_deg")
    dip, direction = np.broadcast_arrays(dip, direction)
    return _wrap360(direction + 180.0), 90.0 - dip


def dip_from_pole_trend_plunge(trend_deg: ArrayLike, plunge_deg: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Dip / dip direction of planes whose pole is given by trend / plunge.

    Parameters
    ----------
    trend_deg : float or array_like
        Trend of the pole, any finite real (mod 360).
    plunge_deg : float or array_like
        Plunge of the pole in [-90, 90] degrees, positive downward. A negative plunge (an upper
        hemisphere normal) is the same plane as the opposite, lower pole.

    Returns
    -------
    dip_deg, dip_direction_deg : ndarray
        dip = 90° - |plunge|; dip direction = trend + 180° for a downward pole, trend for an upward
        normal, in [0, 360).

    Examples
    --------
    >>> dip, dip_direction = dip_from_pole_trend_plunge(120.0, 60.0)
    >>> float(dip), float(dip_direction)
    (30.0, 300.0)
    """
    trend = _as_float_array(trend_deg, "trend_deg")
    plunge = _as_angle_range(plunge_deg, "plunge_deg", -90.0, 90.0, "positive downward")
    trend, plunge = np.broadcast_arrays(trend, plunge)
    return 90.0 - np.abs(plunge), _wrap360(np.where(plunge >= 0, trend + 180.0, trend))


# -- lines ---------------------------------------------------------------------------------------


def vector_from_trend_plunge(trend_deg: ArrayLike, plunge_deg: ArrayLike) -> np.ndarray:
    """Unit vector of lines given by trend / plunge (plunge positive downward).

    Parameters
    ----------
    trend_deg : float or array_like
        Trend τ in degrees clockwise from North, any finite real (taken mod 360).
    plunge_deg : float or array_like
        Plunge ρ in degrees, -90 <= ρ <= 90, positive downward.

    Returns
    -------
    (..., 3) ndarray of float64
        v = (cos ρ sin τ, cos ρ cos τ, -sin ρ).

    Examples
    --------
    >>> vector_from_trend_plunge(90.0, 0.0).round(12) + 0.0     # horizontal, due East
    array([1., 0., 0.])
    >>> vector_from_trend_plunge(0.0, 90.0).round(12) + 0.0     # straight down
    array([ 0.,  0., -1.])
    """
    trend = np.radians(_as_float_array(trend_deg, "trend_deg"))
    plunge = np.radians(_as_angle_range(plunge_deg, "plunge_deg", -90.0, 90.0, "positive downward"))
    trend, plunge = np.broadcast_arrays(trend, plunge)
    cos_plunge = np.cos(plunge)
    return np.stack([cos_plunge * np.sin(trend), cos_plunge * np.cos(trend), -np.sin(plunge)], axis=-1)


def trend_plunge_from_vector(vectors: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Trend and plunge of directed vectors (any non-zero length).

    Parameters
    ----------
    vectors : (..., 3) array_like
        Directions (normalised here). The sign is kept: an upward vector has a negative plunge. For
        the usual line (or pole) convention, apply :func:`to_lower_hemisphere` first.

    Returns
    -------
    trend_deg : ndarray
        Trend in [0, 360); 0 for a vertical vector.
    plunge_deg : ndarray
        Plunge in [-90, 90], positive downward.

    Examples
    --------
    >>> trend, plunge = trend_plunge_from_vector([1.0, 1.0, -np.sqrt(2.0)])
    >>> float(trend), float(plunge)
    (45.0, 45.0)
    """
    unit = _as_vectors(vectors, "vectors")
    horizontal = np.hypot(unit[..., 0], unit[..., 1])
    return _azimuth(unit), np.degrees(np.arctan2(-unit[..., 2], horizontal))


# -- axial helpers -------------------------------------------------------------------------------


def to_lower_hemisphere(vectors: ArrayLike) -> np.ndarray:
    """Flip vectors with z > 0 to their opposite, so every result has z <= 0.

    Parameters
    ----------
    vectors : (..., 3) array_like
        Any finite vectors (not normalised, zero allowed).

    Returns
    -------
    (..., 3) ndarray of float64
        A new array; horizontal vectors (z = 0 exactly) are kept as given.

    Examples
    --------
    >>> to_lower_hemisphere([[0.0, 1.0, 2.0], [1.0, 0.0, -1.0]])
    array([[-0., -1., -2.],
           [ 1.,  0., -1.]])
    """
    array = _as_float_array(vectors, "vectors")
    if array.ndim == 0 or array.shape[-1] != 3:
        raise ValueError(f"vectors must have shape (..., 3) (x East, y North, z Up), got {array.shape}")
    return np.where(array[..., 2:3] > 0, -array, array)


def angle_between(u: ArrayLike, v: ArrayLike, *, axial: bool = True) -> np.ndarray:
    """Angle between lines (axial, 0–90°) or directed vectors (0–180°), in degrees.

    Parameters
    ----------
    u, v : (..., 3) array_like
        Non-zero vectors (normalised here); they broadcast against each other. For planes, pass their
        normals or poles: the angle between two planes is the angle between their normals.
    axial : bool, default True
        True: u and -u are the same line, the result is in [0, 90]. False: directed, in [0, 180].

    Returns
    -------
    ndarray
        The angle in degrees.

    Notes
    -----
    Computed as atan2(|u × v|, u · v), which, unlike acos(u · v), keeps full precision for nearly
    parallel vectors.

    Examples
    --------
    >>> float(angle_between([0, 0, 1], [0, 0, -1]))
    0.0
    >>> float(angle_between([0, 0, 1], [0, 0, -1], axial=False))
    180.0
    >>> float(angle_between([1, 0, 0], [1, 1, 0]).round(12))
    45.0
    """
    a = _as_vectors(u, "u")
    b = _as_vectors(v, "v")
    dot = np.sum(a * b, axis=-1)
    cross = np.linalg.norm(np.cross(a, b), axis=-1)
    return np.degrees(np.arctan2(cross, np.abs(dot) if axial else dot))


def dip_text(dip_deg: float | None, dip_direction_deg: float | None) -> str:
    """A plane as geologists write it, dip / dip direction in whole degrees: ``"69/029"``.

    The one format of set orientations in every rockmass output (command lines and report), so
    that the same set reads the same everywhere (issue 19). ``"undefined"`` when either is None.

    Examples
    --------
    >>> dip_text(68.97, 29.02), dip_text(5.4, 359.7), dip_text(None, 10.0)
    ('69/029', '05/000', 'undefined')
    """
    if dip_deg is None or dip_direction_deg is None:
        return "undefined"
    dip = int(round(float(dip_deg)))
    direction = int(round(float(dip_direction_deg))) % 360
    return f"{dip:02d}/{direction:03d}"
