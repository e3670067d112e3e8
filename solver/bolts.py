"""Rock bolts and cables: fully grouted, as UDEC's cable elements (docs/dem.md §15).

A bolt is a straight chain of nodes joined by axial springs (the steel) and tied to the rock by
grout springs (Itasca 2004, cable elements). Node i of a bolt of axis a sits, at installation, in
the block that contains it (its host) and is tied to the host's point there, which moves with the
block's rigid-body motion. Per step (:func:`rockmass.solver._kernels.bolt_step`):

    G_i ← G_i + k_g,i (Δw_i − Δu_i),   |G_i| ≤ s_g,i,   k_g,i = k_bond l_i,  s_g,i = s_bond l_i, (15.2)
    N_i ← N_i + (EA/h) (Δu_(i+1) − Δu_i),   −N_c ≤ N_i ≤ N_t,                                   (15.3)

with Δw_i the host's displacement at the anchor along a, u_i the node's, l_i the node's share of
the bolt (h, or h/2 at its ends) and N_i the force in the segment from node i to node i+1
(tension positive). A node moves along a under G_i + N_i − N_(i−1); the host takes −G_i a.

The nodes carry a mass: they are integrated by central differences with the blocks' step. The
mass is scaled (eq. (15.5)) so that a node's own frequency is
that of the stiffest block contact at installation: the nodes then follow the blocks nearly
quasi-statically and do not shorten the step much (their rows enter the bound (2.5) through
:func:`bolt_bound`). Steel and grout yield incrementally, exactly as a joint slips, so the energy
they dissipate is booked in the same form (eq. (11.3)) and the ledger closes.

This module builds the node tables (:func:`install_bolts`: explicit bolts and
:class:`~rockmass.solver.settings.BoltPattern` rules), and evaluates what the runner needs besides
the kernel: the time-step bound, the elastic energy and the output table.
"""

from __future__ import annotations

import numpy as np

from . import _kernels as K
from . import tolerances as T
from .settings import BoltPattern, BoltProperties, Settings

__all__ = ["install_bolts", "pattern_bolts", "host_blocks", "bolt_bound", "bolt_energy",
           "bolt_kinetic_energy", "bolt_table", "empty_bolt_tables"]


def host_blocks(engine, xy: np.ndarray) -> np.ndarray:
    """The active block containing each point at the present placement (boundary included; the
    lowest id where two touch), -1 where none does. ``xy``: (n, 2) world points (m)."""
    import shapely

    xy = np.atleast_2d(np.asarray(xy, float))
    c, s = np.cos(engine.rot), np.sin(engine.rot)
    live = np.flatnonzero(engine.active)
    polys = []
    for b in live:
        loc = engine.loc[engine.off[b]:engine.off[b + 1]]
        polys.append(shapely.Polygon(np.column_stack([
            engine.pos[b, 0] + c[b] * loc[:, 0] - s[b] * loc[:, 1],
            engine.pos[b, 1] + s[b] * loc[:, 0] + c[b] * loc[:, 1]])))
    host = np.full(len(xy), -1, np.int64)
    if not polys:
        return host
    tree = shapely.STRtree(polys)
    point_i, poly_i = tree.query(shapely.points(xy), predicate="intersects")
    for p, q in sorted(zip(point_i.tolist(), poly_i.tolist()), key=lambda pq: (pq[0], -live[pq[1]])):
        host[p] = live[q]  # the lowest id wins (sorted last)
    return host


def pattern_bolts(engine, pattern: BoltPattern,
                  new_regions=()) -> list[tuple[np.ndarray, np.ndarray]]:
    """(head, toe) of each bolt of a pattern: heads every ``spacing_m`` along the boundary of the
    opening excavated so far (the blocks of regions > 0 that are out of the model, not failed), at
    (k + ½) P/n along each ring of perimeter P (n = round(P/s), so the spacing is even), each bolt
    ``length_m`` along the wall's normal into the rock; heads kept by ``walls`` and ``box_m``, and
    only where the rock beyond the wall is inside the model's domain. With ``new_regions`` (the
    regions the stage excavates) only walls those regions exposed are bolted: an earlier stage's
    walls keep their own bolts."""
    import shapely
    from shapely.geometry.polygon import orient

    model = engine.model
    dug = (~engine.active) & (model.region > 0) & (~engine.failed)
    if not dug.any():
        return []
    opening = shapely.union_all(model.to_shapely()[dug])
    domain = shapely.Polygon(model.domain_xy_m)
    walls = pattern.walls or ("roof", "left", "right")
    new = (shapely.union_all(model.to_shapely()[np.isin(model.region, new_regions)])
           if len(new_regions) else None)
    near = 1e-6 * max(pattern.spacing_m, pattern.length_m)
    out = []
    for poly in getattr(opening, "geoms", [opening]):
        ring = np.asarray(orient(poly, 1.0).exterior.coords)
        seg = np.diff(ring, axis=0)
        seg_len = np.hypot(seg[:, 0], seg[:, 1])
        cum = np.concatenate([[0.0], np.cumsum(seg_len)])
        n = max(1, round(cum[-1] / pattern.spacing_m))
        for d in (np.arange(n) + 0.5) * cum[-1] / n:
            k = min(int(np.searchsorted(cum, d, side="right")) - 1, len(seg) - 1)
            head = ring[k] + seg[k] * (d - cum[k]) / seg_len[k]
            normal = np.array([seg[k, 1], -seg[k, 0]]) / seg_len[k]  # CCW: out of the opening
            if not _on_walls(normal, walls) or not _in_box(head, pattern.box_m):
                continue
            if new is not None and new.distance(shapely.Point(*head)) > near:
                continue
            if not domain.contains(shapely.Point(*(head + 1e-3 * pattern.length_m * normal))):
                continue
            head = head + T.BOLT_HEAD_INSET * pattern.length_m * normal  # in the rock
            out.append((head, head + pattern.length_m * normal))
    return out


def _on_walls(normal: np.ndarray, walls) -> bool:
    """The wall a normal into the rock belongs to: roof (up), floor (down), left, right."""
    nx, ny = normal
    wall = ("roof" if ny > 0 else "floor") if abs(ny) >= abs(nx) else ("right" if nx > 0 else "left")
    return wall in walls


def _in_box(point, box) -> bool:
    return box is None or (box[0] <= point[0] <= box[2] and box[1] <= point[1] <= box[3])


def _bolt_nodes(start, end, segments: int, props: BoltProperties) -> np.ndarray:
    """Node rows (columns ``BN_*``, host and anchor and mass left to the caller) of one bolt: nodes
    at start + (k/n)(end − start), each grouted over its share l_k of the length (h, h/2 at the
    ends), segments of stiffness EA/h (eq. (15.1))."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    length = float(np.hypot(*(end - start)))
    h = length / segments
    per = props.per_metre()
    rows = np.zeros((segments + 1, K.N_BN_COLUMNS))
    share = np.full(segments + 1, h)
    share[[0, -1]] = 0.5 * h
    rows[:, K.BN_AX:K.BN_AY + 1] = (end - start) / length
    rows[:, K.BN_KG] = per["bond_stiffness_n_m2"] * share
    rows[:, K.BN_SG] = per["bond_strength_n_m"] * share
    rows[:-1, K.BN_NEXT] = np.arange(1, segments + 1)
    rows[-1, K.BN_NEXT] = -1.0
    rows[:-1, K.BN_KA] = per["axial_stiffness_n"] / h
    rows[:, K.BN_NT] = per["yield_force_n"]
    rows[:, K.BN_NC] = per["compressive_yield_force_n"]
    return rows


def _node_masses(engine, rows: np.ndarray) -> np.ndarray:
    """Scaled node masses (eq. (15.5)): m_i = (k_g,i + 2 k_a,(i−1) + 2 k_a,i) / ω_ref², the sum of
    the node's stiffness row over ω_ref², ω_ref² the Gershgorin bound of the block contacts now
    (without contacts: the largest row_i / m_host, so that no node outweighs its host), so that a
    node alone is no stiffer for the step than the stiffest contact."""
    ka = rows[:, K.BN_KA]
    prev = np.concatenate([[0.0], ka[:-1]]) * (np.concatenate([[-1.0], rows[:-1, K.BN_NEXT]]) >= 0)
    row = rows[:, K.BN_KG] + 2.0 * prev + 2.0 * ka
    w2 = engine._stiffness_bound(np.sqrt(engine.inv_mass))
    if w2 <= 0:  # no contact: a node no heavier than its host
        host = rows[:, K.BN_HOST].astype(np.int64)
        hosted = host >= 0
        w2 = float(np.max(row[hosted] / engine.mass[host[hosted], 0], initial=0.0)) or 1.0
    return row / w2


def install_bolts(engine, settings: Settings, stage_name: str) -> int:
    """Add the bolts of ``settings`` installed at the start of stage ``stage_name`` (explicit
    bolts, then patterns) to ``engine``'s node tables, at the present placement, and scale every
    node's mass to the present contacts (eq. (15.5): the step a stage's contacts allow is kept);
    the number of bolts added. Bolt k is named by its ``name``, else ``bolt<k>``; a pattern's
    bolts ``<name or pattern<j>>_<i>``."""
    made = []
    for k, bolt in enumerate(settings.bolts):
        if bolt.stage == stage_name:
            made.append((bolt.name or f"bolt{k}", bolt.start_xy_m, bolt.end_xy_m, bolt.segments,
                         bolt.properties))
    stage = next(s for s in settings.stages if s.name == stage_name)
    for j, pattern in enumerate(settings.bolt_patterns):
        if pattern.stage == stage_name:
            prefix = pattern.name or f"pattern{j}"
            made += [(f"{prefix}_{i}", head, toe, pattern.segments, pattern.properties)
                     for i, (head, toe) in enumerate(pattern_bolts(engine, pattern,
                                                                   stage.excavate))]
    if not made:
        if len(engine.bolt_node):
            engine.bolt_node[:, K.BN_M] = _node_masses(engine, engine.bolt_node)
        return 0
    first = len(engine.bolt_node)
    tables = []
    for name, start, end, segments, props in made:
        rows = _bolt_nodes(start, end, segments, props)
        rows[:-1, K.BN_NEXT] += first + sum(len(t) for t in tables)
        tables.append(rows)
        engine.bolt_names.append(name)
        engine.bolt_stages.append(stage_name)
    rows = np.vstack(tables)
    xy = np.vstack([np.linspace(np.asarray(s, float), np.asarray(e, float), n + 1)
                    for _, s, e, n, _ in made])
    host = host_blocks(engine, xy)
    rows[:, K.BN_HOST] = host
    hosted = host >= 0
    b = host[hosted]
    rel = xy[hosted] - engine.pos[b]
    c, s = np.cos(engine.rot[b]), np.sin(engine.rot[b])
    rows[hosted, K.BN_RX] = c * rel[:, 0] + s * rel[:, 1]  # into the block's frame
    rows[hosted, K.BN_RY] = -s * rel[:, 0] + c * rel[:, 1]
    engine.bolt_node = np.ascontiguousarray(np.vstack([engine.bolt_node, rows]))
    engine.bolt_node[:, K.BN_M] = _node_masses(engine, engine.bolt_node)
    engine.bolt_state = np.ascontiguousarray(np.vstack([engine.bolt_state,
                                                        np.zeros((len(rows), K.N_BS_COLUMNS))]))
    engine.bolt_of_node = np.concatenate([engine.bolt_of_node, np.repeat(
        np.arange(len(engine.bolt_names) - len(made), len(engine.bolt_names)),
        [n + 1 for *_, n, _ in made])])
    engine.bolt_xy = np.vstack([engine.bolt_xy, xy])
    return len(made)


def _grout_rows(engine):
    """(node ids, hosts, anchor arms r (n, 2), axes a (n, 2)) of the grout springs whose host is
    in the model."""
    node = engine.bolt_node
    host = node[:, K.BN_HOST].astype(np.int64)
    i = np.flatnonzero(host >= 0)
    i = i[engine.active[host[i]]]
    b = host[i]
    c, s = np.cos(engine.rot[b]), np.sin(engine.rot[b])
    r = np.column_stack([c * node[i, K.BN_RX] - s * node[i, K.BN_RY],
                         s * node[i, K.BN_RX] + c * node[i, K.BN_RY]])
    return i, b, r, node[i, K.BN_AX:K.BN_AY + 1]


def bolt_bound(engine, scale: np.ndarray) -> float:
    """Gershgorin bound of M^(-1/2) K M^(-1/2) for the bolts' springs alone (0: no bolt), over the
    blocks' dofs (``scale`` = 1/√m, 0 where a dof does not move) and the nodes' (1/√m_i): a grout
    spring couples node i (−1) to its host (a_x, a_y, r × a), a segment its two nodes (−1, +1);
    each adds K |g_r| Σ_c |g_c| to row r, as the contacts do (docs/dem.md eq. (2.5)). Added to
    the contacts' bound it bounds the whole system's ω_max² (a row sum of a sum of matrices is at
    most the sum of their largest row sums)."""
    node = engine.bolt_node
    if not len(node):
        return 0.0
    s_node = 1.0 / np.sqrt(node[:, K.BN_M])
    rows_node = np.zeros(len(node))
    rows_block = np.zeros((engine.nb, 3))
    i, b, r, a = _grout_rows(engine)
    g = np.abs(np.column_stack([a, r[:, 0] * a[:, 1] - r[:, 1] * a[:, 0]])) * scale[b]
    total = s_node[i] + g.sum(1)
    kg = node[i, K.BN_KG]
    np.add.at(rows_node, i, kg * s_node[i] * total)
    np.add.at(rows_block, b, (kg * total)[:, None] * g)
    seg = np.flatnonzero(node[:, K.BN_NEXT] >= 0)
    nxt = node[seg, K.BN_NEXT].astype(np.int64)
    ka = node[seg, K.BN_KA]
    total = s_node[seg] + s_node[nxt]
    np.add.at(rows_node, seg, ka * s_node[seg] * total)
    np.add.at(rows_node, nxt, ka * s_node[nxt] * total)
    return float(max(rows_node.max(), rows_block.max()))


def bolt_energy(engine, dt: float) -> tuple[float, float]:
    """(elastic energy, one step's work increment) of the bolts (J per m): Σ G²/(2k_g) over the
    grout springs plus Σ N²/(2k_a) over the segments; and
    Σ G (Δw − Δu) + Σ N (Δu_next − Δu) for one step of the present velocities, which turns the
    elastic energy into the leapfrog's 'shadow' form as for the contacts (docs/dem.md eq. (11.4))."""
    node, state = engine.bolt_node, engine.bolt_state
    if not len(node):
        return 0.0, 0.0
    held = node[:, K.BN_HOST] >= 0  # a gone host's spring holds G until the kernel releases it
    gh = state[held, K.BS_G]
    i, b, r, a = _grout_rows(engine)
    g = state[i, K.BS_G]
    vw = ((engine.vel[b, 0] - engine.omg[b] * r[:, 1]) * a[:, 0]
          + (engine.vel[b, 1] + engine.omg[b] * r[:, 0]) * a[:, 1])
    seg = np.flatnonzero(node[:, K.BN_NEXT] >= 0)
    nxt = node[seg, K.BN_NEXT].astype(np.int64)
    n = state[seg, K.BS_N]
    v = state[:, K.BS_V]
    elastic = np.sum(gh * gh / (2.0 * node[held, K.BN_KG])) + np.sum(n * n / (2.0 * node[seg, K.BN_KA]))
    work = (np.sum(g * (vw - v[i])) + np.sum(n * (v[nxt] - v[seg]))) * dt
    return float(elastic), float(work)


def bolt_kinetic_energy(engine) -> float:
    """½ Σ m_i v_i² of the bolt nodes (J per m)."""
    return float(0.5 * np.sum(engine.bolt_node[:, K.BN_M] * engine.bolt_state[:, K.BS_V] ** 2))


def bolt_table(engine) -> dict:
    """Per bolt node at the end: bolt name and stage of installation, node index along the bolt,
    installed position (m), host block (-1: none), the axial force of the segment from the node to
    the next (N per m, tension positive; 0 at the last node) and whether it yields now or ever
    did, its plastic elongation (m), the grout's force on the node (N per m, along the bolt
    from start to end), accumulated bond slip (m) and whether it slips now, and the node's
    scaled mass (kg per m, eq. (15.5))."""
    node, state = engine.bolt_node, engine.bolt_state
    bolt = engine.bolt_of_node
    if not len(node):
        return {}
    first = np.searchsorted(bolt, bolt, side="left")
    return {"bolt": np.array(engine.bolt_names, dtype=object)[bolt],
            "stage": np.array(engine.bolt_stages, dtype=object)[bolt],
            "node": np.arange(len(node)) - first,
            "x_m": engine.bolt_xy[:, 0], "y_m": engine.bolt_xy[:, 1],
            "host_block": node[:, K.BN_HOST].astype(np.int64),
            "axial_force_n": state[:, K.BS_N].copy(),
            "yielding": state[:, K.BS_YIELD] != 0, "yielded": state[:, K.BS_YIELDED] != 0,
            "plastic_elongation_m": state[:, K.BS_EP].copy(),
            "bond_force_n": state[:, K.BS_G].copy(), "bond_slip_m": state[:, K.BS_SLIP].copy(),
            "bond_slipping": state[:, K.BS_SLIPPING] != 0, "mass_kg": node[:, K.BN_M].copy()}


def empty_bolt_tables() -> dict:
    """The engine's bolt attributes before any bolt is installed."""
    return {"bolt_node": np.zeros((0, K.N_BN_COLUMNS)), "bolt_state": np.zeros((0, K.N_BS_COLUMNS)),
            "bolt_of_node": np.zeros(0, np.int64), "bolt_xy": np.zeros((0, 2)), "bolt_names": [],
            "bolt_stages": []}

