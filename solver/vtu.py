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
``excavated``       uint8        1 once removed by its excavation stage: a block of a region
                                 k >= 1, inactive and not ``failed`` (a block that failed before
                                 its region was excavated stays ``failed`` only)
==================  ===========  ===============================================================

With deformable blocks every zone is a cell whose points are its nodes at the frame's instant, and
the cells carry :data:`ZONE_CELL_DATA` too: ``stress_pa`` (float64 (4)), ``plastic_state``
(int64) and ``yielded`` (uint8).

:func:`contact_mesh` turns the active contact slots at the end of a run
(:meth:`rockmass.solver.Engine.contact_table`, ``Result.contacts``) into ``contacts.vtu``: one
vertex cell per slot at its contact point (z = 0), with the point data :data:`CONTACT_POINT_DATA`:

========================  ===========  ============================================================
name                      dtype        meaning
========================  ===========  ============================================================
``block_a``, ``block_b``  int64        the two blocks; the normal points from a to b
``normal``                float64 (3)  unit normal n from ``block_a`` to ``block_b`` (z = 0)
``length_m``              float64      contact length the slot stands for, m
``normal_stress_pa``      float64      σ_n, compression positive, Pa
``shear_stress_pa``       float64      τ, positive when b moves along t = (−n_y, n_x) relative to a
``force_b_n_per_m``       float64 (3)  force on ``block_b``, l (σ_n n − τ t), N per m of thickness
                                       (``block_a`` receives its opposite)
``plastic_slip_m``        float64      accumulated plastic shear displacement Σ|Δu_s^p|, m
``opening_m``             float64      gap between the (rounded) blocks, m: the slot's overlap with
                                       its sign flipped (negative: the blocks overlap)
``slipping``              uint8        1 when slipping at the last update
``broken``                uint8        1 for a bond that failed or a contact never bonded
========================  ===========  ============================================================

meshio is imported when a mesh is made or written, not with this module.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["frame_mesh", "contact_mesh", "pvd_text", "write_vtu", "FRAME_CELL_DATA", "ZONE_CELL_DATA",
           "CONTACT_POINT_DATA", "PVD_NUDGE_S"]

#: Names of the cell data of :func:`frame_mesh`, in order.
FRAME_CELL_DATA = ("displacement", "velocity", "rotation_rad", "block_id", "region", "active",
                   "failed", "excavated")
#: Cell data added when the model has deformable blocks (docs/dem.md §16): the zones' stress
#: (σ_xx, σ_yy, σ_zz, σ_xy, compression positive, Pa; zeros on rigid blocks), plastic state bits
#: (1 shear now, 2 tension now, 4 shear in the past, 8 tension in the past; -1 on rigid blocks)
#: and ``yielded`` (1 for a zone that ever yielded).
ZONE_CELL_DATA = ("stress_pa", "plastic_state", "yielded")
#: Names of the point data of :func:`contact_mesh`, in order (module docstring).
CONTACT_POINT_DATA = ("block_a", "block_b", "normal", "length_m", "normal_stress_pa", "shear_stress_pa",
                      "force_b_n_per_m", "plastic_slip_m", "opening_m", "slipping", "broken")

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
        "excavated": ((np.asarray(model.region) >= 1) & ~np.asarray(frame.active, bool)
                      & ~np.asarray(frame.failed, bool)).astype(np.uint8),
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


def contact_mesh(contacts):
    """The active contact slots as a meshio mesh of vertices (``contacts.vtu``).

    Parameters
    ----------
    contacts : dict of (n,) arrays
        :meth:`rockmass.solver.Engine.contact_table` (``Result.contacts``): ``block_a``,
        ``block_b``, ``x_m``, ``y_m``, ``nx``, ``ny``, ``length_m``, ``normal_stress_pa``,
        ``shear_stress_pa``, ``plastic_slip_m``, ``overlap_m``, ``slipping``, ``broken``. An empty
        dict (no contact) gives a mesh without points.

    Returns
    -------
    meshio.Mesh
        Points (n, 3) at the contact points, z = 0; one ``vertex`` cell per point; point data
        :data:`CONTACT_POINT_DATA` (see the module docstring).

    Examples
    --------
    >>> mesh = contact_mesh({"block_a": [0], "block_b": [1], "x_m": [2.0], "y_m": [1.0], "nx": [0.0],
    ...                      "ny": [1.0], "length_m": [0.5], "normal_stress_pa": [2e6],
    ...                      "shear_stress_pa": [1e6], "plastic_slip_m": [0.0], "overlap_m": [1e-4],
    ...                      "slipping": [False], "broken": [False]})
    >>> mesh.point_data["force_b_n_per_m"].tolist(), mesh.point_data["opening_m"].tolist()
    ([[500000.0, 1000000.0, 0.0]], [-0.0001])
    """
    import meshio

    def column(name, dtype=float):
        return np.asarray(contacts.get(name, ()), dtype=dtype).reshape(-1)

    x, y = column("x_m"), column("y_m")
    n = np.column_stack([column("nx"), column("ny"), np.zeros(x.size)])
    t = np.column_stack([-n[:, 1], n[:, 0], np.zeros(x.size)])
    length, sigma, tau = column("length_m"), column("normal_stress_pa"), column("shear_stress_pa")
    data = {"block_a": column("block_a", np.int64), "block_b": column("block_b", np.int64), "normal": n,
            "length_m": length, "normal_stress_pa": sigma, "shear_stress_pa": tau,
            "force_b_n_per_m": length[:, None] * (sigma[:, None] * n - tau[:, None] * t),
            "plastic_slip_m": column("plastic_slip_m"), "opening_m": -column("overlap_m"),
            "slipping": column("slipping", bool).astype(np.uint8), "broken": column("broken", bool).astype(np.uint8)}
    points = np.column_stack([x, y, np.zeros(x.size)])
    cells = [("vertex", np.arange(x.size, dtype=np.int64)[:, None])]
    return meshio.Mesh(points, cells, point_data={name: data[name] for name in CONTACT_POINT_DATA})


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
    """Write a mesh (:func:`frame_mesh`, :func:`contact_mesh`) to ``path`` as VTU, atomically.

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
