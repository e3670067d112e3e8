"""A 2D section of a Poisson disk network generated directly on the plane (docs/fractures.md §12.4).

Only disks that cut the plane matter. For a Poisson network with P30 centres per m³ and radius
density f(r), the disks whose centres lie within r of the plane have, per unit area of the plane,
P30 · 2 E[r] centres, with radii size-biased ∝ r f(r), distance s uniform on [-r, r] and the set's
own orientation distribution; such a disk is cut when |s| < r sin ψ. So :func:`generate_section`
draws, for each set,

1. the number of candidates, Poisson(P30 · 2 E[r] · A) over the window's bounding rectangle grown by
   the largest radius r_max (area A), P30 = P32 / (π E[r²]);
2. size-biased radii (:func:`size_biased_sample`), then normals, then (u, v) uniform on the
   rectangle and s uniform on [-r, r];

and cuts them with the plane (:func:`rockmass.dfn.sampling.sample_plane`'s chord formula). The
traces have the statistics of generating the whole volume and cutting it (P21 = P32 / C23, P20 =
P30 · 2 E[r] / C23, mean trace length π E[r²]/(2 E[r])) at a cost proportional to the section, not the
volume. The one difference: the volume is filled to its P32 target exactly, so its disk count does
not fluctuate, while here the count is Poisson — the expected intensities are the same.

Seeding as :func:`rockmass.dfn.generation.generate`: realization i, set j use spawn key (i, j).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from .generation import DEFAULT_MAX_FRACTURES, FractureSetSpec, _check_index, _check_sets, _set_label, \
    realization_seed, size_upper_bound
from .sampling import _plane_traces, _point, _window, plane_frame
from .sizes import ConstantSize, LognormalSize, PowerLawSize, _check_sample_args, _check_size
from .tracemap import TraceMap

__all__ = ["generate_section", "size_biased_sample"]

#: Grid points of the numerical inverse CDF used for size-biased sampling without a closed form.
_GRID = 20001


def size_biased_sample(size: object, rng: np.random.Generator, n: int) -> np.ndarray:
    """Draw ``n`` radii from the size-biased density r f(r) / E[r] of ``size`` (metres).

    Closed forms where they exist: a constant stays constant; a power law with α >= 1 becomes the
    power law with α - 1 on the same range; a lognormal keeps σ and gains σ² in μ (mean × (1 + cv²),
    same cv), same truncation. Otherwise (power law with α < 1, exponential) by inversion of
    ∫ r f(r) dr tabulated on a 20,001-point grid over [r_min, r_upper] (:func:`size_upper_bound`),
    trapezoidal rule with linear interpolation of the inverse (relative error of the CDF ~1e-8).

    Examples
    --------
    >>> size_biased_sample(ConstantSize(2.0), np.random.default_rng(0), 3).tolist()
    [2.0, 2.0, 2.0]
    """
    _check_size(size)
    _check_sample_args(rng, n)
    if isinstance(size, ConstantSize):
        return size.sample(rng, n)
    if isinstance(size, PowerLawSize) and size.alpha >= 1.0:
        return PowerLawSize(size.r_min_m, size.r_max_m, size.alpha - 1.0).sample(rng, n)
    if isinstance(size, LognormalSize):
        factor = 1.0 + (size.sd_m / size.mean_m) ** 2
        return LognormalSize(size.mean_m * factor, size.sd_m * factor, size.r_min_m, size.r_max_m).sample(rng, n)
    lo, hi = float(size.r_min_m), size_upper_bound(size)
    grid = np.geomspace(lo, hi, _GRID) if lo > 0 else np.linspace(0.0, hi, _GRID)
    weight = grid * size.pdf(grid)
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (weight[1:] + weight[:-1]) * np.diff(grid))])
    cdf /= cdf[-1]
    return np.interp(rng.random(n), cdf, grid)


def generate_section(sets: Sequence[FractureSetSpec], point: ArrayLike, normal: ArrayLike,
                     window_uv_m: ArrayLike, *, seed: int, realization: int = 0,
                     max_fractures: int = DEFAULT_MAX_FRACTURES) -> TraceMap:
    """Traces of a Poisson disk network on one plane, generated on the plane directly.

    Parameters
    ----------
    sets : sequence of FractureSetSpec
        The sets (their P32 targets, sizes and orientations); set j gets ``set`` j.
    point, normal : (3,) array_like of float
        The plane (origin of (u, v) and normal), as in :func:`rockmass.dfn.sampling.sample_plane`.
    window_uv_m : (k, 2) array_like of float or shapely.Polygon
        Section window in the plane frame (u, v), metres.
    seed : int
        Root seed >= 0.
    realization : int, default 0
        Realization index >= 0.
    max_fractures : int, default 5,000,000
        Guard on the number of candidate disks of one set (expected count).

    Returns
    -------
    TraceMap
        Frame ``"plane"``, attributes ``set`` and ``disk`` (candidate index within the set).

    Raises
    ------
    ValueError
        Bad plane, window or seed, or a set needing more than ``max_fractures`` candidates.
    """
    sets = _check_sets(sets)
    origin = _point(point, "point")
    frame = plane_frame(normal)
    polygon = _window(window_uv_m)
    limit = _check_index(max_fractures, "max_fractures")
    realization_seed(seed, realization)  # validates both
    u_axis, v_axis, m = frame
    umin, vmin, umax, vmax = polygon.bounds
    maps = []
    for j, spec in enumerate(sets):
        pad = size_upper_bound(spec.size)
        lo = np.array([umin - pad, vmin - pad])
        hi = np.array([umax + pad, vmax + pad])
        expected = spec.p30 * 2.0 * spec.size.mean() * float(np.prod(hi - lo))
        if expected > limit:
            raise ValueError(f"{_set_label(j, spec)}: the section needs about {expected:.3g} candidate "
                             f"disks, more than max_fractures = {limit}")
        rng = np.random.default_rng(realization_seed(seed, realization, j))
        n = int(rng.poisson(expected))
        radius = size_biased_sample(spec.size, rng, n)
        normal_j = spec.orientation.sample(rng, n)
        uv = lo + rng.random((n, 2)) * (hi - lo)
        s = radius * (2.0 * rng.random(n) - 1.0)
        centre = origin + uv[:, :1] * u_axis + uv[:, 1:] * v_axis + s[:, None] * m
        maps.append(_plane_traces(centre, normal_j, radius, np.full(n, j, dtype=np.int64), origin, frame,
                                  polygon))
    xy = np.concatenate([t.xy_m for t in maps])
    counts = np.concatenate([np.diff(t.offsets) for t in maps])
    attributes = {key: np.concatenate([t.attributes[key] for t in maps]) for key in ("set", "disk")}
    return TraceMap(xy, np.concatenate([[0], np.cumsum(counts)]).astype(np.int64), attributes,
                    maps[0].window_xy_m, "plane")
