"""ParaView output of a run: the blocks of each frame as VTU, the frames as a PVD time series.

A frame (:class:`rockmass.solver.Frame`) places every block of the model: its centroid at
``position_m`` and its rotation ``rotation_rad`` about it. :func:`frame_mesh` turns one frame into a
meshio mesh of polygons (the cells of the model, :func:`rockmass.blockgen.polygon_cells`, the same
layout as blockgen's ``blocks.vtu``) with per-block cell data; :func:`write_vtu` writes such a mesh
atomically; :func:`pvd_text` lists the frame files with their times for ParaView.

Cell data of a frame mesh (one value per block):

==================  ===========  ===============================================================
name                dtype        meaning
==================  ===========  ===============================================================
``displacement``    float64 (3)  centroid displacement from the model's position, m (z = 0)
``velocity``        float64 (3)  centroid velocity, m/s (z = 0)
``rotation_rad``    float64      rotation about the centroid since the start, rad
``block_id``        int64        index of the block in the model
``region``          int64        0 rock, k >= 1 excavation stage k
``active``          uint8        1 while the block takes part in the run
``failed``          uint8        1 once taken out because it kept moving (inactive too)
==================  ===========  ===============================================================

meshio is imported when a mesh is made or written, not with this module.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["frame_mesh", "pvd_text", "write_vtu", "FRAME_CELL_DATA", "PVD_NUDGE_S"]

#: Names of the cell data of :func:`frame_mesh`, in order.
FRAME_CELL_DATA = ("displacement", "velocity", "rotation_rad", "block_id", "region", "active",
                   "failed")

#: Relative time added to a frame whose time is not after the previous one (the end of one stage and
#: the start of the next, after its excavation, share an instant), so that ParaView shows both.
PVD_NUDGE_S = 1e-9


def frame_mesh(model, frame):
    """The blocks of ``model`` placed as ``frame`` places them, as a meshio mesh.

    Parameters
    ----------
    model : rockmass.blockgen.BlockModel
        The model the run started from (vertices, centroids, regions).
    frame : rockmass.solver.Frame
        ``position_m`` (n_blocks, 2) centroids in m, ``rotation_rad`` (n_blocks,),
        ``velocity_m_s`` (n_blocks, 2), ``active`` and ``failed`` (n_blocks,) bool.

    Returns
    -------
    meshio.Mesh
        Points (n_vertices, 3) with z = 0; one cell block per polygon vertex count; cell data
        :data:`FRAME_CELL_DATA` (see the module docstring).

    Notes
    -----
    Vertex v of block i moves rigidly: x = c_i + R(θ_i) (x⁰ − c⁰_i), with c⁰_i the model's centroid,
    c_i the frame's position and R(θ) the rotation by θ counter-clockwise.
    """
    import meshio

    from ..blockgen import polygon_cells

    sizes = np.diff(np.asarray(model.offsets))
    bov = np.repeat(np.arange(model.n_blocks), sizes)  # block of each vertex
    loc = model.xy_m - model.centroid_xy_m[bov]
    c, s = np.cos(frame.rotation_rad)[bov], np.sin(frame.rotation_rad)[bov]
    pos = frame.position_m[bov]
    xy = np.column_stack([pos[:, 0] + c * loc[:, 0] - s * loc[:, 1],
                          pos[:, 1] + s * loc[:, 0] + c * loc[:, 1]])
    points = np.column_stack([xy, np.zeros(len(xy))])
    per_block = {
        "displacement": np.column_stack([frame.position_m - model.centroid_xy_m,
                                         np.zeros(model.n_blocks)]),
        "velocity": np.column_stack([frame.velocity_m_s, np.zeros(model.n_blocks)]),
        "rotation_rad": np.asarray(frame.rotation_rad, float),
        "block_id": np.arange(model.n_blocks, dtype=np.int64),
        "region": np.asarray(model.region, np.int64),
        "active": np.asarray(frame.active, np.uint8),
        "failed": np.asarray(frame.failed, np.uint8),
    }
    cells, groups = polygon_cells(model.offsets)
    data = {name: [per_block[name][idx] for idx in groups] for name in FRAME_CELL_DATA}
    return meshio.Mesh(points, cells, cell_data=data)


def pvd_text(entries) -> str:
    """A ParaView collection (``.pvd``) of ``(time_s, file_name)`` entries, in the order given.

    Parameters
    ----------
    entries : iterable of (float, str)
        Frame time in s and the frame's file name (relative to the ``.pvd``).

    Returns
    -------
    str
        The XML text. Times are strictly increasing: a time not after the previous one is shown
        :data:`PVD_NUDGE_S` x max(1, |previous|) after it (the exact times belong in the run's
        own record).

    Examples
    --------
    >>> print(pvd_text([(0.0, "a.vtu"), (0.0, "b.vtu")]), end="")
    <?xml version="1.0"?>
    <VTKFile type="Collection" version="0.1" byte_order="LittleEndian">
      <Collection>
        <DataSet timestep="0.0" group="" part="0" file="a.vtu"/>
        <DataSet timestep="1e-09" group="" part="0" file="b.vtu"/>
      </Collection>
    </VTKFile>
    """
    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
             "  <Collection>"]
    last = None
    for t, name in entries:
        shown = t if last is None or t > last else last + PVD_NUDGE_S * max(1.0, abs(last))
        lines.append(f'    <DataSet timestep="{shown!r}" group="" part="0" file="{name}"/>')
        last = shown
    lines += ["  </Collection>", "</VTKFile>", ""]
    return "\n".join(lines)


def write_vtu(mesh, path) -> Path:
    """Write a mesh (:func:`frame_mesh`) to ``path`` as VTU, atomically.

    Parameters
    ----------
    mesh : meshio.Mesh
    path : str or path-like
        Destination file; its folder must exist (:func:`rockmass.dfn.atomic.atomic_path`).

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    import meshio

    from ..dfn.atomic import atomic_path

    with atomic_path(path) as tmp:
        meshio.write(tmp, mesh, file_format="vtu")
    return Path(path)
