"""Numba kernels behind :func:`rockmass.blockgen.network.node`: 2-point segments joined into chains
(paths through shared endpoints) and the noded pieces of those chains traced back to the segment
each lies on.

Why: GEOS snap-rounding noding sets up a hot-pixel shuffle (a ``std::random_device``) once per input
line, about half of its time when every line is a 2-point segment; chains of many segments cost the
same noding work with far fewer lines. Both kernels are single sequential walks (O(n)).

Kept in one file with every jitted helper it calls (numba's cache misses edits in other files).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit("Tuple((int64[:], boolean[:], int64[:]))(int64[:, :], int64)", cache=True)
def chain_segments(ends, n_nodes):
    """Join segments into chains through shared nodes.

    ``ends[s] = (start node, end node)`` of segment s (node ids < ``n_nodes``). At each node the
    incident segment ends are paired two by two in order of (segment, end); a chain follows the
    pairs. Chains that start at an unpaired end come first (in order of that end), then closed
    loops (in order of their lowest segment).

    Returns (seg, rev, start): chain c is ``seg[start[c]:start[c + 1]]``, segment ``seg[k]``
    walked from its end to its start where ``rev[k]``.
    """
    n = ends.shape[0]
    count = np.zeros(n_nodes + 1, np.int64)
    for s in range(n):
        count[ends[s, 0] + 1] += 1
        count[ends[s, 1] + 1] += 1
    for v in range(n_nodes):
        count[v + 1] += count[v]
    fill = count[:-1].copy()
    half = np.empty(2 * n, np.int64)  # half-edge h = 2 s + e, grouped by node
    for h in range(2 * n):
        v = ends[h // 2, h % 2]
        half[fill[v]] = h
        fill[v] += 1
    partner = np.full(2 * n, -1, np.int64)
    for v in range(n_nodes):
        for k in range(count[v], count[v + 1] - 1, 2):
            partner[half[k]] = half[k + 1]
            partner[half[k + 1]] = half[k]
    seg = np.empty(n, np.int64)
    rev = np.empty(n, np.bool_)
    start = np.empty(n + 1, np.int64)
    visited = np.zeros(n, np.bool_)
    pos = 0
    n_chains = 0
    for loops in range(2):
        for h0 in range(2 * n):
            if visited[h0 // 2] or (partner[h0] >= 0) != (loops == 1) or (loops == 1 and h0 % 2):
                continue
            start[n_chains] = pos
            n_chains += 1
            h = h0
            while True:  # enter segment h // 2 at its end h % 2, leave at the other end
                s = h // 2
                seg[pos] = s
                rev[pos] = h % 2 == 1
                visited[s] = True
                pos += 1
                nxt = partner[2 * s + 1 - h % 2]
                if nxt < 0 or visited[nxt // 2]:
                    break
                h = nxt
    start[n_chains] = pos
    return seg, rev, start[:n_chains + 1].copy()


@njit("Tuple((int64[:], int64[:], boolean[:]))(int64[:, :], int64[:], int64[:], int64[:], int64[:])",
      cache=True)
def trace_pieces(piece_node, vert_node, start, half_ptr, half):
    """Walk the noded pieces along the chains: which chain position each piece lies on.

    ``piece_node[i]`` are the node ids of the ends of piece i (GEOS output order); chain c has
    positions ``start[c]:start[c + 1]`` and its vertex k + c (node ``vert_node[k + c]``) at the
    start of position k. The pieces follow the chains one after the other, each starting where the
    previous one ended. A piece GEOS gave once for two chains (an edge they share, such as the
    one-cell edge between an extension's rounded end and its rounded crossing) is missing from the
    later chain: the walk steps over it as a *gap*, the piece at the current node (``half``,
    piece ends grouped by node, ``half_ptr`` per node) that reaches the target vertex or the start
    of the next piece; without a unique such piece the walk fails.

    Returns records (piece, chain position, piece reversed along the chain) in walk order, or
    empty arrays when the pieces do not tile the chains.
    """
    m = piece_node.shape[0]
    n_rec = m + m // 8 + 64  # room for the gaps
    rec_piece = np.empty(n_rec, np.int64)
    rec_pos = np.empty(n_rec, np.int64)
    rec_flip = np.zeros(n_rec, np.bool_)
    none = (np.empty(0, np.int64), np.empty(0, np.int64), np.empty(0, np.bool_))
    i = 0
    r = 0
    for c in range(start.shape[0] - 1):
        cur = vert_node[start[c] + c]
        for k in range(start[c], start[c + 1]):
            target = vert_node[k + c + 1]
            last_gap = -1
            while cur != target:
                if i < m and piece_node[i, 0] == cur:
                    p, flip, i = i, False, i + 1
                else:  # a gap: the piece given earlier for another chain
                    if half_ptr.shape[0] == 0:
                        return none  # no pieces by node given: the caller retries with them
                    nxt = piece_node[i, 0] if i < m else -1
                    p = -1
                    for h in half[half_ptr[cur]:half_ptr[cur + 1]]:
                        q, other = h // 2, piece_node[h // 2, 1 - h % 2]
                        if q < i and q != last_gap and (other == target or other == nxt):
                            if p >= 0 and q != p:
                                return none  # ambiguous
                            p, flip = q, h % 2 == 1
                    if p < 0:
                        return none
                    last_gap = p
                if r >= n_rec:
                    return none
                rec_piece[r], rec_pos[r], rec_flip[r] = p, k, flip
                r += 1
                cur = piece_node[p, 0] if flip else piece_node[p, 1]
    if i != m:
        return none
    return rec_piece[:r].copy(), rec_pos[:r].copy(), rec_flip[:r].copy()
