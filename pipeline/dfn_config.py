"""``[dfn]``: seeded generation of disk fracture networks (:mod:`rockmass.dfn.generation`).

Example (every number is range-checked; unknown keys are errors)::

    [dfn]
    seed = 1
    realizations = 3
    max_fractures = 2_000_000

    [dfn.domain]
    min_m = [0.0, 0.0, 0.0]          # x East, y North, z Up, metres
    max_m = [50.0, 80.0, 6.0]

    [[dfn.sets]]
    name = "J1"
    orientation = { distribution = "fisher", dip_deg = 50, dip_direction_deg = 270, kappa = 20 }
    size = { distribution = "power_law", r_min_m = 2.0, r_max_m = 40.0, alpha = 2.5 }
    intensity = { measure = "P32", value = 0.333 }

Orientation ``distribution``: ``fisher`` (``dip_deg`` 0-90, ``dip_direction_deg`` 0-360, ``kappa``
>= 0), ``uniform``, or ``bootstrap`` (``planes_deg = [[dip, dip_direction], ...]``). Size
``distribution``: ``constant`` (``radius_m``), ``power_law`` (``r_min_m`` < ``r_max_m``, ``alpha``
>= 0, density ∝ r^-(alpha+1)), ``lognormal`` (``mean_m``, ``sd_m``, optional ``r_min_m``,
``r_max_m``), ``exponential`` (``scale_m``, optional ``r_min_m``, ``r_max_m``). Intensity ``measure``:
``P32`` (m²/m³, one-sided), ``P10`` (1/m, with the scanline's ``trend_deg`` and ``plunge_deg``) or
``P21`` (m/m², with the sampling plane's ``dip_deg`` and ``dip_direction_deg``); P10 and P21 are
converted to P32 with the set's C13 / C23.

Instead of ``[[dfn.sets]]``, ``[dfn.fit]`` fits the sets from field data (:func:`rockmass.dfn.fit_field`)::

    [dfn.fit]
    scanlines = ["scanline_seed001.csv"]   # relative to this file; trend / plunge / length in each
    n_sets = 3                             # optional: default by BIC
    size_family = "best"                   # power_law | lognormal | exponential | best (AIC)
    orientation = "fisher"                 # or "bootstrap": resample each set's measured poles
    r_max_m = 40.0                         # power-law upper truncation of the fitted radii
    validate = true                        # re-sample every realization like the field data

    [[dfn.fit.faces]]
    file = "face_seed001.geojson"          # traces in the face frame (u right, v up) with a window
    dip_deg = 90.0                         # the face plane; the viewer looks against its upper normal
    dip_direction_deg = 180.0
    point_m = [25.0, 0.0, 3.0]             # world position of (u, v) = (0, 0); needed by validate

Without faces the sets need ``size = {...}`` in ``[dfn.fit]`` (a size table as above).

Load a file that holds only this section with ``load_config(path, model=DFNDocument)``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import AfterValidator, Field, model_validator

from .dfn.generation import BootstrapOrientation, FisherOrientation, FractureSetSpec, IntensityP10, \
    IntensityP21, IntensityP32, UniformOrientation
from .dfn.orientation import pole_from_dip
from .dfn.sizes import ConstantSize, ExponentialSize, LognormalSize, PowerLawSize
from .strict import ConfigFile, StrictModel, config_file, field_problem, library_section

__all__ = ["DFNConfig", "DFNDocument", "DomainConfig", "FaceConfig", "FitConfig", "FractureSetConfig"]

Dip = Annotated[float, Field(ge=0, le=90)]
Azimuth = Annotated[float, Field(ge=0, le=360)]
Length = Annotated[float, Field(gt=0, le=1e6)]
Triple = Annotated[tuple[float, float, float], Field(strict=False)]


class DomainConfig(StrictModel):
    """``[dfn.domain]``: the box ``min_m`` .. ``max_m`` (x East, y North, z Up), metres."""

    min_m: Annotated[Triple, Field(description="lowest corner (x East, y North, z Up)")]
    max_m: Annotated[Triple, Field(description="highest corner, above min_m on every axis")]

    @model_validator(mode="after")
    def _max_above_min(self) -> DomainConfig:
        if not all(hi > lo for lo, hi in zip(self.min_m, self.max_m)):
            raise field_problem(self, "max_m", f"must be > min_m {list(self.min_m)} on every axis, got "
                                f"{list(self.max_m)}", list(self.max_m))
        if max(abs(v) for v in (*self.min_m, *self.max_m)) > 1e7:
            raise field_problem(self, "max_m", "coordinates must be within ±1e7 m", list(self.max_m))
        return self


# -- orientation and size: the library's parameter types (rockmass.dfn.generation, rockmass.dfn.sizes)


def _config_limits(**highs: float):
    """An after-validator refusing values above ``highs`` (per field): bounds a config keeps on the
    library's wider ranges, so that a typo in a file (a radius in mm) stops at the key."""

    def check(value):
        for name, high in highs.items():
            number = getattr(value, name, None)
            if number is not None and number != float("inf") and number > high:
                key = type(value).__pydantic_fields__[name].alias or name
                raise field_problem(value, key, f"must be <= {high:g} in a config, got {number}", number)
        return value

    return AfterValidator(check)


class BootstrapConfig(StrictModel):
    """``distribution = "bootstrap"``: the TOML form of :class:`rockmass.dfn.generation.BootstrapOrientation`,
    which takes poles as an array; the table gives planes as [dip, dip direction] pairs."""

    distribution: Annotated[Literal["bootstrap"], Field(
        description="orientation law: resample measured planes")]
    planes_deg: Annotated[list[Annotated[tuple[Dip, Azimuth], Field(strict=False)]], Field(
        min_length=1, description="measured planes as [dip, dip direction]")]

    def to_library(self) -> BootstrapOrientation:
        planes = np.array(self.planes_deg, dtype=float)
        return BootstrapOrientation(pole_from_dip(planes[:, 0], planes[:, 1]))


OrientationTable = Annotated[FisherOrientation | UniformOrientation | BootstrapConfig, Field(
    discriminator="distribution"), _config_limits(kappa=1e6)]
SizeTable = Annotated[ConstantSize | PowerLawSize | LognormalSize | ExponentialSize,
                      Field(discriminator="distribution"),
                      _config_limits(radius_m=1e6, r_min_m=1e6, r_max_m=1e6, mean_m=1e6, sd_m=1e6,
                                     scale_m=1e6, alpha=20)]


IntensityTable = Annotated[IntensityP32 | IntensityP10 | IntensityP21, Field(discriminator="measure"),
                          _config_limits(p32=1e4, p10=1e4, p21=1e4)]


class FractureSetConfig(library_section(
        FractureSetSpec,
        orientation=(OrientationTable, Field(
            description="orientation law (distribution = fisher, uniform or bootstrap); kappa <= 1e6")),
        size=(SizeTable, Field(
            description="radius law (distribution = constant, power_law, lognormal or exponential); "
                        "radii <= 1e6 m, alpha <= 20")),
        intensity=(IntensityTable, Field(
            description="intensity (measure = P32, P10 or P21); value <= 1e4")))):
    """One ``[[dfn.sets]]`` entry: :class:`rockmass.dfn.generation.FractureSetSpec`, with the
    config's bounds on its tables and bootstrap planes given as [dip, dip direction]."""

    def to_spec(self):
        """The :class:`rockmass.dfn.generation.FractureSetSpec`."""
        o = self.orientation
        return self.to_library(orientation=o.to_library() if isinstance(o, BootstrapConfig) else o)


class FaceConfig(StrictModel):
    """One ``[[dfn.fit.faces]]`` entry: a trace file on a face of known orientation."""

    file: Annotated[ConfigFile, Field(
        description="trace map (GeoJSON / CSV with a convex window) in the face frame")]
    dip_deg: Annotated[Dip, Field(description="dip of the face")]
    dip_direction_deg: Annotated[Azimuth, Field(description="dip direction of the face")]
    point_m: Annotated[Triple | None, Field(
        description="a point of the face plane; none: the origin")] = None


class FitConfig(StrictModel):
    """``[dfn.fit]``: fit the sets from scanlines and face trace maps (:func:`rockmass.dfn.fit_field`).

    Parameters
    ----------
    scanlines : list of str
        1-100 scanline files (CSV with header geometry, :func:`rockmass.dfn.read_scanline`), relative
        to the config file.
    faces : list of FaceConfig, default []
        Trace maps (GeoJSON / CSV with a convex window) on faces.
    n_sets : int, optional
        1-5 sets; default by BIC.
    size_family : {"best", "power_law", "lognormal", "exponential"}, default "best"
    r_max_m : float, default 100
        Power-law upper truncation of fitted radii, metres.
    boundary_tolerance_m : float, optional
        Trace ends closer than this to a window edge are censored (default 1e-9 of the window size).
    size : size table, optional
        Radius law for every set when no face is given (or to override the fitted one).
    orientation : {"fisher", "bootstrap"}, default "fisher"
        Generate each set from its fitted Fisher law, or by resampling its measured poles.
    validate : bool, default false
        Re-sample every realization with the field geometry and write ``validation.json``.
    """

    scanlines: Annotated[list[ConfigFile], Field(min_length=1, max_length=100)]
    faces: Annotated[list[FaceConfig], Field(max_length=100)] = Field(default_factory=list)
    n_sets: int | None = Field(None, ge=1, le=5)
    size_family: Annotated[Literal["best", "power_law", "lognormal", "exponential"], Field(
        description="radius law fitted, or the best by likelihood")] = "best"
    r_max_m: Length = 100.0
    boundary_tolerance_m: float | None = Field(None, ge=0, le=1e3)
    size: SizeTable | None = None
    orientation: Literal["fisher", "bootstrap"] = "fisher"
    # ``validate`` is a (deprecated) BaseModel method, so the field is ``validate_`` with the key as alias,
    # and dumps (the run manifest) use the alias too
    model_config = {**StrictModel.model_config, "serialize_by_alias": True}
    validate_: bool = Field(False, alias="validate")

    def field_files(self, config_path) -> list[Path]:
        """Every scanline and face file, resolved against the config's folder."""
        return [self.path(n, config_path) for n in self.scanlines] + \
            [self.path(f.file, config_path) for f in self.faces]

    @model_validator(mode="after")
    def _sizes_known(self) -> FitConfig:
        if not self.faces and self.size is None:
            raise field_problem(self, "faces", "sizes are fitted from face trace maps: give [[dfn.fit.faces]] "
                                "or a size table `size = {...}`", [])
        return self

    def path(self, name: str, config_path) -> Path:
        return config_file(config_path, name)


class SectionConfig(StrictModel):
    """One ``[[dfn.sections]]`` entry: a plane on which each realization's traces are counted.

    ``point_m`` is the origin of the plane frame (u, v) (:func:`rockmass.dfn.plane_frame` of the upper
    normal of ``dip_deg`` / ``dip_direction_deg``) and ``window_uv_m`` the convex window in that frame.
    """

    name: str = Field("", max_length=64, description="name, used by [blocks.dfn_section]")
    point_m: Annotated[Triple, Field(description="origin of the plane frame (u, v)")]
    dip_deg: Annotated[Dip, Field(description="dip of the plane")]
    dip_direction_deg: Annotated[Azimuth, Field(description="dip direction of the plane")]
    window_uv_m: Annotated[list[Annotated[tuple[float, float], Field(strict=False)]], Field(
        min_length=3, max_length=1000, description="convex window in the plane frame (u, v)")]


class DFNConfig(StrictModel):
    """``[dfn]``: domain, seeding, guard and fracture sets.

    Parameters
    ----------
    domain : DomainConfig
        ``[dfn.domain]``: the box the fractures are generated in.
    seed : int, default 0
        Root seed, 0 <= seed < 2**63 (docs/design.md §3.5 seeding rule).
    realizations : int, default 1
        Number of realizations, 1-10000 (indices 0..K-1).
    max_fractures : int, default 5,000,000
        Guard on the number of fractures one realization may need, 1 to 1e9.
    sets : list of FractureSetConfig
        1-50 sets, or none when ``fit`` is given.
    fit : FitConfig, optional
        Fit the sets from field data instead (exactly one of ``sets`` and ``fit``).
    sections : list of SectionConfig, default []
        Planes on which ``summary.json`` reports the traces of each realization: P21 measured and
        expected (Σ P32 / C23), with its Poisson standard deviation.
    """

    domain: DomainConfig
    seed: int = Field(0, ge=0, le=2 ** 63 - 1)
    realizations: int = Field(1, ge=1, le=10000)
    max_fractures: int = Field(5_000_000, ge=1, le=10 ** 9)
    sets: Annotated[list[FractureSetConfig], Field(max_length=50)] = Field(default_factory=list)
    fit: FitConfig | None = None
    sections: Annotated[list[SectionConfig], Field(max_length=100)] = Field(default_factory=list)

    @model_validator(mode="after")
    def _one_source_of_sets(self) -> DFNConfig:
        if bool(self.sets) == (self.fit is not None):
            raise field_problem(self, "sets", "give the fracture sets either as [[dfn.sets]] or as [dfn.fit] "
                                "(fitted from field data), exactly one of them", [])
        named = [s.name for s in self.sections if s.name]
        if len(set(named)) < len(named):  # [blocks.dfn_section] picks a section by its name
            raise field_problem(self, "sections", f"names must be unique, got {named}", named)
        return self

    def domain_m(self) -> np.ndarray:
        """The domain box as ``(2, 3)`` float64."""
        return np.array([self.domain.min_m, self.domain.max_m], dtype=float)


class DFNDocument(StrictModel):
    """The ``[dfn]`` section of a configuration file: what ``rockmass dfn`` runs and records in its
    manifest (the file may hold other sections too)."""

    dfn: DFNConfig
