"""Stereology of fracture sets: C13 and C23, P10/P21 ↔ P32, Terzaghi weights and the joint P32 solve.

For a set of planar fractures with unit normals n and one-sided intensity P32 (area per volume), a
scanline of direction t and a sampling plane of normal m see ([Wan05]_)::

    P10(t) = P32 · E|n·t|             = P32 / C13(t)
    P21(m) = P32 · E[sqrt(1 - (n·m)²)] = P32 / C23(m)

whatever the fractures' sizes, shapes and positions. Isotropic orientations give C13 = 2 and
C23 = 4/π exactly; Fisher sets are integrated numerically here (docs/fractures.md §7.2 lists check values).

Functions take and return degrees and unit vectors in x = East, y = North, z = Up (docs/fractures.md §1.1).

References
----------
.. [Wan05] Wang, X. (2005). Stereological interpretation of rock fracture traces on borehole walls
   and other cylindrical surfaces. PhD thesis, Virginia Polytechnic Institute and State University.
   (C13 and C23 for Fisher sets, chapters 3-4.)
.. [Ter65] Terzaghi, R. D. (1965). Sources of error in joint surveys. Géotechnique 15(3), 287-304.
   doi:10.1680/geot.1965.15.3.287
.. [LH95] Lawson, C. L., Hanson, R. J. (1995). Solving Least Squares Problems. SIAM, ch. 23 (NNLS).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import i0e

from .orientation import _as_float_array, _as_nonnegative as _nonnegative, _as_scalar, _as_vectors

__all__ = [
    "C13_ISOTROPIC",
    "C23_ISOTROPIC",
    "P32Solution",
    "c13",
    "c13_from_angle",
    "c23",
    "c23_from_angle",
    "p10_from_p32",
    "p21_from_p32",
    "p32_from_p10",
    "p32_from_p21",
    "solve_p32",
    "terzaghi_weights",
]

#: C13 of isotropic (uniform) orientations: 1 / E|cos δ| = 1 / (1/2).
C13_ISOTROPIC = 2.0
#: C23 of isotropic orientations: 1 / E[sin ψ] = 1 / (π/4).
C23_ISOTROPIC = 4.0 / np.pi

# Quadrature: the angle ψ in [0, π] is cut at β (the density's peak) and π/2 (the kink of |cos ψ|)
# into three panels of _GAUSS_NODES Gauss-Legendre nodes each. Measured against closed forms at
# β = 0 and 90° and against independent quadratures in the mean pole's frame (tests/dfn/
# test_stereology.py): relative error < 1e-9 for κ from 1e-6 to 1e8.
_GAUSS_NODES = 32
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(_GAUSS_NODES)
#: The integration range stops where the Fisher factor exp(-κ(1 - cos(ψ - β))) falls below e^-60
#: (~1e-26 of its peak): the neglected mass is < κ·π·e^-60, below 1e-16 for κ < 1e9.
_TAIL_EXPONENT = 60.0


def _fisher_expectations(beta: np.ndarray, kappa: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """E|cos ψ| and E[sin ψ], ψ the angle between a Fisher(κ) vector and an axis at β from the mean.

    ``beta`` (radians, in [0, π/2]) and ``kappa`` (> 0) are 1-d arrays of equal length.

    Rotating the sphere so that the axis is the pole, with ψ its polar angle and χ the azimuth
    about it, n·μ = cos ψ cos β + sin ψ sin β cos χ. The χ-integral of the Fisher density is
    ∫ exp(κ sin ψ sin β cos χ) dχ = 2π I0(κ sin ψ sin β), so the density of ψ is::

        p(ψ) = κ/(1 - e^(-2κ)) · exp(-κ (1 - cos(ψ - β))) · i0e(κ sin ψ sin β) · sin ψ

    with i0e(z) = e^(-z) I0(z): every factor is bounded, nothing overflows for any κ, and p is smooth
    on [0, π]. E[g] = ∫ g p dψ / ∫ p dψ (self-normalised, so the constant cancels and the truncation
    of the tails cancels to first order). |cos ψ| has a kink at π/2, hence the panel edge there.
    """
    half_width = np.where(kappa > _TAIL_EXPONENT / 2.0,
                          2.0 * np.arcsin(np.sqrt(np.minimum(_TAIL_EXPONENT / (2.0 * kappa), 1.0))), np.pi)
    low = np.maximum(beta - half_width, 0.0)
    high = np.minimum(beta + half_width, np.pi)
    edges = np.sort(np.stack([low, np.clip(beta, low, high), np.clip(np.pi / 2.0, low, high), high],
                             axis=1), axis=1)                                      # (m, 4)
    start = edges[:, :-1, None]
    length = (edges[:, 1:] - edges[:, :-1])[:, :, None]                            # (m, 3, 1)
    psi = (start + length * (_NODES + 1.0) / 2.0).reshape(beta.size, -1)           # (m, 3 * nodes)
    weight = (length * _WEIGHTS / 2.0).reshape(beta.size, -1)
    b = beta[:, None]
    k = kappa[:, None]
    density = (np.exp(-2.0 * k * np.sin((psi - b) / 2.0) ** 2)
               * i0e(k * np.sin(psi) * np.sin(b)) * np.sin(psi) * weight)
    total = density.sum(axis=1)
    return (np.abs(np.cos(psi)) * density).sum(axis=1) / total, (np.sin(psi) * density).sum(axis=1) / total


def _constant_from_angle(angle_deg: ArrayLike, kappa: ArrayLike, which: int) -> np.ndarray:
    """C13 (which = 0) or C23 (which = 1) on the broadcast of ``angle_deg`` and ``kappa``."""
    angle = _as_float_array(angle_deg, "angle_deg")
    k = _nonnegative(kappa, "kappa", "Fisher concentration")
    angle, k = np.broadcast_arrays(angle, k)
    # Axial: an axis at β, 180 - β, -β or β + 360 sees the same distribution of |cos ψ| and sin ψ.
    folded = np.radians(np.mod(angle, 180.0))
    beta = np.minimum(folded, np.pi - folded).ravel()
    flat_k = k.ravel()
    result = np.full(beta.size, C13_ISOTROPIC if which == 0 else C23_ISOTROPIC)
    fisher = flat_k > 0
    if fisher.any():
        expectations = _fisher_expectations(beta[fisher], flat_k[fisher])
        result[fisher] = 1.0 / expectations[which]
    return result.reshape(angle.shape)


def c13_from_angle(angle_deg: ArrayLike, kappa: ArrayLike) -> np.ndarray:
    """C13 = 1 / E|cos δ| of a Fisher set for a line at ``angle_deg`` from the set's mean pole.

    Parameters
    ----------
    angle_deg : float or array_like
        Angle β between the scanline and the mean pole, degrees (any real; β and 180 - β are the
        same axis).
    kappa : float or array_like
        Fisher concentration κ >= 0 (0: isotropic); broadcasts with ``angle_deg``.

    Returns
    -------
    ndarray
        C13 >= 1, so that P10 = P32 / C13. κ = 0 gives exactly 2.

    Notes
    -----
    E|n·t| = ∫ |cos ψ| p(ψ) dψ with p the density of the angle ψ between a Fisher vector and the line
    (after integrating the azimuth in closed form, a Bessel function I0), by Gauss-Legendre
    quadrature; relative accuracy better than 1e-9 for 1e-6 <= κ <= 1e8. Closed forms used as test
    oracles: β = 0: E|cos ψ| = (κ ∫|x| e^(κx) dx)/(2 sinh κ); β = 90°: E|cos ψ| = (2/π) E[sin θ]
    = 2 i1e(κ)/(1 - e^(-2κ)). Check values ([Wan05]_, docs/fractures.md §7.2): κ = 10: 0° → 1.111,
    30° → 1.283, 60° → 2.145, 90° → 4.123.

    Examples
    --------
    >>> float(c13_from_angle(45.0, 0.0))
    2.0
    >>> c13_from_angle([0.0, 30.0, 60.0, 90.0], 10.0).round(3)
    array([1.111, 1.283, 2.145, 4.123])
    """
    return _constant_from_angle(angle_deg, kappa, 0)


def c23_from_angle(angle_deg: ArrayLike, kappa: ArrayLike) -> np.ndarray:
    """C23 = 1 / E[sin ψ] of a Fisher set for a plane whose normal is at ``angle_deg`` from the mean pole.

    Parameters
    ----------
    angle_deg : float or array_like
        Angle β between the sampling plane's normal and the set's mean pole, degrees (any real).
    kappa : float or array_like
        Fisher concentration κ >= 0 (0: isotropic); broadcasts with ``angle_deg``.

    Returns
    -------
    ndarray
        C23 >= 1, so that P21 = P32 / C23. κ = 0 gives exactly 4/π.

    Notes
    -----
    Same quadrature as :func:`c13_from_angle` with sin ψ (ψ the angle between a fracture normal and
    the plane's normal) in place of |cos ψ|. Closed form at β = 0 (test oracle):
    E[sin θ] = π i1e(κ)/(1 - e^(-2κ)). Check values ([Wan05]_, docs/fractures.md §7.2): κ = 10:
    0° → 2.625, 30° → 1.776, 60° → 1.191, 90° → 1.051.

    Examples
    --------
    >>> round(float(c23_from_angle(0.0, 0.0)), 6)
    1.27324
    >>> c23_from_angle([0.0, 30.0, 60.0, 90.0], 10.0).round(3)
    array([2.625, 1.776, 1.191, 1.051])
    """
    return _constant_from_angle(angle_deg, kappa, 1)


def _angle_to_mean(vectors: ArrayLike, mean_pole: ArrayLike | None, kappa: float, name: str) -> np.ndarray:
    """Angle in degrees between ``vectors`` and ``mean_pole`` (0 where κ = 0 and no mean is given)."""
    unit = _as_vectors(vectors, name)
    if mean_pole is None:
        if kappa != 0:
            raise ValueError("mean_pole is required when kappa > 0 (a Fisher set has a mean pole)")
        return np.zeros(unit.shape[:-1])
    mean = _as_vectors(mean_pole, "mean_pole")
    cos_angle = np.abs(np.sum(unit * mean, axis=-1))
    sin_angle = np.linalg.norm(np.cross(unit, mean), axis=-1)
    return np.degrees(np.arctan2(sin_angle, cos_angle))


def c13(line_directions: ArrayLike, mean_pole: ArrayLike | None = None, kappa: float = 0.0) -> np.ndarray:
    """C13 of one fracture set for scanlines of the given directions.

    Parameters
    ----------
    line_directions : (..., 3) array_like
        Scanline directions (normalised here; either sense).
    mean_pole : (3,) array_like, optional
        The set's mean pole (either sign); required when ``kappa > 0``.
    kappa : float, default 0.0
        Fisher concentration κ >= 0 (0: isotropic).

    Returns
    -------
    ndarray of shape ``line_directions.shape[:-1]``
        C13, see :func:`c13_from_angle`.

    Examples
    --------
    >>> float(c13([0.0, 0.0, 1.0]))
    2.0
    >>> round(float(c13([0.0, 0.0, 1.0], mean_pole=[0.0, 0.0, -1.0], kappa=50.0)), 3)
    1.02
    """
    k = _as_scalar(kappa, "kappa", low=0.0, what="Fisher concentration")
    return c13_from_angle(_angle_to_mean(line_directions, mean_pole, k, "line_directions"), k)


def c23(face_normals: ArrayLike, mean_pole: ArrayLike | None = None, kappa: float = 0.0) -> np.ndarray:
    """C23 of one fracture set for sampling planes with the given normals.

    Parameters
    ----------
    face_normals : (..., 3) array_like
        Normals of the sampling planes (faces, outcrops, sections; normalised here; either sign).
    mean_pole : (3,) array_like, optional
        The set's mean pole (either sign); required when ``kappa > 0``.
    kappa : float, default 0.0
        Fisher concentration κ >= 0 (0: isotropic).

    Returns
    -------
    ndarray of shape ``face_normals.shape[:-1]``
        C23, see :func:`c23_from_angle`.

    Examples
    --------
    >>> round(float(c23([1.0, 0.0, 0.0], mean_pole=[0.0, 0.0, -1.0], kappa=50.0)), 3)
    1.01
    """
    k = _as_scalar(kappa, "kappa", low=0.0, what="Fisher concentration")
    return c23_from_angle(_angle_to_mean(face_normals, mean_pole, k, "face_normals"), k)


def _as_constant(value: ArrayLike, name: str) -> np.ndarray:
    array = _as_float_array(value, name)
    if (array < 1).any():
        raise ValueError(f"{name} must be >= 1 (C13 = 1/E|cos delta| and C23 = 1/E[sin psi] are at least 1), "
                         f"got {array[array < 1].ravel()[:10].tolist()}")
    return array


def p10_from_p32(p32: ArrayLike, c13_value: ArrayLike) -> np.ndarray:
    """P10 = P32 / C13 (1/m): expected intersections per metre of scanline.

    Examples
    --------
    >>> float(p10_from_p32(2.0, 2.0))
    1.0
    """
    return _nonnegative(p32, "p32", "fracture area per volume, m²/m³") / _as_constant(c13_value, "c13_value")


def p32_from_p10(p10: ArrayLike, c13_value: ArrayLike) -> np.ndarray:
    """P32 = C13 · P10 (m²/m³, one-sided) from intersections per metre of scanline.

    Examples
    --------
    >>> float(p32_from_p10(1.0, 2.0))
    2.0
    """
    return _nonnegative(p10, "p10", "intersections per metre") * _as_constant(c13_value, "c13_value")


def p21_from_p32(p32: ArrayLike, c23_value: ArrayLike) -> np.ndarray:
    """P21 = P32 / C23 (m/m²): expected trace length per unit area of a sampling plane.

    Examples
    --------
    >>> round(float(p21_from_p32(1.0, 4.0 / np.pi)), 6)
    0.785398
    """
    return _nonnegative(p32, "p32", "fracture area per volume, m²/m³") / _as_constant(c23_value, "c23_value")


def p32_from_p21(p21: ArrayLike, c23_value: ArrayLike) -> np.ndarray:
    """P32 = C23 · P21 (m²/m³, one-sided) from trace length per unit area.

    Examples
    --------
    >>> float(p32_from_p21(0.5, 2.0))
    1.0
    """
    return _nonnegative(p21, "p21", "trace length per area, m/m²") * _as_constant(c23_value, "c23_value")


def terzaghi_weights(poles: ArrayLike, line_direction: ArrayLike, min_angle_deg: float = 15.0) -> np.ndarray:
    """Terzaghi weights 1/|cos δ| of fractures hit by a scanline, capped for sub-parallel planes.

    Parameters
    ----------
    poles : (N, 3) array_like or (3,) array_like
        Normals of the intersected fractures (either sign, normalised here).
    line_direction : (3,) array_like
        Direction of the scanline (either sense).
    min_angle_deg : float, default 15.0
        Blind-zone half-angle γ, 0 < γ < 90: a plane at less than γ to the line (δ > 90° - γ) gets the
        weight of a plane at exactly γ, so the largest weight is 1 / sin γ (3.86 at 15°).

    Returns
    -------
    ndarray of shape ``poles.shape[:-1]``
        w = 1 / max(|cos δ|, sin γ), δ the angle between the pole and the line ([Ter65]_). The
        weighted count Σ w / L over a line of length L (the Terzaghi-corrected P10) estimates P32:
        a fracture is hit with probability ∝ |cos δ|, and the weight undoes that.

    Notes
    -----
    The weight diverges as δ → 90° (planes sub-parallel to the line are rarely hit). The cap trades
    that variance for a bias: it undercounts the sub-parallel planes and biases P32 low (up to about
    24 % with a 15° cap, docs/fractures.md §6). Several scanline orientations with :func:`solve_p32`, or a
    model C13 from the fitted orientation distribution, avoid the bias.

    Examples
    --------
    >>> terzaghi_weights([[0, 0, 1], [1, 0, 1], [1, 0, 0]], [0, 0, 1]).round(4)
    array([1.    , 1.4142, 3.8637])
    """
    unit = _as_vectors(poles, "poles")
    line = _as_vectors(line_direction, "line_direction")
    if line.shape != (3,):
        raise ValueError(f"line_direction must be one vector of shape (3,), got {line.shape}")
    gamma = _as_scalar(min_angle_deg, "min_angle_deg", low=0.0, low_open=True, high=90.0,
                       what="blind-zone angle between plane and line, 0 < angle < 90")
    if gamma == 90.0:
        raise ValueError("min_angle_deg must be < 90 (blind-zone angle between plane and line), got 90.0")
    return 1.0 / np.maximum(np.abs(unit @ line), np.sin(np.radians(gamma)))


@dataclass(frozen=True)
class P32Solution:
    """P32 per set from several scanlines and faces (see :func:`solve_p32`).

    Attributes
    ----------
    p32 : (n_sets,) ndarray
        One-sided P32 per set, m²/m³, >= 0.
    sd : (n_sets,) ndarray
        Standard deviation of each P32 (linearised, see :func:`solve_p32`); NaN when the observations
        carry no uncertainty.
    covariance : (n_sets, n_sets) ndarray
        Covariance of ``p32`` (NaN without uncertainties).
    design : (n_obs, n_sets) ndarray
        The linear model: row k holds 1/C13_s(t_k) (lines first) or 1/C23_s(m_j) (faces).
    observed, predicted : (n_obs,) ndarray
        The P10 then P21 values given, and the model's values at ``p32``.
    chi2 : float
        Σ ((predicted - observed)/σ)²; NaN without uncertainties.
    dof : int
        Degrees of freedom n_obs - n_sets (chi2/dof ≈ 1 when the model and the error model hold).
    at_bound : (n_sets,) ndarray of bool
        Sets whose P32 the non-negativity constraint holds at 0.
    """

    p32: np.ndarray
    sd: np.ndarray
    covariance: np.ndarray
    design: np.ndarray
    observed: np.ndarray
    predicted: np.ndarray
    chi2: float
    dof: int
    at_bound: np.ndarray


def _observations(directions: ArrayLike | None, values: ArrayLike | None, counts: ArrayLike | None,
                  sd: ArrayLike | None, names: tuple[str, str, str, str]) -> tuple:
    """Validate one kind of observation (lines or faces): unit vectors, values and their sd."""
    direction_name, value_name, count_name, sd_name = names
    if directions is None and values is None:
        if counts is not None or sd is not None:
            raise ValueError(f"{count_name} / {sd_name} given without {direction_name} and {value_name}")
        return np.empty((0, 3)), np.empty(0), None
    if directions is None or values is None:
        raise ValueError(f"{direction_name} and {value_name} must be given together")
    unit = _as_vectors(directions, direction_name).reshape(-1, 3)
    observed = _nonnegative(values, value_name, "observed intensity").ravel()
    if observed.size != unit.shape[0]:
        raise ValueError(f"{value_name} must hold one value per row of {direction_name}: "
                         f"{observed.size} values for {unit.shape[0]} directions")
    if counts is not None and sd is not None:
        raise ValueError(f"give {count_name} or {sd_name}, not both")
    sigma = None
    if counts is not None:
        n = _nonnegative(counts, count_name, "number of intersections or traces").ravel()
        if n.size != observed.size:
            raise ValueError(f"{count_name} must hold one count per value of {value_name}: "
                             f"{n.size} for {observed.size}")
        zero = np.flatnonzero(n < 1)
        if zero.size:
            raise ValueError(f"{count_name} must be >= 1 for a Poisson standard deviation, got 0 at "
                             f"indices {zero[:10].tolist()}; give {sd_name} for those observations")
        sigma = observed / np.sqrt(n)
    elif sd is not None:
        sigma = _nonnegative(sd, sd_name, "standard deviation").ravel()
        if sigma.size != observed.size:
            raise ValueError(f"{sd_name} must hold one value per value of {value_name}: "
                             f"{sigma.size} for {observed.size}")
    if sigma is not None and (sigma <= 0).any():
        raise ValueError(f"{sd_name if counts is None else value_name} must give a standard deviation "
                         f"> 0 for every observation (indices {np.flatnonzero(sigma <= 0)[:10].tolist()})")
    return unit, observed, sigma


def solve_p32(mean_poles: ArrayLike, kappas: ArrayLike, *,
              line_directions: ArrayLike | None = None, p10: ArrayLike | None = None,
              p10_counts: ArrayLike | None = None, p10_sd: ArrayLike | None = None,
              face_normals: ArrayLike | None = None, p21: ArrayLike | None = None,
              p21_counts: ArrayLike | None = None, p21_sd: ArrayLike | None = None,
              max_condition: float = 1e10) -> P32Solution:
    """P32 of every set at once from scanline P10 and face P21 values, by non-negative least squares.

    Parameters
    ----------
    mean_poles : (n_sets, 3) array_like
        Mean pole of each set (either sign; ignored for a set with κ = 0).
    kappas : (n_sets,) array_like
        Fisher concentration of each set, >= 0.
    line_directions : (n_lines, 3) array_like, optional
        Scanline directions.
    p10 : (n_lines,) array_like, optional
        Observed P10 of each scanline, all sets together (1/m), >= 0.
    p10_counts : (n_lines,) array_like, optional
        Number of intersections N_k behind each P10 (>= 1): σ_k = P10_k / sqrt(N_k).
    p10_sd : (n_lines,) array_like, optional
        Standard deviations of P10 given directly (> 0), instead of ``p10_counts``.
    face_normals : (n_faces, 3) array_like, optional
        Normals of the sampled faces.
    p21 : (n_faces,) array_like, optional
        Observed P21 of each face, all sets together (m/m²), >= 0.
    p21_counts : (n_faces,) array_like, optional
        Number of traces M_j behind each P21 (>= 1): σ_j = P21_j / sqrt(M_j).
    p21_sd : (n_faces,) array_like, optional
        Standard deviations of P21 given directly (> 0), instead of ``p21_counts``.
    max_condition : float, default 1e10
        Largest condition number of the (weighted) design matrix accepted; above it the observations
        cannot tell the sets apart and a ValueError says so.

    Returns
    -------
    P32Solution

    Raises
    ------
    ValueError
        Bad shapes or values (the message names the argument), fewer observations than sets, or
        observation directions that cannot separate the sets (rank-deficient design).

    Notes
    -----
    Model (docs/fractures.md §7.3, eq. (7.4); [Wan05]_):
    P10_k = Σ_s P32_s / C13_s(t_k), P21_j = Σ_s P32_s / C23_s(m_j),
    i.e. d = A x with x = P32 per set. Each row is divided by its σ and
    min ||W(A x - d)||, x >= 0 is solved by NNLS ([LH95]_, :func:`scipy.optimize.nnls`).

    Error model: the intersections on a scanline of length L are Poisson with mean P10·L, so
    sd(P10) = P10/sqrt(N) (relative 1/sqrt(N)); for a face the trace count is Poisson and the trace
    lengths are taken as known, so sd(P21) = P21/sqrt(M) (length scatter would add a factor
    sqrt(1 + CV²) of the trace lengths: pass ``p21_sd`` to include it). Observations are taken as
    independent. σ comes from the observed counts (Neyman's χ²), which slightly favours low
    observations when counts are few: aim for >= 20 counts per observation. The covariance of x is the linearised (AᵀW²A)⁻¹ of the unconstrained problem; for
    a set held at 0 by the constraint it over-states the uncertainty (conservative). Without counts
    or sd the rows get unit weight and ``sd``, ``covariance`` and ``chi2`` are NaN.

    Examples
    --------
    Two perpendicular Fisher sets, three orthogonal scanlines:

    >>> poles = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]
    >>> lines = np.eye(3)
    >>> truth = np.array([1.0, 2.0])
    >>> p10 = sum(truth[s] / c13(lines, poles[s], 20.0) for s in range(2))
    >>> fit = solve_p32(poles, [20.0, 20.0], line_directions=lines, p10=p10, p10_counts=[400, 400, 400])
    >>> fit.p32.round(9)
    array([1., 2.])
    """
    poles = _as_vectors(mean_poles, "mean_poles")
    if poles.ndim != 2 or poles.shape[0] == 0:
        raise ValueError(f"mean_poles must be an (n_sets, 3) array with n_sets >= 1, got {poles.shape}")
    kappa = _nonnegative(kappas, "kappas", "Fisher concentration of each set").ravel()
    if kappa.size != poles.shape[0]:
        raise ValueError(f"kappas must hold one value per set: {kappa.size} for {poles.shape[0]} mean_poles")
    condition_limit = _as_scalar(max_condition, "max_condition", low=1.0)
    lines, p10_values, p10_sigma = _observations(line_directions, p10, p10_counts, p10_sd,
                                                 ("line_directions", "p10", "p10_counts", "p10_sd"))
    faces, p21_values, p21_sigma = _observations(face_normals, p21, p21_counts, p21_sd,
                                                 ("face_normals", "p21", "p21_counts", "p21_sd"))
    n_sets = poles.shape[0]
    observed = np.concatenate([p10_values, p21_values])
    if observed.size < n_sets:
        raise ValueError(f"{observed.size} observations (p10 and p21 values) cannot determine P32 of "
                         f"{n_sets} sets: give at least {n_sets} scanlines or faces")
    weighted = p10_sigma is not None or p21_sigma is not None
    if weighted and ((p10_values.size and p10_sigma is None) or (p21_values.size and p21_sigma is None)):
        raise ValueError("give uncertainties (counts or sd) for both the p10 and the p21 values, or for "
                         "neither")
    design = np.empty((observed.size, n_sets))
    for s in range(n_sets):
        mean = poles[s] if kappa[s] > 0 else None
        design[:p10_values.size, s] = 1.0 / c13(lines, mean, float(kappa[s]))
        design[p10_values.size:, s] = 1.0 / c23(faces, mean, float(kappa[s]))
    sigma = (np.concatenate([p10_sigma if p10_sigma is not None else np.empty(0),
                             p21_sigma if p21_sigma is not None else np.empty(0)])
             if weighted else np.ones(observed.size))
    a = design / sigma[:, None]
    singular = np.linalg.svd(a, compute_uv=False)
    if singular[-1] <= singular[0] / condition_limit:
        raise ValueError(f"the scanline and face orientations cannot separate the {n_sets} sets "
                         f"(design condition number {singular[0] / max(singular[-1], 1e-300):.3g} > "
                         f"max_condition {condition_limit:g}): add scanlines or faces in other directions")
    from scipy.optimize import nnls  # scipy.optimize is slow to import; only the solve needs it

    p32, _ = nnls(a, observed / sigma)
    predicted = design @ p32
    if weighted:
        covariance = np.linalg.inv(a.T @ a)
        chi2 = float(np.sum(((predicted - observed) / sigma) ** 2))
    else:
        covariance = np.full((n_sets, n_sets), np.nan)
        chi2 = float("nan")
    return P32Solution(
        p32=p32,
        sd=np.sqrt(np.diag(covariance)),
        covariance=covariance,
        design=design,
        observed=observed,
        predicted=predicted,
        chi2=chi2,
        dof=int(observed.size - n_sets),
        at_bound=p32 <= 0,
    )
