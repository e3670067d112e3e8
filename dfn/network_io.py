"""Disk networks to and from files: ``fractures.csv`` and ``fractures.vtu`` (ParaView).

CSV
---
One header line ``set,cx,cy,cz,nx,ny,nz,radius`` and one row per disk: set id (integer), centre
(metres, x East, y North, z Up), unit normal and radius (metres). Floats are written with 17
digits of Python's ``repr`` (the shortest string that reads back to the same float64), so reading a
written file gives back the same values bit for bit. The domain box is not part of the file: :func:`read_fractures_csv` takes it as an argument.

VTU
---
Each disk becomes a regular polygon of ``n_vertices`` vertices inscribed in it (meshio ``polygon``
cells, VTK_POLYGON), with integer cell data ``set`` and ``id`` (the row in the network). Files are
written atomically (:mod:`rockmass.dfn.atomic`).
"""

from __future__ import annotations

import os

import numpy as np
from numpy.typing import ArrayLike

from .atomic import atomic_open, atomic_path
from .network import DiskNetwork, _require_network, disk_basis

__all__ = ["CSV_COLUMNS", "read_fractures_csv", "write_fractures_csv", "write_fractures_vtu", "disk_polygons"]

CSV_COLUMNS = ("set", "cx", "cy", "cz", "nx", "ny", "nz", "radius")


def write_fractures_csv(network: DiskNetwork, path: str | os.PathLike) -> None:
    """Write ``network`` as ``set,cx,cy,cz,nx,ny,nz,radius`` rows (atomically; see module docstring).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> net = DiskNetwork([[1, 2, 3]], [[0, 0, 1]], [0.5], [2], [0, 0, 0, 5, 5, 5])
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "fractures.csv"
    >>> write_fractures_csv(net, f)
    >>> print(f.read_text().strip())
    set,cx,cy,cz,nx,ny,nz,radius
    2,1.0,2.0,3.0,0.0,0.0,1.0,0.5
    """
    _require_network(network)
    with atomic_open(path, "w", newline="") as handle:
        handle.write(",".join(CSV_COLUMNS) + "\n")
        if network.n_fractures:
            values = np.column_stack([network.set_id, network.centre_m, network.normal, network.radius_m])
            rows = values.tolist()  # Python floats: repr round-trips exactly
            handle.write("\n".join(f"{int(r[0])},{r[1]!r},{r[2]!r},{r[3]!r},{r[4]!r},{r[5]!r},{r[6]!r},{r[7]!r}"
                                   for r in rows) + "\n")


def read_fractures_csv(path: str | os.PathLike, domain_m: ArrayLike | None = None) -> DiskNetwork:
    """Read a file written by :func:`write_fractures_csv`.

    Parameters
    ----------
    path : str or path-like
    domain_m : (2, 3) or (6,) array_like, optional
        The domain box; default the bounding box of the disks' centres ± radius (a unit box at the
        origin for an empty file).

    Raises
    ------
    ValueError
        Wrong header, a row of the wrong length, a non-numeric or non-finite value, or a bad disk
        (the message names the file and the line).
    """
    shown = os.fspath(path)
    with open(path, encoding="utf-8-sig") as handle:
        lines = handle.read().splitlines()
    if not lines or tuple(c.strip() for c in lines[0].split(",")) != CSV_COLUMNS:
        raise ValueError(f"{shown}: line 1: header must be {','.join(CSV_COLUMNS)}, got "
                         f"{lines[0] if lines else '(empty file)'!r}")
    body = [line for line in lines[1:] if line.strip()]
    try:  # fast path: numpy's C parser (correctly rounded, so the round trip is exact)
        table = np.loadtxt(body, delimiter=",", dtype=np.float64, ndmin=2).reshape(-1, 8) if body \
            else np.zeros((0, 8))
        ok = np.isfinite(table).all() and np.array_equal(table[:, 0], np.round(table[:, 0]))
    except ValueError:
        ok = False
    if ok:
        sets, array = table[:, 0].astype(np.int64), table[:, 1:]
    else:
        sets, array = _parse_rows(lines, shown)
    if domain_m is None:
        if array.shape[0]:
            r = array[:, 6:7]
            domain_m = np.stack([(array[:, :3] - r).min(axis=0), (array[:, :3] + r).max(axis=0)])
        else:
            domain_m = [0, 0, 0, 1, 1, 1]
    try:
        return DiskNetwork(array[:, :3], array[:, 3:6], array[:, 6], sets, domain_m)
    except ValueError as exc:
        raise ValueError(f"{shown}: {exc}") from exc


def _parse_rows(lines: list[str], shown: str) -> tuple[np.ndarray, np.ndarray]:
    """Slow path of the reader: parse row by row so that an error names its line."""
    sets, values = [], []
    for lineno, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        cells = line.split(",")
        if len(cells) != len(CSV_COLUMNS):
            raise ValueError(f"{shown}: line {lineno}: expected {len(CSV_COLUMNS)} values, got {len(cells)}")
        try:
            sets.append(int(cells[0]))
            row = [float(c) for c in cells[1:]]
        except ValueError as exc:
            raise ValueError(f"{shown}: line {lineno}: {exc}") from exc
        if not np.all(np.isfinite(row)):
            raise ValueError(f"{shown}: line {lineno}: values must be finite, got {line!r}")
        values.append(row)
    return np.array(sets, dtype=np.int64), np.array(values, dtype=np.float64).reshape(-1, 7)


def disk_polygons(network: DiskNetwork, n_vertices: int = 16) -> np.ndarray:
    """Vertices of the regular polygon inscribed in each disk, ``(n, n_vertices, 3)`` float64 metres.

    Counter-clockwise seen from the normal's side; vertex 0 on the disk's first basis vector.
    """
    _require_network(network)
    if isinstance(n_vertices, bool) or not isinstance(n_vertices, (int, np.integer)) or n_vertices < 3:
        raise ValueError(f"n_vertices must be an integer >= 3, got {n_vertices!r}")
    e1, e2 = disk_basis(network.normal)
    angle = 2.0 * np.pi * np.arange(n_vertices) / n_vertices
    r = network.radius_m[:, None, None]
    return network.centre_m[:, None, :] + r * (np.cos(angle)[None, :, None] * e1[:, None, :]
                                               + np.sin(angle)[None, :, None] * e2[:, None, :])


def write_fractures_vtu(network: DiskNetwork, path: str | os.PathLike, *, n_vertices: int | ArrayLike = 16) -> None:
    """Write the disks as regular polygons with cell data ``set`` and ``id`` (VTU via meshio).

    Parameters
    ----------
    network : DiskNetwork
    path : str or path-like
        The ``.vtu`` file (written atomically).
    n_vertices : int or sequence of int, default 16
        Polygon vertices per disk, >= 3: one number for all, or one per set id (``n_vertices[set_id]``).
        Disks with the same count form one ``polygon`` cell block (blocks in increasing count).

    Examples
    --------
    >>> import pathlib, tempfile, meshio
    >>> net = DiskNetwork([[1, 2, 3], [0, 0, 0]], [[0, 0, 1]] * 2, [0.5, 1.0], [0, 1], [-5] * 3 + [5] * 3)
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "fractures.vtu"
    >>> write_fractures_vtu(net, f, n_vertices=8)
    >>> mesh = meshio.read(f)
    >>> mesh.cells[0].data.shape, mesh.cell_data["set"][0].tolist()
    ((2, 8), [0, 1])
    """
    import meshio

    _require_network(network)
    counts = np.asarray(n_vertices)
    if counts.dtype.kind not in "iu" or counts.ndim > 1 or (counts < 3).any():
        raise ValueError(f"n_vertices must be an integer >= 3 or one such integer per set, got {n_vertices!r}")
    if counts.ndim == 1:
        if network.n_fractures and network.set_id.max() >= counts.size:
            raise ValueError(f"n_vertices gives {counts.size} counts but set ids go up to {network.set_id.max()}")
        per_disk = counts[network.set_id] if network.n_fractures else np.zeros(0, np.int64)
    else:
        per_disk = np.full(network.n_fractures, int(counts))
    points, cells, set_data, id_data, start = [], [], [], [], 0
    for m in np.unique(per_disk):
        rows = np.flatnonzero(per_disk == m)
        vertices = disk_polygons(network.subset(rows), int(m)).reshape(-1, 3)
        points.append(vertices)
        cells.append(("polygon", start + np.arange(rows.size * m, dtype=np.int64).reshape(rows.size, m)))
        set_data.append(network.set_id[rows].astype(np.int64))
        id_data.append(rows.astype(np.int64))
        start += vertices.shape[0]
    mesh = meshio.Mesh(np.concatenate(points) if points else np.zeros((0, 3)), cells,
                       cell_data={"set": set_data, "id": id_data})
    with atomic_path(path) as tmp:
        meshio.write(tmp, mesh, file_format="vtu")
