"""Build a :class:`~rockmass.blockgen.BlockModel`: cut a domain by joint sets or traces, mark the
excavation stages, merge slivers, make every block convex, and find the contacts.

Steps (each change is listed in ``model.quality``, a
:class:`~rockmass.blockgen.quality.BlockQuality`; nothing is moved silently):

1. **Sources.** The domain outline, each excavation outline, the joints of every set (clipped to the
   domain) and the traces (clipped to the domain).
2. **Noding** (GEOS ``unary_union``) into 2-point segments; each keeps the label of the source it lies
   on (:mod:`rockmass.blockgen.network`).
3. **Dangling ends** (joints or traces ending in intact rock), by ``dangling``: ``"glued"`` (default)
   extends each along its own direction to the first line it meets, as a glued contact (a
   potential crack with intact-rock strength); ``"joint"`` extends it the same way as an ordinary
   joint of its set or trace; ``"drop"`` removes the dangling parts.
4. **Polygonisation** into faces; a face belongs to the first excavation stage whose outline
   contains it (region k), else to the rock mass (region 0).
5. **Slivers.** A block whose mean width 2·area/perimeter is below ``sliver_width_m`` (= the minimum
   edge 2d) is merged with the neighbour of the same region across their shared edges: the
   neighbour whose union with it is convex, else the one sharing the longest boundary. The removed
   edges and both blocks are reported.
6. **Convex decomposition** of concave blocks by bisector cuts (:mod:`rockmass.blockgen.convex`),
   the cuts becoming glued contacts (source ``-2``); reported per block.
7. **Potential cracks** (optional, ``cracks``): the chosen convex rock blocks are subdivided into
   convex sub-blocks (Voronoi or triangular, :mod:`rockmass.blockgen.cracks`) whose internal edges
   are glued contacts with source ``-3`` (:data:`~rockmass.blockgen.model.SOURCE_CRACK`); counts
   in ``quality.cracks``.
8. **Short edges** (``snap_edges``): a block edge shorter than the minimum edge ``2d`` collapses
   onto one node in all the blocks that use it, if they stay convex and every region keeps its area
   (:mod:`rockmass.blockgen.snapping`); each collapse is listed in ``quality.edges_snapped``.
9. **Contacts**: block edges matched by coordinates; consecutive edges of one pair and label are
   summed into one contact.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import shapely

from .convex import convex_cuts, is_reflex, reflex_vertices
from .cracks import Cracks, crack_segments, select_parents
from .excavations import Excavation, _as_ring
from .joints import JointSet, joint_set_segments, seed_sequence
from .model import (CONTACT_KINDS, KIND_DOMAIN, KIND_EXCAVATION, KIND_GLUED, KIND_JOINT, KIND_TRACE,
                    SOURCE_CONVEX_CUT, SOURCE_CRACK, BlockModel)
from .network import (LabelPriority, Sources, collapse_short, dangling_extensions, exterior_coords,
                      label_priority, label_segments, node, polygonize_segments, ring_segments,
                      segment_keys, snap_to_grid, unique_rows)
from .quality import BlockQuality
from .snapping import snap_short_edges
from .tolerances import CRACK_EDGE_FRACTION, model_tolerances

__all__ = ["build", "DANGLING_CHOICES"]

DANGLING_CHOICES = ("glued", "joint", "drop")


def _trace_segments(traces):
    """(n, 2, 2) segments and their trace index from a TraceMap or an (n, 2, 2) array."""
    if hasattr(traces, "segments") and hasattr(traces, "segment_trace_index"):
        segs = np.asarray(traces.segments(), float).reshape(-1, 2, 2)
        idx = np.asarray(traces.segment_trace_index(), np.int64)
    else:
        try:
            segs = np.array(traces, dtype=float)
        except (TypeError, ValueError) as exc:
            raise ValueError("traces must be a TraceMap or an (n, 2, 2) array of segments") from exc
        if segs.ndim != 3 or segs.shape[1:] != (2, 2):
            raise ValueError(f"traces must have shape (n, 2, 2), got {segs.shape}")
        idx = np.arange(len(segs))
    bad = ~np.isfinite(segs).all(axis=(1, 2))
    if bad.any():
        raise ValueError(f"traces: {int(bad.sum())} segments have NaN or infinite coordinates "
                         f"(trace indices {sorted(set(idx[bad].tolist()))[:10]})")
    zero = np.all(segs[:, 0] == segs[:, 1], axis=1)
    return segs[~zero], idx[~zero]


def _clip_segments(segs: np.ndarray, source: np.ndarray, domain):
    """Clip segments to the domain polygon; returns (m, 2, 2) pieces and their source index."""
    if not len(segs):
        return np.empty((0, 2, 2)), np.empty(0, np.int64)
    clipped = shapely.intersection(shapely.linestrings(segs), domain)
    parts, part_of = shapely.get_parts(clipped, return_index=True)
    lines = shapely.get_type_id(parts) == 1
    parts, part_of = parts[lines], part_of[lines]
    coords, index = shapely.get_coordinates(parts, return_index=True)
    same = index[1:] == index[:-1]
    out = np.stack([coords[:-1][same], coords[1:][same]], axis=1)
    src = source[part_of[index[:-1][same]]]
    keep = np.any(out[:, 0] != out[:, 1], axis=1)
    return out[keep], src[keep]


def _ring_edges(faces):
    """Edges of polygons shells and holes (exact: ring by ring)."""
    coords, index = exterior_coords(faces)
    n_int = shapely.get_num_interior_rings(faces)
    ring_face = [np.arange(len(faces))]
    if n_int.sum():
        all_coords, all_index = [coords], [index]
        for k in range(int(n_int.max())):
            has = np.flatnonzero(n_int > k)
            c, i = shapely.get_coordinates(shapely.get_interior_ring(faces[has], k),
                                           return_index=True)
            all_coords.append(c)
            all_index.append(i + sum(len(f) for f in ring_face))
            ring_face.append(has)
        coords, index = np.concatenate(all_coords), np.concatenate(all_index)
    ring_face = np.concatenate(ring_face)
    same = index[1:] == index[:-1]
    seg = np.stack([coords[:-1][same], coords[1:][same]], axis=1)
    return seg, ring_face[index[:-1][same]]


def _pairs(faces, grid_m):
    """Matched edges: (segments, face_a, face_b) with face_b = -1 for unmatched edges."""
    seg, face = _ring_edges(faces)
    keys = segment_keys(seg, grid_m)
    _, inv, counts = unique_rows(keys)
    inv = inv.ravel()
    order = np.argsort(inv, kind="stable")
    first = np.ones(len(order), bool)
    first[1:] = inv[order][1:] != inv[order][:-1]
    a_idx = order[first]
    uniq = inv[a_idx]
    face_a = face[a_idx]
    face_b = np.full(len(a_idx), -1, np.int64)
    second = order[~first]
    face_b[np.searchsorted(uniq, inv[second])] = face[second]
    if (counts > 2).any():
        raise RuntimeError(f"{int((counts > 2).sum())} block edges are shared by more than two blocks "
                           "(overlapping blocks): a noding failure")
    return seg[a_idx], face_a, face_b


def _is_convex(poly, reflex_sin, reflex_m):
    if len(poly.interiors):
        return False
    xy = np.asarray(poly.exterior.coords)[:-1]
    return len(reflex_vertices(xy, reflex_sin, reflex_m)) == 0


def _concave_mask(faces, reflex_sin, reflex_m):
    """Faces that have a hole or a reflex vertex (vectorised over all faces; the rule of
    :func:`rockmass.blockgen.convex.reflex_vertices`)."""
    coords, index = exterior_coords(faces)
    counts = np.bincount(index, minlength=len(faces))
    start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    last = start + counts - 1  # closing point (equal to the first)
    keep = np.ones(len(coords), bool)
    keep[last] = False
    xy, face = coords[keep], index[keep]
    k = counts - 1
    first = np.concatenate([[0], np.cumsum(k)[:-1]])
    pos = np.arange(len(xy)) - first[face]
    prev = first[face] + (pos - 1) % k[face]
    nxt = first[face] + (pos + 1) % k[face]
    reflex_at = is_reflex(xy - xy[prev], xy[nxt] - xy, reflex_sin, reflex_m)
    reflex = np.bincount(face, reflex_at, len(faces)) > 0
    return reflex | (shapely.get_num_interior_rings(faces) > 0)


def _regions(faces, excavations):
    region = np.zeros(len(faces), np.int64)
    pts = shapely.point_on_surface(faces)
    for k, exc in reversed(list(enumerate(excavations, start=1))):
        region[shapely.contains(exc.polygon(), pts)] = k  # earlier stages win on overlap
    return region


def build(domain_xy_m, joint_sets=(), traces=None, excavations=(), *, dangling="glued", seed=0,
          rounding_m=None, min_edge_m=None, merge_slivers=True, convex=True,
          cracks: Cracks | None = None, snap_edges: bool = True) -> BlockModel:
    """Cut a 2D domain into blocks.

    Parameters
    ----------
    domain_xy_m : (k, 2) array_like of float
        Domain outline in metres (a simple polygon, either orientation).
    joint_sets : sequence of JointSet, optional
        UDEC-style joint sets (:class:`rockmass.blockgen.JointSet`).
    traces : TraceMap or (n, 2, 2) array_like, optional
        Traces (a DFN section, an extracted face, a digitised map), clipped to the domain.
    excavations : sequence of Excavation, optional
        Stages in removal order; each must lie inside the domain.
    dangling : {"glued", "joint", "drop"}, default "glued"
        What to do with joint or trace ends inside intact rock (see the module docstring).
    seed : int or numpy.random.SeedSequence, default 0
        Root seed; joint set i draws from child i of ``SeedSequence(seed)``.
    rounding_m, min_edge_m : float, optional
        The solver's corner rounding d (default 1 % of the median edge) and minimum edge (default 2d).
    merge_slivers, convex : bool, default True
        Run steps 5 and 6 of the module docstring.
    cracks : Cracks, optional
        Subdivide intact blocks by potential cracks (step 7); needs ``convex=True``. The cracks
        draw from child ``len(joint_sets)`` of ``SeedSequence(seed)``.
    snap_edges : bool, default True
        Collapse block edges shorter than ``min_edge_m`` (step 8, :mod:`rockmass.blockgen.snapping`).

    Returns
    -------
    BlockModel

    Raises
    ------
    ValueError
        Naming the field: a degenerate domain, an excavation outside the domain, a set or trace map
        that puts no joint in the domain, NaN traces, a bad ``dangling`` choice, a minimum edge
        larger than the blocks.

    Examples
    --------
    >>> m = build([(0, 0), (1, 0), (1, 1), (0, 1)],
    ...           [JointSet(0, 0.25, origin_xy_m=(0, 0)), JointSet(90, 0.25, origin_xy_m=(0, 0))])
    >>> m.n_blocks, float(m.area_m2.min())
    (16, 0.0625)
    """
    domain_xy = _as_ring(domain_xy_m, "domain_xy_m")
    domain = shapely.Polygon(domain_xy)
    if dangling not in DANGLING_CHOICES:
        raise ValueError(f"dangling must be one of {DANGLING_CHOICES}, got {dangling!r}")
    joint_sets = list(joint_sets)
    for i, js in enumerate(joint_sets):
        if not isinstance(js, JointSet):
            raise TypeError(f"joint_sets[{i}] must be a JointSet, got {type(js).__name__}")
    excavations = list(excavations)
    for i, exc in enumerate(excavations):
        if not isinstance(exc, Excavation):
            raise TypeError(f"excavations[{i}] must be an Excavation, got {type(exc).__name__}")
        if not domain.covers(exc.polygon()):
            outside = exc.polygon().difference(domain).area / exc.polygon().area
            raise ValueError(f"excavations[{i}] ({exc.name!r}) lies {'partly' if domain.intersects(exc.polygon()) else 'wholly'} "
                             f"outside the domain ({outside:.1%} of its area)")
    for name, value in (("rounding_m", rounding_m), ("min_edge_m", min_edge_m)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be > 0 and finite, got {value!r}")
    minx, miny, maxx, maxy = domain.bounds
    size = float(math.hypot(maxx - minx, maxy - miny))
    tol0 = model_tolerances(size, size)
    snap_m, label_m, grid = tol0.snap_m, tol0.label_m, tol0.grid_m
    sources = Sources(piece_m=size / 64)
    sources.add(ring_segments(domain_xy), KIND_DOMAIN, -1)
    all_segs = [ring_segments(domain_xy)]
    for k, exc in enumerate(excavations, start=1):
        sources.add(ring_segments(exc.xy_m), KIND_EXCAVATION, k)
        all_segs.append(ring_segments(exc.xy_m))
    root = seed_sequence(seed)
    joint_parts, set_names = [], []
    for i, (js, raw) in enumerate(zip(joint_sets, joint_set_segments(joint_sets, domain_xy, root))):
        segs, _ = _clip_segments(snap_to_grid(raw, grid), np.zeros(len(raw), np.int64), domain)
        if not len(segs):
            raise ValueError(f"joint_sets[{i}]: the set produces no joints in the domain "
                             f"(spacing_m {js.spacing_m:g}, angle_deg {js.angle_deg:g})")
        sources.add(segs, KIND_JOINT, i)
        all_segs.append(segs)
        joint_parts.append((KIND_JOINT, np.full(len(segs), i), segs))
        set_names.append(js.name or f"set {i}")
    n_traces_in = 0
    if traces is not None:
        tsegs, tidx = _trace_segments(traces)
        segs, src = _clip_segments(snap_to_grid(tsegs, grid), tidx, domain)
        if not len(segs):
            raise ValueError("traces: no trace crosses the domain")
        n_traces_in = int(len(np.unique(src)))
        sources.add(segs, KIND_TRACE, src)
        all_segs.append(segs)
    if not joint_sets and traces is None and not excavations and cracks is None:
        raise ValueError("joint_sets, traces or excavations: nothing cuts the domain")
    if cracks is not None:
        if not isinstance(cracks, Cracks):
            raise TypeError(f"cracks must be a Cracks, got {type(cracks).__name__}")
        if not convex:
            raise ValueError("cracks: the potential-crack subdivision needs convex=True (it cuts "
                             "convex blocks into convex pieces)")
        if cracks.within_m is not None and not excavations:
            raise ValueError("cracks.within_m: the model has no excavations to measure from")

    report = {"dangling": {"rule": dangling}, "slivers_merged": [], "convex_splits": [],
              "snapped_cuts": 0,
              "convex_failures": 0}
    report["nodes_merged"] = {"rule": "nodes joined by an edge shorter than snap_m are one node",
                              "count": 0}

    def collapse(segments):
        out, n = collapse_short(segments, snap_m, grid)
        report["nodes_merged"]["count"] += n
        return out

    def renode(segments, chain=False):
        return collapse(node(segments, grid, chain))

    noded = renode(snap_to_grid(np.concatenate(all_segs), grid))
    # 3. dangling ends
    ext, parent, n_dangling = dangling_extensions(noded, grid, 2 * size)
    report["dangling"]["n_dangling_ends"] = int(n_dangling)
    if n_dangling and dangling != "drop":
        # an extension takes the label of the segment it continues (only those are labelled here:
        # the whole network is labelled once its blocks are final)
        kind, src = label_segments(noded[parent], sources, label_m)
        ext_kind = np.full(len(ext), KIND_GLUED) if dangling == "glued" else kind
        for k in np.unique(ext_kind):
            sel = ext_kind == k
            sources.add(ext[sel], int(k), src[sel], priority=LabelPriority.EXTENSION)
        report["dangling"]["n_extended"] = int(len(ext))
        report["dangling"]["extended_length_m"] = float(np.hypot(*(ext[:, 1] - ext[:, 0]).T).sum())
        noded = renode(np.concatenate([noded, ext]), chain=True)  # a noded network: chains pay
    faces = polygonize_segments(noded)
    if dangling == "drop" and n_dangling:
        kept = _ring_edges(faces)[0]
        report["dangling"]["dropped_length_m"] = float(
            np.hypot(*(noded[:, 1] - noded[:, 0]).T).sum()
            - 0.5 * np.hypot(*(kept[:, 1] - kept[:, 0]).T).sum()
            - 0.5 * shapely.length(shapely.boundary(shapely.union_all(faces))))
    region = _regions(faces, excavations)

    # tolerances from the cut blocks
    edges = _ring_edges(faces)[0]
    typical = float(np.median(np.hypot(*(edges[:, 1] - edges[:, 0]).T)))
    if cracks is not None:  # the solver's blocks will be the sub-blocks
        typical = min(typical, CRACK_EDGE_FRACTION * cracks.size_m)
    tol = model_tolerances(size, typical, rounding_m, min_edge_m)
    width = 2 * shapely.area(faces) / shapely.length(faces)
    if tol.min_edge_m > np.median(width):
        raise ValueError(f"min_edge_m ({tol.min_edge_m:g} m) is larger than the blocks (median block "
                         f"width 2·area/perimeter = {np.median(width):g} m); lower min_edge_m or "
                         "rounding_m")

    # 5. slivers
    if merge_slivers:
        noded, faces, region = _merge_slivers(noded, faces, region, tol, report, excavations)
    # 6. convex decomposition
    def make_convex(noded, faces, region):
        # a cut of one face can end on a vertex shared with a neighbour and leave that neighbour
        # with a new reflex vertex: repeat until every face is convex (reported rounds)
        concave = np.flatnonzero(_concave_mask(faces, tol.reflex_sin, tol.reflex_m))
        rounds = 0
        while len(concave) and rounds < 8:
            rounds += 1
            noded, faces, region = _make_convex(noded, faces, region, concave, tol, report,
                                                sources, excavations, collapse)
            concave = np.flatnonzero(_concave_mask(faces, tol.reflex_sin, tol.reflex_m))
        report["convex_rounds"] = report.get("convex_rounds", 0) + rounds
        report["concave_blocks_left"] = len(concave)
        return noded, faces, region

    if convex:
        noded, faces, region = make_convex(noded, faces, region)
    # 7. potential cracks
    if cracks is not None:
        crack_seq = np.random.SeedSequence(root.entropy, spawn_key=(*root.spawn_key, len(joint_sets)))
        noded, faces, region = _add_cracks(noded, faces, region, cracks, crack_seq, tol, report,
                                           sources, excavations, collapse)
        noded, faces, region = make_convex(noded, faces, region)
    # 8. edges shorter than the minimum edge
    if snap_edges:
        kind, src = label_segments(noded, sources, label_m)
        noded, kind, src, faces, region, moved, changes, left = snap_short_edges(
            noded, kind, src, faces, region, tol.min_edge_m, tol.grid_m, tol.reflex_sin,
            tol.reflex_m)
        moved_segs = noded[moved]
        for (k, s_), idx in _groups(kind[moved], src[moved]):
            sources.add(moved_segs[idx], k, s_, priority=label_priority(k, s_))
        report["edges_snapped"] = {
            "rule": "block edges shorter than min_edge_m collapse onto one node in every block "
                    "that uses it, when all those blocks stay convex and the area of each region "
                    "is unchanged; domain and excavation outlines only slide along themselves "
                    "(rockmass.blockgen.snapping)",
            "count": len(changes), "not_snapped": int(left), "changes": changes}
        if convex and changes:
            noded, faces, region = make_convex(noded, faces, region)
    kind, src = label_segments(noded, sources, label_m)
    model = _assemble(faces, region, noded, kind, src, tol, report, domain_xy, excavations,
                      set_names, domain, n_traces_in)
    if cracks is not None:
        model = _with_crack_summary(model)
    return model


def _groups(kind, src):
    """((kind, source), indices) for each distinct label."""
    table = np.column_stack([kind, src])
    if not len(table):
        return []
    labels, inv, counts = unique_rows(table)
    members = np.split(np.argsort(inv.ravel(), kind="stable"), np.cumsum(counts)[:-1])
    return [((int(k), int(s)), idx) for (k, s), idx in zip(labels.tolist(), members)]


def _add_cracks(noded, faces, region, cracks, seq, tol, report, sources, excavations, collapse):
    parents = select_parents(faces, region, cracks, excavations)
    segs, stats = crack_segments(faces, parents, cracks, np.random.default_rng(seq),
                                 tol.sliver_width_m, tol.min_edge_m, 16 * tol.snap_m)
    report["cracks"] = {
        "rule": "convex sub-blocks of the selected intact blocks; internal edges are glued contacts "
                "with contact_source -3 (potential cracks, intact-rock strength)",
        "pattern": cracks.pattern, "size_m": float(cracks.size_m),
        "target_area_m2": float(cracks.size_m) ** 2, **stats}
    if not len(segs):
        return noded, faces, region
    segs = snap_to_grid(segs, tol.grid_m)
    segs = segs[np.any(segs[:, 0] != segs[:, 1], axis=1)]
    sources.add(segs, KIND_GLUED, SOURCE_CRACK, priority=LabelPriority.CRACK)
    return _insert_segments(noded, faces, region, parents, segs, tol, excavations, collapse)


def _insert_segments(noded, faces, region, changed, segs, tol, excavations, collapse):
    """Re-node only the boundaries of the faces ``changed`` with the new segments ``segs`` (cuts
    or cracks inside them) and rebuild those faces: (noded, faces, region)."""
    bseg = _ring_edges(faces[changed])[0]
    touched = _rows_in(segment_keys(noded, tol.grid_m), segment_keys(bseg, tol.grid_m))
    renoded = node(np.concatenate([noded[touched], segs]), tol.grid_m)
    noded = collapse(np.concatenate([noded[~touched], renoded]))
    faces, region = _local_faces(noded, faces, region, changed, excavations, tol.grid_m)
    return noded, faces, region


def _with_crack_summary(model):
    """The model with the counts of its cracks added to ``quality.cracks``: crack contacts, their
    total length, and the area of the blocks bounded by at least one crack (against the target
    ``size_m²``)."""
    is_crack = (model.contact_kind == KIND_GLUED) & (model.contact_source == SOURCE_CRACK)
    blocks = np.unique(model.contact_blocks[is_crack].ravel())
    blocks = blocks[blocks >= 0]
    area = model.area_m2[blocks]
    summary = dict(model.quality.cracks)
    summary["n_crack_contacts"] = int(is_crack.sum())
    summary["crack_length_m"] = float(model.contact_length_m[is_crack].sum())
    summary["n_crack_blocks"] = int(len(blocks))
    if len(blocks):
        summary["crack_block_area_m2"] = {"mean": float(area.mean()), "median": float(np.median(area)),
                                          "min": float(area.min()), "max": float(area.max())}
    return dataclasses.replace(model, quality=dataclasses.replace(model.quality, cracks=summary))


def _merge_slivers(noded, faces, region, tol, report, excavations):
    width = 2 * shapely.area(faces) / shapely.length(faces)
    slivers = np.flatnonzero(width < tol.sliver_width_m)
    if not len(slivers):
        return noded, faces, region
    seg, fa, fb = _pairs(faces, tol.grid_m)
    length = np.hypot(*(seg[:, 1] - seg[:, 0]).T)
    used = np.zeros(len(faces), bool)
    remove = []
    for s in slivers:
        if used[s]:
            continue
        shared = {}
        for sel, other in ((fa == s, fb), (fb == s, fa)):
            for e in np.flatnonzero(sel):
                o = int(other[e])
                if o >= 0 and region[o] == region[s] and not used[o]:
                    shared.setdefault(o, []).append(e)
        if not shared:
            report["slivers_merged"].append({"centroid_xy_m": list(shapely.get_coordinates(
                faces[s].centroid)[0]), "area_m2": float(faces[s].area), "width_m": float(width[s]),
                "merged_into": None, "reason": "no neighbour in the same region: kept"})
            continue
        def score(o):
            union = shapely.union(faces[s], faces[o])
            convex_union = union.geom_type == "Polygon" and _is_convex(union, tol.reflex_sin, tol.reflex_m)
            return (convex_union, sum(length[e] for e in shared[o]))
        best = max(shared, key=score)
        conv, shared_len = score(best)
        used[s] = used[best] = True
        remove.extend(shared[best])
        report["slivers_merged"].append({
            "centroid_xy_m": [float(v) for v in shapely.get_coordinates(faces[s].centroid)[0]],
            "area_m2": float(faces[s].area), "width_m": float(width[s]),
            "merged_into_centroid_xy_m": [float(v) for v in
                                          shapely.get_coordinates(faces[best].centroid)[0]],
            "removed_edge_length_m": float(shared_len), "union_convex": bool(conv)})
    if not remove:
        return noded, faces, region
    drop = segment_keys(seg[remove], tol.grid_m)
    keys = segment_keys(noded, tol.grid_m)
    gone = _rows_in(keys, drop)
    noded = noded[~gone]
    faces, region = _local_faces(noded, faces, region, np.flatnonzero(used), excavations, tol.grid_m)
    return noded, faces, region


def _local_faces(noded, faces, region, changed, excavations, grid_m):
    """Faces of the network ``noded`` after a local change (a local rebuild, not a full
    polygonisation).

    A face is *kept* when every one of its edges is still a segment of the network and it is not in
    ``changed`` (faces known to hold new segments: cuts, cracks). The others are rebuilt by
    polygonising the segments that do not lie between two kept faces (or a kept face and the domain
    boundary); a rebuilt face that holds a kept face (the kept face again, when all its edges
    bordered rebuilt faces, or the outline around a group of kept faces) is dropped.
    Kept faces keep their region; rebuilt ones get theirs from the excavation outlines.
    """
    seg, fa, fb = _pairs(faces, grid_m)
    ekeys = segment_keys(seg, grid_m)
    nkeys = segment_keys(noded, grid_m)
    both = np.concatenate([ekeys, nkeys])
    _, inv, _ = unique_rows(both)
    inv = inv.ravel()
    e_inv, n_inv = inv[:len(ekeys)], inv[len(ekeys):]
    present = np.isin(e_inv, n_inv)
    kept = np.ones(len(faces), bool)
    kept[np.asarray(changed, np.int64)] = False
    kept[fa[~present]] = False
    kept[fb[~present & (fb >= 0)]] = False
    if kept.all():
        return faces, region
    # network segments between two kept faces (or a kept face and the outside) stay out
    inside = present & kept[fa] & np.where(fb >= 0, kept[np.maximum(fb, 0)], True)
    lookup = np.zeros(inv.max() + 1, bool)
    lookup[e_inv[inside]] = True
    local = noded[~lookup[n_inv]]
    new = polygonize_segments(local)
    if len(new):
        # a rebuilt face that holds a kept face (the kept face itself, or the outline of a group of
        # kept faces whose inner edges stayed out) is not a block
        kept_faces = faces[kept]
        i, j = shapely.STRtree(kept_faces).query(new)
        holds = shapely.contains_properly(new[i], shapely.point_on_surface(kept_faces[j]))
        new = np.delete(new, np.unique(i[holds]))
    return (np.concatenate([faces[kept], new]),
            np.concatenate([region[kept], _regions(new, excavations)]))


def _rows_in(a, b):
    """Mask of rows of int array ``a`` that occur in ``b``."""
    both = np.concatenate([a, b])
    _, inv, _ = unique_rows(both)
    inv = inv.ravel()
    return np.isin(inv[:len(a)], inv[len(a):])


def _make_convex(noded, faces, region, concave, tol, report, sources, excavations, collapse):
    """Cut the faces ``concave`` (indices, :func:`_concave_mask`) into convex pieces."""
    cuts = []
    for i in concave.tolist():
        c, n_snapped, n_failed = convex_cuts(faces[i], tol.reflex_sin, tol.min_edge_m,
                                             16 * tol.snap_m, reflex_m=tol.reflex_m)
        report["snapped_cuts"] += int(n_snapped)
        report["convex_failures"] += int(n_failed)
        report["convex_splits"].append({
            "centroid_xy_m": [float(v) for v in shapely.get_coordinates(faces[i].centroid)[0]],
            "area_m2": float(faces[i].area), "region": int(region[i]), "n_cuts": len(c),
            "n_pieces": len(c) + 1 - len(faces[i].interiors), "snapped": int(n_snapped)})
        cuts.extend(c)
    if not cuts:
        return noded, faces, region
    cuts = np.array(cuts)
    sources.add(cuts, KIND_GLUED, SOURCE_CONVEX_CUT,
                priority=LabelPriority.CONVEX_CUT)
    return _insert_segments(noded, faces, region, concave, cuts, tol, excavations, collapse)


def _assemble(faces, region, noded, kind, src, tol, report, domain_xy, excavations, set_names,
              domain, n_traces_in):
    # block order: rows bottom to top, then left to right (stable ids for a given input)
    centre = shapely.get_coordinates(shapely.centroid(faces))
    order = np.lexsort((centre[:, 0], np.round(centre[:, 1] / tol.snap_m / 1e3)))
    faces, region = faces[order], region[order]
    coords, index = exterior_coords(faces)
    counts = np.bincount(index, minlength=len(faces)) - 1  # open rings
    keep = np.ones(len(coords), bool)
    ends = np.cumsum(counts + 1) - 1
    keep[ends] = False
    xy = coords[keep]
    offsets = np.concatenate([[0], np.cumsum(counts)])
    # contacts
    seg, fa, fb = _pairs(faces, tol.grid_m)
    ekeys = segment_keys(seg, tol.grid_m)
    nkeys = segment_keys(noded, tol.grid_m)
    both = np.concatenate([ekeys, nkeys])
    _, inv, _ = unique_rows(both)
    inv = inv.ravel()
    lookup = np.full(inv.max() + 1, -1, np.int64)
    lookup[inv[len(ekeys):]] = np.arange(len(nkeys))
    where = lookup[inv[:len(ekeys)]]
    if (where < 0).any():
        raise RuntimeError(f"{int((where < 0).sum())} block edges are not in the cut network")
    ek, es = kind[where], src[where]
    if (ek < 0).any():
        raise RuntimeError(f"{int((ek < 0).sum())} block edges have no source line")
    a = np.where(fb < 0, fa, np.minimum(fa, fb))
    b = np.where(fb < 0, -1, np.maximum(fa, fb))
    # unmatched edges lie on the domain boundary
    length = np.hypot(*(seg[:, 1] - seg[:, 0]).T)
    ek = np.where(b < 0, KIND_DOMAIN, ek)
    es = np.where(b < 0, -1, es)
    table = np.column_stack([a, b, ek, es])
    uniq, cinv, _ = unique_rows(table)
    clen = np.bincount(cinv.ravel(), length, len(uniq))
    contact_blocks, contact_kind, contact_source = uniq[:, :2], uniq[:, 2], uniq[:, 3]
    # quality
    areas = shapely.area(faces)
    nxt = np.arange(len(xy)) + 1
    nxt[offsets[1:] - 1] = offsets[:-1]
    edge_len = np.hypot(*(xy[nxt] - xy).T)
    block_of_vertex = np.repeat(np.arange(len(faces)), counts)
    tiny = np.flatnonzero(edge_len < tol.min_edge_m)
    rect = shapely.minimum_rotated_rectangle(faces)
    rc = shapely.get_coordinates(shapely.get_exterior_ring(rect)).reshape(len(faces), 5, 2)
    s1 = np.hypot(*(rc[:, 1] - rc[:, 0]).T)
    s2 = np.hypot(*(rc[:, 2] - rc[:, 1]).T)
    with np.errstate(divide="ignore", invalid="ignore"):
        aspect = np.maximum(s1, s2) / np.minimum(s1, s2)
    domain_area = domain.area
    total = float(areas.sum())
    excavated = float(areas[region > 0].sum())
    report.update({
        "n_blocks": int(len(faces)),
        "n_blocks_by_region": {name: int((region == k).sum())
                               for k, name in enumerate(["rock"] + [e.name for e in excavations])},
        "n_contacts": int(len(uniq)),
        "n_contacts_by_kind": {name: int((contact_kind == k).sum())
                               for k, name in enumerate(CONTACT_KINDS)},
        "area_m2": {"min": float(areas.min()), "median": float(np.median(areas)),
                    "max": float(areas.max()), "mean": float(areas.mean())},
        "aspect_ratio": {"median": float(np.median(aspect)), "max": float(np.max(aspect))},
        "smallest_edge_m": float(edge_len.min()),
        "tiny_edges": {"count": int(len(tiny)), "rule": "edges shorter than min_edge_m that remain "
                       "(no collapse allowed by the snapping rule, see edges_snapped, or "
                       "snap_edges off) are listed",
                       "blocks": sorted(set(block_of_vertex[tiny].tolist()))[:100]},
        "area_balance": {"domain_m2": float(domain_area), "blocks_m2": total,
                         "excavated_m2": excavated, "rock_m2": total - excavated,
                         "relative_error": abs(total - domain_area) / domain_area},
        "n_traces_used": n_traces_in,
        "tolerances": tol.to_dict(),
    })
    return BlockModel(xy_m=xy, offsets=offsets, region=region,
                      region_names=["rock"] + [e.name for e in excavations],
                      contact_blocks=contact_blocks, contact_length_m=clen,
                      contact_kind=contact_kind, contact_source=contact_source,
                      set_names=set_names, domain_xy_m=domain_xy,
                      quality=BlockQuality.from_dict(report))
