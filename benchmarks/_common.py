"""Shared helpers of the benchmark scripts: timing, the machine header, the table and JSON output."""

from __future__ import annotations

import json
import os
import platform
import statistics
import time
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"


def timed(fn, repeat: int = 20):
    """(first call seconds, median warm seconds, last return value). The first call compiles."""
    t0 = time.perf_counter()
    value = fn()
    first = time.perf_counter() - t0
    warm = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        value = fn()
        warm.append(time.perf_counter() - t0)
    return first, statistics.median(warm), value


def header(title: str) -> str:
    import numba

    return (f"{title}\nmachine: {platform.machine()} {platform.processor() or ''} "
            f"{os.cpu_count()} cores, python {platform.python_version()}, numba {numba.__version__} "
            f"({numba.config.NUMBA_NUM_THREADS} threads)")


def table(rows: list[dict], columns: list[tuple[str, str]]) -> str:
    """Fixed-width table; ``columns`` are (key, format) pairs."""
    cells = [[format(r[k], f) if r.get(k) is not None else "-" for k, f in columns] for r in rows]
    widths = [max(len(k), *(len(c[i]) for c in cells)) for i, (k, _) in enumerate(columns)]
    lines = ["  ".join(k.ljust(w) for (k, _), w in zip(columns, widths))]
    lines += ["  ".join(c.ljust(w) for c, w in zip(row, widths)) for row in cells]
    return "\n".join(lines)


def save(name: str, payload: dict) -> Path:
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / f"{name}.json"
    path.write_text(json.dumps(payload, indent=2))
    return path


#: Detector names the benchmarks take: ExtractParams' detectors, "cnn", the learned chain with
#: the shipped convolutional network, "auto-cnn", "auto" without the network among its
#: candidates (``auto_network_ratio = inf``: the two-detector "auto" of docs/imaging.md §3.3, the
#: default up to session 26; "auto" runs the network where it keeps the pixel model, §3.6), and
#: "fine", ``rockmass extract --joints all`` (every joint, hairlines too: the settings
#: :data:`rockmass.imaging.extract.EVERY_JOINT`, §8.4).
DETECTOR_NAMES = ("auto", "learned", "ridge", "cnn", "auto-cnn", "fine")


def detector_params(name: str, **settings):
    """The ExtractParams of a benchmark's detector name (:data:`DETECTOR_NAMES`) and settings."""
    from rockmass.imaging.extract import EVERY_JOINT, ExtractParams

    if name == "fine":
        return ExtractParams(**{**EVERY_JOINT, **settings})
    if name == "cnn":
        return ExtractParams(detector="learned", pixel_model="cnn", **settings)
    if name == "auto-cnn":
        return ExtractParams(detector="auto", **{"auto_network_ratio": float("inf"), **settings})
    return ExtractParams(detector=name, **settings)
