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

With deformable blocks every zone is a cell whose points are its nodes at the frame's instant, and
the cells carry :data:`ZONE_CELL_DATA` too: ``stress_pa`` (float64 (4)), ``plastic_state``
(int64) and ``yielded`` (uint8).

meshio is imported when a mesh is made or written, not with this module.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["frame_mesh", "pvd_text", "write_vtu", "FRAME_CELL_DATA", "ZONE_CELL_DATA",
           "PVD_NUDGE_S"]

#: Names of the cell data of :func:`frame_mesh`, in order.
FRAME_CELL_DATA = ("displacement", "velocity", "rotation_rad", "block_id", "region", "active",
                   "failed")
#: Cell data added when the model has deformable blocks (docs/dem.md §16): the zones' stress
#: (σ_xx, σ_yy, σ_zz, σ_xy, compression positive, Pa; zeros on rigid blocks), plastic state bits
#: (1 shear now, 2 tension now, 4 shear in the past, 8 tension in the past; -1 on rigid blocks)
#: and ``yielded`` (1 for a zone that ever yielded).
ZONE_CELL_DATA = ("stress_pa", "plastic_state", "yielded")

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
    names = FRAME_CELL_DATA
    if frame.zones is not None:  # deformable blocks: zones drawn on their nodes, with stress
        names = FRAME_CELL_DATA + ZONE_CELL_DATA
        _zone_cells(model, frame, points, per_block)
    cells, groups = polygon_cells(model.offsets)
    data = {name: [per_block[name][idx] for idx in groups] for name in names}
    return meshio.Mesh(points, cells, cell_data=data)


def _zone_cells(model, frame, points, per_block) -> None:
    """Place the zones' vertices on their nodes (each zone is a block of ``model``, its vertices
    its nodes in order) and add the zones' cell data (zeros and -1 on rigid blocks)."""
    z = frame.zones
    tri, block = z["triangles"], z["zone_block"]
    starts = np.asarray(model.offsets)[block]
    for q in range(3):
        points[starts + q, :2] = z["nodes_m"][tri[:, q]]
    stress = np.zeros((model.n_blocks, 4))
    stress[block] = z["stress_pa"]
    state = np.full(model.n_blocks, -1, np.int64)
    state[block] = z["plastic_state"]
    per_block["stress_pa"] = stress
    per_block["plastic_state"] = state
    per_block["yielded"] = np.where(state > 0, (state & 12) != 0, False).astype(np.uint8)


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
