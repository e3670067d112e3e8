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

__all__ = ["write_blocks3d_vtu"]

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
