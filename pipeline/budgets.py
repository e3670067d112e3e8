"""Resource budgets checked before work starts (issue 18): a config within its documented ranges
can still ask for more memory than the machine has, and then dies late with an empty
``MemoryError``. A stage estimates what it will need from the config alone and refuses, with exit
code 2, an estimate above the limit, naming the field, the estimate and the limit, and how to raise it.

The memory limit is 80 % of the machine's physical memory, or the environment variable
:data:`MAX_MEMORY_ENV` (``ROCKMASS_MAX_MEMORY=16G``; suffixes K, M, G, T in powers of 1024, or
bytes). The trace maps of ``rockmass traces`` have a count limit instead (their cost is time,
not memory: :func:`check_traces`, ``--max-traces`` or :data:`MAX_TRACES_ENV`). Estimates are upper
bounds made from measured costs (each constant says how it was measured), so a refused config
would have needed at least a good part of what the message says.
"""

from __future__ import annotations

import os
import re

from .errors import InputError

__all__ = ["MAX_MEMORY_ENV", "DFN_BYTES_HELD", "DFN_BYTES_WRITTEN", "DFN_BYTES_PER_VERTEX",
           "BLOCK_BYTES", "parse_size", "memory_limit", "check_memory", "dfn_memory_bytes",
           "block_count_terms", "BLOCK3D_BYTES", "block3d_count_terms", "MAX_TRACES_ENV",
           "DEFAULT_MAX_TRACES", "TRACE_SECONDS",
           "positive_count", "positive_count_arg", "trace_limit_arg", "max_traces", "check_traces"]

MAX_MEMORY_ENV = "ROCKMASS_MAX_MEMORY"
_SHARE_OF_RAM = 0.8

#: Bytes each fracture of a realization holds until the outputs are written (centre, normal,
#: radius, set: 64 B). Measured with tracemalloc: 4 realizations of 2.3e5 disks peak 44 MB above 1.
DFN_BYTES_HELD = 64
#: Peak bytes per fracture while one realization is generated and written, besides its vertices
#: (drawing batches, clipped areas, the CSV text), and per polygon vertex of ``fractures.vtu``.
#: Measured with tracemalloc on ``rockmass dfn`` (2.3e5 disks, n_vertices 8 and 32: peaks of 1.7
#: and 6.0 kB per disk): 300 B + 180 B per vertex, rounded up.
DFN_BYTES_WRITTEN = 300
DFN_BYTES_PER_VERTEX = 180

#: Peak bytes per block of ``rockmass blocks`` (build, blocks.json, vtu, plot). Measured with
#: tracemalloc on a 12 m square cut by two sets: 2.1e3 and 8.2e3 blocks peak at 48 and 67 MB, so
#: 3.1 kB per block above a fixed 45 MB; rounded up.
BLOCK_BYTES = 4096

#: Peak bytes per piece of ``rockmass blocks3d`` (cut, keyblocks, shapes, vtu, csv, plot). Measured
#: with tracemalloc on 12 m and 16 m cubes cut by three persistent sets 1 m apart: 2352 and 5151
#: pieces peak at 12.9 and 28.3 MB, 5.5 kB per piece; rounded up.
BLOCK3D_BYTES = 8192

_SIZE = re.compile(r"\s*([0-9]+(?:\.[0-9]*)?(?:[eE][+-]?[0-9]+)?)\s*([kKmMgGtT]?)(?:i?[bB])?\s*")
_UNITS = {"": 1, "k": 2**10, "m": 2**20, "g": 2**30, "t": 2**40}


def parse_size(text: str) -> int | None:
    """A memory size from text: bytes, or a number with K, M, G or T (powers of 1024, an optional
    ``B`` or ``iB``); None if it is not one or not positive.

    >>> parse_size("16G"), parse_size("1.5 GiB"), parse_size("5e8"), parse_size("lots")
    (17179869184, 1610612736, 500000000, None)
    """
    match = _SIZE.fullmatch(text)
    if match is None:
        return None
    value = int(float(match.group(1)) * _UNITS[match.group(2).lower()])
    return value if value > 0 else None


def _physical_memory() -> int | None:
    """Bytes of physical memory, or None where the platform does not say."""
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return None


def memory_limit() -> tuple[int | None, str]:
    """The memory limit in bytes (None: no limit known) and where it comes from, for messages."""
    text = os.environ.get(MAX_MEMORY_ENV)
    if text is not None and text.strip():
        value = parse_size(text)
        if value is None:
            raise InputError(f"{MAX_MEMORY_ENV} must be a memory size such as 16G or 500M, got "
                             f"{text!r}")
        return value, f"{MAX_MEMORY_ENV}"
    total = _physical_memory()
    if total is None:
        return None, "no limit"
    return int(_SHARE_OF_RAM * total), f"{_SHARE_OF_RAM:.0%} of this machine's memory"


def _gib(n_bytes: float) -> str:
    return f"{n_bytes / 2**30:.3g} GiB"


def check_memory(needed_bytes: float, where: str, what: str, fix: str) -> None:
    """Refuse (:class:`InputError`, exit 2) an estimate of ``needed_bytes`` above the limit.

    Parameters
    ----------
    needed_bytes : float
        The estimate.
    where : str
        The config file and field the estimate comes from (``site.toml: dfn.sets[0].intensity``).
    what : str
        What needs it, with the numbers behind the estimate (``3 realizations of 1.2e8 fractures``).
    fix : str
        What the user can lower instead.
    """
    limit, source = memory_limit()
    if limit is not None and needed_bytes > limit:
        raise InputError(f"{where}: {what} need about {_gib(needed_bytes)} of memory, more than "
                         f"the limit of {_gib(limit)} ({source}); {fix}, or raise the limit with "
                         f"{MAX_MEMORY_ENV}=SIZE (e.g. 64G)")


def dfn_memory_bytes(expected: list[float], realizations: int, n_vertices: list[int]) -> float:
    """Peak memory of ``rockmass dfn`` (bytes, an upper estimate): every realization's fractures
    held until the outputs are written, plus one realization generated and written.

    Parameters
    ----------
    expected : list of float
        Expected number of disks drawn per set (:func:`rockmass.dfn.expected_counts`).
    realizations : int
        Number of realizations.
    n_vertices : list of int
        Polygon vertices per disk of each set (``fractures.vtu``).

    >>> dfn_memory_bytes([1e6], 1, [16]) == 1e6 * (64 + 300 + 16 * 180)
    True
    """
    total = sum(expected)
    written = sum(n * (DFN_BYTES_WRITTEN + DFN_BYTES_PER_VERTEX * v)
                  for n, v in zip(expected, n_vertices))
    return realizations * total * DFN_BYTES_HELD + written


def block_count_terms(domain_xy_m, joints: list[tuple[float, float]],
                      crack_size_m: float | None) -> dict[str, float]:
    """Expected number of blocks a domain cut by persistent joint sets and potential cracks gives,
    by where they come from (an upper estimate: joints of finite length give fewer).

    Lines cut a convex region of area A into at most 1 + (lines) + (crossings) pieces; set i has
    about D / s_i lines (D: the bounding box diagonal), and sets i and j cross
    A |sin(a_i - a_j)| / (s_i s_j) times. Cracks split the rock into pieces of about
    ``crack_size_m``²: A / size².

    Parameters
    ----------
    domain_xy_m : (n, 2) sequence of float
        The domain polygon.
    joints : list of (angle_deg, spacing_m)
        Each joint set's direction and mean spacing.
    crack_size_m : float or None
        ``[blocks.cracks] size_m``, if any.

    Returns
    -------
    dict
        ``{"lines": ..., "crossings": ..., "cracks": ...}`` (counts, float).

    >>> terms = block_count_terms([(0, 0), (12, 0), (12, 12), (0, 12)], [(30, 0.125), (90, 0.125)], None)
    >>> round(terms["crossings"])  # 144 m² sin 60° / 0.125²; rockmass blocks gives 8196 blocks
    7981
    """
    import math

    xs = [float(p[0]) for p in domain_xy_m]
    ys = [float(p[1]) for p in domain_xy_m]
    n = len(xs)
    area = 0.5 * abs(sum(xs[i] * ys[(i + 1) % n] - xs[(i + 1) % n] * ys[i] for i in range(n)))
    diagonal = math.hypot(max(xs) - min(xs), max(ys) - min(ys))
    lines = sum(diagonal / s for _, s in joints)
    crossings = sum(area * abs(math.sin(math.radians(a1 - a2))) / (s1 * s2)
                    for k, (a1, s1) in enumerate(joints) for a2, s2 in joints[k + 1:])
    cracks = area / crack_size_m ** 2 if crack_size_m else 0.0
    return {"lines": lines, "crossings": crossings, "cracks": cracks}


def block3d_count_terms(box_m, sets: list[tuple[tuple[float, float, float], float]]) -> dict[str, float]:
    """Expected number of pieces a box cut by persistent plane sets gives, by where they come from.

    Generic planes cut a convex body into 1 + (planes) + (intersection lines) + (intersection
    points) pieces, counting those that meet the body. For an axis-aligned box of sides L_k and
    face areas A_k (the face normal to axis k): set i (unit normal n_i, spacing s_i) has
    Σ_k |n_ik| L_k / s_i planes; sets i and j meet in Σ_k |(n_i × n_j)_k| A_k / (s_i s_j) lines;
    sets i, j, k in V |det(n_i, n_j, n_k)| / (s_i s_j s_k) points (V the box volume).

    Parameters
    ----------
    box_m : (2, 3) sequence of float
        The lowest and the highest corner.
    sets : list of ((3,) normal, spacing_m)
        Each set's unit normal and mean spacing.

    Returns
    -------
    dict
        ``{"planes": ..., "lines": ..., "points": ...}`` (counts, float).

    >>> terms = block3d_count_terms([(0, 0, 0), (1, 1, 1)], [((1, 0, 0), 0.5), ((0, 1, 0), 0.5),
    ...                                                      ((0, 0, 1), 0.5)])
    >>> 1 + sum(terms.values())  # 2 planes per set inside the cube for a generic origin: 3³ pieces
    27.0
    """
    import itertools

    import numpy as np

    box = np.asarray(box_m, dtype=float)
    sides = box[1] - box[0]
    faces = np.array([sides[1] * sides[2], sides[0] * sides[2], sides[0] * sides[1]])
    normals = [np.asarray(n, dtype=float) for n, _ in sets]
    spacing = [float(s) for _, s in sets]
    planes = sum(float(np.abs(n) @ sides) / s for n, s in zip(normals, spacing))
    lines = sum(float(np.abs(np.cross(normals[i], normals[j])) @ faces) / (spacing[i] * spacing[j])
                for i, j in itertools.combinations(range(len(sets)), 2))
    points = sum(float(np.prod(sides)) * abs(float(np.linalg.det(np.stack([normals[i], normals[j],
                                                                             normals[k]]))))
                 / (spacing[i] * spacing[j] * spacing[k])
                 for i, j, k in itertools.combinations(range(len(sets)), 3))
    return {"planes": planes, "lines": lines, "points": points}


# ------------------------------------------------------------------------------------- traces

MAX_TRACES_ENV = "ROCKMASS_MAX_TRACES"
#: Traces ``rockmass traces`` analyses by default: about 40 s of work at :data:`TRACE_SECONDS`.
DEFAULT_MAX_TRACES = 200_000
#: Seconds per trace of the statistics of ``rockmass traces`` (read, sets, topology, intensity,
#: Mauldon, box count). Measured on Boolean two-set maps (benchmarks/bench_trace_stats.py's
#: generator, λ = 1 / L²), on an idle machine: 10⁴ traces 1.6 s, 10⁵ traces 17 s (the set fit's
#: EM two thirds of it), so 1.7e-4 s a trace, rounded up; the plots of ``--out`` add about a third.
#: 10⁶ traces took 336 s on a loaded machine (the EM 261 s, reading 29 s), before any plot.
TRACE_SECONDS = 1.8e-4


def positive_count(text: str) -> int | None:
    """``text`` as a positive whole number (``2e5`` accepted), or None.

    >>> positive_count("2e5"), positive_count("0"), positive_count("1.5"), positive_count("x")
    (200000, None, None, None)
    """
    try:
        value = float(text)
    except ValueError:
        return None
    return int(value) if value >= 1 and value == int(value) else None


def positive_count_arg(text: str, noun: str) -> int:
    """``text`` as an ``argparse`` option value: a positive number of ``noun`` (e.g. ``traces``)."""
    import argparse

    value = positive_count(text)
    if value is None:
        raise argparse.ArgumentTypeError(f"must be a positive number of {noun}, got {text!r}")
    return value


def trace_limit_arg(text: str) -> int:
    """``argparse`` type of ``--max-traces``: a positive number of traces."""
    return positive_count_arg(text, "traces")


def max_traces(option: int | None = None) -> tuple[int, str]:
    """The trace limit in force and where it comes from: ``option`` (``--max-traces``), else the
    environment variable :data:`MAX_TRACES_ENV`, else :data:`DEFAULT_MAX_TRACES`.

    >>> max_traces(5)
    (5, '--max-traces')
    """
    if option is not None:
        return int(option), "--max-traces"
    text = os.environ.get(MAX_TRACES_ENV)
    if text is None or not text.strip():
        return DEFAULT_MAX_TRACES, "the default"
    value = positive_count(text)
    if value is None:
        raise InputError(f"{MAX_TRACES_ENV} must be a positive number of traces, got {text!r}")
    return value, MAX_TRACES_ENV


def check_traces(n_traces: int, where: str, option: int | None = None) -> None:
    """Refuse (:class:`InputError`, exit 2) a trace map of more than the trace limit before its
    statistics start, naming ``where`` (the file), the count, the limit and the time it would take.

    >>> check_traces(10, "map.geojson", option=100)
    >>> check_traces(10**6, "map.geojson", option=100)
    Traceback (most recent call last):
    ...
    rockmass.errors.InputError: map.geojson: 1000000 traces, more than the limit of 100 (--max-traces); their statistics would take about 3 min (1.8e-04 s a trace); raise the limit with --max-traces N or the environment variable ROCKMASS_MAX_TRACES=N, or split the map
    """
    limit, source = max_traces(option)
    if n_traces > limit:
        seconds = n_traces * TRACE_SECONDS
        took = f"{seconds / 60:.0f} min" if seconds >= 120 else f"{seconds:.0f} s"
        raise InputError(f"{where}: {n_traces} traces, more than the limit of {limit} ({source}); "
                         f"their statistics would take about {took} ({TRACE_SECONDS:.1e} s a "
                         f"trace); raise the limit with --max-traces N or the environment variable "
                         f"{MAX_TRACES_ENV}=N, or split the map")
