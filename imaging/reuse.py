"""Work shared between extractions of one photograph with several back-end settings.

:mod:`rockmass.imaging.site_back_end` extracts each labelled photo with 18 settings of the learned
detector's back end (hysteresis levels, length floor). The settings change nothing before the
probability map, and the length floor nothing before it is applied to the traces, so inside a
:func:`shared_work` block :func:`rockmass.imaging.extract.extract` computes the flattened face and
the probability map once per model, image and mask, and the joint pixels, the traces and their
attributes once per setting of everything but the floor (docs/imaging.md §3.2). Outside a block
nothing is kept and no key is built. What a block computed is dropped when it ends; blocks do not
nest.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from contextlib import contextmanager
from typing import Any

import numpy as np

__all__ = ["shared_work", "reused", "array_digest"]

#: What :func:`reused` keeps while a :func:`shared_work` block is open (key -> value); else None.
_KEPT: dict | None = None


@contextmanager
def shared_work():
    """Within this block :func:`reused` computes each value once per key."""
    global _KEPT
    if _KEPT is not None:
        raise RuntimeError("shared_work() blocks do not nest")
    _KEPT = {}
    try:
        yield
    finally:
        _KEPT = None


def reused(key: Callable[[], Hashable], compute: Callable[[], Any]) -> tuple[Any, bool]:
    """(value, kept): ``compute()``, or within :func:`shared_work` the value computed before for an
    equal ``key()``. ``kept`` is True when the value is held by the block, to be returned again:
    the caller must copy what it changes. ``key`` is called only within a block (a digest of a
    large array costs milliseconds).

    Examples
    --------
    >>> with shared_work():
    ...     first = reused(lambda: "k", lambda: [1])
    ...     again = reused(lambda: "k", lambda: [2])
    >>> first, again, reused(lambda: "k", lambda: [3])
    (([1], True), ([1], True), ([3], False))
    """
    if _KEPT is None:
        return compute(), False
    name = key()
    if name not in _KEPT:
        _KEPT[name] = compute()
    return _KEPT[name], True


def array_digest(array) -> tuple | None:
    """(shape, dtype, 16-byte BLAKE2b digest of the bytes) of an array: a key part that tells
    equal arrays from different ones; None for None (no mask, say)."""
    import hashlib

    if array is None:
        return None
    array = np.ascontiguousarray(array)
    return array.shape, array.dtype.str, hashlib.blake2b(array.data, digest_size=16).digest()
