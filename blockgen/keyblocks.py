"""Keyblocks around an opening: removability, failure mode and factor of safety (block theory).

For each in-situ block of a :class:`~rockmass.blockgen.blocks3d.BlockSet3D` that has a free face on an
excavation (docs/blocks.md §9; Goodman & Shi 1985; Warburton 1981):

1. **Faces.** Its contact faces are the real fractures it shares with other rock blocks, grouped by
   plane, each with the outward normal m_i (from the block into the rock beyond), area A_i and the
   strength (φ_i, c_i) of its joint set. A block touching the domain box is reported as
   ``boundary`` and not analysed (the box is not a physical surface).
2. **Removability.** The block can translate into the opening without pushing into any neighbour iff
   some direction s has s·m_i ≤ 0 for every contact face and s·f > 0 for the outward normal f of its
   largest free face (a linear programme). Otherwise it is ``locked`` (tapered).
3. **Mode under its weight** r = ρ g V (0, 0, −1):
   - ``fall`` when r·m_i ≤ 0 for every face (it lifts off or slides freely along all of them):
     factor of safety 0;
   - ``slide`` on face i when r·m_i > 0 and the direction s = r − (r·m_i) m_i has s·m_j ≤ 0 for
     every other face: N = r·m_i, T = |s|, FS = (N tan φ_i + c_i A_i) / T;
   - ``slide2`` on faces i, j when r = N_i m_i + N_j m_j + T e with e = ±(m_i × m_j)/|m_i × m_j|,
     N_i, N_j > 0, T > 0 and e·m_k ≤ 0 for every other face:
     FS = (N_i tan φ_i + N_j tan φ_j + c_i A_i + c_j A_j) / T;
   - ``stable`` when its weight pushes into its faces in no admissible direction.

The apex height is the largest distance of the block's vertices from the plane of its largest free
face.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .polyhedra import LABEL_BOX

__all__ = ["Keyblock", "keyblocks", "MODES"]

MODES = ("fall", "slide", "slide2", "stable", "locked", "boundary")
#: directions within this cosine of a face plane count as along it.
_ALONG = 1e-9


@dataclass(frozen=True)
class Keyblock:
    """One in-situ block with a free face: ``block`` id, ``volume_m3``, ``free_area_m2``,
    ``apex_height_m``, ``mode`` (one of :data:`MODES`), ``planes`` (labels of the faces it slides
    on, or all contact labels for ``fall``), ``factor_of_safety`` (inf when ``stable`` or
    ``locked``, NaN-free) and ``direction`` (unit sliding or falling direction, zeros otherwise)."""

    block: int
    volume_m3: float
    free_area_m2: float
    apex_height_m: float
    mode: str
    planes: tuple[int, ...]
    factor_of_safety: float
    direction: tuple[float, float, float]


def keyblocks(blocks, strength: dict[int, tuple[float, float]], density_kg_m3: float = 2700.0,
              gravity_m_s2: float = 9.81) -> list[Keyblock]:
    """Analyse every in-situ block that has a free face.

    Parameters
    ----------
    blocks : BlockSet3D
        Cut with at least one tunnel.
    strength : dict
        Fracture label → (friction angle in degrees, cohesion in Pa); a missing label is
        frictionless and cohesionless (conservative).
    density_kg_m3, gravity_m_s2 : float
        Rock density and gravity.
    """
    faces, free = _block_faces(blocks)
    out = []
    for block in sorted(free):
        pieces = np.flatnonzero(blocks.block_id == block)
        volume = float(blocks.volume_m3[pieces].sum())
        free_area = sum(a for a, _, _ in free[block])
        area, normal, point = max(free[block], key=lambda f: f[0])
        vertices = np.concatenate([blocks.pieces[p].vertices_m() for p in pieces])
        apex = float(((point - vertices) @ normal).max())
        contacts = faces.get(block, [])
        touches_box = any(LABEL_BOX in blocks.pieces[p].labels for p in pieces)
        weight = density_kg_m3 * gravity_m_s2 * volume * np.array([0.0, 0.0, -1.0])
        if touches_box:
            mode, planes, fs, direction = "boundary", (), math.inf, np.zeros(3)
        elif not _removable([m for m, _, _ in contacts], normal):
            mode, planes, fs, direction = "locked", (), math.inf, np.zeros(3)
        else:
            mode, planes, fs, direction = _mode(weight, contacts, strength)
        out.append(Keyblock(int(block), volume, float(free_area), apex, mode, planes, float(fs),
                            tuple(float(v) for v in direction)))
    return out


def _block_faces(blocks):
    """Per block: contact faces [(m, area, label)] merged by plane label and normal, and free faces
    [(area, outward normal, a point of the plane)]."""
    contact: dict[int, dict] = {}
    free: dict[int, list] = {}
    planes = blocks.planes
    for (a, b, j), area in zip(blocks.links, blocks.link_area_m2):
        n, label = planes.normal[j], int(planes.label[j])
        for mine, other, outward in ((a, b, n), (b, a, -n)):
            block, beyond = blocks.block_id[mine], blocks.block_id[other]
            if block < 0 or block == beyond:
                continue
            if beyond < 0:
                free.setdefault(block, []).append((float(area), outward, n * planes.offset_m[j]))
            else:
                key = (label, tuple(np.round(outward, 9)))
                entry = contact.setdefault(block, {}).setdefault(key, [outward, 0.0, label])
                entry[1] += float(area)
    return {b: [tuple(v) for v in d.values()] for b, d in contact.items()}, free


def _removable(normals: list, free_normal: np.ndarray) -> bool:
    """Is there s with s·m_i ≤ 0 for every contact normal and s·f ≥ 1 (into the opening)?"""
    from scipy.optimize import linprog

    a_ub = np.array([*normals, -free_normal]) if normals else -free_normal[None]
    b_ub = np.array([0.0] * len(normals) + [-1.0])
    res = linprog(np.zeros(3), A_ub=a_ub, b_ub=b_ub, bounds=[(-1e3, 1e3)] * 3, method="highs")
    return bool(res.status == 0)


def _mode(weight: np.ndarray, contacts: list, strength: dict):
    """Fall, slide on one face or on two, or stable, with the factor of safety (module docstring)."""
    normals = [m for m, _, _ in contacts]
    w = float(np.linalg.norm(weight))
    if all(weight @ m <= _ALONG * w for m in normals):
        return "fall", tuple(lab for _, _, lab in contacts), 0.0, weight / w
    for i, (m, area, label) in enumerate(contacts):
        n_force = weight @ m
        s = weight - n_force * m
        t = float(np.linalg.norm(s))
        if n_force > 0 and t > _ALONG * w and all(s @ contacts[k][0] <= _ALONG * t
                                                   for k in range(len(contacts)) if k != i):
            phi, c = strength.get(label, (0.0, 0.0))
            return "slide", (label,), (n_force * math.tan(math.radians(phi)) + c * area) / t, s / t
    for i in range(len(contacts)):
        for j in range(i + 1, len(contacts)):
            mi, ai, li = contacts[i]
            mj, aj, lj = contacts[j]
            e = np.cross(mi, mj)
            if np.linalg.norm(e) < 1e-9:
                continue
            e /= np.linalg.norm(e)
            if weight @ e < 0:
                e = -e
            ni, nj, t = np.linalg.solve(np.stack([mi, mj, e], axis=1), weight)
            if ni > 0 and nj > 0 and t > _ALONG * w and all(e @ contacts[k][0] <= _ALONG
                                                          for k in range(len(contacts)) if k not in (i, j)):
                phi_i, c_i = strength.get(li, (0.0, 0.0))
                phi_j, c_j = strength.get(lj, (0.0, 0.0))
                resisting = (ni * math.tan(math.radians(phi_i)) + nj * math.tan(math.radians(phi_j))
                             + c_i * ai + c_j * aj)
                return "slide2", (li, lj), resisting / t, e
    return "stable", (), math.inf, np.zeros(3)
