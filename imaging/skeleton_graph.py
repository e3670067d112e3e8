"""Skeleton of a joint mask as a graph, its repairs, and the chaining of branches into traces.

Steps (docs/imaging.md §5), each a function returning a new :class:`SkeletonGraph`:

1. :func:`build_graph` — thin the mask (Zhang–Suen [2]_, :func:`skeletonize`) and read its pixel
   graph, classified as skan [1]_ does: *nodes* are end pixels (one neighbour) and junctions (three
   or more; a cluster of touching junction pixels is one node), *branches* the pixel chains between.
2. :func:`prune_spurs` — remove end branches shorter than a length at junctions, merge the
   junctions that become pass-through (degree 2), repeat until nothing changes.
3. :func:`repair_crossings` — a skeleton splits an X crossing of two lines into two Y nodes joined
   by a short branch; merge them when they are close and the four branches pair into two straight
   lines.
4. :func:`bridge_gaps` — join two line ends across a gap only when the gap is short *and* both end
   tangents point along it.
5. :func:`chain_traces` — follow branches through nodes, continuing at each node along the pair of
   branches that is most nearly straight, into trace polylines.

Coordinates are pixel (row, col) floats throughout; metres come later, in
:mod:`rockmass.imaging.vectorize`.

References
----------
.. [1] Nunez-Iglesias, J., Blanch, A. J., Looker, O., Dixon, M. W., Tilley, L. (2018). A new Python
   library to analyse skeleton images confirms malaria parasite remodelling of the red blood cell
   membrane skeleton. PeerJ 6:e4312. :DOI:`10.7717/peerj.4312`
.. [2] Zhang, T. Y., Suen, C. Y. (1984). A fast parallel algorithm for thinning digital patterns.
   Communications of the ACM 27(3), 236-239.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["SkeletonGraph", "skeletonize", "build_graph", "prune_spurs", "repair_crossings",
           "bridge_gaps", "chain_traces", "end_directions", "chain_end_directions"]

#: Branch directions are measured between these arc lengths from the branch end, pixels (past the
#: hook a skeleton makes where it enters a junction; the defaults of every step below).
TANGENT_SKIP_PX, TANGENT_REACH_PX = 2.0, 12.0


@dataclass(frozen=True, eq=False)
class SkeletonGraph:
    """Nodes and branches of a skeleton, in pixel (row, col) coordinates.

    Attributes
    ----------
    node_rc_px : (n_nodes, 2) float64
        Node positions (the mean of a junction cluster's pixels).
    branch_rc_px : (n_branch_vertices, 2) float64
        Branch pixel chains, ragged: branch i is ``branch_rc_px[branch_offsets[i]:branch_offsets[i+1]]``,
        ordered from its ``src`` node to its ``dst`` node.
    branch_offsets : (n_branches + 1,) int64
    src, dst : (n_branches,) int64
        End nodes of each branch (equal for a closed loop).
    partners : (n_branches, 2, 2) int64
        For the start (index 0) and end (index 1) of each branch, the (branch, side) it continues
        into, or (-1, -1) where the trace ends. Set by :func:`bridge_gaps`; junction pairing is
        decided in :func:`chain_traces`.
    """

    node_rc_px: np.ndarray
    branch_rc_px: np.ndarray
    branch_offsets: np.ndarray
    src: np.ndarray
    dst: np.ndarray
    partners: np.ndarray

    @property
    def n_nodes(self) -> int:
        return int(self.node_rc_px.shape[0])

    @property
    def n_branches(self) -> int:
        return int(self.branch_offsets.size - 1)

    def branch(self, i: int) -> np.ndarray:
        """(k, 2) pixel chain of branch ``i``, src to dst."""
        return self.branch_rc_px[self.branch_offsets[i]:self.branch_offsets[i + 1]]

    def degrees(self) -> np.ndarray:
        """(n_nodes,) int64 number of branch ends at each node (a loop counts twice)."""
        return (np.bincount(self.src, minlength=self.n_nodes)
                + np.bincount(self.dst, minlength=self.n_nodes)).astype(np.int64)

    def branch_lengths_px(self) -> np.ndarray:
        """(n_branches,) float64 polyline length of each branch, pixels."""
        steps = np.hypot(*np.diff(self.branch_rc_px, axis=0).T)
        is_step = np.ones(steps.size, dtype=bool)
        is_step[self.branch_offsets[1:-1] - 1] = False  # no step between consecutive branches
        index = np.repeat(np.arange(self.n_branches), np.maximum(np.diff(self.branch_offsets) - 1, 0))
        return np.bincount(index, weights=steps[is_step], minlength=self.n_branches)


class _Graph:
    """Mutable working copy of a :class:`SkeletonGraph` (Python lists; a few thousand branches)."""

    def __init__(self, graph: SkeletonGraph):
        self.nodes = [np.array(p, dtype=np.float64) for p in graph.node_rc_px]
        self.branches = [np.array(graph.branch(i), dtype=np.float64) for i in range(graph.n_branches)]
        self.src = graph.src.tolist()
        self.dst = graph.dst.tolist()
        self.partners = {(i, s): (int(graph.partners[i, s, 0]), int(graph.partners[i, s, 1]))
                         for i in range(graph.n_branches) for s in (0, 1)
                         if graph.partners[i, s, 0] >= 0}
        self.alive = [True] * len(self.branches)

    def ends_at(self):
        """node -> list of (branch, side) of the live branches."""
        table: dict[int, list[tuple[int, int]]] = {}
        for b, live in enumerate(self.alive):
            if live:
                table.setdefault(self.src[b], []).append((b, 0))
                table.setdefault(self.dst[b], []).append((b, 1))
        return table

    def length(self, b: int) -> float:
        return float(np.hypot(*np.diff(self.branches[b], axis=0).T).sum())

    def merge_pass_through(self) -> bool:
        """Join the two branches at every node of degree 2 that is not a loop's own node."""
        changed = False
        table = self.ends_at()
        for node, ends in table.items():
            if len(ends) != 2:
                continue
            (b1, s1), (b2, s2) = ends
            if b1 == b2 or not (self.alive[b1] and self.alive[b2]):
                continue
            if (b1, s1) in self.partners or (b2, s2) in self.partners:
                continue
            # orient b1 to end at the node, b2 to start at it
            p1 = self.branches[b1] if s1 == 1 else self.branches[b1][::-1]
            p2 = self.branches[b2] if s2 == 0 else self.branches[b2][::-1]
            far1 = self.src[b1] if s1 == 1 else self.dst[b1]
            far2 = self.dst[b2] if s2 == 0 else self.src[b2]
            far_partner1 = self.partners.pop((b1, 1 - s1), None)
            far_partner2 = self.partners.pop((b2, 1 - s2), None)
            self.alive[b1] = self.alive[b2] = False
            new = len(self.branches)
            self.branches.append(np.vstack([p1, p2[1:]]))
            self.src.append(far1)
            self.dst.append(far2)
            self.alive.append(True)
            for side, partner in ((0, far_partner1), (1, far_partner2)):
                if partner is not None:
                    self.partners[(new, side)] = partner
                    self.partners[partner] = (new, side)
            table[far1] = [(new, 0) if e == (b1, 1 - s1) else e for e in table.get(far1, [])]
            table[far2] = [(new, 1) if e == (b2, 1 - s2) else e for e in table.get(far2, [])]
            changed = True
        return changed

    def freeze(self) -> SkeletonGraph:
        keep = [b for b, live in enumerate(self.alive) if live]
        used = sorted({self.src[b] for b in keep} | {self.dst[b] for b in keep})
        renumber = {old: new for new, old in enumerate(used)}
        rebranch = {old: new for new, old in enumerate(keep)}
        chains = [self.branches[b] for b in keep]
        partners = np.full((len(keep), 2, 2), -1, dtype=np.int64)
        for (b, s), (pb, ps) in self.partners.items():
            if b in rebranch and pb in rebranch:
                partners[rebranch[b], s] = (rebranch[pb], ps)
        counts = np.array([c.shape[0] for c in chains], dtype=np.int64)
        return SkeletonGraph(
            node_rc_px=np.array([self.nodes[n] for n in used], dtype=np.float64).reshape(-1, 2),
            branch_rc_px=np.vstack(chains) if chains else np.zeros((0, 2)),
            branch_offsets=np.concatenate([[0], np.cumsum(counts)]).astype(np.int64),
            src=np.array([renumber[self.src[b]] for b in keep], dtype=np.int64),
            dst=np.array([renumber[self.dst[b]] for b in keep], dtype=np.int64),
            partners=partners)


def skeletonize(binary) -> np.ndarray:
    """One-pixel-wide, 8-connected skeleton of a binary mask (Zhang–Suen [2]_, scikit-image).

    Notes
    -----
    The skeleton is not a medial axis: it shortens each line end by about half the line width
    (docs/imaging.md §7), and it splits an X crossing of thick lines into two Y junctions, which
    :func:`repair_crossings` undoes.
    """
    from skimage.morphology import skeletonize as _skeletonize

    return _skeletonize(np.asarray(binary, dtype=bool))


def _empty_graph() -> SkeletonGraph:
    return SkeletonGraph(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(1, dtype=np.int64),
                         np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64),
                         np.zeros((0, 2, 2), dtype=np.int64))


def build_graph(skeleton) -> SkeletonGraph:
    """The graph of a one-pixel skeleton, each cluster of touching junction pixels one node.

    Parameters
    ----------
    skeleton : (H, W) bool array_like
        A skeleton (from :func:`skeletonize`); isolated single pixels are ignored.

    Returns
    -------
    SkeletonGraph
        No partners set yet.

    Notes
    -----
    Pixels are classified by their number of 8-neighbours as skan does [1]_: one (an end) or three
    and more (a junction) make a node; two, a branch interior. Unlike skan, touching junction
    pixels are one node (8-connected components, at their mean pixel), so an X made of a junction
    block is one node of degree 4 rather than a knot of one-step branches. A closed loop without
    nodes gets a node at its first pixel in raster order. Two-step loops on a junction cluster (a
    4-connected staircase corner) are dropped, and the degree-2 nodes they leave merged away. The
    branch walk is a numba kernel
    (``_skeleton_kernels._walk_branches``, cached on disk): skan's own graph is a numba jitclass,
    which cannot be cached and costs about 5 s of compilation in every new process.
    """
    import cv2

    from ._skeleton_kernels import _walk_branches

    sk = np.asarray(skeleton)
    if sk.ndim != 2:
        raise ValueError(f"skeleton must be a 2-D image, got shape {sk.shape}")
    padded = np.zeros((sk.shape[0] + 2, sk.shape[1] + 2), dtype=np.uint8)
    padded[1:-1, 1:-1] = sk != 0
    kernel = np.ones((3, 3), dtype=np.float32)
    kernel[1, 1] = 0
    neighbours = cv2.filter2D(padded, cv2.CV_16S, kernel, borderType=cv2.BORDER_CONSTANT)
    padded[(neighbours == 0)] = 0  # isolated pixels are no trace
    is_node = (padded == 1) & ((neighbours == 1) | (neighbours >= 3))
    n_labels, labels = cv2.connectedComponents(is_node.view(np.uint8), connectivity=8,
                                               ltype=cv2.CV_32S)
    node_id = labels.astype(np.int64) - 1  # background (0) -> -1
    n_pixels = int(np.count_nonzero(padded))
    if n_pixels < 2:
        return _empty_graph()
    out_rc = np.empty((3 * n_pixels + 2, 2), dtype=np.int64)
    out_offsets = np.empty(8 * n_pixels + 2, dtype=np.int64)
    out_src = np.empty(8 * n_pixels + 1, dtype=np.int64)
    out_dst = np.empty(8 * n_pixels + 1, dtype=np.int64)
    visited = np.zeros(padded.shape, dtype=np.uint8)
    n_b, n_v = _walk_branches(padded, node_id, visited, out_rc, out_offsets, out_src, out_dst)
    rc = out_rc[:n_v].astype(np.float64) - 1.0  # remove the padding
    offsets = out_offsets[:n_b + 1].copy()
    src, dst = out_src[:n_b].copy(), out_dst[:n_b].copy()
    n_nodes = n_labels - 1
    rows, cols = np.nonzero(node_id >= 0)
    ids = node_id[rows, cols]
    count = np.bincount(ids, minlength=n_nodes).astype(np.float64)
    node_rc = np.column_stack([np.bincount(ids, weights=rows - 1.0, minlength=n_nodes),
                               np.bincount(ids, weights=cols - 1.0, minlength=n_nodes)])
    node_rc = node_rc / np.maximum(count, 1)[:, None]
    loops = np.flatnonzero(src < 0)
    if loops.size:  # a node at the first pixel of each closed loop
        loop_nodes = n_nodes + np.arange(loops.size)
        node_rc = np.vstack([node_rc, rc[offsets[loops]]])
        src[loops] = dst[loops] = loop_nodes
    graph = SkeletonGraph(node_rc_px=node_rc, branch_rc_px=rc, branch_offsets=offsets, src=src,
                          dst=dst, partners=np.full((n_b, 2, 2), -1, dtype=np.int64))
    # staircase artefacts: a 4-connected corner makes a junction cluster with a 2-step loop on it;
    # drop those loops, then merge the pass-through (degree 2) nodes they leave
    work = _Graph(graph)
    for b in np.flatnonzero((src == dst) & (np.diff(offsets) <= 4)):
        if graph.degrees()[src[b]] > 2:
            work.alive[b] = False
    work.merge_pass_through()
    return work.freeze()


def prune_spurs(graph: SkeletonGraph, min_length_px: float) -> SkeletonGraph:
    """Remove, repeatedly, end branches shorter than ``min_length_px`` that hang off a junction.

    Parameters
    ----------
    graph : SkeletonGraph
    min_length_px : float
        Spurs (one end free, the other at a node of degree >= 3) shorter than this are removed;
        after each round the nodes left with two branches are merged away, so a branch that
        continues a line is measured whole in the next round.

    Returns
    -------
    SkeletonGraph
        Isolated branches (both ends free) are kept whatever their length.
    """
    work = _Graph(graph)
    work.merge_pass_through()
    while True:
        table = work.ends_at()
        degree = {node: len(ends) for node, ends in table.items()}
        spurs = []
        for b, live in enumerate(work.alive):
            if not live or work.src[b] == work.dst[b]:
                continue
            d0, d1 = degree[work.src[b]], degree[work.dst[b]]
            if ((d0 == 1 and d1 >= 3) or (d1 == 1 and d0 >= 3)) and work.length(b) < min_length_px:
                spurs.append(b)
        if not spurs:
            break
        # where all branches of a node but one (or all) are spurs, the node is a forked line end
        # (or a small isolated star): keep the spur that continues the line, the straightest on
        # from the one other branch (the longest spur of a star)
        by_node: dict[int, list[int]] = {}
        for b in spurs:
            node = work.src[b] if degree[work.src[b]] >= 3 else work.dst[b]
            by_node.setdefault(node, []).append(b)
        for node, bs in by_node.items():
            if degree[node] - len(bs) <= 1:
                stems = [b for b, _ in table[node] if b not in bs]
                kept = _continuation(work, node, stems[0], bs) if stems else max(bs, key=work.length)
                bs.remove(kept)
            for b in bs:
                work.alive[b] = False
                work.partners.pop((b, 0), None)
                work.partners.pop((b, 1), None)
        work.merge_pass_through()
    return work.freeze()


def _continuation(work: _Graph, node: int, stem: int, spurs: list[int]) -> int:
    """The spur at ``node`` that continues branch ``stem`` with the least turn (directions as in
    :func:`end_directions`, at its default arc lengths)."""
    def leaving(b):
        chain = work.branches[b] if work.src[b] == node else work.branches[b][::-1]
        return _direction(chain, TANGENT_SKIP_PX, TANGENT_REACH_PX)

    into = leaving(stem)
    return min(spurs, key=lambda b: (_deviation_deg(into, leaving(b)), -work.length(b)))


def _unit(vector) -> np.ndarray:
    norm = float(np.hypot(*vector))
    return vector / norm if norm > 0 else np.zeros(2)


def _direction(chain: np.ndarray, skip_px: float, reach_px: float) -> np.ndarray:
    """Unit direction along a pixel chain from its first point, between arc lengths skip and reach.

    The first ``skip_px`` (a junction's distorted zone) are left out when the chain is long enough;
    a chain shorter than ``reach_px`` uses its far end.
    """
    if chain.shape[0] < 2:
        return np.zeros(2)
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(chain, axis=0).T))])
    total = arc[-1]
    reach = min(reach_px, total)
    skip = min(skip_px, reach / 3.0)
    near = chain[int(np.searchsorted(arc, skip))]
    far = chain[min(int(np.searchsorted(arc, reach)), chain.shape[0] - 1)]
    if np.array_equal(near, far):
        near = chain[0]
    return _unit(far - near)


def end_directions(graph: SkeletonGraph, *, skip_px: float = TANGENT_SKIP_PX,
                   reach_px: float = TANGENT_REACH_PX) -> np.ndarray:
    """(n_branches, 2, 2) unit directions at each branch end, pointing *into* the branch.

    ``[i, 0]`` is at the src end, ``[i, 1]`` at the dst end; measured between arc lengths
    ``skip_px`` and ``reach_px`` from the end (see :func:`_direction`).
    """
    return _directions_of(graph.branch_rc_px, graph.branch_offsets, skip_px, reach_px)


def chain_end_directions(chains, *, skip_px: float = TANGENT_SKIP_PX,
                         reach_px: float = TANGENT_REACH_PX) -> np.ndarray:
    """(n_chains, 2, 2) unit directions into each (k, 2) pixel chain at its first (``[i, 0]``) and
    its last point (``[i, 1]``), as :func:`end_directions` measures them on branches."""
    chains = [np.asarray(c, dtype=np.float64).reshape(-1, 2) for c in chains]
    offsets = np.concatenate([[0], np.cumsum([len(c) for c in chains])])
    points = np.concatenate(chains) if chains else np.zeros((0, 2))
    return _directions_of(points, offsets, skip_px, reach_px)


def _directions_of(points, offsets, skip_px: float, reach_px: float) -> np.ndarray:
    """:func:`_direction` at both ends of every chain ``points[offsets[i]:offsets[i + 1]]``, by a
    numba kernel (the Python rule costs about 60 us a chain end): the same arithmetic, the same
    bits."""
    from ._skeleton_kernels import _end_directions

    skip_px, reach_px = float(skip_px), float(reach_px)
    if not (np.isfinite(skip_px) and skip_px >= 0.0) or np.isnan(reach_px):
        raise ValueError(f"skip_px must be finite and >= 0 and reach_px a number, got {skip_px}, "
                         f"{reach_px}")
    # copies where needed: the kernel takes writable C-ordered arrays of one dtype
    points = np.require(points, dtype=np.float64, requirements=("C", "W"))
    offsets = np.require(offsets, dtype=np.int64, requirements=("C", "W"))
    if offsets.size == 0 or offsets[0] != 0 or np.any(np.diff(offsets) < 0) \
            or offsets[-1] > len(points):
        raise ValueError("chain offsets must start at 0, never decrease and end within the points")
    out = np.zeros((offsets.size - 1, 2, 2))
    _end_directions(points, offsets, skip_px, reach_px, out)
    return out


def _deviation_deg(d_a: np.ndarray, d_b: np.ndarray) -> float:
    """Turn, in degrees, of a path that comes in along -d_a and leaves along d_b (0 = straight)."""
    cosine = float(np.clip(-np.dot(d_a, d_b), -1.0, 1.0))
    return float(np.degrees(np.arccos(cosine)))


#: At a junction, a pair that takes in a short dangling branch (see :func:`chain_traces`) must be
#: straighter than a pair of through-branches by this much to be preferred, degrees.
SHORT_DANGLING_TURN_PENALTY_DEG = 15.0


def _best_pairing(directions: list[np.ndarray], max_turn_deg: float,
                  short_dangling: list[bool] | None = None) -> list[tuple[int, int]]:
    """Greedy straight-through pairs among branch directions at a node, each turn <= max_turn_deg.

    Pairs are taken straightest first, a pair with a ``short_dangling`` branch ranked as if it
    turned :data:`SHORT_DANGLING_TURN_PENALTY_DEG` more.
    """
    n = len(directions)
    penalty = [SHORT_DANGLING_TURN_PENALTY_DEG if short_dangling and short_dangling[i] else 0.0
               for i in range(n)]
    candidates = []
    for i in range(n):
        for j in range(i + 1, n):
            turn = _deviation_deg(directions[i], directions[j])
            if turn <= max_turn_deg:
                candidates.append((turn + max(penalty[i], penalty[j]), i, j))
    used, pairs = set(), []
    for _, i, j in sorted(candidates):
        if i not in used and j not in used:
            pairs.append((i, j))
            used.update((i, j))
    return pairs


def repair_crossings(graph: SkeletonGraph, *, max_link_px: float, max_turn_deg: float = 30.0,
                     skip_px: float = TANGENT_SKIP_PX,
                     reach_px: float = TANGENT_REACH_PX) -> SkeletonGraph:
    """Merge the two Y nodes a skeleton makes of one X crossing into one node of degree 4.

    Parameters
    ----------
    graph : SkeletonGraph
    max_link_px : float
        Longest branch between the two Y nodes (about the joint width, or a few times it for
        crossings at a low angle, where the Y nodes lie further apart).
    max_turn_deg : float, default 30.0
        The four other branches must pair into two lines, each turning by at most this.
    skip_px, reach_px : float
        Where branch directions are measured (see :func:`end_directions`).

    Returns
    -------
    SkeletonGraph
        The linking branch removed, the two nodes merged at their midpoint.
    """
    work = _Graph(graph)
    directions = end_directions(graph, skip_px=skip_px, reach_px=reach_px)
    dir_of = {(b, s): directions[b, s] for b in range(graph.n_branches) for s in (0, 1)}
    table = work.ends_at()
    links = sorted((work.length(b), b) for b, live in enumerate(work.alive)
                   if live and work.src[b] != work.dst[b]
                   and len(table[work.src[b]]) == 3 and len(table[work.dst[b]]) == 3)
    merged_nodes: set[int] = set()
    for length, link in links:
        if length > max_link_px:
            break
        a, b = work.src[link], work.dst[link]
        if a in merged_nodes or b in merged_nodes:
            continue
        others = [e for e in table[a] + table[b] if e[0] != link]
        if len(others) != 4 or len({e[0] for e in others}) != 4:
            continue
        # each straight line must cross the link: one branch from each Y node; of the two ways
        # to pair them so, take the straighter and accept it when both lines turn little
        at_a = [dir_of[e] for e in others if e in table[a]]
        at_b = [dir_of[e] for e in others if e not in table[a]]
        if len(at_a) != 2:
            continue
        turn = min(max(_deviation_deg(at_a[0], at_b[k]), _deviation_deg(at_a[1], at_b[1 - k]))
                   for k in (0, 1))
        if turn > max_turn_deg:
            continue
        work.alive[link] = False
        work.nodes[a] = 0.5 * (work.nodes[a] + work.nodes[b])
        for branch_id, side in table[b]:
            if branch_id == link:
                continue
            if side == 0:
                work.src[branch_id] = a
            else:
                work.dst[branch_id] = a
        merged_nodes.update((a, b))
    return work.freeze()


def bridge_gaps(graph: SkeletonGraph, *, max_distance_px: float, max_angle_deg: float = 20.0,
                skip_px: float = TANGENT_SKIP_PX,
                reach_px: float = TANGENT_REACH_PX) -> SkeletonGraph:
    """Pair free line ends across gaps no longer than a distance and aligned within an angle.

    Parameters
    ----------
    graph : SkeletonGraph
    max_distance_px : float
        Longest gap bridged, pixels (end to end).
    max_angle_deg : float, default 20.0
        Both end tangents must point along the gap: the angle between each end's outward tangent
        and the gap vector is at most this. Two collinear ends pass; two ends offset sideways, or
        meeting at an angle, do not.
    skip_px, reach_px : float
        Where end tangents are measured (see :func:`end_directions`).

    Returns
    -------
    SkeletonGraph
        With ``partners`` set for the bridged ends; the geometry is unchanged (the chained trace
        jumps straight across the gap).

    Notes
    -----
    Candidate pairs (a k-d tree query within the distance) are accepted greedily by a cost
    :math:`d\\,(1 + \\theta_a/\\theta_{max} + \\theta_b/\\theta_{max})`, shortest and straightest first,
    each end used once.
    """
    from scipy.spatial import cKDTree

    degrees = graph.degrees()
    directions = end_directions(graph, skip_px=skip_px, reach_px=reach_px)
    ends, points, outward = [], [], []
    for b in range(graph.n_branches):
        chain = graph.branch(b)
        for side, node in ((0, graph.src[b]), (1, graph.dst[b])):
            if degrees[node] == 1 and graph.partners[b, side, 0] < 0:
                ends.append((b, side))
                points.append(chain[0] if side == 0 else chain[-1])
                outward.append(-directions[b, side])
    partners = graph.partners.copy()
    if len(ends) < 2:
        return SkeletonGraph(graph.node_rc_px, graph.branch_rc_px, graph.branch_offsets,
                             graph.src, graph.dst, partners)
    points = np.asarray(points)
    tree = cKDTree(points)
    candidates = []
    cos_limit = np.cos(np.radians(max_angle_deg))
    for i, j in tree.query_pairs(max_distance_px):
        if ends[i][0] == ends[j][0]:
            continue
        gap = points[j] - points[i]
        dist = float(np.hypot(*gap))
        if dist < 1e-9:
            turn = _deviation_deg(-outward[i], outward[j])
            if turn > max_angle_deg:
                continue
            candidates.append((0.0, i, j))
            continue
        unit = gap / dist
        cos_i, cos_j = float(np.dot(outward[i], unit)), float(np.dot(outward[j], -unit))
        if cos_i < cos_limit or cos_j < cos_limit:
            continue
        angle_i = np.degrees(np.arccos(min(cos_i, 1.0)))
        angle_j = np.degrees(np.arccos(min(cos_j, 1.0)))
        cost = dist * (1.0 + (angle_i + angle_j) / max(max_angle_deg, 1e-9))
        candidates.append((cost, i, j))
    used = set()
    for _, i, j in sorted(candidates):
        if i in used or j in used:
            continue
        used.update((i, j))
        (bi, si), (bj, sj) = ends[i], ends[j]
        partners[bi, si] = (bj, sj)
        partners[bj, sj] = (bi, si)
    return SkeletonGraph(graph.node_rc_px, graph.branch_rc_px, graph.branch_offsets,
                         graph.src, graph.dst, partners)


def _short_dangling(graph: SkeletonGraph, max_length_px: float) -> np.ndarray:
    """(n_branches,) bool: branches shorter than ``max_length_px`` from a junction (degree 3 or
    more) to a free end (degree 1, not bridged to another end)."""
    degree = graph.degrees()
    end_degree = np.column_stack([degree[graph.src], degree[graph.dst]])  # (n_branches, 2 ends)
    free = (end_degree == 1) & (graph.partners[:, :, 0] < 0)
    junction = end_degree >= 3
    dangling = (free[:, 0] & junction[:, 1]) | (free[:, 1] & junction[:, 0])
    return dangling & (graph.branch_lengths_px() < max_length_px)


def chain_traces(graph: SkeletonGraph, *, max_turn_deg: float = 30.0, min_length_px: float = 0.0,
                 skip_px: float = TANGENT_SKIP_PX,
                 reach_px: float = TANGENT_REACH_PX) -> list[np.ndarray]:
    """Join branches into traces: straight through junctions, across bridged gaps.

    Parameters
    ----------
    graph : SkeletonGraph
    max_turn_deg : float, default 30.0
        At a junction, two branches continue one trace when the path through them turns by at most
        this; pairs are taken greedily, straightest first. So an X gives two traces, and a T gives
        the bar as one trace with the stem ending at it. A *short dangling* branch (shorter than
        ``2 * reach_px``, from the junction to a free end) ranks as if it turned
        :data:`SHORT_DANGLING_TURN_PENALTY_DEG` more: its direction is measured over a few pixels
        bent by the junction, and a texture spur just over the pruning length would otherwise take
        a line's continuation and leave two overlapping traces.
    min_length_px : float, default 0.0
        Traces shorter than this (pixels, along the chain) are dropped.
    skip_px, reach_px : float
        Where branch directions are measured (see :func:`end_directions`).

    Returns
    -------
    list of (k, 2) float64 ndarray
        Trace polylines in pixel (row, col), consecutive duplicate vertices removed.
    """
    n = graph.n_branches
    partner = {}
    for b in range(n):
        for s in (0, 1):
            if graph.partners[b, s, 0] >= 0:
                partner[(b, s)] = (int(graph.partners[b, s, 0]), int(graph.partners[b, s, 1]))
    directions = end_directions(graph, skip_px=skip_px, reach_px=reach_px)
    at_node: dict[int, list[tuple[int, int]]] = {}
    for b in range(n):
        at_node.setdefault(int(graph.src[b]), []).append((b, 0))
        at_node.setdefault(int(graph.dst[b]), []).append((b, 1))
    short_dangling = _short_dangling(graph, 2.0 * reach_px)
    for node, ends in at_node.items():
        free = [e for e in ends if e not in partner]
        if len(free) == 2 and len(ends) == 2 and free[0][0] != free[1][0]:
            partner[free[0]], partner[free[1]] = free[1], free[0]  # a pass-through node
            continue
        if len(free) < 2:
            continue
        for i, j in _best_pairing([directions[e] for e in free], max_turn_deg,
                                  [bool(short_dangling[b]) for b, _ in free]):
            partner[free[i]], partner[free[j]] = free[j], free[i]

    visited = np.zeros(n, dtype=bool)
    traces = []

    def walk(b, side):
        pieces = []
        while not visited[b]:
            visited[b] = True
            chain = graph.branch(b)
            pieces.append(chain if side == 0 else chain[::-1])
            nxt = partner.get((b, 1 - side))
            if nxt is None:
                break
            b, side = nxt
        return np.vstack(pieces)

    starts = [(b, s) for b in range(n) for s in (0, 1) if (b, s) not in partner]
    for b, s in starts + [(b, 0) for b in range(n)]:  # then closed chains
        if visited[b]:
            continue
        line = walk(b, s)
        keep = np.ones(line.shape[0], dtype=bool)
        keep[1:] = np.any(np.diff(line, axis=0) != 0, axis=1)
        line = line[keep]
        if line.shape[0] < 2:
            continue
        if np.hypot(*np.diff(line, axis=0).T).sum() >= min_length_px:
            traces.append(line)
    return traces
