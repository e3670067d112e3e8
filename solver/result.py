"""What a DEM run returns: per-stage reports, final state, histories, frames, block energies."""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import asdict, dataclass, field, fields

import numpy as np

__all__ = ["StageResult", "EnergyLedger", "Frame", "Result", "STATUS_OK", "STATUS_FAILED_BLOCKS",
           "FAILED_STATUSES"]

STATUS_OK = "ok"
STATUS_FAILED_BLOCKS = "failed_blocks"
FAILED_STATUSES = ("overlap", "unstable")


@dataclass(frozen=True, eq=False)
class EnergyLedger(Mapping):
    """A stage's energy ledger, J per metre of thickness (docs/dem.md §11).

    Work in (``work_gravity_j`` + ``work_boundary_j``) equals the change of kinetic and strain
    energy (of the contacts, and ``bolt_strain_*`` of the bolts' steel and grout; the kinetic
    energy includes the bolt nodes') plus what was dissipated (slip, bond breakage, damping, the
    bolts' grout slip and steel yield) and what left with blocks taken out; ``residual_j`` is what
    does not balance. ``damping_dissipation_j`` is the sum of the local,
    viscous (Rayleigh) and quiet-boundary terms. It reads like the ``energy`` object of
    ``result.json`` (a read-only mapping of these names), and :attr:`relative_error` is the guard's
    measure of it.
    """

    work_gravity_j: float
    work_boundary_j: float
    kinetic_start_j: float
    kinetic_end_j: float
    strain_start_j: float
    strain_end_j: float
    slip_dissipation_j: float
    breakage_dissipation_j: float
    damping_dissipation_j: float
    local_damping_j: float
    viscous_damping_j: float
    quiet_boundary_j: float
    removed_blocks_j: float
    residual_j: float
    # rock bolts (docs/dem.md §15; kernel entries E_BOLT_SLIP, E_BOLT_YIELD)
    bolt_strain_start_j: float = 0.0
    bolt_strain_end_j: float = 0.0
    bolt_slip_dissipation_j: float = 0.0
    bolt_yield_dissipation_j: float = 0.0
    # deformable blocks (docs/dem.md §16.5; kernel entries E_ZONE_PLASTIC, E_ZONE_MIXED)
    zone_plastic_dissipation_j: float = 0.0
    zone_mixed_work_j: float = 0.0

    def __getitem__(self, key: str) -> float:
        if key not in _LEDGER_TERMS:
            raise KeyError(key)
        return getattr(self, key)

    def __iter__(self) -> Iterator[str]:
        return iter(_LEDGER_TERMS)

    def __len__(self) -> int:
        return len(_LEDGER_TERMS)

    @property
    def turnover_j(self) -> float:
        """The energy turned over: |every term| added up, plus 10⁻⁶ of the strain energy held (the
        round-off of a large stored energy is not an error of the stage)."""
        return (abs(self.work_gravity_j) + abs(self.work_boundary_j)
                + abs(self.kinetic_end_j - self.kinetic_start_j)
                + abs(self.strain_end_j - self.strain_start_j)
                + abs(self.slip_dissipation_j) + abs(self.breakage_dissipation_j)
                + abs(self.damping_dissipation_j) + abs(self.removed_blocks_j)
                + abs(self.bolt_strain_end_j - self.bolt_strain_start_j)
                + abs(self.bolt_slip_dissipation_j) + abs(self.bolt_yield_dissipation_j)
                + 1e-6 * (self.strain_start_j + self.strain_end_j
                          + self.bolt_strain_start_j + self.bolt_strain_end_j))

    @property
    def relative_error(self) -> float:
        """|residual| / turnover (0 when nothing turned over)."""
        turnover = self.turnover_j
        return abs(self.residual_j) / turnover if turnover > 0 else 0.0


_LEDGER_TERMS = tuple(f.name for f in fields(EnergyLedger))


@dataclass(frozen=True)
class StageResult:
    """Report of one stage (every number finite; ``status`` says how the stage ended:
    ``converged`` / ``max_steps`` (static), ``failed_blocks`` (static: blocks kept moving and were
    taken out, ``converged`` says whether the rest reached equilibrium), ``completed`` (dynamic),
    ``overlap`` / ``unstable``).

    Displacements are the largest vertex displacement of a block from the run's reference state
    (after the initial equilibrium stage): ``max_displacement_m`` over the blocks still in the
    model, ``max_displacement_boundary_m`` over those that touched an excavated block;
    ``..._equilibrium_m`` the same without blocks smaller than ``Settings.sliver_area_m2``;
    ``max_displacement_stage_m`` from the stage's start. ``monitors``: displacement of the points
    fixed on the excavation boundary (``crown``, ``left_wall``, ``right_wall``, ``invert``; empty
    before anything is excavated). ``time_step_cuts``: how often contacts that formed during the
    stage lowered the time step. ``worst_block`` / ``worst_ratio``: the block with the largest
    own unbalanced force or moment ratio at the end (−1 / 0 when none moves).
    ``failed_blocks``: :meth:`rockmass.solver.failure.FailedBlock.to_dict` of each block taken out.
    """

    name: str
    kind: str
    status: str
    steps: int
    time_step_s: float
    stable_time_step_s: float
    simulated_time_s: float
    converged: bool | None
    unbalanced_ratio: float
    max_displacement_m: float
    max_displacement_boundary_m: float
    max_displacement_stage_m: float
    max_displacement_equilibrium_m: float
    max_displacement_boundary_equilibrium_m: float
    monitors: dict
    worst_block: int
    worst_ratio: float
    failed_blocks: list
    slipping_contacts: int
    open_contacts: int
    newly_broken_contacts: int
    broken_contacts: int
    detached_blocks: int
    blocks_removed: int
    energy: EnergyLedger
    wall_time_s: float
    contact_rebuilds: int
    diagnostic: str | None = None
    time_step_cuts: int = 0


@dataclass(frozen=True)
class Frame:
    """Block placement at one instant (for blocks_NNNN.vtu); ``failed``: blocks taken out so far
    because they kept moving (inactive too). ``zones``: with deformable blocks, their nodes'
    positions ``nodes_m``, the zones' ``stress_pa`` (compression positive) and ``plastic_state``
    at that instant, with the ``triangles`` and each zone's block ``zone_block``
    (docs/dem.md §16); None without."""

    stage: str
    step: int
    time_s: float
    position_m: np.ndarray
    rotation_rad: np.ndarray
    velocity_m_s: np.ndarray
    active: np.ndarray
    failed: np.ndarray
    zones: dict | None = None


@dataclass(frozen=True)
class Result:
    """Result of :func:`rockmass.solver.run`.

    ``displacement_m`` / ``rotation_rad`` / ``velocity_m_s``: final state of every block (excavated
    blocks keep their last values and ``active`` False). ``history``: columns of the monitored
    blocks (``time_s``, ``stage``, ``<name>_ux_m``, ``<name>_uy_m``, ``<name>_vx_m_s``,
    ``<name>_contact_fx_n`` (sum of contact forces on the block), …). ``contacts``: the active
    contact slots at the end (:meth:`Engine.contact_table`). ``bolts``: the bolt nodes at the end
    (:func:`rockmass.solver.bolts.bolt_table`: axial force along each bolt, yielded segments,
    bond slip; empty without bolts). ``zones``: the zones of deformable blocks at the end
    (:func:`rockmass.solver.deformable.zone_table`: nodes and their displacement, triangles,
    stress, strain, plastic state, and the original block of each block of the result — with
    deformable blocks the result's blocks are the model's pieces, each zone one; empty without);
    ``pieces``: that model of pieces (a BlockModel; None without deformable blocks).
    ``block_energy``: per block volume (area × 1 m), mass, peak velocity and peak kinetic energy
    over the dynamic stages (as in Kiran & Juneja 2022, Fig. 7; docs/dem.md, References).
    ``status`` is ``ok``, ``failed_blocks`` (blocks kept moving in a static stage and were taken
    out; ``failed`` marks them) or the failure of the last stage.
    """

    stages: list
    displacement_m: np.ndarray
    rotation_rad: np.ndarray
    velocity_m_s: np.ndarray
    active: np.ndarray
    history: dict
    frames: list
    block_energy: dict
    contacts: dict = field(default_factory=dict)
    status: str = STATUS_OK
    diagnostic: str | None = None
    info: dict = field(default_factory=dict)
    failed: np.ndarray | None = None
    bolts: dict = field(default_factory=dict)
    zones: dict = field(default_factory=dict)
    pieces: object = None

    @property
    def ok(self) -> bool:
        return self.status == STATUS_OK

    def stage(self, name: str) -> StageResult:
        for s in self.stages:
            if s.name == name:
                return s
        raise KeyError(f"no stage named {name!r} (stages: {[s.name for s in self.stages]})")

    def energy_table(self, n_bins: int = 8) -> list[dict]:
        """Blocks binned by volume (log bins): count, mean and max peak kinetic energy and speed."""
        vol = self.block_energy["volume_m3"]
        ke = self.block_energy["peak_kinetic_energy_j"]
        v = self.block_energy["peak_velocity_m_s"]
        keep = vol > 0
        if not keep.any():
            return []
        edges = np.geomspace(vol[keep].min(), vol[keep].max() * (1 + 1e-12), n_bins + 1)
        idx = np.clip(np.searchsorted(edges, vol, side="right") - 1, 0, n_bins - 1)
        rows = []
        for i in range(n_bins):
            sel = keep & (idx == i)
            if not sel.any():
                continue
            rows.append({"volume_min_m3": float(edges[i]), "volume_max_m3": float(edges[i + 1]),
                         "blocks": int(sel.sum()),
                         "mean_peak_kinetic_energy_j": float(ke[sel].mean()),
                         "max_peak_kinetic_energy_j": float(ke[sel].max()),
                         "mean_peak_velocity_m_s": float(v[sel].mean()),
                         "max_peak_velocity_m_s": float(v[sel].max())})
        return rows

    def to_json_dict(self) -> dict:
        return {"status": self.status, "diagnostic": self.diagnostic,
                "stages": [asdict(s) for s in self.stages],
                "max_displacement_m": float(np.max(np.hypot(*self.displacement_m[self.active].T),
                                                   initial=0.0)),
                "block_energy_vs_volume": self.energy_table(),
                "info": self.info} | ({"bolts": self.bolt_summary()} if self.bolts else {}) | (
                    {"zones": self.zone_summary()} if self.zones else {})

    def zone_summary(self) -> dict:
        """Deformable blocks at the end: zones, nodes, the area of the zones that yielded (ever,
        and at the last step; m² per m), the largest plastic strain and the largest node
        displacement (m)."""
        z = self.zones
        live = z["live"]
        ever = live & (z["plastic_state"] & 12 != 0)  # shear or tension, in the past
        now = live & (z["plastic_state"] & 3 != 0)
        return {"zones": int(live.sum()), "nodes": int(len(z["nodes_m"])),
                "plastic_area_m2": float(z["area_m2"][ever].sum()),
                "plastic_area_now_m2": float(z["area_m2"][now].sum()),
                "shear_yield_area_m2": float(z["area_m2"][live & (z["plastic_state"] & 4 != 0)].sum()),
                "tension_yield_area_m2": float(z["area_m2"][live & (z["plastic_state"] & 8 != 0)].sum()),
                "max_plastic_strain": float(np.max(z["plastic_strain"][live], initial=0.0)),
                "max_node_displacement_m": float(np.max(np.hypot(*z["node_displacement_m"].T),
                                                        initial=0.0))}

    def bolt_summary(self) -> list[dict]:
        """Per bolt: stage installed, largest and smallest axial force (N per m, tension +),
        segments yielded (ever), nodes slipping now, largest bond slip (m)."""
        t = self.bolts
        rows = []
        for name in dict.fromkeys(t["bolt"]):
            mine = t["bolt"] == name
            rows.append({"bolt": str(name), "stage": str(t["stage"][mine][0]),
                         "max_axial_force_n": float(np.max(t["axial_force_n"][mine])),
                         "min_axial_force_n": float(np.min(t["axial_force_n"][mine])),
                         "yielded_segments": int(np.sum(t["yielded"][mine])),
                         "slipping_nodes": int(np.sum(t["bond_slipping"][mine])),
                         "max_bond_slip_m": float(np.max(t["bond_slip_m"][mine]))})
        return rows
