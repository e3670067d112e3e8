"""Initial stress, boundary tractions and quiet boundaries turned into the engine's arrays.

Stress fields are linear in y at most (uniform, or gravity with K₀), so forces on a straight edge of
length L between points P₀, P₁ with tractions t₀, t₁ are lumped *consistently* (linear element):
F₀ = L(2t₀ + t₁)/6 at P₀ and F₁ = L(t₀ + 2t₁)/6 at P₁, which keeps the resultant and its moment
exact — so a block under an equilibrium stress field starts in equilibrium (docs/dem.md §9.3).
"""

from __future__ import annotations

import numpy as np

from . import _kernels as K
from .engine import FIXED
from .settings import SIDES, BoundaryStress, InSituStress, QuietBoundary

__all__ = ["stress_at", "apply_insitu", "apply_boundary_stress", "quiet_edge_table"]


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
    ``bottom`` / ``top``: a roller or a clamp) carry the in-situ traction too, as the same kind of
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
    held = (engine.base_mode == FIXED) | (engine.dof_input >= 0)
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
    for f, p in ((f0, p0), (f1, p1)):
        r = p - engine.pos0[blocks]
        np.add.at(engine.ext_f, blocks, f)
        np.add.at(engine.ext_a, blocks, r[:, 0] * f[:, 1] - r[:, 1] * f[:, 0])
        np.add.at(engine.ext_b, blocks, -(r[:, 0] * f[:, 0] + r[:, 1] * f[:, 1]))


def quiet_edge_table(engine, quiet: QuietBoundary) -> np.ndarray:
    """Rows ``block, local midpoint (2), local outward normal (2), length, ρC_p, ρC_s`` for the
    quiet sides (:func:`rockmass.solver._kernels.quiet_forces`)."""
    cp, cs = engine.settings.material.wave_speeds()
    rho = engine.settings.material.density_kg_m3
    edges = engine.edges
    on = np.flatnonzero(edges.on(quiet.sides))
    if not len(on):
        raise ValueError(f"quiet boundary on {quiet.sides}: no block edge lies on these sides")
    blocks = edges.block[on]
    mid = 0.5 * (edges.p0[on] + edges.p1[on]) - engine.pos0[blocks]
    length = np.hypot(*(edges.p1[on] - edges.p0[on]).T)
    return np.ascontiguousarray(np.column_stack([blocks, mid, edges.normal[on], length,
                                                 np.full(len(on), rho * cp),
                                                 np.full(len(on), rho * cs)]))
