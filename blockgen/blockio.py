"""Block model files: ``blocks.json`` (exact round trip) and ``blocks.vtu`` (meshio polygons).

``blocks.json`` layout (version 1)::

    {"format": "rockmass.blocks", "version": 1,
     "region_names": [...], "set_names": [...], "contact_kinds": [...],
     "domain_xy_m": [[x, y], ...],
     "blocks": [{"id": 0, "region": 0, "vertices": [[x, y], ...], "area_m2": a}, ...],
     "contacts": [{"blocks": [i, j], "length_m": l, "kind": "joint", "source": 0}, ...],
     "quality": {...}}

A contact's ``source`` is the joint-set index (``joint``), the trace index (``trace``), the stage
(``excavation``), ``-1`` (``domain``); for ``glued`` the extended set or trace index, ``-2`` for a
convex-decomposition cut and ``-3`` for a potential crack (:data:`rockmass.blockgen.SOURCE_CRACK`).

Floats are written with Python's shortest round-trip repr, so reading the file rebuilds the same
arrays bit for bit and writing again gives the same text. Areas are written for readers; they are
recomputed from the vertices on reading.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .model import CONTACT_KINDS, BlockModel

__all__ = ["to_json_dict", "from_json_dict", "write_json", "read_json", "write_vtu", "polygon_cells",
           "FORMAT"]

FORMAT = "rockmass.blocks"
VERSION = 1


def to_json_dict(model: BlockModel) -> dict:
    """The JSON document of ``model`` (plain Python types)."""
    xy = model.xy_m.tolist()
    off = model.offsets.tolist()
    blocks = [{"id": i, "region": int(model.region[i]), "vertices": xy[off[i]:off[i + 1]],
               "area_m2": float(model.area_m2[i])} for i in range(model.n_blocks)]
    contacts = [{"blocks": [int(a), int(b)], "length_m": float(length),
                 "kind": CONTACT_KINDS[int(k)], "source": int(s)}
                for (a, b), length, k, s in zip(model.contact_blocks.tolist(),
                                                model.contact_length_m.tolist(),
                                                model.contact_kind.tolist(),
                                                model.contact_source.tolist())]
    return {"format": FORMAT, "version": VERSION, "region_names": list(model.region_names),
            "set_names": list(model.set_names), "contact_kinds": list(CONTACT_KINDS),
            "domain_xy_m": model.domain_xy_m.tolist(), "blocks": blocks, "contacts": contacts,
            "quality": {} if model.quality is None else model.quality.to_dict()}


def from_json_dict(doc: dict, name: str = "blocks.json") -> BlockModel:
    """Rebuild a :class:`BlockModel` from :func:`to_json_dict` output; ValueError names the field."""
    if doc.get("format") != FORMAT or doc.get("version") != VERSION:
        raise ValueError(f"{name}: format/version must be {FORMAT!r}/{VERSION}, got "
                         f"{doc.get('format')!r}/{doc.get('version')!r}")
    try:
        verts = [np.asarray(b["vertices"], float).reshape(-1, 2) for b in doc["blocks"]]
        kinds = {k: i for i, k in enumerate(CONTACT_KINDS)}
        contacts = doc["contacts"]
        return BlockModel(
            xy_m=np.concatenate(verts) if verts else np.empty((0, 2)),
            offsets=np.concatenate([[0], np.cumsum([len(v) for v in verts])]).astype(np.int64),
            region=[b["region"] for b in doc["blocks"]],
            region_names=doc["region_names"],
            contact_blocks=np.asarray([c["blocks"] for c in contacts], np.int64).reshape(-1, 2),
            contact_length_m=[c["length_m"] for c in contacts],
            contact_kind=[kinds[c["kind"]] for c in contacts],
            contact_source=[c["source"] for c in contacts],
            set_names=doc["set_names"], domain_xy_m=doc["domain_xy_m"], quality=doc["quality"])
    except (KeyError, TypeError) as exc:
        raise ValueError(f"{name}: missing or malformed field {exc}") from exc


def dumps(model: BlockModel) -> str:
    return json.dumps(to_json_dict(model), indent=1, allow_nan=False)


def write_json(model: BlockModel, path) -> Path:
    """Write ``blocks.json`` atomically (:mod:`rockmass.dfn.atomic`)."""
    from rockmass.dfn.atomic import atomic_open

    path = Path(path)
    with atomic_open(path, "w") as f:
        f.write(dumps(model))
    return path


def read_json(path) -> BlockModel:
    """Read ``blocks.json``."""
    path = Path(path)
    return from_json_dict(json.loads(path.read_text(encoding="utf-8")), name=str(path))


def _block_sets(model: BlockModel) -> np.ndarray:
    """Joint set of each block's longest joint contact (-1 when it has none)."""
    best_len = np.zeros(model.n_blocks)
    best_set = np.full(model.n_blocks, -1, np.int64)
    joint = np.flatnonzero(model.contact_kind == CONTACT_KINDS.index("joint"))
    for c in joint[np.argsort(model.contact_length_m[joint], kind="stable")]:
        for b in model.contact_blocks[c]:
            if b >= 0 and model.contact_length_m[c] >= best_len[b]:
                best_len[b] = model.contact_length_m[c]
                best_set[b] = model.contact_source[c]
    return best_set


def polygon_cells(offsets) -> tuple[list[tuple[str, np.ndarray]], list[np.ndarray]]:
    """meshio cell blocks of ragged polygons: one block per vertex count, as meshio groups them.

    Parameters
    ----------
    offsets : (n_blocks + 1,) array_like of int
        Block ``i`` owns vertices ``offsets[i]:offsets[i + 1]`` (:class:`BlockModel` layout).

    Returns
    -------
    cells : list of (str, (n_k, k) int64)
        ``("triangle" | "quad" | "polygon", connectivity)`` per vertex count ``k``, increasing; the
        connectivity indexes the model's vertex array.
    groups : list of (n_k,) int64
        The block ids of each cell block, in its order: cell data of block ``i`` goes at its
        position in ``groups`` (``[values[idx] for idx in groups]``).

    Examples
    --------
    >>> cells, groups = polygon_cells([0, 3, 7, 10])
    >>> [(kind, conn.tolist()) for kind, conn in cells], [g.tolist() for g in groups]
    ([('triangle', [[0, 1, 2], [7, 8, 9]]), ('quad', [[3, 4, 5, 6]])], [[0, 2], [1]])
    """
    offsets = np.asarray(offsets, np.int64)
    sizes = np.diff(offsets)
    cells, groups = [], []
    for k in np.unique(sizes):
        idx = np.flatnonzero(sizes == k)
        cells.append(("polygon" if k > 4 else {3: "triangle", 4: "quad"}[int(k)],
                      offsets[idx][:, None] + np.arange(k)[None, :]))
        groups.append(idx)
    return cells, groups


def write_vtu(model: BlockModel, path) -> Path:
    """Write ``blocks.vtu`` atomically: one polygon per block with cell data ``block_id``,
    ``region`` and ``set`` (the joint set of the block's longest joint contact, -1 if it has none;
    the set of each contact is in ``blocks.json``)."""
    import meshio

    from rockmass.dfn.atomic import atomic_path

    points = np.column_stack([model.xy_m, np.zeros(len(model.xy_m))])
    block_set = _block_sets(model)
    cells, groups = polygon_cells(model.offsets)
    meshio_mesh = meshio.Mesh(points, cells, cell_data={
        "block_id": groups, "region": [model.region[idx] for idx in groups],
        "set": [block_set[idx] for idx in groups]})
    with atomic_path(Path(path)) as tmp:
        meshio.write(tmp, meshio_mesh, file_format="vtu")
    return Path(path)
