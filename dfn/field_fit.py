"""Fracture sets fitted from field data: orientation, size and P32 per set, with uncertainties.

Inputs are scanline surveys (:class:`~rockmass.dfn.scanline.Scanline`) and trace maps on faces of
known orientation (:class:`FaceSurvey`). :func:`fit_field` does, in order:

1. **Orientation.** The poles of every scanline together are clustered into joint sets by a mixture of
   bipolar Fisher laws (:func:`~rockmass.dfn.sets3d.fit_sets_3d`, number of sets by BIC or given);
   each set's mean pole comes from its orientation tensor and κ = (N − 1)/(N − R)
   (docs/fractures.md §3.1, eq. (3.5); Fisher et al. 1987),
   with sd(κ) ≈ κ / √(N − 1) (2κ(N − R) is χ² with 2(N − 1) degrees of freedom, [Fis53]_) and the
   α95 confidence cone. Scanline sampling favours planes normal to the line (Terzaghi); with κ of
   10 or more and lines not sub-parallel to a set this biases the mean by less than the α95 cone,
   and is not corrected here.
2. **Traces to sets.** On a face with normal m a plane with pole n leaves traces along n × m; each trace
   goes to the set whose mean trace direction on that face is nearest (axial angle in the face).
3. **Size.** Per set, a disk radius law fitted by maximum likelihood to the set's censored trace
   lengths on every face at once (:func:`~rockmass.dfn.size_fit.fit_sizes`, [Las82]_); the family is
   given or chosen by AIC. Faces count as independent samples: faces that meet or lie within a
   disk diameter of each other share disks, and the sd of the size parameters is then optimistic.
4. **P32.** Per set, from every scanline's P10 and every face's P21 of that set at once:
   P10_k = P32 / C13(t_k), P21_j = P32 / C23(m_j) with the set's fitted Fisher C13 / C23, solved by
   non-negative least squares with :func:`~rockmass.dfn.stereology.solve_p32` ([Wan05]_). The
   weights are Poisson: sd(P10_k) = √N_k / L_k (N_k hits, at least 1), sd(P21_j) =
   P21_j √(1 + CV²) / √M_j (M_j traces, CV the coefficient of variation of their lengths; a face
   with fewer than 2 traces of the set gets sd = mean trace length / area, what one trace gives).

References
----------
.. [Fis53] Fisher, R. A. (1953). Dispersion on a sphere. Proc. R. Soc. Lond. A 217, 295-305.
.. [Las82] Laslett, G. M. (1982). Censoring and edge effects in areal and line transect sampling of
   rock joint traces. Mathematical Geology 14(2), 125-140.
.. [Wan05] Wang, X. (2005). Stereological interpretation of rock fracture traces on borehole walls and
   other cylindrical surfaces. PhD thesis, Virginia Tech (C13, C23 of Fisher sets).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from .generation import (
    BootstrapOrientation,
    FisherOrientation,
    FractureSetSpec,
    IntensityP32,
)
from .orientation import _as_vectors, dip_from_normal, normal_from_dip
from .sampling import plane_frame
from .scanline import Scanline
from .sets3d import JointSets3D, fit_sets_3d
from .size_fit import FAMILIES, SizeFit, censored_traces, fit_sizes
from .stereology import solve_p32
from .tracemap import TraceMap

__all__ = ["FaceSurvey", "FieldFit", "FittedSet", "assign_traces", "fit_field"]


@dataclass(frozen=True, eq=False)
class FaceSurvey:
    """A trace map on a planar face of known orientation.

    Parameters
    ----------
    trace_map : TraceMap
        Traces in the face frame (u right, v up, metres) with a convex ``window_xy_m``.
    normal : (3,) array_like
        Unit normal m of the face pointing towards the viewer; the face frame is
        :func:`~rockmass.dfn.sampling.plane_frame` (m) (normalised here).
    point_m : (3,) array_like, optional
        World position (x East, y North, z Up) of the frame's origin; needed only to re-sample a
        generated network on this face.
    name : str, default ""
        Label (e.g. the file name).
    """

    trace_map: TraceMap
    normal: np.ndarray
    point_m: np.ndarray | None = None
    name: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.trace_map, TraceMap):
            raise TypeError(f"trace_map must be a TraceMap, got {type(self.trace_map).__name__}")
        if self.trace_map.window_xy_m is None:
            raise ValueError(f"{self.name or 'face'}: the trace map has no window polygon; P21 and the "
                             "censored-length fit need the sampled area")
        normal = _as_vectors(self.normal, "normal")
        if normal.shape != (3,):
            raise ValueError(f"normal must be one vector of shape (3,), got {normal.shape}")
        object.__setattr__(self, "normal", normal)
        if self.point_m is not None:
            point = np.asarray(self.point_m, dtype=np.float64)
            if point.shape != (3,) or not np.isfinite(point).all():
                raise ValueError(f"point_m must be 3 finite numbers (x, y, z metres), got {self.point_m!r}")
            object.__setattr__(self, "point_m", point)

    @classmethod
    def from_dip(cls, trace_map: TraceMap, dip_deg: float, dip_direction_deg: float,
                 point_m: ArrayLike | None = None, name: str = "") -> FaceSurvey:
        """A face given by its dip / dip direction; the viewer stands on the side the face looks to
        (m = the upper normal; for a vertical face, horizontal towards the dip direction)."""
        return cls(trace_map, normal_from_dip(dip_deg, dip_direction_deg), point_m, name)

    @property
    def area_m2(self) -> float:
        return float(self.trace_map.window_polygon().area)


@dataclass(frozen=True)
class FittedSet:
    """One fitted fracture set (see :func:`fit_field`); angles in degrees, P32 in m²/m³ (one-sided)."""

    mean_dip_deg: float
    mean_dip_direction_deg: float
    mean_pole: np.ndarray
    kappa: float
    kappa_sd: float
    alpha95_deg: float
    n_poles: int
    p32: float
    p32_sd: float
    p32_chi2: float
    p32_dof: int
    n_observations: int
    size: SizeFit | None
    n_traces: int
    name: str = ""
    poles: np.ndarray | None = field(default=None, repr=False)

    def spec(self, size: object | None = None, *, orientation: str = "fisher", n_vertices: int = 16) -> FractureSetSpec:
        """The :class:`FractureSetSpec` to generate this set.

        ``size`` overrides the fitted radius law; ``orientation`` is ``"fisher"`` (the fitted mean and
        κ) or ``"bootstrap"`` (the set's measured poles resampled, :class:`BootstrapOrientation`).
        """
        size = size if size is not None else (self.size.size if self.size is not None and self.size.ok else None)
        if size is None:
            raise ValueError(f"set {self.name!r}: no size law was fitted (no traces on any face); give one")
        if not self.p32 > 0:
            raise ValueError(f"set {self.name!r}: fitted P32 is 0 (no intersections or traces of this set)")
        if orientation == "fisher":
            model = FisherOrientation(self.mean_dip_deg, self.mean_dip_direction_deg, self.kappa)
        elif orientation == "bootstrap":
            if self.poles is None or len(self.poles) == 0:
                raise ValueError(f"set {self.name!r}: no measured poles to bootstrap from")
            model = BootstrapOrientation(self.poles)
        else:
            raise ValueError(f"orientation must be 'fisher' or 'bootstrap', got {orientation!r}")
        return FractureSetSpec(model, size, IntensityP32(self.p32), name=self.name, n_vertices=n_vertices)

    def as_dict(self) -> dict:
        """JSON-ready (no NaN)."""
        def num(v):
            return float(v) if v is not None and np.isfinite(v) else None
        return {"name": self.name,
                "orientation": {"distribution": "fisher", "dip_deg": num(self.mean_dip_deg),
                                "dip_direction_deg": num(self.mean_dip_direction_deg), "kappa": num(self.kappa),
                                "kappa_sd": num(self.kappa_sd), "alpha95_deg": num(self.alpha95_deg),
                                "n_poles": self.n_poles},
                "intensity": {"measure": "P32", "value": num(self.p32), "sd": num(self.p32_sd),
                              "chi2": num(self.p32_chi2), "dof": self.p32_dof,
                              "n_observations": self.n_observations},
                "size": None if self.size is None else self.size.as_dict(),
                "n_traces": self.n_traces}


@dataclass(frozen=True, eq=False)
class FieldFit:
    """Result of :func:`fit_field`.

    Attributes
    ----------
    sets : tuple of FittedSet
        In the order of :func:`~rockmass.dfn.sets3d.fit_sets_3d` (by dip direction).
    joint_sets : JointSets3D
        The pole clustering.
    scanline_membership : tuple of (n_k,) int64
        Set of each intersection, per scanline.
    face_membership : tuple of (n_traces,) int64
        Set of each trace, per face.
    size_fits : tuple of dict
        Every candidate size fit per set (:func:`~rockmass.dfn.size_fit.fit_sizes`; empty without traces).
    """

    sets: tuple
    joint_sets: JointSets3D
    scanline_membership: tuple
    face_membership: tuple
    size_fits: tuple = field(default=())

    def specs(self, sizes: Sequence[object | None] | None = None, *, orientation: str = "fisher",
              n_vertices: int = 16) -> list[FractureSetSpec]:
        """:meth:`FittedSet.spec` of every set (``sizes``: one override or None per set)."""
        sizes = [None] * len(self.sets) if sizes is None else list(sizes)
        return [s.spec(z, orientation=orientation, n_vertices=n_vertices) for s, z in zip(self.sets, sizes)]

    def as_dict(self) -> dict:
        return {"n_sets": len(self.sets), "selected_by": self.joint_sets.selected_by,
                "bic": {str(k): (None if v is None else float(v)) for k, v in self.joint_sets.bic.items()},
                "sets": [s.as_dict() for s in self.sets],
                "size_candidates": [{k: f.as_dict() for k, f in fits.items() if k != "best"}
                                    for fits in self.size_fits]}


def _trace_directions_uv(trace_map: TraceMap) -> np.ndarray:
    """Unit direction (u, v) of each trace from its first to its last vertex, (n, 2)."""
    first = trace_map.xy_m[trace_map.offsets[:-1]]
    last = trace_map.xy_m[trace_map.offsets[1:] - 1]
    d = last - first
    norm = np.linalg.norm(d, axis=1, keepdims=True)
    return np.divide(d, norm, out=np.zeros_like(d), where=norm > 0)


def assign_traces(face: FaceSurvey, mean_poles: ArrayLike) -> np.ndarray:
    """Set of each trace on a face: the set whose mean plane's trace direction is nearest.

    Parameters
    ----------
    face : FaceSurvey
    mean_poles : (k, 3) array_like
        Mean pole of each set.

    Returns
    -------
    (n_traces,) int64
        Index into ``mean_poles``.

    Notes
    -----
    The mean plane of set s cuts the face along d_s = n_s × m; in the face frame (u, v) that is
    (d_s·u, d_s·v). The axial angle between a trace and d_s is arccos |t·d_s|. A set whose mean plane
    is parallel to the face (|n_s × m| < 1e-6) leaves no preferred direction and is never chosen.

    Examples
    --------
    >>> tm = TraceMap.from_polylines([[(0, 0), (1, 0)], [(0, 0), (0, 1)]], window=[(-2, -2), (2, -2), (2, 2), (-2, 2)])
    >>> face = FaceSurvey(tm, [0.0, 1.0, 0.0])          # vertical face looking North: u West, v up
    >>> assign_traces(face, [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]).tolist()   # horizontal, N-S vertical planes
    [0, 1]
    """
    poles = _as_vectors(mean_poles, "mean_poles").reshape(-1, 3)
    u, v, m = plane_frame(face.normal)
    d = np.cross(poles, m)
    length = np.linalg.norm(d, axis=1)
    d_uv = np.stack([d @ u, d @ v], axis=1) / np.where(length > 1e-6, length, 1.0)[:, None]
    t = _trace_directions_uv(face.trace_map)
    score = np.abs(t @ d_uv.T)
    score[:, length <= 1e-6] = -1.0
    return np.argmax(score, axis=1).astype(np.int64)


def _check_inputs(scanlines, faces) -> tuple[list[Scanline], list[FaceSurvey]]:
    scanlines = [scanlines] if isinstance(scanlines, Scanline) else list(scanlines)
    faces = [faces] if isinstance(faces, FaceSurvey) else list(faces)
    for k, s in enumerate(scanlines):
        if not isinstance(s, Scanline):
            raise TypeError(f"scanlines[{k}] must be a Scanline, got {type(s).__name__}")
    for k, f in enumerate(faces):
        if not isinstance(f, FaceSurvey):
            raise TypeError(f"faces[{k}] must be a FaceSurvey, got {type(f).__name__}")
    if not scanlines:
        raise ValueError("at least one scanline is needed: set orientations are fitted from scanline poles")
    if sum(s.n_intersections for s in scanlines) < 2:
        raise ValueError("the scanlines hold fewer than 2 intersections in all: no set can be fitted")
    return scanlines, faces


@dataclass(frozen=True)
class _TraceSample:
    """P21 and mean length of the clipped traces of one window, with Poisson standard deviations."""

    m: int                   # traces with a non-zero length in the window
    p21: float               # Σ l / A, m/m²
    p21_sd: float | None     # P21 √((1 + CV²)/M); None for M < 2 (no spread to measure)
    mean_m: float | None     # mean clipped length (window-censored), m
    mean_sd: float | None    # sd(l) / √M


def _trace_sample(lengths_m: np.ndarray, area_m2: float) -> _TraceSample:
    """Counts are Poisson and lengths scatter with coefficient of variation CV, so
    var(Σ l) = M E[l²] = M mean² (1 + CV²) and sd(P21) = P21 √((1 + CV²)/M) (sample CV, ddof 1)."""
    ell = np.asarray(lengths_m, dtype=np.float64)
    ell = ell[ell > 0]
    m = int(ell.size)
    p21 = float(ell.sum() / area_m2)
    if m < 2:
        return _TraceSample(m, p21, None, float(ell.mean()) if m else None, None)
    mean, var = float(ell.mean()), float(ell.var(ddof=1))
    return _TraceSample(m, p21, p21 * float(np.sqrt((1.0 + var / mean ** 2) / m)), mean, float(np.sqrt(var / m)))


def _p32_of_set(pole: np.ndarray, kappa: float, s: int, scanlines, scan_member, faces, face_member,
                face_lengths) -> tuple:
    """solve_p32 for one set from its P10 on every scanline and P21 on every face."""
    lines = np.array([sl.direction for sl in scanlines])
    n_hits = np.array([np.sum(mem == s) for mem in scan_member], dtype=float)
    lengths = np.array([sl.length_m for sl in scanlines])
    p10 = n_hits / lengths
    p10_sd = np.sqrt(np.maximum(n_hits, 1.0)) / lengths
    kwargs = {"line_directions": lines, "p10": p10, "p10_sd": p10_sd}
    if faces:
        all_lengths = np.concatenate([l for l in face_lengths]) if face_lengths else np.empty(0)
        typical = float(np.mean(all_lengths)) if all_lengths.size else 1.0
        p21, p21_sd = [], []
        for face, mem, clipped in zip(faces, face_member, face_lengths):
            area = face.area_m2
            sample = _trace_sample(clipped[mem == s], area)
            p21.append(sample.p21)
            # fewer than 2 traces: the sd one trace of typical length would give
            p21_sd.append(sample.p21_sd if sample.p21_sd else typical / area)
        kwargs.update(face_normals=np.array([f.normal for f in faces]), p21=np.array(p21),
                      p21_sd=np.array(p21_sd))
    sol = solve_p32(pole[None, :], [kappa], **kwargs)
    return float(sol.p32[0]), float(sol.sd[0]), float(sol.chi2), int(sol.dof), int(sol.observed.size)


def fit_field(scanlines: Scanline | Sequence[Scanline], faces: FaceSurvey | Sequence[FaceSurvey] = (), *,
              n_sets: int | None = None, size_family: str = "best", r_max_m: float = 100.0,
              tolerance_m: float | None = None, names: Sequence[str] | None = None, seed: int = 0) -> FieldFit:
    """Fit orientation (Fisher), disk size law and P32 of every joint set from field data.

    Parameters
    ----------
    scanlines : Scanline or sequence of Scanline
        At least one, with 2 or more intersections in all (orientations come from their poles).
    faces : FaceSurvey or sequence of FaceSurvey, default ()
        Trace maps on faces (sizes and P21). Without faces the sets have no size law
        (:meth:`FittedSet.spec` then needs one) and P32 comes from the scanlines alone.
    n_sets : int, optional
        Number of sets; default chosen by BIC (:func:`~rockmass.dfn.sets3d.fit_sets_3d`).
    size_family : {"best", "power_law", "lognormal", "exponential"}, default "best"
        Disk radius law; "best" fits all three and keeps the smallest AIC.
    r_max_m : float, default 100
        Upper truncation of a power law of radii (metres, > 0).
    tolerance_m : float, optional
        Trace ends closer than this to a window boundary are censored
        (:func:`~rockmass.dfn.size_fit.censored_traces`).
    names : sequence of str, optional
        Set names (default "S1", "S2", ...).
    seed : int, default 0
        Seed of the clustering's initialisation (the fit is deterministic for a given seed).

    Returns
    -------
    FieldFit

    Raises
    ------
    ValueError
        No scanline or too few poles, an unknown ``size_family``, a face without a window.
    TypeError
        An input of the wrong type.

    Notes
    -----
    The steps, their formulas and sources are in the module docstring.
    """
    scanlines, faces = _check_inputs(scanlines, faces)
    if size_family != "best" and size_family not in FAMILIES:
        raise ValueError(f"size_family must be 'best' or one of {', '.join(FAMILIES)}, got {size_family!r}")
    families = FAMILIES if size_family == "best" else (size_family,)
    poles = np.concatenate([s.poles() for s in scanlines])
    joint_sets = fit_sets_3d(poles, n_sets, seed=seed)
    k = joint_sets.n_sets
    if names is not None and len(names) != k:
        raise ValueError(f"names must hold one name per set: {len(names)} for {k} sets")
    names = list(names) if names is not None else [f"S{j + 1}" for j in range(k)]
    bounds = np.cumsum([0] + [s.n_intersections for s in scanlines])
    scan_member = tuple(np.split(joint_sets.membership, bounds[1:-1]))
    face_member = tuple(assign_traces(f, joint_sets.mean_pole) for f in faces)
    censored = [[censored_traces(f.trace_map, tolerance_m=tolerance_m, selection=mem == s)
                 for f, mem in zip(faces, face_member)] for s in range(k)]
    from .intensity import clipped_lengths_m

    face_lengths = [np.asarray(clipped_lengths_m(f.trace_map)) for f in faces]
    sets, size_fits = [], []
    for s in range(k):
        fit = joint_sets.fits[s]
        pole = joint_sets.mean_pole[s]
        kappa = float(fit.kappa) if fit is not None else float(joint_sets.mixture_kappa[s])
        n_poles = int(joint_sets.count[s])
        p32, p32_sd, chi2, dof, n_obs = _p32_of_set(pole, kappa, s, scanlines, scan_member, faces, face_member,
                                                    face_lengths)
        samples = [c for c in censored[s] if c.n_traces]
        fits = fit_sizes(samples, families=families, r_max_m=r_max_m) if samples else {}
        size_fits.append(fits)
        dip, dd = dip_from_normal(pole)
        sets.append(FittedSet(
            mean_dip_deg=float(dip), mean_dip_direction_deg=float(dd), mean_pole=pole, kappa=kappa,
            kappa_sd=kappa / np.sqrt(max(n_poles - 1, 1)),
            alpha95_deg=float(fit.alpha95_deg) if fit is not None else float("nan"), n_poles=n_poles,
            p32=p32, p32_sd=p32_sd, p32_chi2=chi2, p32_dof=dof, n_observations=n_obs,
            size=fits.get("best"), n_traces=int(sum(c.n_traces for c in samples)), name=names[s],
            poles=poles[joint_sets.membership == s]))
    return FieldFit(tuple(sets), joint_sets, scan_member, face_member, tuple(size_fits))
