"""The Fisher distribution of poles: sampling, density, fitting, confidence and variability cones.

A Fisher set about the unit mean pole μ with concentration κ >= 0 has the density, per steradian,

    f(n) = κ / (2π (1 - e^(-2κ))) · exp(κ (μ·n - 1))        (κ = 0: 1 / (4π), uniform)

written with exp(κ(μ·n − 1)) rather than the textbook κ e^(κ μ·n) / (4π sinh κ) so that nothing
overflows for large κ. The angle θ between n and μ then has

    CDF  F(θ) = (1 - e^(-κ (1 - cos θ))) / (1 - e^(-2κ))       (κ = 0: (1 - cos θ) / 2)

and φ, the azimuth about μ, is uniform. Poles are axial (n and -n are the same plane), so fitting
works with the orientation tensor (:func:`fit_fisher`).

Functions take and return degrees and ``(..., 3) float64`` unit vectors in x = East, y = North,
z = Up (docs/fractures.md §1.1). Random draws use a caller-owned :class:`numpy.random.Generator`.

References
----------
.. [Fis53] Fisher, R. A. (1953). Dispersion on a sphere. Proceedings of the Royal Society of London
   A 217, 295-305. doi:10.1098/rspa.1953.0064
.. [Woo94] Wood, A. T. A. (1994). Simulation of the von Mises Fisher distribution. Communications
   in Statistics - Simulation and Computation 23(1), 157-164. doi:10.1080/03610919408813161
.. [Duf17] Duff, T., Burgess, J., Christensen, P., Hery, C., Kensler, A., Liani, M., Villemin, R.
   (2017). Building an orthonormal basis, revisited. Journal of Computer Graphics Techniques 6(1),
   1-8.
.. [Fis87] Fisher, N. I., Lewis, T., Embleton, B. J. J. (1987). Statistical Analysis of Spherical
   Data. Cambridge University Press. (orientation tensor, §3.2.4; κ estimate, §5.3.2)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .orientation import (
    _as_angle_range,
    _as_nonnegative,
    _as_scalar,
    _as_vectors,
    dip_from_normal,
    to_lower_hemisphere,
)

__all__ = [
    "FisherFit",
    "confidence_cone",
    "fisher_angle_cdf",
    "fisher_angle_pdf",
    "fisher_density",
    "fit_fisher",
    "orientation_tensor",
    "sample_fisher",
    "variability_cone",
]

#: Below this κ the sampler uses the κ = 0 (uniform) branch cos θ = 2u - 1. The exact density
#: differs from uniform by a factor e^(κ(cos θ - 1))·2κ/(1 - e^(-2κ)) = 1 + O(κ), so the branch
#: changes the distribution by less than 1e-12 (far below anything a sample can resolve), and it
#: keeps (1 - u)·expm1(-2κ) away from subnormal numbers.
_KAPPA_UNIFORM = 1e-12


def _check_kappa(kappa: ArrayLike) -> np.ndarray:
    """κ as a float64 array with every entry finite and >= 0."""
    return _as_nonnegative(kappa, "kappa", "Fisher concentration")


def _one_minus_cos_quantile(q: np.ndarray, kappa: np.ndarray) -> np.ndarray:
    """1 - cos θ at which the Fisher angle CDF equals ``q`` (0 <= q <= 1).

    From F(θ) = q: 1 - cos θ = -ln(1 - q (1 - e^(-2κ))) / κ = -log1p(q · expm1(-2κ)) / κ, which
    is exact to rounding for every κ > 0: log1p/expm1 keep the small-κ case (where the argument is
    ~ -2κq) accurate and nothing overflows for large κ. κ < 1e-12: the uniform limit 2q.
    """
    small = kappa < _KAPPA_UNIFORM
    safe = np.where(small, 1.0, kappa)
    value = -np.log1p(q * np.expm1(-2.0 * safe)) / safe
    return np.clip(np.where(small, 2.0 * q, value), 0.0, 2.0)


def _orthonormal_basis(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors e1, e2 with (e1, e2, axis) a right-handed orthonormal basis.

    The branch-free construction of [Duf17]_ (listing 3): no division by a small number for any unit
    axis, including ±z, and continuous except across the plane z = 0 where the sign switches.
    """
    x, y, z = axis
    sign = 1.0 if z >= 0 else -1.0
    a = -1.0 / (sign + z)
    b = x * y * a
    e1 = np.array([1.0 + sign * x * x * a, sign * b, -sign * x])
    e2 = np.array([b, sign + y * y * a, -y])
    return e1, e2


def sample_fisher(rng: np.random.Generator, mean_pole: ArrayLike, kappa: float, n: int) -> np.ndarray:
    """Draw unit vectors from the Fisher distribution about ``mean_pole``; stable for every κ >= 0.

    Parameters
    ----------
    rng : numpy.random.Generator
        Source of randomness (give each fracture set its own ``SeedSequence`` child, docs/fractures.md §11.2).
        Exactly two uniforms per vector are drawn, in the order (q for all vectors, u for all).
    mean_pole : (3,) array_like
        Mean direction μ, any non-zero length (normalised here); either hemisphere.
    kappa : float
        Concentration κ >= 0 (0: uniform on the sphere). Any finite value works, up to 1e300.
    n : int
        Number of vectors, n >= 0.

    Returns
    -------
    (n, 3) ndarray of float64
        Unit vectors distributed about μ itself (not folded to the lower hemisphere: for poles use
        :func:`~rockmass.dfn.orientation.to_lower_hemisphere`, the same planes).

    Notes
    -----
    With q and u uniform on [0, 1) ([Woo94]_, in a form stable for all κ; docs/fractures.md §3.1,
    eq. (3.3))::

        1 - cos θ = -log1p(q · expm1(-2κ)) / κ     (= -ln(1 - q + q e^(-2κ)) / κ)
        φ = 2π u,   sin θ = sqrt((1 - cos θ)(1 + cos θ))

    Limit cases: κ → 0 gives 1 - cos θ → 2q smoothly through log1p/expm1, and κ < 1e-12
    takes that uniform branch exactly (the textbook form κ⁻¹ ln(e^κ - u (e^κ - e^-κ)) is 0/0 at κ = 0);
    large κ never forms e^κ (overflow for κ > 709 in the textbook form), and working with 1 - cos θ
    instead of cos θ keeps sin θ accurate when θ ~ κ^(-1/2) is tiny. The vector
    (sin θ cos φ, sin θ sin φ, cos θ) about +z is then mapped onto μ with the orthonormal basis of
    [Duf17]_, which has no singular direction (μ = ±z included).

    Examples
    --------
    >>> rng = np.random.default_rng(42)
    >>> poles = sample_fisher(rng, [0.0, 0.0, -1.0], kappa=1e8, n=3)
    >>> np.allclose(poles, [0.0, 0.0, -1.0], atol=1e-3)
    True
    """
    if not isinstance(rng, np.random.Generator):
        raise TypeError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    mean = _as_vectors(mean_pole, "mean_pole")
    if mean.shape != (3,):
        raise ValueError(f"mean_pole must be one vector of shape (3,), got {mean.shape}")
    kappa_value = _as_scalar(kappa, "kappa", low=0.0, what="Fisher concentration")
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
        raise TypeError(f"n must be an integer, got {n!r}")
    if n < 0:
        raise ValueError(f"n must be >= 0 (number of vectors), got {n}")
    q = rng.random(n)  # [0, 1): q < 1 keeps the logarithm finite even when expm1(-2κ) rounds to -1
    u = rng.random(n)
    one_minus_cos = _one_minus_cos_quantile(q, np.float64(kappa_value))
    cos_theta = 1.0 - one_minus_cos
    sin_theta = np.sqrt(one_minus_cos * (2.0 - one_minus_cos))
    phi = 2.0 * np.pi * u
    e1, e2 = _orthonormal_basis(mean)
    out = (sin_theta * np.cos(phi))[:, None] * e1 + (sin_theta * np.sin(phi))[:, None] * e2 \
        + cos_theta[:, None] * mean
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def _normaliser(kappa: np.ndarray) -> np.ndarray:
    """κ / (1 - e^(-2κ)), with its κ → 0 limit 1/2 (it is >= 1/2 and ~κ for large κ)."""
    small = kappa < _KAPPA_UNIFORM
    safe = np.where(small, 1.0, kappa)
    return np.where(small, 0.5, safe / -np.expm1(-2.0 * safe))


def fisher_density(vectors: ArrayLike, mean_pole: ArrayLike, kappa: ArrayLike) -> np.ndarray:
    """Fisher probability density per steradian at unit vectors ``vectors``.

    Parameters
    ----------
    vectors : (..., 3) array_like
        Directions (normalised here).
    mean_pole : (..., 3) array_like
        Mean direction μ (normalised here); broadcasts with ``vectors``.
    kappa : float or array_like
        Concentration κ >= 0.

    Returns
    -------
    ndarray
        f = κ exp(κ (μ·n - 1)) / (2π (1 - e^(-2κ))), per steradian; 1/(4π) for κ = 0. The density
        is directional: for axial data (poles of either sign) add the density at -n.

    Examples
    --------
    >>> float(fisher_density([0, 0, 1], [0, 0, 1], 0.0) * 4 * np.pi)
    1.0
    """
    n = _as_vectors(vectors, "vectors")
    mean = _as_vectors(mean_pole, "mean_pole")
    k = _check_kappa(kappa)
    cos_angle = np.clip(np.sum(n * mean, axis=-1), -1.0, 1.0)
    return _normaliser(k) * np.exp(k * (cos_angle - 1.0)) / (2.0 * np.pi)


def fisher_angle_pdf(theta_deg: ArrayLike, kappa: ArrayLike) -> np.ndarray:
    """Density of the angle θ between a Fisher vector and the mean, per degree.

    Parameters
    ----------
    theta_deg : float or array_like
        Angle in degrees, 0 <= θ <= 180.
    kappa : float or array_like
        Concentration κ >= 0; broadcasts with ``theta_deg``.

    Returns
    -------
    ndarray
        g(θ) = κ sin θ exp(-κ (1 - cos θ)) / (1 - e^(-2κ)) · π/180 (κ = 0: sin θ / 2 · π/180), so
        that it integrates to 1 over 0–180 degrees.

    Examples
    --------
    >>> float(fisher_angle_pdf(90.0, 0.0) * 180 / np.pi)
    0.5
    """
    theta, one_minus_cos, k = _angle_terms(theta_deg, kappa)
    return _normaliser(k) * np.sin(theta) * np.exp(-k * one_minus_cos) * (np.pi / 180.0)


def _angle_terms(theta_deg: ArrayLike, kappa: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Validated θ (radians), 1 - cos θ = 2 sin²(θ/2) (exact for small θ, unlike 1 - cos θ) and κ."""
    theta = np.radians(_as_angle_range(theta_deg, "theta_deg", 0.0, 180.0, "angle from the mean pole"))
    return theta, 2.0 * np.sin(theta / 2.0) ** 2, _check_kappa(kappa)


def fisher_angle_cdf(theta_deg: ArrayLike, kappa: ArrayLike) -> np.ndarray:
    """Probability that a Fisher vector lies within θ of the mean.

    Parameters are those of :func:`fisher_angle_pdf`.

    Returns
    -------
    ndarray
        F(θ) = (1 - e^(-κ(1 - cos θ))) / (1 - e^(-2κ)), evaluated as expm1(-κ(1 - cos θ)) / expm1(-2κ)
        with 1 - cos θ = 2 sin²(θ/2) (accurate for tiny θ and tiny κ); κ = 0: (1 - cos θ)/2.

    Examples
    --------
    >>> round(float(fisher_angle_cdf(90.0, 0.0)), 12)
    0.5
    >>> float(fisher_angle_cdf(180.0, 1e4))
    1.0
    """
    _, one_minus_cos, k = _angle_terms(theta_deg, kappa)
    small = k < _KAPPA_UNIFORM
    safe = np.where(small, 1.0, k)
    value = np.expm1(-safe * one_minus_cos) / np.expm1(-2.0 * safe)
    return np.clip(np.where(small, one_minus_cos / 2.0, value), 0.0, 1.0)


def variability_cone(kappa: ArrayLike, coverage: float = 0.95) -> np.ndarray:
    """Half-angle of the cone about the mean that holds ``coverage`` of a Fisher set's poles.

    Parameters
    ----------
    kappa : float or array_like
        Concentration κ >= 0.
    coverage : float, default 0.95
        Fraction of the poles inside the cone, 0 <= coverage <= 1 (0.63 gives the "1σ" cone).

    Returns
    -------
    ndarray
        θ in degrees with F(θ) = coverage: 1 - cos θ = -log1p(coverage · expm1(-2κ)) / κ, a closed
        form exact for every κ (κ = 0: 1 - cos θ = 2 · coverage). For large κ,
        θ ≈ sqrt(-2 ln(1 - coverage) / κ) rad, e.g. 140°/sqrt(κ) for 95 %.

    Examples
    --------
    >>> round(float(variability_cone(0.0, coverage=0.5)), 9)
    90.0
    >>> round(float(variability_cone(100.0, coverage=0.95)), 2)   # 140/sqrt(100) = 14.0 roughly
    14.06
    """
    k = _check_kappa(kappa)
    q = _as_scalar(coverage, "coverage", low=0.0, high=1.0, what="fraction of the poles")
    one_minus_cos = _one_minus_cos_quantile(np.float64(q), k)
    return np.degrees(2.0 * np.arcsin(np.sqrt(one_minus_cos / 2.0)))


def confidence_cone(n: int, resultant_length: float, confidence: float = 0.95) -> float:
    """Half-angle of the cone of confidence about a sample mean direction ([Fis53]_), in degrees.

    Parameters
    ----------
    n : int
        Number of unit vectors, N >= 2.
    resultant_length : float
        Length R of their vector sum (after flipping to a common hemisphere), 0 < R <= N.
    confidence : float, default 0.95
        Confidence level 1 - p, 0 < confidence < 1.

    Returns
    -------
    float
        α with cos α = 1 - ((N - R)/R)((1/p)^(1/(N-1)) - 1) ([Fis53]_, eq. 6.3 in [Fis87]_),
        evaluated as α = 2 asin(sqrt((1 - cos α)/2)) for accuracy at small α; 180 when the right side
        falls below -1 (too few or too scattered vectors to bound the mean). α95 ≈ 140°/sqrt(κN).

    Examples
    --------
    >>> round(confidence_cone(100, 99.0), 3)   # kappa ~ 99: 140/sqrt(99 * 100) = 1.41 roughly
    1.427
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
        raise TypeError(f"n must be an integer, got {n!r}")
    if n < 2:
        raise ValueError(f"n must be >= 2 (a confidence cone needs two or more poles), got {n}")
    r = _as_scalar(resultant_length, "resultant_length", low=0.0, low_open=True, high=float(n),
                   what="length of the vector sum, at most n")
    level = _as_scalar(confidence, "confidence", low=0.0, low_open=True, high=1.0 - 1e-16,
                       what="confidence level 1 - p")
    p = 1.0 - level
    one_minus_cos = (n - r) / r * np.expm1(-np.log(p) / (n - 1))
    if one_minus_cos >= 2.0:
        return 180.0
    return float(np.degrees(2.0 * np.arcsin(np.sqrt(one_minus_cos / 2.0))))


def orientation_tensor(vectors: ArrayLike) -> np.ndarray:
    """Orientation tensor T = (1/N) Σ n nᵀ of unit vectors ([Fis87]_ §3.2.4).

    Parameters
    ----------
    vectors : (N, 3) array_like
        N >= 1 non-zero vectors (normalised here); the sign of each does not matter.

    Returns
    -------
    (3, 3) ndarray of float64
        Symmetric, positive semi-definite, trace 1.

    Examples
    --------
    >>> orientation_tensor([[0, 0, 1], [0, 0, -1]])
    array([[0., 0., 0.],
           [0., 0., 0.],
           [0., 0., 1.]])
    """
    unit = _as_poles(vectors)
    return unit.T @ unit / unit.shape[0]


def _as_poles(vectors: ArrayLike, name: str = "vectors") -> np.ndarray:
    unit = _as_vectors(vectors, name)
    if unit.ndim != 2 or unit.shape[0] == 0:
        raise ValueError(f"{name} must be an (N, 3) array with N >= 1, got shape {unit.shape}")
    return unit


@dataclass(frozen=True)
class FisherFit:
    """Fisher statistics of one set of poles (see :func:`fit_fisher`).

    Attributes
    ----------
    mean_pole : (3,) ndarray
        Unit mean pole: the principal eigenvector of the orientation tensor, on the lower
        hemisphere (z <= 0).
    kappa : float
        Concentration estimate κ = (N - 1)/(N - R), finite (N - R is floored, see
        :func:`fit_fisher`).
    n : int
        Number of poles N.
    resultant_length : float
        R = |Σ n_i| of the poles flipped to the mean pole's hemisphere.
    alpha95_deg : float
        Confidence cone of the mean at the fit's ``confidence`` level ([Fis53]_).
    variability_63_deg, variability_95_deg : float
        Cones about the mean holding 63 % and 95 % of the fitted Fisher distribution.
    eigenvalues : (3,) ndarray
        Eigenvalues of the orientation tensor, descending (sum 1).
    eigenvectors : (3, 3) ndarray
        The matching unit eigenvectors as columns; column 0 is ``mean_pole``.
    poles : (N, 3) ndarray
        The input poles, normalised and flipped to the mean pole's hemisphere.
    """

    mean_pole: np.ndarray
    kappa: float
    n: int
    resultant_length: float
    alpha95_deg: float
    variability_63_deg: float
    variability_95_deg: float
    eigenvalues: np.ndarray
    eigenvectors: np.ndarray
    poles: np.ndarray

    @property
    def mean_dip_deg(self) -> float:
        """Dip of the mean plane in degrees."""
        return float(dip_from_normal(self.mean_pole)[0])

    @property
    def mean_dip_direction_deg(self) -> float:
        """Dip direction of the mean plane in degrees, [0, 360)."""
        return float(dip_from_normal(self.mean_pole)[1])


def fit_fisher(poles: ArrayLike, *, resolution_deg: float = 1.0, confidence: float = 0.95) -> FisherFit:
    """Mean pole (orientation tensor), κ, and cones of one set of axial poles.

    Parameters
    ----------
    poles : (N, 3) array_like
        N >= 2 plane normals or poles of either sign (normalised here; input not modified).
    resolution_deg : float, default 1.0
        Reading resolution δ of the orientations (> 0, < 90), which bounds κ (below).
    confidence : float, default 0.95
        Level of the confidence cone ``alpha95_deg``.

    Returns
    -------
    FisherFit

    Notes
    -----
    1. T = (1/N) Σ n nᵀ ([Fis87]_ §3.2.4); the mean pole is the eigenvector of its largest
       eigenvalue, taken on the lower hemisphere. Unlike the vector mean, this is right for axial
       data, e.g. a sub-vertical set whose poles fall on both sides of the stereonet.
    2. Each pole is flipped to the mean pole's hemisphere (n·μ >= 0) and R = |Σ n_i|.
    3. κ = (N - 1)/(N - R) ([Fis87]_ eq. 5.30, the small-sample form of (N - 1)/(N - R) rather
       than N/(N - R)). N - R is computed without cancellation as N·S/(N + R) with
       S = Σ|n_i - n̄|² (from N² - R² = N·S), so tight sets keep their precision.
    4. Limits: N - R -> 0 (identical readings) would give κ = ∞. N - R is floored at
       N (1 - cos δ) with δ = ``resolution_deg``, so κ <= (N - 1)/(N (1 - cos δ)) (≈ 6565 for 1°,
       N large): a concentration finer than the readings cannot be resolved. N = 1 is an error (no
       dispersion to measure); N = 2 gives κ = 1/(2 - R).

    Examples
    --------
    >>> poles = [[0.1, 0.0, -1.0], [-0.1, 0.0, -1.0], [0.0, 0.1, -1.0], [0.0, -0.1, -1.0]]
    >>> fit = fit_fisher(poles)
    >>> fit.mean_pole.round(12) + 0.0
    array([ 0.,  0., -1.])
    >>> round(fit.kappa, 2)     # 3 / (4 - 4/sqrt(1.01))
    151.12
    """
    unit = _as_poles(poles, "poles")
    n = unit.shape[0]
    if n < 2:
        raise ValueError(f"poles must hold at least 2 vectors to estimate kappa, got {n}")
    resolution = _as_scalar(resolution_deg, "resolution_deg", low=0.0, low_open=True, high=90.0,
                            what="reading resolution of an orientation")
    tensor = unit.T @ unit / n
    eigenvalues, eigenvectors = np.linalg.eigh(tensor)
    order = np.argsort(eigenvalues)[::-1]
    eigenvalues, eigenvectors = eigenvalues[order], eigenvectors[:, order]
    mean = to_lower_hemisphere(eigenvectors[:, 0])
    eigenvectors = eigenvectors.copy()
    eigenvectors[:, 0] = mean
    flipped = np.where((unit @ mean < 0)[:, None], -unit, unit)
    resultant = float(np.linalg.norm(flipped.sum(axis=0)))
    spread = float(np.sum((flipped - flipped.mean(axis=0)) ** 2))
    n_minus_r = n * spread / (n + resultant)
    floor = n * 2.0 * np.sin(np.radians(resolution) / 2.0) ** 2  # N (1 - cos δ)
    kappa = (n - 1) / max(n_minus_r, floor)
    return FisherFit(
        mean_pole=mean,
        kappa=float(kappa),
        n=n,
        resultant_length=min(resultant, float(n)),
        alpha95_deg=confidence_cone(n, min(resultant, float(n)), confidence),
        variability_63_deg=float(variability_cone(kappa, 0.63)),
        variability_95_deg=float(variability_cone(kappa, 0.95)),
        eigenvalues=eigenvalues,
        eigenvectors=eigenvectors,
        poles=flipped,
    )
