"""Disk networks to and from files: ``fractures.csv`` and ``fractures.vtu`` (ParaView).

CSV
---
One header line ``set,cx,cy,cz,nx,ny,nz,radius`` and one row per disk: set id (integer), centre
(metres, x East, y North, z Up), unit normal and radius (metres). Floats are written with 17
digits of Python's ``repr`` (the shortest string that reads back to the same float64), so reading a
written file gives back the same values bit for bit. The domain box is not part of the file: :func:`read_fractures_csv` takes it as an argument.

VTU
---
``fractures.vtu``: each disk becomes the regular polygon of ``n_vertices`` vertices inscribed in it
(meshio ``polygon`` cells, VTK_POLYGON), clipped to the domain box (:func:`clip_disk_polygons`: a
polygon crossing a face of the box is cut along it; one wholly outside is left out), with the cell
data :data:`FRACTURE_CELL_DATA`:

=====================  =======  ==========================================================
name                   dtype    meaning
=====================  =======  ==========================================================
``set``                int64    set id
``id``                 int64    row of the disk in the network (0-based data row of ``fractures.csv``)
``dip_deg``            float64  dip of the disk's plane, 0–90°
``dip_direction_deg``  float64  dip direction, clockwise from North (+y), 0–360°
                                (:func:`rockmass.dfn.dip_from_normal`; 0 for a horizontal disk)
``radius_m``           float64  radius of the whole disk, m (also of a clipped one)
``clipped``            uint8    1 when the box cut the disk's polygon
=====================  =======  ==========================================================

``sections.vtu`` (:func:`write_section_traces_vtu`): the traces of the disks on planar sections
(:func:`rockmass.dfn.sample_plane`) in world coordinates, one ``line`` cell per straight piece, with
the cell data :data:`SECTION_CELL_DATA`. Files are written atomically (:mod:`rockmass.dfn.atomic`).
"""

from __future__ import annotations

import os

import numpy as np
from numpy.typing import ArrayLike

from .atomic import atomic_open, atomic_path
from .network import DiskNetwork, _require_network, as_box, disk_basis

__all__ = ["CSV_COLUMNS", "FRACTURE_CELL_DATA", "SECTION_CELL_DATA", "read_fractures_csv", "write_fractures_csv",
           "write_fractures_vtu", "write_section_traces_vtu", "disk_polygons", "clip_disk_polygons"]

CSV_COLUMNS = ("set", "cx", "cy", "cz", "nx", "ny", "nz", "radius")
#: Clipped polygon vertices closer than this times the disk's radius are one vertex.
_MERGE = 1e-9
#: Names of the cell data of ``fractures.vtu``, in order (module docstring).
FRACTURE_CELL_DATA = ("set", "id", "dip_deg", "dip_direction_deg", "radius_m", "clipped")
#: Names of the cell data of ``sections.vtu``, in order (:func:`write_section_traces_vtu`).
SECTION_CELL_DATA = ("section", "set", "id", "length_m")


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


def _vertex_counts(network: DiskNetwork, n_vertices: int | ArrayLike) -> np.ndarray:
    """Polygon vertices of each disk, ``(n,)`` int64, from one count or one count per set id."""
    counts = np.asarray(n_vertices)
    if counts.dtype.kind not in "iu" or counts.ndim > 1 or (counts < 3).any():
        raise ValueError(f"n_vertices must be an integer >= 3 or one such integer per set, got {n_vertices!r}")
    if counts.ndim == 0:
        return np.full(network.n_fractures, int(counts), dtype=np.int64)
    if network.n_fractures and network.set_id.max() >= counts.size:
        raise ValueError(f"n_vertices gives {counts.size} counts but set ids go up to {network.set_id.max()}")
    return counts.astype(np.int64)[network.set_id] if network.n_fractures else np.zeros(0, np.int64)


def clip_disk_polygons(network: DiskNetwork, n_vertices: int | ArrayLike = 16, *,
                       box: ArrayLike | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The disks' inscribed polygons (:func:`disk_polygons`) clipped to a box, in the ragged layout.

    Parameters
    ----------
    network : DiskNetwork
    n_vertices : int or sequence of int, default 16
        Polygon vertices per disk, >= 3: one number for all, or one per set id (``n_vertices[set_id]``).
    box : (2, 3) or (6,) array_like, optional
        Default the network's domain.

    Returns
    -------
    xyz_m : (N, 3) float64
        Vertices in metres; polygon k is ``xyz_m[offsets[k]:offsets[k + 1]]``, in the order of
        its disk's polygon (counter-clockwise seen from the normal's side), with the points where
        its edges cross the box's faces. A polygon cut by the box has up to ``n_vertices`` + 6
        vertices.
    offsets : (k + 1,) int64
    disk : (k,) int64
        Row of each polygon's disk in ``network``, increasing. Disks whose polygon lies outside
        the box, or only touches it, are left out.
    clipped : (k,) bool
        True for a polygon that the box cut (it had vertices outside the box).

    Notes
    -----
    Sutherland–Hodgman clipping by the six planes of the box, in a numba kernel run only on the
    polygons with vertices on both sides of a face. A disk cut by a face keeps the exact part of
    its polygon inside the box, so its area is that of the clipped polygon, within the
    polygon-to-disk factor 1 - (m/2π) sin(2π/m) of a whole one (:mod:`rockmass.dfn.network`).

    Examples
    --------
    >>> net = DiskNetwork([[0, 0, 0], [9, 9, 9]], [[0, 0, 1]] * 2, [1.0, 0.5], [0, 0], [0, 0, -1, 5, 5, 1])
    >>> xyz, offsets, disk, clipped = clip_disk_polygons(net, 4)
    >>> disk.tolist(), clipped.tolist(), xyz.round(12).tolist()       # disk 1 lies outside the box
    ([0], [True], [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0]])
    """
    _require_network(network)
    b = network.domain_m if box is None else as_box(box, "box")
    return _ragged_polygons(network, _vertex_counts(network, n_vertices), b)


def _ragged_polygons(network: DiskNetwork, per_disk: np.ndarray, b: np.ndarray | None) -> tuple:
    """:func:`clip_disk_polygons` of validated arguments; ``b`` None keeps every whole polygon."""
    counts = np.zeros(network.n_fractures, dtype=np.int64)
    clipped = np.zeros(network.n_fractures, dtype=bool)
    groups = []  # (rows, (k, width, 3) vertices) per vertex count of the whole polygons
    for m in np.unique(per_disk).tolist():
        rows = np.flatnonzero(per_disk == m)
        polygons = disk_polygons(network.subset(rows), m)
        if b is None:
            counts[rows] = m
            groups.append((rows, polygons))
            continue
        below, above = polygons < b[0], polygons > b[1]
        outside = (below.all(axis=1) | above.all(axis=1)).any(axis=1)   # every vertex beyond one face
        cut = ~outside & (below | above).any(axis=(1, 2))
        counts[rows] = np.where(outside, 0, m)
        clipped[rows] = cut
        if cut.any():
            from ._clip_kernels import clip_polygons  # numba: loaded only when a disk is cut

            width = m + 6
            padded = np.zeros((rows.size, width, 3))
            padded[:, :m] = polygons
            part = np.empty((int(cut.sum()), width, 3))
            n_part = np.empty(part.shape[0], dtype=np.int64)
            f64 = lambda a: np.ascontiguousarray(a, dtype=np.float64)  # noqa: E731 (one signature)
            clip_polygons(f64(polygons[cut]), f64(b[0]), f64(b[1]),
                          f64(_MERGE * network.radius_m[rows[cut]]), part, n_part)
            padded[cut] = part
            counts[rows[cut]] = n_part
            polygons = padded
        groups.append((rows, polygons))
    disk = np.flatnonzero(counts)
    offsets = np.concatenate([[0], np.cumsum(counts[disk])]).astype(np.int64)
    start = np.zeros(network.n_fractures, dtype=np.int64)
    start[disk] = offsets[:-1]
    xyz = np.empty((int(offsets[-1]), 3))
    for rows, polygons in groups:
        keep = np.arange(polygons.shape[1]) < counts[rows][:, None]           # (k, width)
        where = start[rows][:, None] + np.arange(polygons.shape[1])[None, :]
        xyz[where[keep]] = polygons[keep]
    return xyz, offsets, disk, clipped[disk]


def _polygon_blocks(offsets: np.ndarray) -> tuple[list, list]:
    """meshio ``polygon`` cell blocks of ragged polygons: one block per vertex count (increasing),
    and the polygons of each block (indices into the ragged list)."""
    sizes = np.diff(offsets)
    cells, members = [], []
    for c in np.unique(sizes).tolist():
        which = np.flatnonzero(sizes == c)
        cells.append(("polygon", offsets[which][:, None] + np.arange(c, dtype=np.int64)[None, :]))
        members.append(which)
    return cells, members


def write_fractures_vtu(network: DiskNetwork, path: str | os.PathLike, *, n_vertices: int | ArrayLike = 16,
                        clip: bool = True) -> dict:
    """Write the disks as polygons clipped to the domain, with dip, dip direction, radius, set and id
    (VTU via meshio; the cell data of the module docstring).

    Parameters
    ----------
    network : DiskNetwork
    path : str or path-like
        The ``.vtu`` file (written atomically).
    n_vertices : int or sequence of int, default 16
        Polygon vertices per disk, >= 3: one number for all, or one per set id (``n_vertices[set_id]``).
        Polygons with the same vertex count form one ``polygon`` cell block (blocks in increasing
        count); a clipped polygon has its own count (up to ``n_vertices`` + 6).
    clip : bool, default True
        Clip the polygons to ``network.domain_m`` (:func:`clip_disk_polygons`); False writes every
        whole polygon.

    Returns
    -------
    dict
        ``polygons`` (written), ``clipped`` (of those, cut by the domain) and ``outside`` (disks
        left out: their polygon lies outside the domain or only touches it).

    Examples
    --------
    >>> import pathlib, tempfile, meshio
    >>> net = DiskNetwork([[1, 2, 3], [0, 0, 0]], [[0, 0, 1]] * 2, [0.5, 1.0], [0, 1], [-5] * 3 + [5] * 3)
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "fractures.vtu"
    >>> write_fractures_vtu(net, f, n_vertices=8)
    {'polygons': 2, 'clipped': 0, 'outside': 0}
    >>> mesh = meshio.read(f)
    >>> mesh.cells[0].data.shape, mesh.cell_data["set"][0].tolist(), mesh.cell_data["dip_deg"][0].tolist()
    ((2, 8), [0, 1], [0.0, 0.0])
    """
    import meshio

    from .orientation import dip_from_normal

    _require_network(network)
    xyz, offsets, disk, clipped = _ragged_polygons(network, _vertex_counts(network, n_vertices),
                                                   network.domain_m if clip else None)
    dip, dip_direction = dip_from_normal(network.normal[disk].reshape(-1, 3))
    per_polygon = {"set": network.set_id[disk].astype(np.int64), "id": disk.astype(np.int64),
                   "dip_deg": np.asarray(dip, float), "dip_direction_deg": np.asarray(dip_direction, float),
                   "radius_m": network.radius_m[disk].astype(float), "clipped": clipped.astype(np.uint8)}
    cells, members = _polygon_blocks(offsets)
    mesh = meshio.Mesh(xyz, cells, cell_data={name: [per_polygon[name][idx] for idx in members]
                                              for name in FRACTURE_CELL_DATA})
    with atomic_path(path) as tmp:
        meshio.write(tmp, mesh, file_format="vtu")
    return {"polygons": int(disk.size), "clipped": int(clipped.sum()),
            "outside": int(network.n_fractures - disk.size)}


def write_section_traces_vtu(network: DiskNetwork, sections, path: str | os.PathLike) -> dict:
    """Write the traces of ``network`` on planar sections as VTU line cells in world coordinates.

    Parameters
    ----------
    network : DiskNetwork
    sections : sequence of (point, normal, window_uv_m)
        Each plane as :func:`rockmass.dfn.sample_plane` takes it: a point (origin of the plane's
        (u, v) frame, :func:`rockmass.dfn.plane_frame` of ``normal``), the plane normal and the
        window polygon in (u, v) metres.
    path : str or path-like
        The ``.vtu`` file (written atomically).

    Returns
    -------
    dict
        ``traces``: the number of traces per section.

    Notes
    -----
    Each straight piece of a trace (a non-convex window may split one) is a ``line`` cell with
    the cell data :data:`SECTION_CELL_DATA`: ``section`` (index in ``sections``), ``set``, ``id``
    (the disk's row in the network, as ``id`` in ``fractures.vtu``) and ``length_m`` (the whole
    trace's length inside the window, m). The traces are those the section statistics count: the
    whole disks cut by the plane, clipped to the window, not to the domain box.

    Examples
    --------
    >>> import pathlib, tempfile, meshio
    >>> net = DiskNetwork([[0, 0, 0]], [[1, 0, 0]], [2.0], [3], [-5, -5, -5, 5, 5, 5])
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "sections.vtu"
    >>> write_section_traces_vtu(net, [([0, 0, 0], [0, 0, 1], [(-5, -5), (5, -5), (5, 5), (-5, 5)])], f)
    {'traces': [1]}
    >>> mesh = meshio.read(f)
    >>> mesh.points[mesh.cells[0].data[0]].round(12).tolist(), mesh.cell_data["length_m"][0].tolist()
    ([[0.0, 2.0, 0.0], [0.0, -2.0, 0.0]], [4.0])
    """
    import meshio

    from .sampling import plane_frame, sample_plane

    _require_network(network)
    points, counts = [np.zeros((0, 3))], []
    data = {"section": [np.zeros(0, np.int64)], "set": [np.zeros(0, np.int64)], "id": [np.zeros(0, np.int64)],
            "length_m": [np.zeros(0)]}
    for k, (point, normal, window) in enumerate(sections):
        traces = sample_plane(network, point, normal, window)
        u, v, _ = plane_frame(normal)
        segments = traces.segments().reshape(-1, 2)                       # (2 s, 2): (u, v) per end
        points.append(np.asarray(point, float) + segments[:, :1] * u + segments[:, 1:] * v)
        owner = traces.segment_trace_index()
        data["section"].append(np.full(owner.size, k, dtype=np.int64))
        data["set"].append(np.asarray(traces.attributes["set"], np.int64)[owner])
        data["id"].append(np.asarray(traces.attributes["disk"], np.int64)[owner])
        data["length_m"].append(traces.lengths_m()[owner])
        counts.append(traces.n_traces)
    xyz = np.concatenate(points)
    lines = np.arange(xyz.shape[0], dtype=np.int64).reshape(-1, 2)
    mesh = meshio.Mesh(xyz, [("line", lines)], cell_data={name: [np.concatenate(data[name])]
                                                          for name in SECTION_CELL_DATA})
    with atomic_path(path) as tmp:
        meshio.write(tmp, mesh, file_format="vtu")
    return {"traces": counts}
