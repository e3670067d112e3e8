"""Numba kernel of the pixel model's forward pass (:meth:`rockmass.imaging.learned.Stage.predict`,
docs/imaging.md §3.1, eq. (3.2)).

Written out rather than left to NumPy's matrix product: the product goes to the BLAS library,
which splits these small products (32 x 27 weights times a few thousand pixels) over threads
that wait for work by spinning; "auto" runs the classifier in one thread while its ridge chain
runs in another, and the spinning threads take the other core's time
(``benchmarks/bench_pixel_inference.py`` measures both, alone and beside the ridge chain). The
kernel runs in its caller's thread, without the interpreter lock, and sums in one fixed order, so
its probabilities do not depend on the number of threads either.

Kept apart from its wrapper (the project's kernel rule: kernels take plain arrays and write into
caller-allocated outputs; the wrapper validates).
"""

from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def mlp_forward(x, low, high, mean, weights, biases, sizes, block, out):
    """Logistic output of a ReLU network for each column of ``x``, into ``out``.

    Parameters
    ----------
    x : (F, N) float32
        Inputs, one column per pixel.
    low, high, mean : (F,) float32
        Each input is clipped to [low, high], then ``mean`` is subtracted.
    weights : (sum of n_out * n_in,) float32
        The layers' weight matrices, each (n_out, n_in) in row order, one after the other.
    biases : (sum of n_out,) float32
    sizes : (L + 1,) int64
        Widths: F, the hidden layers', 1.
    block : int
        Pixels per pass through the layers (their hidden values stay in the processor's cache).
    out : (N,) float32
        1 / (1 + exp(-clip(z, -30, 30))) of the last layer's z.
    """
    n_features, n = x.shape
    n_layers = sizes.size - 1
    width = 0
    for k in range(sizes.size):
        width = max(width, sizes[k])
    a = np.empty((width, block), np.float32)
    b = np.empty((width, block), np.float32)
    for start in range(0, n, block):
        m = min(block, n - start)
        for f in range(n_features):
            lo, hi, mu = low[f], high[f], mean[f]
            for p in range(m):
                v = x[f, start + p]
                if v < lo:
                    v = lo
                elif v > hi:
                    v = hi
                a[f, p] = v - mu
        w_at = 0
        b_at = 0
        for layer in range(n_layers):
            n_in, n_out = sizes[layer], sizes[layer + 1]
            j = 0
            while j < n_out:  # four outputs at a time: each input value is read once for four
                k = min(4, n_out - j)
                for r in range(k):
                    bias = biases[b_at + j + r]
                    for p in range(m):
                        b[j + r, p] = bias
                for i in range(n_in):
                    if k == 4:
                        w0 = weights[w_at + j * n_in + i]
                        w1 = weights[w_at + (j + 1) * n_in + i]
                        w2 = weights[w_at + (j + 2) * n_in + i]
                        w3 = weights[w_at + (j + 3) * n_in + i]
                        for p in range(m):
                            v = a[i, p]
                            b[j, p] += w0 * v
                            b[j + 1, p] += w1 * v
                            b[j + 2, p] += w2 * v
                            b[j + 3, p] += w3 * v
                    else:
                        for r in range(k):
                            w = weights[w_at + (j + r) * n_in + i]
                            for p in range(m):
                                b[j + r, p] += w * a[i, p]
                j += k
            if layer < n_layers - 1:  # ReLU between layers
                for j in range(n_out):
                    for p in range(m):
                        if b[j, p] < 0.0:
                            b[j, p] = 0.0
            w_at += n_in * n_out
            b_at += n_out
            a, b = b, a
        for p in range(m):
            z = min(max(a[0, p], -30.0), 30.0)
            out[start + p] = 1.0 / (1.0 + math.exp(-z))
