"""The DEM state and its operations: set-up from a BlockModel, contact search, time step, in-situ
stress, excavation and stepping. :func:`rockmass.solver.run` drives it stage by stage.

The arrays follow the layout of :mod:`rockmass.solver._kernels`; this class owns them and is the
only place that calls the kernels.
"""

from __future__ import annotations

import math

import numpy as np

from ..blockgen.tolerances import ROUNDING_FRACTION
from . import _kernels as K
from . import tolerances as T
from .bolts import bolt_bound, bolt_kinetic_energy, empty_bolt_tables
from .deformable import ZONE_STATE, DeformableBlocks
from .selectors import domain_edges, select_blocks
from .settings import ContinuouslyYielding, Coulomb, Settings

__all__ = ["Engine", "joint_table", "rounded_corners", "strip_collinear"]

_DOF = {"x": 0, "y": 1, "r": 2}
FREE, FIXED, PRESCRIBED = 0, 1, 2


def joint_table(models: list) -> np.ndarray:
    """Rows of the kernel's joint-model table (columns ``P_*`` of :mod:`._kernels`)."""
    table = np.zeros((len(models), K.N_PROP_COLUMNS))
    for row, m in zip(table, models):
        if isinstance(m, Coulomb):
            row[K.P_MODEL] = K.MODEL_COULOMB
            row[K.P_KN], row[K.P_KS] = m.kn_pa_m, m.ks_pa_m
            row[K.P_TANPHI] = math.tan(math.radians(m.friction_deg))
            row[K.P_COH], row[K.P_TEN] = m.cohesion_pa, m.tension_pa
            row[K.P_TANPSI] = math.tan(math.radians(m.dilation_deg))
            row[K.P_TANPHIR] = math.tan(math.radians(m.residual_deg))
            row[K.P_MAXDIL] = (m.max_dilation_m if math.isfinite(m.max_dilation_m)
                               else T.NO_DILATION_LIMIT_M)
        elif isinstance(m, ContinuouslyYielding):
            row[K.P_MODEL] = K.MODEL_CY
            row[K.P_KN], row[K.P_KS] = m.an_pa_m, m.as_pa_m
            row[K.P_EN], row[K.P_ES] = m.en, m.es
            row[K.P_PHIM0] = math.radians(m.initial_friction_deg)
            row[K.P_PHIB] = math.radians(m.basic_friction_deg)
            row[K.P_ROUGH] = m.roughness_m
            row[K.P_TANPHI] = math.tan(math.radians(m.initial_friction_deg))
        else:  # pragma: no cover - Settings checks the types
            raise TypeError(f"unknown joint model {m!r}")
    return table


def _add_rows(rows: np.ndarray, index: np.ndarray, values: np.ndarray):
    """rows[index[i]] += values[i] for repeated indices: np.add.at by bincount (224k rows of 3
    into 45k: 1.1 ms against 6.4 ms)."""
    for j in range(rows.shape[1]):
        rows[:, j] += np.bincount(index, weights=values[:, j], minlength=len(rows))


def ring_neighbours(offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Indices of the next and the previous vertex of every vertex, each block a closed ring
    ``offsets[b]:offsets[b+1]``."""
    idx = np.arange(offsets[-1])
    nxt = idx + 1
    nxt[offsets[1:] - 1] = offsets[:-1]
    prv = idx - 1
    prv[offsets[:-1]] = offsets[1:] - 1
    return nxt, prv


def strip_collinear(xy: np.ndarray, offsets: np.ndarray, tol_m: float):
    """Drop vertices where a block's boundary runs straight on: the vertex lies less than ``tol_m``
    from the chord between its two neighbours, h = |e₀ × e₁| / |e₀ + e₁| (e₀, e₁ the edges into
    and out of it).

    blockgen keeps such vertices where a neighbour's corner meets an edge (T-junctions), so that
    contacts match edge by edge; for the rigid-block narrow phase they would split one face into
    collinear pieces, and the separating-axis test could pick a piece that does not face the
    neighbour (the two blocks then touch at a point). Area, centroid and inertia are taken from
    the block model, unchanged. A block that would keep fewer than 3 vertices is kept as given.
    """
    n = len(offsets) - 1
    block = np.repeat(np.arange(n), np.diff(offsets))
    nxt, prv = ring_neighbours(offsets)
    e0 = xy - xy[prv]
    e1 = xy[nxt] - xy
    cross = e0[:, 0] * e1[:, 1] - e0[:, 1] * e1[:, 0]
    chord = np.hypot(*(e0 + e1).T)
    keep = np.abs(cross) >= tol_m * chord
    counts = np.bincount(block[keep], minlength=n)
    if (counts < 3).any():  # degenerate block: keep it as given
        bad = counts < 3
        keep |= bad[block]
        counts = np.bincount(block[keep], minlength=n)
    return np.ascontiguousarray(xy[keep]), np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)


def rounded_corners(loc: np.ndarray, off: np.ndarray, normal: np.ndarray, rounding: float):
    """Rounded corners of convex blocks: arc centres, tangent lengths and each block's radius.

    Every corner of block b is replaced by a circular arc of radius r_b tangent to its two edges
    (outward unit normals n₁ of the edge ending at the vertex v, n₂ of the edge starting there).
    The arc centre lies r_b inside both edges, C = v − r_b (n₁ + n₂)/(1 + n₁·n₂), and touches them
    at the tangent length r_b tan(θ/2) = r_b |n₁ × n₂|/(1 + n₁·n₂) from v (θ the turn at v). The
    rounded block is its inner polygon of centres (the block inset by r_b) grown by a disk of
    radius r_b, so contacts between rounded blocks are distances between inner polygons minus the
    two radii (UDEC's rounding; docs/dem.md §3.1; Cundall 1988).

    r_b is the rounding d, reduced on a block whose corners would eat more than half of an edge
    (sharp sliver corners): r_b = min(d, min over edges ½ L / (tan(θ₀/2) + tan(θ₁/2))), so every
    edge keeps at least half of its length flat.

    A vertex where the boundary runs straight on (a T-junction's vertex in the through-going
    block; exactly collinear or reflex by round-off) has no arc (tangent length 0) but its centre
    is still inset, C = v − r_b n (the same formula at n₁ = n₂): the inner polygon is then the
    block inset by r_b everywhere. Left on the boundary, such a centre met the neighbour's inner
    polygon where both share that vertex and made a false overlap of r_a + r_b at rest.

    Parameters
    ----------
    loc : (V, 2) ndarray
        Vertices about each block's centroid, counter-clockwise, ``off`` the block offsets.
    normal : (V, 2) ndarray
        Outward unit normal of the edge that starts at each vertex.
    rounding : float
        The rounding d (m), > 0.

    Returns
    -------
    centre : (V, 2) ndarray
        Arc centres about the centroid.
    tangent : (V,) ndarray
        Tangent lengths r_b tan(θ/2) (m).
    radius : (B,) ndarray
        r_b of each block (m).
    """
    nb = len(off) - 1
    block = np.repeat(np.arange(nb), np.diff(off))
    nxt, prv = ring_neighbours(off)
    n1, n2 = normal[prv], normal
    cos_turn = np.einsum("ij,ij->i", n1, n2)
    sin_turn = n1[:, 0] * n2[:, 1] - n1[:, 1] * n2[:, 0]  # > 0 at the convex corners
    unit_tan = np.where(sin_turn > 0, sin_turn / np.maximum(1.0 + cos_turn, 1e-12), 0.0)
    length = np.hypot(*(loc[nxt] - loc).T)
    fit = 0.5 * length / np.maximum(unit_tan + unit_tan[nxt], T.TINY)
    radius = np.full(nb, float(rounding))
    np.minimum.at(radius, block, fit)
    r = radius[block]
    inward = (n1 + n2) / np.maximum(1.0 + cos_turn, 1e-12)[:, None]
    inset = (sin_turn > 0) | (cos_turn > 0)  # convex corners and straight-on vertices
    centre = loc - np.where(inset, r, 0.0)[:, None] * inward
    return np.ascontiguousarray(centre), r * unit_tan, radius


class Engine(DeformableBlocks):
    """Mutable DEM state of one model under one :class:`~rockmass.solver.Settings`."""

    def __init__(self, model, settings: Settings, zoned=None):
        """``zoned``: the :class:`~rockmass.solver.deformable.ZonedModel` when blocks are
        deformable (``model`` is then its model of pieces)."""
        from rockmass.blockgen.model import CONTACT_KINDS, KIND_JOINT

        self.model = model
        self.zoned = zoned
        self.settings = settings
        nb = model.n_blocks
        self.nb = nb
        # the block model's own edges, with its own offsets
        edge = model.xy_m[ring_neighbours(np.asarray(model.offsets))[0]] - model.xy_m
        self.median_edge_m = float(np.median(np.hypot(edge[:, 0], edge[:, 1])))
        # the d the model was built for (blockgen keeps every edge >= 2d with it), else 1 % of the
        # median edge (hand-made models)
        built_for = None if model.quality is None else model.quality.tolerances.rounding_m
        self.rounding_m = settings.rounding_m or built_for or ROUNDING_FRACTION * self.median_edge_m
        xy, self.off = strip_collinear(model.xy_m, np.asarray(model.offsets, np.int64),
                                       T.COLLINEAR_ROUNDINGS * self.rounding_m)
        block_of_vertex = np.repeat(np.arange(nb), np.diff(self.off))
        self.loc = np.ascontiguousarray(xy - model.centroid_xy_m[block_of_vertex])
        self.pos = np.ascontiguousarray(model.centroid_xy_m.copy())
        self.pos0 = self.pos.copy()
        self.rot = np.zeros(nb)
        self.vel = np.zeros((nb, 2))
        self.omg = np.zeros(nb)
        rho = settings.material.density_kg_m3
        area = model.area_m2
        polar = model.second_moment_m4[:, 0] + model.second_moment_m4[:, 1]
        self.mass = np.ascontiguousarray(np.column_stack([rho * area, rho * area, rho * polar]))
        self.active = np.ones(nb, np.bool_)
        self.failed = np.zeros(nb, np.bool_)  # taken out by the runner: kept moving
        self.radius = np.sqrt(np.maximum.reduceat((self.loc ** 2).sum(1), self.off[:-1]))
        edge = self.loc[ring_neighbours(self.off)[0]] - self.loc
        normal = np.column_stack([edge[:, 1], -edge[:, 0]]) / np.hypot(edge[:, 0], edge[:, 1])[:, None]
        centre, tangent, radius = rounded_corners(self.loc, self.off, normal, self.rounding_m)
        self.lgeo = np.ascontiguousarray(np.column_stack([normal, centre, tangent,
                                                          radius[block_of_vertex]]))
        self.wv = np.empty((len(self.loc), K.N_WV_COLUMNS))
        self.ctol_m = settings.contact_tolerance_m or self.rounding_m
        self.overlap_limit_m = T.OVERLAP_LIMIT_ROUNDINGS * self.rounding_m
        self.hysteresis_m = T.HYSTERESIS_ROUNDINGS * self.rounding_m

        # joint models by contact label
        labels = list(settings.joints)
        self.props = joint_table([settings.joints[k] for k in labels])
        self.default_prop = labels.index("default")

        def label_row(kind, source):
            name = CONTACT_KINDS[kind]
            if kind == KIND_JOINT and 0 <= source < len(model.set_names):
                if model.set_names[source] in settings.joints:
                    return labels.index(model.set_names[source])
            return labels.index(name) if name in settings.joints else self.default_prop

        inner = model.contact_blocks[:, 1] >= 0
        cb = np.sort(model.contact_blocks[inner], axis=1)
        key = cb[:, 0] * nb + cb[:, 1]
        rows = np.array([label_row(k, s) for k, s in zip(model.contact_kind[inner],
                                                          model.contact_source[inner])], np.int64)
        order = np.lexsort((-model.contact_length_m[inner], key))  # longest label of a pair first
        key, rows = key[order], rows[order]
        first = np.ones(len(key), bool)
        first[1:] = key[1:] != key[:-1]
        self.init_key = np.ascontiguousarray(key[first])
        self.init_prop = np.ascontiguousarray(rows[first])
        self.init_brk = np.zeros(len(self.init_key))

        # boundaries
        self.edges = domain_edges(model, T.DOMAIN_EDGE_FRACTION * max(self.median_edge_m, 1e-12))
        self.base_mode = np.zeros((nb, 3), np.int8)
        parent = None if zoned is None else zoned.parent
        for fix in settings.fixes:
            ids = select_blocks(model, fix.where, self.edges, parent)
            if not len(ids):
                raise ValueError(f"fix {fix.where!r} selects no block")
            for d in fix.dofs:
                self.base_mode[ids, _DOF[d]] = FIXED
        self.dof_input = np.full((nb, 3), -1, np.int64)
        for i, inp in enumerate(settings.velocity_inputs):
            ids = select_blocks(model, inp.where, self.edges, parent)
            if not len(ids):
                raise ValueError(f"velocity input {inp.where!r} selects no block")
            self.dof_input[ids, _DOF[inp.component]] = i
        self.ext_f = np.zeros((nb, 2))
        self.ext_a = np.zeros(nb)
        self.ext_b = np.zeros(nb)
        self.quiet_edges = np.zeros((0, 8))
        # free field (docs/dem.md §14.2): the sides' blocks are held normal to the side in static
        # stages; the columns are set up per dynamic stage (rockmass.solver.free_field)
        self.ff_hold = np.zeros((nb, 3), np.bool_)
        if settings.free_field is not None:
            sides = self.edges.on(settings.free_field.sides)
            self.ff_hold[np.unique(self.edges.block[sides]), 0] = True
        self.ff_edges = np.zeros((0, 9))
        self.ff_elem = np.zeros((0, K.N_FF_COLUMNS))
        self.ff_state = np.zeros((0, 4))
        # rock bolts (docs/dem.md §15): node tables, filled stage by stage (rockmass.solver.bolts)
        for name, value in empty_bolt_tables().items():
            setattr(self, name, value)
        self.gravity = np.array(settings.gravity_m_s2, float)
        self._set_up_zones(zoned)

        # pairs
        self.pa = np.empty(0, np.int64)
        self.pb = np.empty(0, np.int64)
        self.pprop = np.empty(0, np.int64)
        self.pref = np.empty(0, np.int8)
        self.pinit = np.empty(0, np.int64)
        self.S = np.zeros((0, 2, K.N_SLOT_COLUMNS))
        self.fpair = np.zeros((0, 6))
        self.E = np.zeros(K.N_ENERGY)
        self.time_s = 0.0
        self.n_rebuilds = -1  # the set-up build below is not counted
        self.set_stage_modes(dynamic=False)
        self.rebuild()

    # ----------------------------------------------------------------- modes and boundaries --
    def set_stage_modes(self, dynamic: bool):
        """Fixed dofs from the fixes; velocity-input dofs prescribed in dynamic stages, held fixed
        in static ones; excavated blocks are inactive."""
        self.mode = self.base_mode.copy()
        inp = self.dof_input >= 0
        self.mode[inp] = PRESCRIBED if dynamic else FIXED
        if not dynamic:  # free-field sides: rollers in static stages
            self.mode[self.ff_hold & (self.mode == FREE)] = FIXED
        self.inv_mass = np.where(self.mode == FREE, 1.0 / self.mass, 0.0)
        self.movable = (self.mode != FIXED).any(axis=1) & self.active
        if self.zoned is not None:
            self._set_node_modes()
        self.wake_all()

    def wake_all(self):
        """Every block that can move is awake (blocks that cannot are marked asleep)."""
        self.asleep = (~self.movable).astype(np.int8)
        self.calm = np.zeros(self.nb, np.int64)

    @property
    def margin_m(self) -> float:
        extra = 0.0
        if len(self.S):
            act = self.S[:, :, K.ACT] != 0
            if act.any():
                extra = float(np.max((self.S[:, :, K.U0] + self.S[:, :, K.DIL])[act], initial=0.0))
        return max(T.MARGIN_TOLERANCES * (self.ctol_m + extra),
                   T.MARGIN_EDGE_FRACTION * self.median_edge_m)

    def rebuild(self):
        """Broad phase and pair remap (state of surviving pairs kept)."""
        K.world_vertices(self.loc, self.lgeo, self.off, self.pos, self.rot, self.active, self.wv)
        margin = self.margin_m
        if self.zoned is not None:
            K.zone_world_vertices(self.zones_tuple(), self.off, self.lgeo, self.wv)
        pa, pb = K.broad_phase(self.wv, self.off, self.active, self.movable, self.group, margin)
        n = len(pa)
        S = np.zeros((n, 2, K.N_SLOT_COLUMNS))
        pref = np.zeros(n, np.int8)
        pinit = np.zeros(n, np.int64)
        pprop = np.zeros(n, np.int64)
        K.remap_pairs(self.pa, self.pb, self.S, self.pref, self.pinit, pa, pb, self.nb, S, pref,
                      pinit, pprop, self.init_key, self.init_prop, self.default_prop, self.init_brk)
        self.pa, self.pb, self.S, self.pref, self.pinit, self.pprop = pa, pb, S, pref, pinit, pprop
        self.fpair = np.zeros((n, 6))
        self.bp_ptr, self.bp_idx = K.block_pair_index(pa, pb, self.nb)
        self.ref_pos = self.pos.copy()
        self.ref_rot = self.rot.copy()
        self.margin = margin
        self.n_rebuilds += 1

    # ------------------------------------------------------------------ kernel arguments --
    def blocks_tuple(self) -> K.Blocks:
        """The per-block arrays as the kernels take them (:class:`rockmass.solver._kernels.Blocks`)."""
        return K.Blocks(self.loc, self.lgeo, self.off, self.radius, self.mass, self.inv_mass,
                        self.mode, self.dof_input, self.active, self.movable, self.pos, self.rot,
                        self.vel, self.omg, self.asleep, self.calm, self.wv, self.zone_of,
                        self.srate)

    def zones_tuple(self) -> K.Zoning:
        """The deformable blocks' zones and nodes as the kernels take them
        (:class:`rockmass.solver._kernels.Zoning`; empty arrays without deformable blocks)."""
        z = self.zone_state
        return K.Zoning(z["xy"], z["vel"], z["mass"], z["inv_mass"], z["mode"], z["node_input"],
                        z["fext"], z["tri"], z["zmat"], z["mtab"], z["sig"], z["strain"],
                        z["state"], z["eps_p"], z["live"], z["zone_block"], z["mixed"],
                        z["fint"], z["fcon"], z["fabs"], z["node_ev"], z["node_a"], z["presc"])

    def pairs_tuple(self) -> K.Pairs:
        """The pair list and contact state as the kernels take them (:class:`._kernels.Pairs`)."""
        return K.Pairs(self.pa, self.pb, self.pprop, self.pref, self.pinit, self.init_brk,
                       self.props, self.S, self.fpair, self.bp_ptr, self.bp_idx, self.ref_pos,
                       self.ref_rot)

    def loads_tuple(self, presc_val: np.ndarray) -> K.Loads:
        """Applied loads and the prescribed velocities ``presc_val`` (steps, inputs) of a chunk."""
        return K.Loads(self.gravity, self.ext_f, self.ext_a, self.ext_b, self.quiet_edges,
                       presc_val, self.ff_edges, self.ff_elem, self.ff_state, self.bolt_node,
                       self.bolt_state)

    def kernel_params(self, dt: float = 0.0, *, alpha_local: float = 0.0, alpha_mass: float = 0.0,
                      beta: float = 0.0, tol_ratio: float = 0.0, block_tol: float = 0.0,
                      sleep_ratio: float = 0.0, sleep_speed: float = 0.0,
                      w2_new: float = math.inf, ref_inputs: tuple[int, int] = (-1, -1)
                      ) -> np.ndarray:
        """The kernels' float64 parameter vector (indices ``PRM_*`` of :mod:`._kernels`): the
        scalars of a call and the numeric policy of :mod:`.tolerances`. The defaults give a
        detection pass: no motion, no damping, no equilibrium test, no sleeping. ``ref_inputs``:
        the velocity inputs (columns of ``presc_val``) whose x and y velocities the
        mass-proportional damping is relative to (-1: absolute velocity)."""
        entries = (
            (K.PRM_DT, dt), (K.PRM_CTOL, self.ctol_m), (K.PRM_HYST, self.hysteresis_m),
            (K.PRM_ROUNDING, self.rounding_m), (K.PRM_OVL_LIMIT, self.overlap_limit_m),
            (K.PRM_MARGIN, self.margin), (K.PRM_ALPHA_LOCAL, alpha_local),
            (K.PRM_ALPHA_MASS, alpha_mass), (K.PRM_BETA, beta), (K.PRM_TOL_RATIO, tol_ratio),
            (K.PRM_BLOCK_TOL, block_tol), (K.PRM_CHECK_EVERY, T.CHECK_EVERY),
            (K.PRM_SLEEP_RATIO, sleep_ratio), (K.PRM_SLEEP_STEPS, T.SLEEP_STEPS),
            (K.PRM_SLEEP_SPEED, sleep_speed), (K.PRM_W2_NEW, w2_new), (K.PRM_WAKE, T.WAKE_FACTOR),
            (K.PRM_REBUILD, T.REBUILD_MARGIN_FRACTION), (K.PRM_CY_CLAMP, T.CY_REVERSAL_CLAMP),
            (K.PRM_CY_SLIP_F, T.CY_SLIPPING_F), (K.PRM_CY_PROBE, T.CY_PROBE_STRESS_FACTOR),
            (K.PRM_CY_PROBE_FLOOR, T.CY_PROBE_FLOOR_PA), (K.PRM_FACING_COS, T.FACING_COS),
            (K.PRM_BOND_GAP, T.BOND_GAP_ROUNDINGS), (K.PRM_FACE_MIN, T.FACE_MIN_FRACTION),
            (K.PRM_DEGENERATE, T.DEGENERATE_DISTANCE), (K.PRM_TINY, T.TINY),
            (K.PRM_REF_X, ref_inputs[0]), (K.PRM_REF_Y, ref_inputs[1]))
        prm = np.full(K.N_PRM, np.nan)
        for index, value in entries:
            prm[index] = value
        assert not np.isnan(prm).any(), "a kernel parameter has no value"
        return prm

    def advance(self, n_steps: int, presc_val: np.ndarray, out: np.ndarray, dt: float,
                **params) -> int:
        """Run :func:`rockmass.solver._kernels.advance` for up to ``n_steps`` steps of ``dt``
        (``params``: the keywords of :meth:`kernel_params`); returns its ``RC_*`` code."""
        # no deformable block: None, so the kernel's specialisation without zones is the one
        # compiled (a rigid model does not pay the zone kernels' compilation)
        return K.advance(n_steps, self.blocks_tuple(), self.pairs_tuple(),
                         self.loads_tuple(presc_val),
                         self.zones_tuple() if self.zoned is not None else None,
                         self.kernel_params(dt, **params), self.E, out)

    def detect(self):
        """Run the narrow phase once without motion: establishes the contact slots."""
        K.world_vertices(self.loc, self.lgeo, self.off, self.pos, self.rot, self.active, self.wv)
        if self.zoned is not None:
            K.zone_world_vertices(self.zones_tuple(), self.off, self.lgeo, self.wv)
        K.contact_forces(self.blocks_tuple(), self.pairs_tuple(), np.zeros(self.nb, np.int8),
                         self.kernel_params(), np.zeros(K.N_ENERGY))

    def excavate(self, regions):
        """Remove the blocks of the given excavation stages (regions) and wake every block; the
        caller rebuilds the contacts (the runner does once the stage's modes are set)."""
        if not len(regions):
            return
        self.remove_blocks(np.isin(self.model.region, np.asarray(regions)))

    def remove_blocks(self, which):
        """Take blocks (ids or a mask) out of the model: inactive, at rest, every other block
        awake; the caller rebuilds the contacts."""
        self.active[which] = False
        self.vel[which] = 0.0
        self.omg[which] = 0.0
        self.movable &= self.active
        if self.zoned is not None:
            self._set_node_modes()
        self.wake_all()

    def _active_slots(self):
        """(pair, slot, state rows) of the active contact slots."""
        p, k = np.nonzero(self.S[:, :, K.ACT] != 0)
        return p, k, self.S[p, k]

    # ------------------------------------------------------------------------- time step --
    def stable_time_step(self, beta: float = 0.0) -> float:
        """Critical time step 2/ω_max from a Gershgorin bound on M^(-1/2) K M^(-1/2).

        Each active slot adds K g gᵀ (K = k_n l or k_s l, g the slot's relative-displacement row
        over the 6 dofs of its two blocks). Row sums of |M^(-1/2) K M^(-1/2)| bound the largest
        eigenvalue, so 2/√(max row sum) ≤ 2/ω_max: a rigorous (conservative) limit for the present
        contacts. Damping, explicit in the scheme, lowers it: with γ a bound on the eigenvalues of
        M^(-1/2) C M^(-1/2), Δt ≤ 4 / (√(4ω² + γ²) + γ) — for a damping ratio ξ = γ/(2ω) this is
        (2/ω)(√(1 + ξ²) − ξ) (docs/dem.md §2.3, eq. (2.6)), and it falls as ω or γ grows, so the two bounds give
        a safe step. C holds the stiffness-proportional Rayleigh term β K (γ ≤ β ω²) and the
        quiet-boundary dashpots of :attr:`quiet_edges` (Gershgorin row sums like K: a dashpot on a
        small boundary block, c/m large, is what limits the step there). The bolts' springs add
        their own largest row (:func:`rockmass.solver.bolts.bolt_bound`; docs/dem.md §15.2).
        """
        scale = np.sqrt(self.inv_mass)  # 0 for dofs that do not move
        gamma = self._dashpot_bound(scale)
        lam = self._stiffness_bound(scale)
        ff_lam, ff_gamma = self._free_field_bound()
        lam, gamma = max(lam, ff_lam), max(gamma, ff_gamma)
        lam += bolt_bound(self, scale)  # docs/dem.md §15: rows of a sum add
        lam += self._zone_bound()  # docs/dem.md §16.6
        if lam <= 0 and gamma <= 0:
            return math.inf
        gamma += beta * lam
        return 4.0 / (math.sqrt(4.0 * lam + gamma * gamma) + gamma)

    def _dashpot_bound(self, scale) -> float:
        """Gershgorin bound γ of M^(-1/2) C M^(-1/2) for the quiet-boundary and free-field dashpots
        (c = L ρC_p along the edge normal, L ρC_s along it, at the edge midpoint)."""
        q = np.vstack([self.quiet_edges, self.ff_edges[:, :8]])
        if not len(q):
            return 0.0
        b = q[:, 0].astype(np.int64)
        c, s = np.cos(self.rot[b]), np.sin(self.rot[b])
        r = np.column_stack([c * q[:, 1] - s * q[:, 2], s * q[:, 1] + c * q[:, 2]])
        n = np.column_stack([c * q[:, 3] - s * q[:, 4], s * q[:, 3] + c * q[:, 4]])
        t = np.column_stack([-n[:, 1], n[:, 0]])
        rows = np.zeros((self.nb, 3))
        for coef, d in ((q[:, 5] * q[:, 6], n), (q[:, 5] * q[:, 7], t)):
            g = np.column_stack([d[:, 0], d[:, 1], r[:, 0] * d[:, 1] - r[:, 1] * d[:, 0]])
            g = np.abs(g) * scale[b]
            _add_rows(rows, b, (coef * g.sum(1))[:, None] * g)  # row sums, as for K
        return float(rows.max())

    def _free_field_bound(self) -> tuple[float, float]:
        """(ω², γ) Gershgorin bounds of the free-field columns (chains of masses m_i = ρh_i per
        unit width on joints k_i, dashpots c_i at a quiet end; docs/dem.md §14.2), which step with
        the model: row i of M^(-1/2) K M^(-1/2) sums to (k_i + k_(i−1))/m_i + k_i/√(m_i m_(i+1))
        + k_(i−1)/√(m_i m_(i−1)), for the stiffer of the shear and normal joints."""
        e = self.ff_elem
        if not len(e):
            return 0.0, 0.0
        m = e[:, K.FF_M]
        above = e[:, K.FF_ABOVE].astype(np.int64)
        has = above >= 0
        rows = np.zeros(len(e))
        for col in (K.FF_KX, K.FF_KY):
            k = np.where(has, e[:, col], 0.0)
            link = k / np.sqrt(m * m[np.where(has, above, 0)])
            own = np.zeros(len(e))
            np.add.at(own, np.flatnonzero(has), k[has])
            np.add.at(own, above[has], k[has])
            off = link.copy()
            np.add.at(off, above[has], link[has])
            rows = np.maximum(rows, own / m + off)
        gamma = np.max(np.maximum(e[:, K.FF_CX], e[:, K.FF_CY]) / m)
        return float(rows.max()), float(gamma)

    def _stiffness_bound(self, scale) -> float:
        """Gershgorin bound ω² of M^(-1/2) K M^(-1/2) for the active contact slots (0: none)."""
        return float(self._stiffness_rows(scale).max(initial=0.0))

    def _stiffness_rows(self, scale) -> np.ndarray:
        """(B, 3) Gershgorin row sums of |S K S| per block dof (x, y, θ) for the active contact
        slots, S = diag(``scale``) (all zero without contacts)."""
        p, k, slot = self._active_slots()
        if not len(p):
            return np.zeros((self.nb, 3))
        length = slot[:, K.LEN]
        props = self.props[self.pprop[p]]
        kn = props[:, K.P_KN] * length
        ks = props[:, K.P_KS] * length
        cy = props[:, K.P_MODEL] == K.MODEL_CY
        if cy.any():  # tangent stiffness a σ^e at twice the present stress (e > 0 only)
            sig = np.maximum(T.CY_PROBE_STRESS_FACTOR * slot[:, K.FN] / np.maximum(length, T.TINY),
                             T.CY_PROBE_FLOOR_PA)
            kn = np.where(cy, kn * sig ** props[:, K.P_EN], kn)
            ks = np.where(cy, ks * sig ** props[:, K.P_ES], ks)
        a, b = self.pa[p], self.pb[p]
        n = slot[:, [K.NX, K.NY]]
        t = np.column_stack([-n[:, 1], n[:, 0]])
        pt = slot[:, [K.PX, K.PY]]
        ra = pt - self.pos[a]
        rb = pt - self.pos[b]
        rows = np.zeros((self.nb, 3))
        for stiff, d in ((kn, n), (ks, t)):
            ga = np.column_stack([-d[:, 0], -d[:, 1], -(ra[:, 0] * d[:, 1] - ra[:, 1] * d[:, 0])])
            gb = np.column_stack([d[:, 0], d[:, 1], rb[:, 0] * d[:, 1] - rb[:, 1] * d[:, 0]])
            ga = np.abs(ga) * scale[a]
            gb = np.abs(gb) * scale[b]
            s = ga.sum(1) + gb.sum(1)  # row i of |g gᵀ| sums to |g_i| Σ|g|
            _add_rows(rows, a, (stiff * s)[:, None] * ga)
            _add_rows(rows, b, (stiff * s)[:, None] * gb)
        return rows

    def scale_block_masses(self, static: bool) -> None:
        """Density scaling of the rigid blocks in a static stage (``Settings.density_scaling``,
        docs/dem.md §10.4). With R_i the Gershgorin row of the contact stiffness at dof i (unit
        masses) and ω²_i = R_i/m_i, the dofs with ω²_i above the median ω̃² over the free rigid
        dofs step with the mass m_i = R_i/ω̃² instead: M⁻¹K then has no row above ω̃² (Gershgorin
        on M⁻¹K, similar to M^(-1/2) K M^(-1/2)), so the step grows by up to ω_max/ω̃. Gravity
        keeps the true mass (the kernel weighs with ``mass``, steps with ``inv_mass``). Dynamic
        stages, zones (§16.6) and a model without contacts keep the true masses."""
        if not (static and self.settings.density_scaling):
            return
        rows = self._stiffness_rows(np.ones((self.nb, 3)))
        free = (self.inv_mass > 0) & (self.zone_of < 0)[:, None] & (rows > 0)
        if not free.any():
            return
        target = float(np.median(rows[free] * self.inv_mass[free]))
        inv = np.minimum(self.inv_mass, target / np.maximum(rows, T.TINY))
        self.inv_mass = np.where(free, inv, self.inv_mass)

    # ---------------------------------------------------------------------- state summaries --
    def strain_energy(self) -> float:
        """Elastic energy in the contacts, Σ l(∫σ du_n + τ²/2k_s) over active slots, and in the
        zones of deformable blocks (:meth:`zone_strain_energy`) (J per m)."""
        p, k, slot = self._active_slots()
        if not len(p):
            return self.zone_strain_energy()
        props = self.props[self.pprop[p]]
        length = slot[:, K.LEN]
        sig = slot[:, K.FN] / np.maximum(length, T.TINY)
        tau = slot[:, K.TAU]
        kn, ks, en = props[:, K.P_KN], props[:, K.P_KS], props[:, K.P_EN]
        cy = props[:, K.P_MODEL] == K.MODEL_CY
        es = np.where(cy, props[:, K.P_ES], 0.0)
        ks_t = ks * np.where(es > 0, np.maximum(sig, 0.0) ** es, 1.0)
        normal = np.where(cy, np.maximum(sig, 0.0) ** (2 - en) / (kn * (2 - en)), 0.5 * sig ** 2 / kn)
        shear = np.where(ks_t > 0, 0.5 * tau ** 2 / np.maximum(ks_t, T.TINY), 0.0)
        return float(np.sum(length * (normal + shear))) + self.zone_strain_energy()

    def contact_increment_work(self, dt: float) -> tuple[float, float]:
        """(Σ F_n Δδ, Σ F_s Δu_s) over active slots for one step of the present velocities:
        Δδ = −v_rel·n Δt (closure), Δu_s = v_rel·t Δt. With the leapfrog, the strain energy that
        matches the work of the contact forces is the 'shadow' ½ F_{n}·u_{n+1} (½k u_n u_{n+1} for a
        linear spring), which differs from ½k u_n² by half of this term (see the runner's ledger)."""
        p, k, slot = self._active_slots()
        if not len(p):
            return 0.0, 0.0
        a, b = self.pa[p], self.pb[p]
        pt = slot[:, [K.PX, K.PY]]
        ra, rb = pt - self.pos[a], pt - self.pos[b]
        va = self.vel[a] + self.omg[a, None] * np.column_stack([-ra[:, 1], ra[:, 0]])
        vb = self.vel[b] + self.omg[b, None] * np.column_stack([-rb[:, 1], rb[:, 0]])
        vr = vb - va
        n = slot[:, [K.NX, K.NY]]
        vn = vr[:, 0] * n[:, 0] + vr[:, 1] * n[:, 1]
        vt = -vr[:, 0] * n[:, 1] + vr[:, 1] * n[:, 0]
        return float(np.sum(slot[:, K.FN] * -vn) * dt), float(np.sum(slot[:, K.FS] * vt) * dt)

    def kinetic_energy(self) -> float:
        """½ Σ m v² over the free dofs of the active blocks, and the bolt nodes' (J per m); m is
        the mass a dof steps with (1/``inv_mass``: the true mass but in density-scaled static
        stages, §10.4, whose ledger must book the kinetic energy the steps put in)."""
        m = 1.0 / np.where(self.inv_mass > 0, self.inv_mass, 1.0)
        free = self.active[:, None] & (self.mode == FREE)  # prescribed dofs are the boundary's
        free &= (self.zone_of < 0)[:, None]  # a zone's motion is its nodes'
        v2 = np.column_stack([self.vel ** 2, self.omg ** 2])
        return (float(0.5 * np.sum(np.where(free, m * v2, 0.0))) + bolt_kinetic_energy(self)
                + self._node_kinetic_energy())

    def vertex_displacement(self, ref_pos, ref_rot) -> np.ndarray:
        """Largest vertex displacement of each block from a reference placement (m)."""
        out = np.zeros(self.nb)
        c, s = np.cos(self.rot), np.sin(self.rot)
        c0, s0 = np.cos(ref_rot), np.sin(ref_rot)
        b = np.repeat(np.arange(self.nb), np.diff(self.off))
        x, y = self.loc[:, 0], self.loc[:, 1]
        dx = self.pos[b, 0] + c[b] * x - s[b] * y - (ref_pos[b, 0] + c0[b] * x - s0[b] * y)
        dy = self.pos[b, 1] + s[b] * x + c[b] * y - (ref_pos[b, 1] + s0[b] * x + c0[b] * y)
        np.maximum.at(out, b, np.hypot(dx, dy))
        return out

    def contact_force_on(self, block: int) -> np.ndarray:
        """Sum of the contact forces (fx, fy, moment) on a block at the last step (N per m)."""
        out = np.zeros(3)
        for e in self.bp_idx[self.bp_ptr[block]:self.bp_ptr[block + 1]]:
            out += self.fpair[e >> 1, 3 * (e & 1):3 * (e & 1) + 3]
        return out

    def contact_table(self) -> dict:
        """Active contact slots: blocks, point, normal (a to b), length, σ_n (compression +),
        τ, plastic slip, slipping / broken flags."""
        p, k, slot = self._active_slots()
        length = np.maximum(slot[:, K.LEN], T.TINY)
        return {"block_a": self.pa[p], "block_b": self.pb[p], "x_m": slot[:, K.PX],
                "y_m": slot[:, K.PY], "nx": slot[:, K.NX], "ny": slot[:, K.NY],
                "length_m": slot[:, K.LEN], "normal_stress_pa": slot[:, K.FN] / length,
                "shear_stress_pa": slot[:, K.TAU], "plastic_slip_m": slot[:, K.USP],
                "overlap_m": slot[:, K.OVL], "slipping": slot[:, K.SLIP] != 0,
                "broken": (slot[:, K.BRK] != 0) & self.bonds(self.pprop[p])}

    def bonds(self, prop: np.ndarray) -> np.ndarray:
        """Whether the joint models of rows ``prop`` of the joint table are bonds (cohesion or
        tension > 0; docs/dem.md §7): only a bond can be broken. A contact of another model is
        flagged "broken" in its slots (a corner that touched across a gap, never bonded) but has
        nothing to break."""
        rows = self.props[prop]
        return (rows[:, K.P_COH] > 0.0) | (rows[:, K.P_TEN] > 0.0)

    def snapshot(self) -> tuple:
        zone = {k: self.zone_state[k].copy() for k in ZONE_STATE}
        return tuple(a.copy() for a in (self.pos, self.rot, self.vel, self.omg, self.S, self.E,
                                        self.init_brk, self.ff_state, self.bolt_state,
                                        self.srate)) + (self.time_s, zone)

    def restore(self, snap):
        """Back to a :meth:`snapshot` taken since the last rebuild (same pair list)."""
        (self.pos, self.rot, self.vel, self.omg, self.S, self.E, self.init_brk, self.ff_state,
         self.bolt_state, self.srate, self.time_s) = \
            tuple(a.copy() if isinstance(a, np.ndarray) else a for a in snap[:-1])
        for key, value in snap[-1].items():
            self.zone_state[key] = value.copy()
        self.rebuild()
