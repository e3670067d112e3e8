"""``blocks3d.vtu``: the faces of a 3D block model as polygons for ParaView, with per-face cell data.

Every face of every piece is one polygon cell (meshio groups them by vertex count, as
:func:`rockmass.blockgen.blockio.polygon_cells` does for 2D blocks). Cell data: ``piece``, ``block``
(in-situ block, −1 for excavated pieces), ``excavated`` (0/1), ``face_label`` (fracture or set id;
−1 the domain box; −2 − k the walls of tunnel k), ``block_volume_m3`` and, when a keyblock table is
given, ``keyblock_mode`` (index into :data:`rockmass.blockgen.keyblocks.MODES`, −1 for blocks
without a free face) and ``factor_of_safety`` (−1 where not analysed; finite values as computed,
``1e30`` for stable or locked blocks, whose factor is infinite).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .blockio import polygon_cells
from .keyblocks import MODES

__all__ = ["write_blocks3d_vtu", "block_mesh", "export_blocks", "piece_triangles"]

#: stands for an infinite factor of safety in the VTU (VTK readers do not all accept inf).
INFINITE_FS = 1e30


def write_blocks3d_vtu(blocks, path, keyblocks=None) -> Path:
    """Write the faces of ``blocks`` (a :class:`~rockmass.blockgen.blocks3d.BlockSet3D`) atomically.

    ``keyblocks`` is the list :func:`rockmass.blockgen.keyblocks.keyblocks` returned, or None.
    """
    import meshio

    from rockmass.dfn.atomic import atomic_path

    faces, piece, label = [], [], []
    for p, poly in enumerate(blocks.pieces):
        faces.extend(poly.faces)
        piece.extend([p] * len(poly.faces))
        label.extend(blocks.planes.label[j] if j >= 0 else j for j in poly.labels)
    piece = np.asarray(piece, np.int64)
    offsets = np.concatenate([[0], np.cumsum([len(f) for f in faces])]).astype(np.int64)
    block = blocks.block_id[piece]
    volumes = blocks.block_volumes_m3()
    mode = np.full(blocks.n_blocks + 1, -1, np.int64)        # last entry: excavated pieces
    fs = np.full(blocks.n_blocks + 1, -1.0)
    for k in keyblocks or ():
        mode[k.block] = MODES.index(k.mode)
        fs[k.block] = min(k.factor_of_safety, INFINITE_FS)
    per_face = {"piece": piece, "block": block, "excavated": blocks.excavated[piece].astype(np.int64),
                "face_label": np.asarray(label, np.int64),
                "block_volume_m3": np.where(block >= 0, volumes[block], 0.0),
                "keyblock_mode": mode[block], "factor_of_safety": fs[block]}
    cells, groups = polygon_cells(offsets)
    mesh = meshio.Mesh(np.concatenate(faces), cells,
                       cell_data={name: [values[g] for g in groups] for name, values in per_face.items()})
    path = Path(path)
    with atomic_path(path) as tmp:
        meshio.write(tmp, mesh, file_format="vtu")
    return path


def piece_triangles(piece) -> np.ndarray:
    """The fan triangles ``(t, 3, 3)`` of a convex polyhedron's faces (outward, counter-clockwise)."""
    return np.concatenate([np.stack([np.broadcast_to(f[0], (len(f) - 2, 3)), f[1:-1], f[2:]], axis=1)
                           for f in piece.faces])


def block_mesh(blocks, block: int):
    """The in-situ block ``block`` as one :class:`trimesh.Trimesh`: the closed surfaces of its convex
    pieces together (the glued faces between them are inside the block, one copy per piece), so its
    volume, centre of mass and inertia are the block's."""
    import trimesh

    members = np.flatnonzero(blocks.block_id == block)
    if not len(members):
        raise ValueError(f"no in-situ block {block} (blocks: 0..{blocks.n_blocks - 1})")
    triangles = np.concatenate([piece_triangles(blocks.pieces[p]) for p in members])
    return trimesh.Trimesh(**trimesh.triangles.to_kwargs(triangles))


def export_blocks(blocks, path, which=None) -> Path:
    """Write in-situ blocks (``which``: block ids, default all) as one mesh file in any format
    trimesh writes, chosen by the suffix (``.ply``, ``.stl``, ``.obj``, ``.glb``), atomically."""
    import trimesh

    from rockmass.dfn.atomic import atomic_path

    ids = range(blocks.n_blocks) if which is None else which
    scene = trimesh.util.concatenate([block_mesh(blocks, int(b)) for b in ids])
    path = Path(path)
    with atomic_path(path) as tmp:
        scene.export(tmp, file_type=path.suffix.lstrip(".").lower())
    return path
