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

    [[solve.bolt_patterns]]             # bolts by rule around the opening (docs/dem.md §15)
    stage = "arch"                      # installed at the start of this stage
    length_m = 5.0
    spacing_m = 1.5
    walls = ["roof", "left", "right"]
    [solve.bolt_patterns.properties]    # steel and grout of each bolt (UDEC cable)
    axial_stiffness_n = 1e8             # E·A (or youngs_modulus_pa and diameter_m)
    yield_force_n = 2.5e5
    bond_stiffness_n_m2 = 1e9
    bond_strength_n_m = 4e5
    out_of_plane_spacing_m = 1.5
    # [[solve.bolts]]: one bolt: start_xy_m, end_xy_m, stage, properties, segments

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

Parameters are declared once, on the solver's types
---------------------------------------------------
The tables ``material``, ``joints.*``, ``insitu``, ``fixes``, ``boundary_stress``, ``quiet``,
``monitors``, ``bolts``, ``bolt_patterns`` and the ``sine`` / ``ricker`` histories *are* the
solver's dataclasses
(:mod:`rockmass.solver.settings`: names, units, defaults, ranges, descriptions and cross-field
rules live there). :class:`SolveConfig`, :class:`StageConfig` and :class:`VelocityInputConfig` are
generated from :class:`~rockmass.solver.Settings`, :class:`~rockmass.solver.Stage` and
:class:`~rockmass.solver.VelocityInput` (:func:`rockmass.strict.library_section`); this module adds
only what TOML needs besides: ``blocks_file``, excavation stages by name, CSV histories. A new
parameter of the solver is therefore a new key here without an edit to this file.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field, Strict

from .solver.settings import (BandRecord, BoundaryStress, ContinuouslyYielding, Coulomb, Fix, InSituStress,
                              Material, Monitor, QuietBoundary, Ricker, Settings, Sine, Stage,
                              TableSine, VelocityInput)
from .strict import ConfigFile, StrictModel, config_file, in_folder, library_section

__all__ = ["SolveConfig", "SolveDocument", "MaterialConfig", "CoulombConfig", "CYConfig",
           "InSituConfig", "FixConfig", "BoundaryStressConfig", "SineConfig", "RickerConfig",
           "CsvHistoryConfig", "VelocityInputConfig", "QuietConfig", "MonitorConfig",
           "StageConfig", "read_history_csv"]

# the TOML tables that are the solver's own types (names kept for importers of this module)
MaterialConfig = Material
CoulombConfig = Coulomb
CYConfig = ContinuouslyYielding
InSituConfig = InSituStress
FixConfig = Fix
BoundaryStressConfig = BoundaryStress
SineConfig = Sine
RickerConfig = Ricker
QuietConfig = QuietBoundary
MonitorConfig = Monitor


class CsvHistoryConfig(StrictModel):
    """``type = "csv"``: a CSV file of ``time,value`` rows (relative to the config file; one header
    line and ``#`` comments allowed), values times ``scale``. ``kind = "acceleration"`` integrates
    the samples once (trapezoid, :meth:`rockmass.solver.TableHistory.integrated`) into velocity."""

    type: Annotated[Literal["csv"], Field(description="history kind: \"csv\"")]
    file: Annotated[ConfigFile, Field(description="CSV file of time,value rows")]
    kind: Annotated[Literal["velocity", "acceleration"], Field(
        description="what the values are (acceleration is integrated once)")] = "velocity"
    scale: Annotated[float, Field(ge=-1e6, le=1e6, description="factor on the values")] = 1.0

    def path(self, base: Path) -> Path:
        """The file, relative to the folder ``base`` of the config file."""
        return in_folder(base, self.file)

    def read(self, path: Path, where: str | None = None):
        """The :class:`~rockmass.solver.TableHistory` of the CSV file ``path`` read with this
        table's ``kind`` and ``scale`` (:func:`read_history_csv`; ``run`` and ``study`` read it
        before any stage runs)."""
        return read_history_csv(path, self.kind, self.scale, where)

    def to_solver(self, base: Path, where: str | None = None):
        """The :class:`~rockmass.solver.TableHistory` of the file."""
        return self.read(self.path(base), where)


HistoryConfig = Annotated[Sine | TableSine | BandRecord | Ricker | CsvHistoryConfig, Field(discriminator="type")]


def read_history_csv(path: Path, kind: str, scale: float, where: str | None = None):
    """A :class:`~rockmass.solver.TableHistory` from a ``time,value`` CSV (velocity in m/s, or
    acceleration in m/s² integrated once). Raises ``InputError`` naming the file, line and ``where``
    (the config field, when the caller does not name it itself)."""
    import csv

    from .errors import InputError
    from .solver import TableHistory

    shown = f"{path}: {where}" if where else f"{path}"
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise InputError(f"{shown}: cannot read the history file: {exc.strerror or exc}") from exc
    times, values = [], []
    for lineno, row in enumerate(csv.reader(text.splitlines()), start=1):
        if not row or not "".join(row).strip() or row[0].lstrip().startswith("#"):
            continue
        if len(row) < 2:
            raise InputError(f"{shown}: line {lineno}: expected time,value, got {row!r}")
        try:
            t, v = float(row[0]), float(row[1])
        except ValueError as exc:
            if not times and lineno == 1:
                continue  # a header line
            raise InputError(f"{shown}: line {lineno}: not a number: {row[:2]!r}") from exc
        times.append(t)
        values.append(v * scale)
    try:
        table = TableHistory(tuple(times), tuple(values), source=str(path))
    except ValueError as exc:
        raise InputError(f"{where}: {exc}" if where else str(exc)) from exc
    return table.integrated() if kind == "acceleration" else table


class VelocityInputConfig(library_section(VelocityInput, history=(HistoryConfig, Field(
        description="velocity history: a table with type = \"sine\", \"table_sine\", "
                    "\"band_record\", \"ricker\" or \"csv\"")))):
    """``[[solve.velocity_inputs]]``: :class:`rockmass.solver.VelocityInput` (dynamic stages) whose
    history is a sine (of velocity, or of the table's displacement), a Ricker wavelet or a CSV
    file."""


_Excavation = Annotated[str, Strict(), Field(min_length=1)] | Annotated[int, Strict(), Field(ge=1)]


class StageConfig(library_section(Stage, excavate=(
        Annotated[list[_Excavation], Field(max_length=64)],
        Field(default_factory=list, description="excavation stages of the block model removed at "
                                                "the start, by name or region number")))):
    """``[[solve.stages]]``: :class:`rockmass.solver.Stage`. ``excavate`` lists excavation stages of
    the block model by name (``"arch"``) or region number (1, 2, ...)."""

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


class SolveConfig(library_section(Settings, stages=list[StageConfig],
                                  velocity_inputs=list[VelocityInputConfig])):
    """``[solve]``: everything :func:`rockmass.solver.run` needs besides the blocks.

    Every key of :class:`rockmass.solver.Settings` (same names, units, defaults and ranges: it is
    generated from them), ``stages`` and ``velocity_inputs`` in their TOML form
    (:class:`StageConfig`, :class:`VelocityInputConfig`), and ``blocks_file``: a ``blocks.json``
    relative to the config file; without it the ``[blocks]`` section of the same file is built.
    """

    blocks_file: Annotated[ConfigFile | None, Field(
        description="blocks.json written by rockmass blocks; none: the [blocks] section")] = None

    def blocks_path(self, config_path) -> Path | None:
        return config_file(config_path, self.blocks_file)

    def to_settings(self, model, config_path):
        """:class:`rockmass.solver.Settings` for ``model`` (excavation names resolved against its
        regions, CSV histories read relative to ``config_path``). Raises ``InputError`` naming the
        file and the field (``solve.stages[1].excavate``)."""
        from .blockgen.model import CONTACT_KINDS
        from .errors import InputError, reading

        base = Path(config_path).parent
        shown = str(config_path)

        def build(field, make):
            try:
                return make()
            except InputError:
                raise
            except ValueError as exc:
                raise InputError(f"{shown}: solve{'.' + field if field else ''}: {exc}") from exc

        known = ["default", *model.set_names, *(k for k in CONTACT_KINDS if k != "domain")]
        for label in self.joints:
            if label not in known:
                raise InputError(f"{shown}: solve.joints.{label}: no contact has this label (a "
                                 f"joint set name of the block model, a contact kind or default: "
                                 f"{', '.join(map(repr, known))})")
        _check_model_references(self, model, build)
        stages = []
        for i, s in enumerate(self.stages):
            regions = build(f"stages[{i}].excavate", lambda s=s: s.regions(model))
            stages.append(build(f"stages[{i}]", lambda s=s, r=regions: s.to_library(excavate=r)))
        inputs = []
        for i, v in enumerate(self.velocity_inputs):
            field = f"velocity_inputs[{i}].history"
            history = v.history
            if isinstance(history, CsvHistoryConfig):  # named as run and study name it
                with reading(history.path(base), f"solve.{field}.file", config=config_path):
                    history = history.to_solver(base)
            inputs.append(build(f"velocity_inputs[{i}]", lambda v=v, h=history: v.to_library(
                history=h)))
        return build("", lambda: self.to_library(stages=tuple(stages),
                                                 velocity_inputs=tuple(inputs)))


def _check_model_references(cfg, model, build) -> None:
    """The selectors of ``fixes`` / ``velocity_inputs`` and the monitors checked against ``model``
    before the solver starts, so that a problem names its key path (the solver itself finds them
    too, but names only the monitor or the selector)."""
    from .solver.selectors import SIDES, require_point_in_domain, select_blocks

    for table in ("fixes", "velocity_inputs"):
        for i, item in enumerate(getattr(cfg, table)):
            if item.where.strip() not in SIDES:  # a side needs the engine's edges: always valid
                build(f"{table}[{i}].where", lambda w=item.where: select_blocks(model, w, None))
    for i, m in enumerate(cfg.monitors):
        if m.block is not None and not 0 <= m.block < model.n_blocks:
            build(f"monitors[{i}].block", lambda m=m: _raise(
                f"must be a block index in [0, {model.n_blocks}), got {m.block}"))
        elif m.block is None:
            build(f"monitors[{i}].point_xy_m", lambda m=m: require_point_in_domain(
                model, m.name, m.point_xy_m))


def _raise(message: str):
    raise ValueError(message)


class SolveDocument(StrictModel):
    """Top level with the ``[solve]`` section only."""

    solve: SolveConfig
