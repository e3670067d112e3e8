"""The distinct element (DEM) core: polygonal blocks on joint contacts (2D, unit thickness), rigid or
deformable (meshed into triangular zones, :mod:`rockmass.solver.zones`, docs/dem.md §16).

Public names
------------
:func:`run`
    ``run(model, settings) -> Result``: the stages of a run (:mod:`rockmass.solver.runner`).
:class:`Settings`, :class:`Stage`, :class:`Material`, :class:`Coulomb`,
:class:`ContinuouslyYielding`, :class:`InSituStress`, :class:`Fix`, :class:`BoundaryStress`,
:class:`VelocityInput`, :class:`Sine`, :class:`TableSine`, :class:`BandRecord`, :class:`Ricker`,
:class:`TableHistory`,
:class:`QuietBoundary`, :class:`FreeField`, :class:`Monitor`, :class:`Bolt`,
:class:`BoltPattern`, :class:`BoltProperties`, :class:`Deformable`
    What a run needs besides the blocks (:mod:`rockmass.solver.settings`).
:class:`Elastic`, :class:`MohrCoulomb`, :class:`HoekBrown`
    The zones' constitutive models of deformable blocks (:mod:`rockmass.solver.zones`).
:class:`Result`, :class:`StageResult`, :class:`Frame`
    What it returns (:mod:`rockmass.solver.result`).
:class:`Engine`
    The mutable state and its operations, for tests and custom drivers (:mod:`rockmass.solver.engine`).

Also: :mod:`rockmass.solver.failure` (blocks that keep moving in a static stage: detected,
classified as fall / slide / rotation, taken out) and :mod:`rockmass.solver.monitoring` (points
fixed on the excavation boundary: crown, walls, invert), :mod:`rockmass.solver.bolts` (rock bolts:
cable elements grouted into the blocks, docs/dem.md §15), :mod:`rockmass.solver.zones` and
:mod:`rockmass.solver.deformable` (deformable blocks: zones, constitutive models, the zoned
model, docs/dem.md §16), :mod:`rockmass.solver.vtu` (the frames as
ParaView files: ``blocks_NNNN.vtu`` and ``blocks.pvd``) and :mod:`rockmass.solver.tolerances` (the
numeric policy, each constant with its reason). The formulas are in docs/dem.md.

The numba kernels (:mod:`rockmass.solver._kernels`) load on first use of :func:`run` or
:class:`Engine`; importing this package does not compile anything.
"""

from .result import Frame, Result, StageResult
from .settings import (BandRecord, Bolt, BoltPattern, BoltProperties, BoundaryStress, ContinuouslyYielding,
                       Coulomb, Deformable, Fix, FreeField, InSituStress, Material, Monitor,
                       QuietBoundary, Ricker, Settings, Sine, Stage, TableHistory, TableSine,
                       VelocityInput)
from .zones import Elastic, HoekBrown, MohrCoulomb

__all__ = ["run", "Engine", "Settings", "Stage", "Material", "Coulomb", "ContinuouslyYielding",
           "InSituStress", "Fix", "BoundaryStress", "VelocityInput", "Sine", "TableSine", "BandRecord",
           "Ricker",
           "TableHistory", "QuietBoundary", "FreeField", "Monitor", "Bolt", "BoltPattern",
           "BoltProperties", "Deformable", "Elastic", "MohrCoulomb", "HoekBrown", "Result",
           "StageResult", "Frame"]


def __getattr__(name):  # numba only when a run starts
    if name == "run":
        from .runner import run

        return run
    if name == "Engine":
        from .engine import Engine

        return Engine
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
