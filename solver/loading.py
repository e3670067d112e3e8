"""Initial stress, boundary tractions and quiet boundaries turned into the engine's arrays.

Stress fields are linear in y at most (uniform, or gravity with K₀), so forces on a straight edge of
length L between points P₀, P₁ with tractions t₀, t₁ are lumped *consistently* (linear element):
F₀ = L(2t₀ + t₁)/6 at P₀ and F₁ = L(t₀ + 2t₁)/6 at P₁, which keeps the resultant and its moment
exact — so a block under an equilibrium stress field starts in equilibrium (docs/dem.md §9.3).
"""

from __future__ import annotations

import numpy as np

from . import _kernels as K
from . import tolerances as T
from .deformable import add_node_forces, set_zone_stress, zone_centroids
from .engine import FIXED
from .settings import SIDES, BoundaryStress, InSituStress, QuietBoundary

__all__ = ["stress_at", "apply_insitu", "apply_boundary_stress", "quiet_edge_table",
           "boundary_edge_table", "boundary_impedance", "block_faces", "joint_compliance",
           "rock_mass_compliance"]


def stress_at(insitu: InSituStress, points: np.ndarray, unit_weight: float, y_ref: float):
    """Compression-positive (σ_xx, σ_yy, σ_xy) at the points (see :class:`InSituStress`)."""
    y = points[:, 1]
    syy = np.full(len(points), insitu.syy_pa, float)
    sxx = np.full(len(points), insitu.sxx_pa, float)
    if insitu.gravity_gradient:
        gravity_part = unit_weight * (y_ref - y)
        syy = syy + gravity_part
        sxx = sxx + insitu.k0 * gravity_part
    return sxx, syy, np.full(len(points), insitu.sxy_pa, float)


def _y_ref(engine, insitu: InSituStress) -> float:
    return float(engine.model.domain_xy_m[:, 1].max()) if insitu.y_ref_m is None else insitu.y_ref_m


def _unit_weight(engine) -> float:
    return engine.settings.material.density_kg_m3 * float(np.hypot(*engine.gravity))


def _lumped(t0, t1, length):
    return length * (2 * t0 + t1) / 6.0, length * (t0 + 2 * t1) / 6.0


def apply_insitu(engine, insitu: InSituStress):
    """Write the in-situ stress into the active contact slots: σ_n = n·σ·n, τ = −t·σ·n
    (compression-positive σ), lumped over each face (a block-model contact with both slots
    active); the normal offset U0 makes the joint law return exactly that σ_n at the present
    overlap. A face that rounded corners cover is one slot loaded with the face's whole traction
    (:func:`_covered_face_stress`). Corner-only touches start at zero force."""
    if engine.zoned is not None:  # the zones of deformable blocks start at it too (§16.8)
        sxx, syy, sxy = stress_at(insitu, zone_centroids(engine), _unit_weight(engine),
                                  _y_ref(engine, insitu))
        set_zone_stress(engine, sxx, syy, sxy)
    S = engine.S
    act = S[:, :, K.ACT] != 0
    if not act.any():
        return
    pts = S[:, :, [K.PX, K.PY]].reshape(-1, 2)
    sxx, syy, sxy = stress_at(insitu, pts, _unit_weight(engine), _y_ref(engine, insitu))
    n = S[:, :, [K.NX, K.NY]].reshape(-1, 2)
    t = np.column_stack([-n[:, 1], n[:, 0]])
    sn = n[:, 0] ** 2 * sxx + 2 * n[:, 0] * n[:, 1] * sxy + n[:, 1] ** 2 * syy
    tn = -(t[:, 0] * (sxx * n[:, 0] + sxy * n[:, 1]) + t[:, 1] * (sxy * n[:, 0] + syy * n[:, 1]))
    sn = sn.reshape(-1, 2)
    tn = tn.reshape(-1, 2)
    both = act.all(axis=1)
    # only faces of the block model carry the initial stress; blocks that merely touch at a
    # corner (four blocks meeting at a point) start unloaded
    model_face = engine.pinit >= 0
    covered = model_face & (act.sum(axis=1) == 1)  # faces inside rounded corners: one slot
    face_pair = model_face & (both | covered)
    length = S[:, :, K.LEN]
    face = length.sum(axis=1)
    sig = sn.copy()
    tau = tn.copy()
    f0, f1 = _lumped(sn[both, 0], sn[both, 1], face[both])
    sig[both, 0], sig[both, 1] = f0 / length[both, 0], f1 / length[both, 1]
    f0, f1 = _lumped(tn[both, 0], tn[both, 1], face[both])
    tau[both, 0], tau[both, 1] = f0 / length[both, 0], f1 / length[both, 1]
    for p in np.flatnonzero(covered):
        k = 0 if act[p, 0] else 1
        sig[p, k], tau[p, k] = _covered_face_stress(engine, insitu, p, k)
    props = engine.props[engine.pprop]
    for k in range(2):
        rows = np.flatnonzero(act[:, k])
        pr = props[rows]
        s = np.where(face_pair[rows], sig[rows, k], 0.0)
        tau[rows, k] = np.where(face_pair[rows], tau[rows, k], 0.0)
        cy = pr[:, K.P_MODEL] == K.MODEL_CY
        en = pr[:, K.P_EN]
        un = np.where(cy, np.maximum(s, 0.0) ** (1 - en) / ((1 - en) * pr[:, K.P_KN]), s / pr[:, K.P_KN])
        # faces start at their in-situ closure; other touches start unloaded: an overlap is
        # zeroed, a gap (rounded corners apart) stays open
        ovl = S[rows, k, K.OVL]
        S[rows, k, K.U0] = np.where(face_pair[rows], un - ovl, -np.maximum(ovl, 0.0))
        S[rows, k, K.TAU] = tau[rows, k]
        S[rows, k, K.FN] = s * S[rows, k, K.LEN]
        S[rows, k, K.FS] = tau[rows, k] * S[rows, k, K.LEN]
    engine.rebuild()  # the margin grows with the stored closure


def _covered_face_stress(engine, insitu: InSituStress, p: int, k: int) -> tuple[float, float]:
    """(σ_n, τ) for the one slot ``k`` of pair ``p``, a face of the block model so short that the
    rounded corners around it cover it (their tangent lengths exceed it), which the narrow phase
    makes a rounded-corner contact whose normal is not the face's.

    The slot carries the face's whole in-situ load: F = Σ σ(mᵢ)·nᵢ Lᵢ over the straight pieces of
    the shared boundary (midpoint mᵢ, normal nᵢ oriented like the slot's, length Lᵢ; exact for a
    stress linear in position), resolved on the slot's normal n and tangent t = (−n_y, n_x):
    σ_n = n·F / L_slot, τ = −t·F / L_slot (the sign convention of :func:`apply_insitu`). Without it
    that share of the in-situ load would be missing from both blocks. The slot's point is not the
    face's centre, so a moment of the order of |F| × the rounding radius stays unbalanced.
    """
    import shapely

    S, model = engine.S, engine.model
    a, b = int(engine.pa[p]), int(engine.pb[p])
    shared = shapely.Polygon(model.polygon(a)).boundary.intersection(
        shapely.Polygon(model.polygon(b)).boundary)
    n_slot = S[p, k, [K.NX, K.NY]]
    force = np.zeros(2)
    for part in shapely.get_parts(shared):  # line pieces (points where they only touch: none)
        if part.geom_type != "LineString":
            continue
        xy = np.asarray(part.coords)
        d = np.diff(xy, axis=0)
        seg = np.hypot(d[:, 0], d[:, 1])
        normal = np.column_stack([d[:, 1], -d[:, 0]]) / np.maximum(seg, 1e-300)[:, None]
        normal *= np.where(normal @ n_slot < 0, -1.0, 1.0)[:, None]
        mid = 0.5 * (xy[1:] + xy[:-1])
        sxx, syy, sxy = stress_at(insitu, mid, _unit_weight(engine), _y_ref(engine, insitu))
        force += np.array([np.sum((sxx * normal[:, 0] + sxy * normal[:, 1]) * seg),
                           np.sum((sxy * normal[:, 0] + syy * normal[:, 1]) * seg)])
    t_slot = np.array([-n_slot[1], n_slot[0]])
    slot_len = S[p, k, K.LEN]
    return float(n_slot @ force / slot_len), float(-(t_slot @ force) / slot_len)


def apply_boundary_stress(engine, loads: tuple[BoundaryStress, ...], insitu: InSituStress | None):
    """Constant tractions −σ·n_out on the domain edges of the chosen sides (force and the moment
    terms that rotate with the block, see :func:`rockmass.solver._kernels.advance`).

    With an in-situ stress, the domain edges of every other side (no user load) whose block is
    *held* normal to that side (a fix or a velocity input on x for ``left`` / ``right``, on y for
    ``bottom`` / ``top``: a roller or a clamp; a free-field side, docs/dem.md §14.2) carry the
    in-situ traction too, as the same kind of
    constant load. Reason: :func:`apply_insitu` loads only the contacts, and the traction missing on
    such an edge is the reaction of the rock beyond the boundary. The support carries its force (a
    fixed degree of freedom ignores forces) but not its moment, so a block on a roller, free to
    rotate, would start with the moment of the missing traction unbalanced (up to 6.0e7 N·m/m at
    step 1 on the bottom blocks of ``samples/solve_cavern.toml``, 6.7e-8 with the traction; issue
    14 saw its first stage move blocks 0.17 mm). With the traction every block starts in force and
    moment equilibrium (exact for the linear in-situ field: the lumping is consistent), and the
    support's moment stays the in-situ one as the model deforms, as for any constant boundary
    stress. Sides that are neither loaded nor held stay traction-free: a free surface is the
    user's choice, and a load there would also push its free blocks (the verification column
    starts out of balance on purpose). A face inside the model so short that rounded corners
    cover it still leaves a small moment (:func:`_covered_face_stress`).
    """
    engine.ext_f[:] = 0.0
    engine.ext_a[:] = 0.0
    engine.ext_b[:] = 0.0
    engine.zone_state["fext"][:] = 0.0
    edges = engine.edges
    for load in loads:
        on = np.flatnonzero(edges.on(load.sides))
        if not len(on):
            raise ValueError(f"boundary stress on {load.sides}: no block edge lies on these sides")
        if load.from_insitu:
            if insitu is None:
                raise ValueError("boundary stress from_insitu needs an in-situ stress")
            _add_tractions(engine, on, insitu)
        else:
            _add_tractions(engine, on, (load.sxx_pa, load.syy_pa, load.sxy_pa))
    if insitu is None:
        return
    loaded = {side for load in loads for side in load.sides}
    free = [side for side in SIDES if side not in loaded]
    if not free:
        return
    normal_dof = np.where(edges.side < SIDES.index("bottom"), 0, 1)  # left, right: x; else y
    held = (engine.base_mode == FIXED) | (engine.dof_input >= 0) | engine.ff_hold
    on = np.flatnonzero(edges.on(free) & held[edges.block, normal_dof])
    if len(on):
        _add_tractions(engine, on, insitu)


def _add_tractions(engine, on: np.ndarray, stress):
    """Add the constant tractions −σ·n_out of ``stress`` (an :class:`InSituStress`, or constant
    (σ_xx, σ_yy, σ_xy)) on the domain edges ``on`` to the blocks' external loads, lumped
    consistently to the edge ends."""
    edges = engine.edges
    blocks = edges.block[on]
    p0, p1, nrm = edges.p0[on], edges.p1[on], edges.normal[on]
    length = np.hypot(*(p1 - p0).T)
    if isinstance(stress, InSituStress):
        uw, yr = _unit_weight(engine), _y_ref(engine, stress)
        s0 = stress_at(stress, p0, uw, yr)
        s1 = stress_at(stress, p1, uw, yr)
    else:
        s0 = s1 = tuple(np.full(len(on), float(v)) for v in stress)
    trac = []
    for sxx, syy, sxy in (s0, s1):
        trac.append(-np.column_stack([sxx * nrm[:, 0] + sxy * nrm[:, 1],
                                      sxy * nrm[:, 0] + syy * nrm[:, 1]]))
    f0, f1 = _lumped(trac[0], trac[1], length[:, None])
    zoned = engine.zone_of[blocks] >= 0
    if zoned.any():  # a zone's edge: its two nodes take the forces (docs/dem.md §16.8)
        for f, p in ((f0, p0), (f1, p1)):
            add_node_forces(engine, blocks[zoned], p[zoned], f[zoned])
        blocks, p0, p1, f0, f1 = (a[~zoned] for a in (blocks, p0, p1, f0, f1))
    for f, p in ((f0, p0), (f1, p1)):
        r = p - engine.pos0[blocks]
        np.add.at(engine.ext_f, blocks, f)
        np.add.at(engine.ext_a, blocks, r[:, 0] * f[:, 1] - r[:, 1] * f[:, 0])
        np.add.at(engine.ext_b, blocks, -(r[:, 0] * f[:, 0] + r[:, 1] * f[:, 1]))


#: A domain edge of a block counts as one of its joint faces (the rock mass goes on beyond the cut
#: the way it is jointed inside) when one of the block's joint faces is within 10° of parallel to it
#: (|cos| of the angle between the normals): the base of a column of blocks on horizontal joints is
#: the joint the column would continue with; the side of that column is not a joint.
PARALLEL_COS = float(np.cos(np.radians(10.0)))


def _slot_stiffness(engine, p, slot) -> tuple[np.ndarray, np.ndarray]:
    """(k_n, k_s) (Pa/m) of active slots: the joint model's, a continuously yielding joint at
    its tangent a σ^e at the present stress (docs/dem.md §6)."""
    props = engine.props[engine.pprop[p]]
    sig = np.maximum(slot[:, K.FN] / np.maximum(slot[:, K.LEN], T.TINY), T.CY_PROBE_FLOOR_PA)
    cy = props[:, K.P_MODEL] == K.MODEL_CY
    kn = np.where(cy, props[:, K.P_KN] * sig ** props[:, K.P_EN], props[:, K.P_KN])
    ks = np.where(cy, props[:, K.P_KS] * sig ** props[:, K.P_ES], props[:, K.P_KS])
    return kn, ks


def block_faces(engine, b: int) -> np.ndarray:
    """Joint faces of block ``b``: rows (length l, unit normal (2), k_n, k_s) of the active contact
    slots of its block-model faces (corner touches and contacts formed later left out), plus its
    domain edges that are parallel (:data:`PARALLEL_COS`) to one of them, with those faces'
    length-weighted mean stiffnesses."""
    pairs = engine.bp_idx[engine.bp_ptr[b]:engine.bp_ptr[b + 1]] >> 1
    slot = engine.S[pairs].reshape(-1, K.N_SLOT_COLUMNS)
    p = np.repeat(pairs, 2)
    keep = (slot[:, K.ACT] != 0) & (engine.pinit[p] >= 0)
    p, slot = p[keep], slot[keep]
    kn, ks = _slot_stiffness(engine, p, slot)
    faces = np.column_stack([slot[:, K.LEN], slot[:, K.NX], slot[:, K.NY], kn, ks])
    edges = engine.edges
    extra = []
    for e in np.flatnonzero(edges.block == b) if len(faces) else ():
        parallel = np.abs(faces[:, 1:3] @ edges.normal[e]) > PARALLEL_COS
        if parallel.any():
            w = faces[parallel, 0]
            extra.append([np.hypot(*(edges.p1[e] - edges.p0[e])), *edges.normal[e],
                          w @ faces[parallel, 3] / w.sum(), w @ faces[parallel, 4] / w.sum()])
    return np.vstack([faces, extra]) if extra else faces


def joint_compliance(faces: np.ndarray, area: float, direction) -> tuple[float, float]:
    """(1/M, 1/G) (1/Pa): the compliance the joint faces of a block (:func:`block_faces`) add to
    the rock mass along the unit vector ``direction`` n — uniaxial stress along n for M, pure shear
    in the n–t plane for G (docs/dem.md §14.1, eqs. (14.1)–(14.2)).

    Each face of length l is shared by two blocks, so it stands for l / (2A) of joint area per
    unit volume of a block of area A. A face with unit normal m carries σ_n = σ c² and
    τ = σ c s of a stress σ along n (c = m·n, s = (−m_y, m_x)·n), and σ_n = 2τ c s,
    τ' = τ (c² − s²) of a shear τ, so equating strain energies (the equivalent continuum of a
    jointed rock; Amadei & Goodman 1981, Schoenberg 1980):

        1/M = Σ_f (l_f / 2A) c² (c² / k_n + s² / k_s),
        1/G = Σ_f (l_f / 2A) (4 c² s² / k_n + (c² − s²)² / k_s).

    For one set of spacing s_j parallel to the boundary (c = 1) this is 1/(k_n s_j), 1/(k_s s_j):
    the chain of rigid blocks of docs/dem.md §13, problem 11, whose long-wave impedance is
    √(ρ k_n s_j).
    """
    if not len(faces):
        return 0.0, 0.0
    n = np.asarray(direction, float)
    w = faces[:, 0] / (2.0 * area)
    c = faces[:, 1] * n[0] + faces[:, 2] * n[1]
    s = -faces[:, 2] * n[0] + faces[:, 1] * n[1]
    kn, ks = faces[:, 3], faces[:, 4]
    inv_m = float(np.sum(w * c * c * (c * c / kn + s * s / ks)))
    inv_g = float(np.sum(w * (4 * c * c * s * s / kn + (c * c - s * s) ** 2 / ks)))
    return inv_m, inv_g


def rock_mass_compliance(engine, blocks: np.ndarray, directions: np.ndarray,
                         rule: str = "rock_mass") -> np.ndarray:
    """(1/M, 1/G) (1/Pa) per row: the rock mass at each block along each unit direction, by
    ``rule`` (docs/dem.md §14.1): ``"rock_mass"`` its joints (:func:`joint_compliance` of
    :func:`block_faces`; along a direction no joint crosses, the intact rock if its moduli are
    given, else 0: rigid); ``"rock_mass_intact"`` the joints in series with the intact rock,
    1/M = 1/M_rock + 1/M_joints (Schoenberg 1980); ``"rock"`` the intact rock, M = K + 4G/3
    and G."""
    material = engine.settings.material
    intact = np.array(material.moduli()) if material.has_moduli else None
    inv = np.zeros((len(blocks), 2))
    if rule != "rock":
        faces = {}
        for i, (b, n) in enumerate(zip(blocks, directions)):
            if b not in faces:
                faces[b] = block_faces(engine, int(b))
            inv[i] = joint_compliance(faces[b], float(engine.model.area_m2[b]), n)
    if intact is not None and rule != "rock_mass":
        inv += 1.0 / intact
    elif intact is not None:
        inv = np.where(inv > 0, inv, 1.0 / intact)
    return inv


def boundary_impedance(engine, boundary, blocks: np.ndarray, normals: np.ndarray,
                       sides) -> tuple[np.ndarray, np.ndarray]:
    """(ρC_p, ρC_s) (Pa·s/m) of the dashpots on boundary edges of ``blocks`` with outward unit
    ``normals`` (a :class:`QuietBoundary` or :class:`FreeField` ``boundary``; docs/dem.md §14.1):
    ρC = √(ρ M) with M, G of :func:`rock_mass_compliance` along the normal by
    ``boundary.impedance``. A given ``p_wave_speed_m_s`` / ``s_wave_speed_m_s`` replaces ρC_p /
    ρC_s by ρ times it. Raises ValueError where the impedance is infinite (rigid rock along a
    normal, no moduli to fall back on) on a block that can move (0 on one that cannot: blocks held
    in every degree of freedom have no contacts among themselves in the solver)."""
    rho = engine.settings.material.density_kg_m3
    inv = rock_mass_compliance(engine, blocks, normals, boundary.impedance)
    z = np.sqrt(rho / np.where(inv > 0, inv, np.nan))
    for col, speed in enumerate((boundary.p_wave_speed_m_s, boundary.s_wave_speed_m_s)):
        if speed is not None:
            z[:, col] = rho * speed
    held = (engine.mode[blocks] != 0).all(axis=1)  # no free dof: its dashpots do nothing
    z[held] = np.nan_to_num(z[held])
    if np.isnan(z).any():
        i = int(np.flatnonzero(np.isnan(z).any(axis=1))[0])
        raise ValueError(f"boundary on {tuple(sides)}: no joint of block {int(blocks[i])} "
                         f"crosses the direction ({normals[i][0]:.3g}, {normals[i][1]:.3g}), so "
                         "its rock mass is rigid there; give material.bulk_modulus_pa and "
                         "shear_modulus_pa or the wave speeds")
    return z[:, 0], z[:, 1]


def boundary_edge_table(engine, boundary, sides) -> np.ndarray:
    """Rows ``block, local midpoint (2), local outward normal (2), length, ρC_p, ρC_s`` of the
    domain edges on ``sides`` (:func:`rockmass.solver._kernels.quiet_forces`), impedances by
    :func:`boundary_impedance`."""
    edges = engine.edges
    on = np.flatnonzero(edges.on(sides))
    if not len(on):
        raise ValueError(f"boundary on {tuple(sides)}: no block edge lies on these sides")
    blocks = edges.block[on]
    mid = 0.5 * (edges.p0[on] + edges.p1[on]) - engine.pos0[blocks]
    length = np.hypot(*(edges.p1[on] - edges.p0[on]).T)
    zp, zs = boundary_impedance(engine, boundary, blocks, edges.normal[on], sides)
    return np.ascontiguousarray(np.column_stack([blocks, mid, edges.normal[on], length, zp, zs]))


def quiet_edge_table(engine, quiet: QuietBoundary) -> np.ndarray:
    """The quiet sides' rows of :func:`boundary_edge_table`."""
    return boundary_edge_table(engine, quiet, quiet.sides)
