"""``[solve]``: the DEM run section (:func:`rockmass.solver.run`), strict and range-checked.

The section maps one-to-one onto :class:`rockmass.solver.Settings` (same field names, same units and
sign conventions: stresses compression positive in Pa, joint stiffnesses in Pa/m, angles in degrees).
Example::

    [solve]
    blocks_file = "out/blocks.json"     # or a [blocks] section in the same file
    gravity_m_s2 = [0.0, -9.81]

    [solve.material]
    density_kg_m3 = 2700.0

    [solve.joints.default]              # a label: joint set name, contact kind or "default"
    model = "coulomb"                   # or "cy" (continuously yielding)
    kn_pa_m = 1e10
    ks_pa_m = 5e9
    friction_deg = 30.0

    [[solve.fixes]]
    where = "bottom"                    # side, "region:K", "box:x0,y0,x1,y1", "blocks:i,j"
    dofs = "xyr"

    [[solve.velocity_inputs]]
    where = "bottom"
    component = "x"
    history = { type = "sine", amplitude = 0.1, frequency_hz = 2.0, cycles = 4 }
    # or { type = "ricker", amplitude = ..., peak_frequency_hz = ... }
    # or { type = "csv", file = "motion.csv", kind = "acceleration", scale = 9.81 }

    [[solve.monitors]]
    name = "crown"
    point_xy_m = [0.0, 16.0]

    [[solve.stages]]
    name = "equilibrium"
    [[solve.stages]]
    name = "arch"
    excavate = ["arch"]                 # excavation stage names (or region numbers) of the model

The blocks come from ``blocks_file`` (a ``blocks.json`` written by ``rockmass blocks``, relative to
the config file) or, when it is absent, from the ``[blocks]`` section of the same file (built
exactly as ``rockmass blocks`` builds it). :meth:`SolveConfig.to_settings` turns the section into
:class:`~rockmass.solver.Settings` for a given model; ``rockmass solve`` and the Python API
therefore run the same thing.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field, model_validator

from .strict import StrictModel, field_problem

__all__ = ["SolveConfig", "SolveDocument", "MaterialConfig", "CoulombConfig", "CYConfig",
           "InSituConfig", "FixConfig", "BoundaryStressConfig", "SineConfig", "RickerConfig",
           "CsvHistoryConfig", "VelocityInputConfig", "QuietConfig", "MonitorConfig",
           "StageConfig", "StageClock", "read_history_csv"]

Coord = Annotated[float, Field(ge=-1e7, le=1e7)]
Point = Annotated[tuple[Coord, Coord], Field(strict=False)]
Stiffness = Annotated[float, Field(gt=0, le=1e16)]
Friction = Annotated[float, Field(ge=0, lt=90)]
Stress = Annotated[float, Field(ge=-1e11, le=1e11)]
Name = Annotated[str, Field(min_length=1, max_length=64)]
Side = Literal["left", "right", "bottom", "top"]
Sides = Annotated[list[Side], Field(min_length=1, max_length=4)]
Where = Annotated[str, Field(min_length=1, max_length=4096)]


class MaterialConfig(StrictModel):
    """``[solve.material]``: :class:`rockmass.solver.Material` (density; moduli for quiet
    boundaries only, the blocks are rigid)."""

    density_kg_m3: float = Field(2700.0, gt=0, le=1e5)
    bulk_modulus_pa: float | None = Field(None, gt=0, le=1e13)
    shear_modulus_pa: float | None = Field(None, gt=0, le=1e13)

    def to_solver(self):
        from .solver import Material

        return Material(**self.model_dump())


class CoulombConfig(StrictModel):
    """``model = "coulomb"``: :class:`rockmass.solver.Coulomb` (brittle Coulomb slip)."""

    model: Literal["coulomb"]
    kn_pa_m: Stiffness
    ks_pa_m: Stiffness
    friction_deg: Friction
    cohesion_pa: float = Field(0.0, ge=0, le=1e11)
    tension_pa: float = Field(0.0, ge=0, le=1e11)
    dilation_deg: float = Field(0.0, ge=0, lt=60)
    residual_friction_deg: Friction | None = None
    max_dilation_m: float | None = Field(None, ge=0, le=1e3)

    def to_solver(self):
        import math

        from .solver import Coulomb

        values = self.model_dump(exclude={"model"})
        if values["max_dilation_m"] is None:
            values["max_dilation_m"] = math.inf
        return Coulomb(**values)


class CYConfig(StrictModel):
    """``model = "cy"``: :class:`rockmass.solver.ContinuouslyYielding` (seed 001 eqs. 4–13)."""

    model: Literal["cy"]
    an_pa_m: Stiffness
    as_pa_m: Stiffness
    initial_friction_deg: Friction = 59.3
    basic_friction_deg: Friction = 30.0
    roughness_m: float = Field(1e-4, gt=0, le=1e3)
    en: float = Field(0.0, ge=0, lt=1)
    es: float = Field(0.0, ge=0, lt=1)

    @model_validator(mode="after")
    def _basic_below_initial(self):
        if self.basic_friction_deg > self.initial_friction_deg:
            raise field_problem(self, "basic_friction_deg", "must not exceed initial_friction_deg "
                                f"({self.initial_friction_deg}), got {self.basic_friction_deg}",
                                self.basic_friction_deg)
        return self

    def to_solver(self):
        from .solver import ContinuouslyYielding

        return ContinuouslyYielding(**self.model_dump(exclude={"model"}))


JointConfig = Annotated[CoulombConfig | CYConfig, Field(discriminator="model")]


class InSituConfig(StrictModel):
    """``[solve.insitu]``: :class:`rockmass.solver.InSituStress` (compression positive, Pa)."""

    sxx_pa: Stress = 0.0
    syy_pa: Stress = 0.0
    sxy_pa: Stress = 0.0
    gravity_gradient: bool = False
    k0: float = Field(1.0, ge=0, le=100)
    y_ref_m: Coord | None = None

    def to_solver(self):
        from .solver import InSituStress

        return InSituStress(**self.model_dump())


class FixConfig(StrictModel):
    """``[[solve.fixes]]``: :class:`rockmass.solver.Fix` (``where`` selector, ``dofs`` of x, y, r)."""

    where: Where
    dofs: Annotated[str, Field(pattern=r"^[xyr]{1,3}$")] = "xyr"

    def to_solver(self):
        from .solver import Fix

        return Fix(**self.model_dump())


class BoundaryStressConfig(StrictModel):
    """``[[solve.boundary_stress]]``: :class:`rockmass.solver.BoundaryStress`."""

    sides: Sides
    sxx_pa: Stress = 0.0
    syy_pa: Stress = 0.0
    sxy_pa: Stress = 0.0
    from_insitu: bool = False

    def to_solver(self):
        from .solver import BoundaryStress

        return BoundaryStress(**self.model_dump())


class SineConfig(StrictModel):
    """``type = "sine"``: v(t) = amplitude sin(2π f t) for ``cycles`` cycles (all time if absent)."""

    type: Literal["sine"]
    amplitude: float = Field(ge=-1e6, le=1e6)
    frequency_hz: float = Field(gt=0, le=1e7)
    cycles: float | None = Field(None, gt=0, le=1e7)

    def to_solver(self, base: Path, where: str):
        from .solver import Sine

        return Sine(self.amplitude, self.frequency_hz, self.cycles)


class RickerConfig(StrictModel):
    """``type = "ricker"``: a Ricker wavelet of peak frequency f centred at ``t0_s`` (1.5/f)."""

    type: Literal["ricker"]
    amplitude: float = Field(ge=-1e6, le=1e6)
    peak_frequency_hz: float = Field(gt=0, le=1e7)
    t0_s: float | None = Field(None, ge=0, le=1e7)

    def to_solver(self, base: Path, where: str):
        from .solver import Ricker

        return Ricker(self.amplitude, self.peak_frequency_hz, self.t0_s)


class CsvHistoryConfig(StrictModel):
    """``type = "csv"``: a CSV file of ``time,value`` rows (relative to the config file; one header
    line and ``#`` comments allowed), values times ``scale``. ``kind = "acceleration"`` integrates
    the samples once (trapezoid, :meth:`rockmass.solver.TableHistory.integrated`) into velocity."""

    type: Literal["csv"]
    file: Annotated[str, Field(min_length=1)]
    kind: Literal["velocity", "acceleration"] = "velocity"
    scale: float = Field(1.0, ge=-1e6, le=1e6)

    def path(self, base: Path) -> Path:
        p = Path(self.file)
        return p if p.is_absolute() else base / p

    def to_solver(self, base: Path, where: str):
        return read_history_csv(self.path(base), self.kind, self.scale, where)


HistoryConfig = Annotated[SineConfig | RickerConfig | CsvHistoryConfig, Field(discriminator="type")]


def read_history_csv(path: Path, kind: str, scale: float, where: str):
    """A :class:`~rockmass.solver.TableHistory` from a ``time,value`` CSV (velocity in m/s, or
    acceleration in m/s² integrated once). Raises ``InputError`` naming the file, line and ``where``."""
    import csv

    from .errors import InputError
    from .solver import TableHistory

    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise InputError(f"{path}: {where}: cannot read the history file: "
                         f"{exc.strerror or exc}") from exc
    times, values = [], []
    for lineno, row in enumerate(csv.reader(text.splitlines()), start=1):
        if not row or not "".join(row).strip() or row[0].lstrip().startswith("#"):
            continue
        if len(row) < 2:
            raise InputError(f"{path}: {where}: line {lineno}: expected time,value, got {row!r}")
        try:
            t, v = float(row[0]), float(row[1])
        except ValueError as exc:
            if not times and lineno == 1:
                continue  # a header line
            raise InputError(f"{path}: {where}: line {lineno}: not a number: {row[:2]!r}") from exc
        times.append(t)
        values.append(v * scale)
    try:
        table = TableHistory(tuple(times), tuple(values), source=str(path))
    except ValueError as exc:
        raise InputError(f"{where}: {exc}") from exc
    return table.integrated() if kind == "acceleration" else table


class StageClock:
    """A history on the dynamic stage's own clock: t = 0 at the first instant it is evaluated.

    :func:`rockmass.solver.run` evaluates velocity histories only in dynamic stages, at the run's
    time, which includes the pseudo-time of the static stages before; wrapped, a ``Sine`` with
    ``cycles`` starts at phase 0 when the shaking starts and ends after whole cycles (see
    /tmp/solver_bugs.md). The first call's first time is ``t_start + dt/2`` (mid-step), so
    ``t_start`` is recovered from the first two samples. If the solver already passes stage time
    the shift is 0 and this is a no-op. One instance per run (:meth:`SolveConfig.to_settings`).
    """

    def __init__(self, history):
        self.history = history
        self.t_start_s = None

    def __call__(self, t):
        import numpy as np

        t = np.asarray(t, float)
        if self.t_start_s is None and t.size:
            half = 0.5 * (t.flat[1] - t.flat[0]) if t.size > 1 else 0.0
            self.t_start_s = float(t.flat[0] - half)
        return self.history(t - (self.t_start_s or 0.0))

    def __repr__(self) -> str:
        return f"StageClock({self.history!r})"


class VelocityInputConfig(StrictModel):
    """``[[solve.velocity_inputs]]``: :class:`rockmass.solver.VelocityInput` (dynamic stages)."""

    where: Where
    component: Literal["x", "y"]
    history: HistoryConfig


class QuietConfig(StrictModel):
    """``[solve.quiet]``: :class:`rockmass.solver.QuietBoundary` (viscous boundary on ``sides``;
    needs ``material.bulk_modulus_pa`` and ``shear_modulus_pa``)."""

    sides: Sides


class MonitorConfig(StrictModel):
    """``[[solve.monitors]]``: the block containing ``point_xy_m``, or block number ``block``."""

    name: Annotated[str, Field(pattern=r"^[A-Za-z0-9_\-]{1,40}$")]
    point_xy_m: Point | None = None
    block: int | None = Field(None, ge=0)

    @model_validator(mode="after")
    def _one_of(self):
        if (self.point_xy_m is None) == (self.block is None):
            raise field_problem(self, "point_xy_m", "give exactly one of point_xy_m and block",
                                self.point_xy_m)
        return self


class StageConfig(StrictModel):
    """``[[solve.stages]]``: :class:`rockmass.solver.Stage`. ``excavate`` lists excavation stages of
    the block model by name (``"arch"``) or region number (1, 2, ...)."""

    name: Name
    kind: Literal["static", "dynamic"] = "static"
    excavate: Annotated[list[Annotated[str, Field(min_length=1)] | Annotated[int, Field(ge=1)]],
                        Field(max_length=64)] = Field(default_factory=list)
    max_steps: int = Field(200_000, ge=1, le=10 ** 10)
    tolerance: float = Field(1e-5, gt=0, le=1)
    block_tolerance: float = Field(1e-3, gt=0, le=1)
    local_damping: float = Field(0.8, ge=0, lt=1)
    duration_s: float | None = Field(None, gt=0, le=1e6)
    rayleigh_ratio: float = Field(0.0, ge=0, lt=1)
    rayleigh_frequency_hz: float | None = Field(None, gt=0, le=1e9)
    time_step_s: float | None = Field(None, gt=0, le=1e3)
    frames: int = Field(10, ge=0, le=10_000)
    history_every: int = Field(0, ge=0, le=10 ** 9)

    @model_validator(mode="after")
    def _kind_needs(self):
        if self.kind == "dynamic" and self.duration_s is None:
            raise field_problem(self, "duration_s", "a dynamic stage needs duration_s (> 0 s)", None)
        if self.rayleigh_ratio > 0 and self.rayleigh_frequency_hz is None:
            raise field_problem(self, "rayleigh_frequency_hz", "required when rayleigh_ratio > 0",
                                None)
        return self

    def regions(self, model) -> tuple[int, ...]:
        """Region numbers of ``excavate`` in ``model`` (ValueError naming the unknown entry)."""
        names = list(model.region_names)
        out = []
        for item in self.excavate:
            if isinstance(item, str):
                if item not in names[1:]:
                    raise ValueError(f"unknown excavation stage {item!r} (the block model has "
                                     f"{', '.join(map(repr, names[1:])) or 'none'})")
                out.append(names.index(item))
            else:
                if item >= len(names):
                    raise ValueError(f"region {item} does not exist (the block model has regions "
                                     f"1..{len(names) - 1})")
                out.append(item)
        return tuple(out)


class SolveConfig(StrictModel):
    """``[solve]``: everything :func:`rockmass.solver.run` needs besides the blocks.

    Parameters
    ----------
    blocks_file : str, optional
        ``blocks.json`` relative to the config file; without it the ``[blocks]`` section of the same
        file is built.
    joints : table of label -> joint model
        Needs ``default``; other labels are joint set names or contact kinds (``joint``, ``trace``,
        ``glued``, ``excavation``) as in :class:`rockmass.solver.Settings`.
    stages : list of StageConfig
        At least one, unique names, run in order.
    material, gravity_m_s2, insitu, fixes, boundary_stress, velocity_inputs, quiet, monitors,
    rounding_m, contact_tolerance_m, time_step_safety, sleep, failure_displacement_m,
    failure_checks, sliver_area_m2, energy_tolerance
        As in :class:`rockmass.solver.Settings`.
    """

    blocks_file: Annotated[str, Field(min_length=1)] | None = None
    material: MaterialConfig = Field(default_factory=MaterialConfig)
    joints: Annotated[dict[Annotated[str, Field(min_length=1, max_length=64)], JointConfig],
                      Field(min_length=1)]
    gravity_m_s2: Annotated[tuple[Annotated[float, Field(ge=-1e4, le=1e4)],
                                  Annotated[float, Field(ge=-1e4, le=1e4)]],
                            Field(strict=False)] = (0.0, -9.81)
    insitu: InSituConfig | None = None
    fixes: Annotated[list[FixConfig], Field(max_length=256)] = Field(default_factory=list)
    boundary_stress: Annotated[list[BoundaryStressConfig], Field(max_length=16)] = \
        Field(default_factory=list)
    velocity_inputs: Annotated[list[VelocityInputConfig], Field(max_length=64)] = \
        Field(default_factory=list)
    quiet: QuietConfig | None = None
    monitors: Annotated[list[MonitorConfig], Field(max_length=1000)] = Field(default_factory=list)
    stages: Annotated[list[StageConfig], Field(min_length=1, max_length=1000)]
    rounding_m: float | None = Field(None, gt=0, le=1e6)
    contact_tolerance_m: float | None = Field(None, gt=0, le=1e6)
    time_step_safety: float = Field(0.5, gt=0, le=1)
    sleep: bool = False
    failure_displacement_m: float | None = Field(None, gt=0, le=1e6)
    failure_checks: int = Field(3, ge=1, le=1000)
    sliver_area_m2: float = Field(0.0, ge=0, le=1e12)
    energy_tolerance: float = Field(0.2, gt=0, le=1e6)

    @model_validator(mode="after")
    def _cross(self):
        if "default" not in self.joints:
            raise field_problem(self, "joints", "needs a 'default' joint model ([solve.joints."
                                "default]: used for any contact whose set or kind has none, and "
                                "for contacts formed during the run)", sorted(self.joints))
        names = [s.name for s in self.stages]
        if len(set(names)) != len(names):
            raise field_problem(self, "stages", f"stage names must be unique, got {names}", names)
        monitors = [m.name for m in self.monitors]
        if len(set(monitors)) != len(monitors):
            raise field_problem(self, "monitors", f"monitor names must be unique, got {monitors}",
                                monitors)
        if self.quiet is not None and (self.material.bulk_modulus_pa is None
                                       or self.material.shear_modulus_pa is None):
            raise field_problem(self, "quiet", "quiet boundaries need material.bulk_modulus_pa "
                                "and material.shear_modulus_pa", None)
        return self

    def blocks_path(self, config_path) -> Path | None:
        if self.blocks_file is None:
            return None
        p = Path(self.blocks_file)
        return p if p.is_absolute() else Path(config_path).parent / p

    def to_settings(self, model, config_path):
        """:class:`rockmass.solver.Settings` for ``model`` (excavation names resolved against its
        regions, CSV histories read relative to ``config_path``). Raises ``InputError`` naming the
        file and the field (``solve.stages[1].excavate``)."""
        from .errors import InputError
        from .solver import Monitor, QuietBoundary, Settings, Stage, VelocityInput

        base = Path(config_path).parent
        shown = str(config_path)

        def build(field, make):
            try:
                return make()
            except InputError:
                raise
            except ValueError as exc:
                raise InputError(f"{shown}: solve{'.' + field if field else ''}: {exc}") from exc

        from .blockgen.model import CONTACT_KINDS

        known = ["default", *model.set_names, *(k for k in CONTACT_KINDS if k != "domain")]
        for label in self.joints:
            if label not in known:
                raise InputError(f"{shown}: solve.joints.{label}: no contact has this label (a "
                                 f"joint set name of the block model, a contact kind or default: "
                                 f"{', '.join(map(repr, known))})")
        joints = {label: build(f"joints.{label}", j.to_solver) for label, j in self.joints.items()}
        stages = []
        for i, s in enumerate(self.stages):
            regions = build(f"stages[{i}].excavate", lambda s=s: s.regions(model))
            values = s.model_dump(exclude={"excavate"})
            stages.append(build(f"stages[{i}]", lambda v=values, r=regions: Stage(**v, excavate=r)))
        inputs = []
        for i, v in enumerate(self.velocity_inputs):
            field = f"velocity_inputs[{i}].history"
            history = build(field, lambda v=v, field=field: v.history.to_solver(base,
                                                                                f"solve.{field}"))
            inputs.append(build(f"velocity_inputs[{i}]", lambda v=v, h=history: VelocityInput(
                v.where, v.component, StageClock(h))))
        monitors = [build(f"monitors[{i}]", lambda m=m: Monitor(
            m.name, None if m.point_xy_m is None else tuple(m.point_xy_m), m.block))
            for i, m in enumerate(self.monitors)]
        return build("", lambda: Settings(
            joints=joints, stages=tuple(stages),
            material=self.material.to_solver(),
            gravity_m_s2=tuple(self.gravity_m_s2),
            insitu=None if self.insitu is None else self.insitu.to_solver(),
            fixes=tuple(build(f"fixes[{i}]", f.to_solver) for i, f in enumerate(self.fixes)),
            boundary_stress=tuple(build(f"boundary_stress[{i}]", b.to_solver)
                                  for i, b in enumerate(self.boundary_stress)),
            velocity_inputs=tuple(inputs),
            quiet=None if self.quiet is None else QuietBoundary(tuple(self.quiet.sides)),
            monitors=tuple(monitors), rounding_m=self.rounding_m,
            contact_tolerance_m=self.contact_tolerance_m,
            time_step_safety=self.time_step_safety, sleep=self.sleep,
            failure_displacement_m=self.failure_displacement_m,
            failure_checks=self.failure_checks, sliver_area_m2=self.sliver_area_m2,
            energy_tolerance=self.energy_tolerance))


class SolveDocument(StrictModel):
    """Top level with the ``[solve]`` section only."""

    solve: SolveConfig
