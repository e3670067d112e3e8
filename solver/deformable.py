"""Deformable blocks in a run: the blocks chosen by ``Settings.deformable`` zoned, each zone a block
of the contact search (docs/dem.md §16.8).

:func:`zone_model` turns a :class:`~rockmass.blockgen.BlockModel` into the model the engine solves:
rigid blocks stay as they are; a deformable block is replaced by its triangular zones
(:func:`rockmass.solver.zones.mesh_polygon`), each a *piece* of the new model with the region of
its block. The block model's contacts become contacts between the pieces that touch along them,
with the same kind and joint set, and a zone on the domain outline keeps its boundary contact (the
sides' selectors find it). Zones of one block share nodes and never touch in the contact search
(their ``group`` is their block); their stresses hold them together. What stays of the original
model: ``parent`` (the block of each piece) and ``blocks:i`` selectors, which name original
blocks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .selectors import domain_edges, select_blocks
from .zones import lumped_masses, material_table, mesh_polygon, stiffness_rows, triangle_areas

__all__ = ["ZonedModel", "zone_model"]


@dataclass(frozen=True)
class ZonedModel:
    """A block model with deformable blocks replaced by their zones.

    Attributes
    ----------
    model : BlockModel
        The pieces: rigid blocks and zones, in the original blocks' order.
    parent : (P,) int64
        The original block of each piece.
    zone_of : (P,) int64
        The zone a piece is (index into ``tri``), -1 for a rigid block.
    nodes : (N, 2) float64
        Node positions (m); ``tri`` (Z, 3) the zones (counter-clockwise), ``zone_block`` (Z,)
        their pieces, ``zmat`` (Z,) their row of ``mtab`` (the zone-material table).
    rows : (N,) float64
        Gershgorin row sums of the zones' stiffness per node (the time step, §16.6).
    """

    model: object
    parent: np.ndarray
    zone_of: np.ndarray
    nodes: np.ndarray
    tri: np.ndarray
    zone_block: np.ndarray
    zmat: np.ndarray
    mtab: np.ndarray
    rows: np.ndarray

    @property
    def mixed(self) -> bool:
        """Whether any zone has the nodal mixed discretisation (per material in ``mtab``,
        docs/dem.md §16.2)."""
        from . import _kernels as K

        return bool(self.mtab[:, K.ZM_MIXED].any())

    def group(self) -> np.ndarray:
        """Contact-search group of each piece: its original block for zones, -1 for rigid
        blocks (pieces of one group never pair)."""
        return np.where(self.zone_of >= 0, self.parent, -1).astype(np.int64)


def _chosen_blocks(model, deformable, edges) -> np.ndarray:
    """Index of the ``deformable`` entry that zones each block (-1: rigid; also a chosen block
    smaller than the entry's ``min_block_area_m2``); a block chosen twice is an error naming both
    entries."""
    spec_of = np.full(model.n_blocks, -1, np.int64)
    for i, spec in enumerate(deformable):
        ids = select_blocks(model, spec.where, edges)
        if not len(ids):
            raise ValueError(f"deformable[{i}].where {spec.where!r} selects no block")
        ids = ids[model.area_m2[ids] >= spec.min_block_area_m2]  # slivers stay rigid
        twice = ids[spec_of[ids] >= 0]
        if len(twice):
            raise ValueError(f"deformable[{i}].where {spec.where!r}: block {int(twice[0])} is "
                             f"already zoned by deformable[{int(spec_of[twice[0]])}]")
        spec_of[ids] = i
    return spec_of


def zone_model(model, settings) -> ZonedModel | None:
    """The model with the blocks of ``settings.deformable`` zoned (None when there are none).

    Zone edges within the engine's domain-edge tolerance of the domain outline or of a
    neighbour's outline lie on it.
    """
    from rockmass.blockgen.model import BlockModel

    from . import tolerances as T
    from .engine import ring_neighbours

    if not settings.deformable:
        return None
    edge = model.xy_m[ring_neighbours(np.asarray(model.offsets))[0]] - model.xy_m
    edge_tol_m = T.DOMAIN_EDGE_FRACTION * max(float(np.median(np.hypot(*edge.T))), 1e-12)
    spec_of = _chosen_blocks(model, settings.deformable, domain_edges(model, edge_tol_m))
    models = [spec.model for spec in settings.deformable]
    polys, parent, zone_of, node_chunks, tri_chunks, zmat = [], [], [], [], [], []
    n_nodes = n_zones = 0
    for b in range(model.n_blocks):
        ring = model.polygon(b)
        if spec_of[b] < 0:
            polys.append(ring)
            parent.append(b)
            zone_of.append(-1)
            continue
        spec = settings.deformable[spec_of[b]]
        nodes, tri = mesh_polygon(ring, spec.zone_size_m)
        node_chunks.append(nodes)
        tri_chunks.append(tri + n_nodes)
        n_nodes += len(nodes)
        for t in tri:
            polys.append(nodes[t])
            parent.append(b)
            zone_of.append(n_zones)
            n_zones += 1
        zmat.append(np.full(len(tri), spec_of[b], np.int64))
    parent = np.asarray(parent, np.int64)
    zone_of = np.asarray(zone_of, np.int64)
    nodes = np.vstack(node_chunks)
    tri = np.vstack(tri_chunks).astype(np.int64)
    zmat = np.concatenate(zmat)
    zone_block = np.flatnonzero(zone_of >= 0)
    zone_block = zone_block[np.argsort(zone_of[zone_block])]
    offsets = np.concatenate([[0], np.cumsum([len(p) for p in polys])]).astype(np.int64)
    xy = np.vstack(polys)
    contacts = _piece_contacts(model, polys, parent, zone_of, edge_tol_m)
    derived = BlockModel(xy_m=xy, offsets=offsets, region=model.region[parent],
                         region_names=model.region_names, contact_blocks=contacts[0],
                         contact_length_m=contacts[1], contact_kind=contacts[2],
                         contact_source=contacts[3], set_names=model.set_names,
                         domain_xy_m=model.domain_xy_m, quality=model.quality)
    from . import _kernels as K

    mtab = material_table(models, [spec.mixed for spec in settings.deformable])
    rows = stiffness_rows(nodes, tri, mtab[zmat, K.ZM_K], mtab[zmat, K.ZM_G])
    return ZonedModel(model=derived, parent=parent, zone_of=zone_of, nodes=nodes, tri=tri,
                      zone_block=zone_block, zmat=zmat, mtab=mtab, rows=rows)


def _piece_contacts(model, polys, parent, zone_of, tol):
    """Contacts of the pieces: the block model's contacts between blocks carried over to the
    pieces of the two blocks whose outlines run together for more than ``tol`` (the shared length
    measured within ``tol``), and its domain contacts to the zones with an edge on the domain
    outline. Returns (blocks (C, 2), length, kind, source)."""
    import shapely

    pieces_of = [[] for _ in range(model.n_blocks)]
    for i, b in enumerate(parent):
        pieces_of[b].append(i)
    outline = [shapely.LinearRing(p) for p in polys]
    domain = shapely.LinearRing(model.domain_xy_m)
    rows, lengths, kinds, sources = [], [], [], []

    def add(i, j, length, kind, source):
        rows.append((i, j))
        lengths.append(length)
        kinds.append(kind)
        sources.append(source)

    for c in range(model.n_contacts):
        a, b = (int(v) for v in model.contact_blocks[c])
        kind, source = int(model.contact_kind[c]), int(model.contact_source[c])
        if b < 0:
            for i in pieces_of[a]:
                if zone_of[i] < 0:
                    add(i, -1, float(model.contact_length_m[c]), kind, source)
                    continue
                on = _length_on(polys[i], domain, tol)
                if on > 0:
                    add(i, -1, on, kind, source)
            continue
        if zone_of[pieces_of[a][0]] < 0 and zone_of[pieces_of[b][0]] < 0:
            add(pieces_of[a][0], pieces_of[b][0], float(model.contact_length_m[c]), kind, source)
            continue
        shared = shapely.Polygon(model.polygon(a)).boundary.intersection(
            shapely.Polygon(model.polygon(b)).boundary.buffer(tol)).buffer(tol)
        near_a = [i for i in pieces_of[a] if outline[i].intersects(shared)]
        near_b = [j for j in pieces_of[b] if outline[j].intersects(shared)]
        for i in near_a:
            along = outline[i].intersection(shared)
            for j in near_b:
                length = along.intersection(outline[j].buffer(tol)).length
                if length > 4 * tol:  # more than a corner touching the other's edge
                    add(i, j, length, kind, source)
    return (np.asarray(rows, np.int64).reshape(-1, 2), np.asarray(lengths, float),
            np.asarray(kinds, np.int64), np.asarray(sources, np.int64))


def _length_on(ring: np.ndarray, line, tol: float) -> float:
    """Length of the edges of ``ring`` whose two ends lie within ``tol`` of ``line``."""
    import shapely

    near = shapely.distance(shapely.points(ring), line) <= tol
    nxt = np.roll(np.arange(len(ring)), -1)
    on = near & near[nxt]
    return float(np.hypot(*(ring[nxt] - ring)[on].T).sum())


#: The zone arrays that change as the model steps (kept by Engine.snapshot / restore).
ZONE_STATE = ("xy", "vel", "sig", "strain", "state", "eps_p", "live", "mode", "inv_mass")


class DeformableBlocks:
    """The :class:`~rockmass.solver.engine.Engine`'s part for deformable blocks: the node and
    zone arrays (``zone_state``), the nodes' degrees of freedom from their pieces', and the zones'
    share of the time step and of the energies (docs/dem.md §16.6–§16.8)."""

    def _set_up_zones(self, zoned) -> None:
        from . import _kernels as K

        nb = self.nb
        self.zone_of = np.full(nb, -1, np.int64) if zoned is None else zoned.zone_of.copy()
        self.group = np.full(nb, -1, np.int64) if zoned is None else zoned.group()
        self.srate = np.zeros((nb, 3))
        if zoned is None:
            nn = nz = 0
            nodes, tri = np.zeros((0, 2)), np.zeros((0, 3), np.int64)
            zmat, mtab = np.zeros(0, np.int64), np.zeros((0, K.N_ZM_COLUMNS))
            zone_block, mixed, rows, mass = np.zeros(0, np.int64), False, np.zeros(0), np.zeros(0)
        else:
            nodes, tri, zmat, mtab = zoned.nodes, zoned.tri, zoned.zmat, zoned.mtab
            zone_block, mixed, rows = zoned.zone_block, zoned.mixed, zoned.rows
            nn, nz = len(nodes), len(tri)
            mass = lumped_masses(nodes, tri, self.settings.material.density_kg_m3)
        self.node_x0 = np.ascontiguousarray(nodes, float).copy()
        self.node_rows = rows
        self.zone_state = {
            "xy": self.node_x0.copy(), "vel": np.zeros((nn, 2)), "mass": mass,
            "inv_mass": np.zeros(nn), "mode": np.zeros((nn, 2), np.int64),
            "node_input": np.full((nn, 2), -1, np.int64), "fext": np.zeros((nn, 2)),
            "tri": np.ascontiguousarray(tri, np.int64), "zmat": np.ascontiguousarray(zmat, np.int64),
            "mtab": np.ascontiguousarray(mtab), "sig": np.zeros((nz, K.N_ZS_COLUMNS)),
            "strain": np.zeros((nz, 3)), "state": np.zeros(nz, np.int64), "eps_p": np.zeros(nz),
            "live": np.ones(nz, np.bool_), "zone_block": np.ascontiguousarray(zone_block, np.int64),
            "mixed": np.array([int(mixed)], np.int64), "fint": np.zeros((nn, 2)),
            "fcon": np.zeros((nn, 2)), "fabs": np.zeros(nn), "node_ev": np.zeros(nn),
            "node_a": np.zeros(nn), "presc": np.zeros((nn, 2))}
        if zoned is not None:
            self._node_on_outline = self._nodes_on_domain()

    def _nodes_on_domain(self) -> np.ndarray:
        """Nodes on the domain outline (within the domain-edge tolerance)."""
        import shapely

        from . import tolerances as T

        tol = T.DOMAIN_EDGE_FRACTION * max(self.median_edge_m, 1e-12)
        ring = shapely.LinearRing(self.model.domain_xy_m)
        return shapely.distance(shapely.points(self.node_x0), ring) <= tol

    def _set_node_modes(self) -> None:
        """Node dofs from their pieces' (docs/dem.md §16.8): a node takes a piece's fixed or
        prescribed dof when it lies on the domain outline or the piece has no edge on it (a
        side's fix holds the outline, a region's fix the whole zone); the zones of inactive
        pieces are dead and their nodes held. The zones' blocks are always movable and their
        inverse masses are their lightest node's (the contact stiffness bound)."""
        from .engine import FIXED, PRESCRIBED

        z = self.zone_state
        tri, zb = z["tri"], z["zone_block"]
        z["live"][:] = self.active[zb]
        mode = np.zeros_like(z["mode"])
        node_input = np.full_like(z["node_input"], -1)
        on_domain = np.zeros(len(zb), bool)
        if len(self.edges.block):
            on_domain[np.isin(zb, self.edges.block)] = True
        for q in range(3):
            n = tri[:, q]
            applies = z["live"] & (self._node_on_outline[n] | ~on_domain)
            for d in range(2):
                block_mode = self.mode[zb, d]
                for kind in (FIXED, PRESCRIBED):
                    take = applies & (block_mode == kind)
                    mode[n[take], d] = np.maximum(mode[n[take], d], kind)
                    if kind == PRESCRIBED:
                        node_input[n[take], d] = self.dof_input[zb[take], d]
        alive = np.zeros(len(mode), bool)
        alive[tri[z["live"]].ravel()] = True
        mode[~alive] = FIXED
        z["mode"][:] = mode
        z["node_input"][:] = node_input
        z["vel"][~alive] = 0.0
        live = self.zone_of >= 0
        self.movable[live] = self.active[live]
        self.inv_mass[live] = 0.0
        kept = z["inv_mass"]  # a stage's scaled masses stay (blocks taken out mid-stage)
        self._set_node_inverse_masses(np.where(
            alive, np.where(kept > 0, kept, 1.0 / np.maximum(z["mass"], 1e-300)), 0.0))

    def scale_node_masses(self, static: bool) -> None:
        """Node masses for the stage (docs/dem.md §16.6). Dynamic: the true lumped masses. Static
        (density scaling; the path to equilibrium is not physical, only its end): each node
        gets at least the mass that puts its own Gershgorin row — its zones' stiffness R_i plus
        the contacts on its zones, each slot's k l taken whole by every node of its zone — at the
        rigid blocks' ω², so a small or thin zone does not set the step of the whole model."""
        if self.zoned is None:
            return
        z = self.zone_state
        alive = np.zeros(len(z["xy"]), bool)
        alive[z["tri"][z["live"]].ravel()] = True
        true = np.where(alive, z["mass"], 0.0)
        self._set_node_inverse_masses(np.where(alive, 1.0 / np.maximum(true, 1e-300), 0.0))
        if not static:
            return
        rows = self.node_rows + self._node_contact_rows()
        saved = z["inv_mass"].copy()
        self._set_node_inverse_masses(np.zeros_like(saved))  # the rigid blocks' own bound
        limit = self.stable_time_step()
        self._set_node_inverse_masses(saved)
        own = rows[alive] / np.maximum(true[alive], 1e-300)
        if not len(own):
            return
        target = (2.0 / limit) ** 2 if np.isfinite(limit) else float(np.median(own))
        mass = np.where(alive, np.maximum(true, rows / target), 0.0)
        self._set_node_inverse_masses(np.where(alive, 1.0 / np.maximum(mass, 1e-300), 0.0))

    def _set_node_inverse_masses(self, inv: np.ndarray) -> None:
        """Nodes' integration masses, and their zones' blocks' (the lightest node's)."""
        z = self.zone_state
        z["inv_mass"][:] = inv
        zb = z["zone_block"]
        lightest = inv[z["tri"]].max(axis=1)
        self.inv_mass[zb, 0] = self.inv_mass[zb, 1] = np.where(z["live"], lightest, 0.0)

    def _node_contact_rows(self) -> np.ndarray:
        """Per node, 4 Σ k l over the active slots on its zones (normal and shear; a bound of
        their Gershgorin rows: each weight ≤ 1, Σ|g| ≤ 4)."""
        from . import _kernels as K
        from .loading import _slot_stiffness

        z = self.zone_state
        rows = np.zeros(len(z["xy"]))
        p, k, slot = self._active_slots()
        if not len(p):
            return rows
        kn, ks = _slot_stiffness(self, p, slot)
        stiff = 4.0 * (kn + ks) * slot[:, K.LEN]
        for side in (self.pa[p], self.pb[p]):
            zone = self.zone_of[side]
            on = zone >= 0
            for q in range(3):
                np.add.at(rows, z["tri"][zone[on], q], stiff[on])
        return rows

    def _zone_bound(self) -> float:
        """Gershgorin bound of the zones' stiffness, max R_i/m_i over the free live nodes."""
        z = self.zone_state
        if not len(z["tri"]):
            return 0.0
        free = (z["mode"] == 0).any(axis=1)
        return float(np.max(self.node_rows * z["inv_mass"] * free, initial=0.0))

    def _node_kinetic_energy(self) -> float:
        """½ Σ m v² of the free node dofs, with the masses they step with (scaled in static
        stages, §16.6)."""
        z = self.zone_state
        free = (z["mode"] == 0) & (z["inv_mass"] > 0)[:, None]
        mass = 1.0 / np.where(z["inv_mass"] > 0, z["inv_mass"], 1.0)
        return float(0.5 * np.sum(mass[:, None] * z["vel"] ** 2 * free))

    def zone_strain_energy(self) -> float:
        """Elastic energy of the live zones, Σ A ½σ:C:σ (C the isotropic compliance, σ_zz
        included; docs/dem.md §16.5) (J per m)."""
        from . import _kernels as K

        z = self.zone_state
        if not len(z["tri"]):
            return 0.0
        s, m = z["sig"], z["mtab"][z["zmat"]]
        p = s[:, :3].sum(axis=1) / 3
        dev2 = ((s[:, :3] - p[:, None]) ** 2).sum(axis=1) + 2 * s[:, K.ZS_XY] ** 2
        u = p ** 2 / (2 * m[:, K.ZM_K]) + dev2 / (4 * m[:, K.ZM_G])
        return float(np.sum(u * triangle_areas(z["xy"], z["tri"]) * z["live"]))


def piece_near_centre(zoned: ZonedModel, pieces, block: int) -> int:
    """The piece of original ``block`` nearest to the block's centroid (a monitor named by block
    on a zoned block follows that zone)."""
    ids = np.flatnonzero(zoned.parent == block)
    if not len(ids):
        raise ValueError(f"block {block} out of range")
    area = pieces.area_m2[ids]
    centre = (pieces.centroid_xy_m[ids] * area[:, None]).sum(axis=0) / area.sum()
    return int(ids[np.argmin(np.hypot(*(pieces.centroid_xy_m[ids] - centre).T))])


#: Plastic state names of the zones, by the kernels' bits (docs/dem.md §16.3).
PLASTIC_STATES = {"shear_now": 1, "tension_now": 2, "shear_past": 4, "tension_past": 8}


def zone_table(engine) -> dict:
    """The deformable blocks' zones at the end of a run: ``nodes_m`` (N, 2) and their
    ``node_displacement_m``, ``triangles`` (Z, 3), ``zone_block`` (the result's block of each
    zone), ``parent_block`` (the original block of each of the result's blocks), ``stress_pa``
    (Z, 4: σ_xx, σ_yy, σ_zz, σ_xy, compression positive), ``strain`` (Z, 3: ε_xx, ε_yy, ε_xy,
    extension positive), ``plastic_strain``, ``plastic_state`` (bits of :data:`PLASTIC_STATES`),
    ``live`` and ``area_m2``; empty without deformable blocks."""
    if engine.zoned is None:
        return {}
    z = engine.zone_state
    xy, tri = z["xy"], z["tri"]
    area = triangle_areas(xy, tri)
    return {"nodes_m": xy.copy(), "node_displacement_m": xy - engine.node_x0,
            "triangles": tri.copy(), "zone_block": z["zone_block"].copy(),
            "parent_block": engine.zoned.parent.copy(), "stress_pa": -z["sig"],
            "strain": z["strain"].copy(), "plastic_strain": z["eps_p"].copy(),
            "plastic_state": z["state"].copy(), "live": z["live"].copy(), "area_m2": area}


def zone_centroids(engine) -> np.ndarray:
    """Present centroids of the zones (Z, 2)."""
    z = engine.zone_state
    return z["xy"][z["tri"]].mean(axis=1)


def set_zone_stress(engine, sxx, syy, sxy) -> None:
    """Zone stresses from compression-positive in-plane components (arrays over the zones), with
    the plane-strain σ_zz = ν(σ_xx + σ_yy) of an elastic medium loaded from zero
    (ν = (3K − 2G)/(2(3K + G)) of each zone's material)."""
    from . import _kernels as K

    z = engine.zone_state
    m = z["mtab"][z["zmat"]]
    nu = (3 * m[:, K.ZM_K] - 2 * m[:, K.ZM_G]) / (2 * (3 * m[:, K.ZM_K] + m[:, K.ZM_G]))
    z["sig"][:, K.ZS_XX] = -sxx
    z["sig"][:, K.ZS_YY] = -syy
    z["sig"][:, K.ZS_ZZ] = -nu * (sxx + syy)
    z["sig"][:, K.ZS_XY] = -sxy


def add_node_forces(engine, blocks: np.ndarray, points: np.ndarray, forces: np.ndarray) -> None:
    """Add ``forces`` (n, 2) at ``points`` on the outlines of zones' blocks to the node of each
    zone at that point (the zone's vertex nearest to it) as external loads."""
    z = engine.zone_state
    nodes = z["tri"][engine.zone_of[blocks]]  # (n, 3)
    gap = np.hypot(*(z["xy"][nodes] - points[:, None, :]).transpose(2, 0, 1))
    at = nodes[np.arange(len(blocks)), np.argmin(gap, axis=1)]
    np.add.at(z["fext"], at, forces)


def zone_rows(zones: dict) -> dict:
    """Columns of ``zones.csv``: per zone its block and original block, centroid, area, stress
    (compression positive), strain, plastic strain and state (:func:`zone_table`)."""
    tri, xy = zones["triangles"], zones["nodes_m"]
    centre = xy[tri].mean(axis=1)
    s, e, state = zones["stress_pa"], zones["strain"], zones["plastic_state"]
    block = zones["zone_block"]
    return {"zone": np.arange(len(tri)), "block": block, "parent_block": zones["parent_block"][block],
            "live": zones["live"].astype(np.int64), "x_m": centre[:, 0], "y_m": centre[:, 1],
            "area_m2": zones["area_m2"], "sxx_pa": s[:, 0], "syy_pa": s[:, 1], "szz_pa": s[:, 2],
            "sxy_pa": s[:, 3], "exx": e[:, 0], "eyy": e[:, 1], "exy": e[:, 2],
            "plastic_strain": zones["plastic_strain"],
            **{name: ((state & bit) != 0).astype(np.int64) for name, bit in PLASTIC_STATES.items()}}
