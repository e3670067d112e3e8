"""Provenance: ``manifest.json`` records what produced a run's outputs.

A manifest answers "could I reproduce this folder?": the rockmass version and the versions of the
libraries that decide numerical results, the machine, the exact command, the resolved configuration
and its hash, the SHA-256 of every input file, the seeds, and how long each step took.

Library versions come from :mod:`importlib.metadata`, so none of those libraries is imported (the CLI
stays fast, and a manifest can be written before anything heavy is loaded).
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import os
import platform
from collections.abc import Iterable, Mapping
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

from .atomic import atomic_write_json, to_jsonable
from .errors import InputError

__all__ = ["MANIFEST_NAME", "TRACKED_DISTRIBUTIONS", "build_manifest", "write_manifest", "file_sha256"]

MANIFEST_NAME = "manifest.json"
MANIFEST_VERSION = 1

#: Distributions whose versions are recorded (names as on PyPI, as importlib.metadata knows them).
TRACKED_DISTRIBUTIONS = (
    "numpy",
    "scipy",
    "numba",
    "opencv-python-headless",
    "scikit-image",
    "shapely",
    "matplotlib",
    "pydantic",
    "trimesh",
    "meshio",
    "tqdm",
)

_CHUNK = 1 << 20  # 1 MiB


def _dist_version(name: str) -> str | None:
    try:
        return version(name)
    except PackageNotFoundError:
        return None


def _rockmass_version() -> str:
    from . import __version__

    return __version__


def file_sha256(path: str | os.PathLike) -> tuple[str, int]:
    """SHA-256 hex digest and size in bytes of a file, read in 1 MiB chunks.

    Parameters
    ----------
    path : str or path-like
        The file.

    Returns
    -------
    (str, int)
        Hex digest and number of bytes hashed (counted while reading, so the two always agree).

    Raises
    ------
    InputError
        If the file does not exist, is a folder, or cannot be read; the message names the file.
    """
    shown = os.fspath(path)
    digest = hashlib.sha256()
    size = 0
    try:
        with open(path, "rb") as fh:
            while chunk := fh.read(_CHUNK):
                digest.update(chunk)
                size += len(chunk)
    except FileNotFoundError as exc:
        raise InputError(f"{shown}: input file not found") from exc
    except IsADirectoryError as exc:
        raise InputError(f"{shown}: input is a folder, expected a file") from exc
    except OSError as exc:
        raise InputError(f"{shown}: cannot read input file: {exc.strerror or exc}") from exc
    return digest.hexdigest(), size


def _platform() -> dict[str, Any]:
    info: dict[str, Any] = {
        "python": platform.python_version(),
        "implementation": platform.python_implementation(),
        "platform": platform.platform(),
        "machine": platform.machine(),
        "cpu_count": os.cpu_count(),
    }
    threads = os.environ.get("NUMBA_NUM_THREADS")
    if threads is not None:
        info["NUMBA_NUM_THREADS"] = threads
    return info


def build_manifest(
    *,
    command: list[str] | tuple[str, ...] | str,
    config: Any = None,
    inputs: Iterable[str | os.PathLike] = (),
    seeds: Mapping[str, Any] | None = None,
    timings_s: Mapping[str, float] | None = None,
    extra: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """Build the provenance record of a run, as plain JSON types.

    Parameters
    ----------
    command : list of str or str
        The command line as run (``sys.argv``) or a description of the call. A list is stored as a
        list of strings (path-like items converted with ``os.fspath``).
    config : pydantic model, mapping or None, default None
        The configuration. A model is stored *resolved* (defaults filled in) with
        ``model_dump(mode="json")``; ``config_hash`` is :func:`rockmass.config.config_hash` of it.
    inputs : iterable of path-like, default ()
        Input files. Each is hashed now (streamed) and recorded as ``{"path", "sha256", "bytes"}``,
        with ``path`` as given.
    seeds : mapping or None, default None
        Seeds used (root seed, spawn keys, ...).
    timings_s : mapping of str to float or None, default None
        Wall-clock time of each step in seconds.
    extra : mapping or None, default None
        Anything else worth recording (stages skipped and why, warnings, ...).

    Returns
    -------
    dict
        Keys in this order: ``manifest_version``, ``rockmass_version``, ``created_utc`` (ISO 8601,
        second precision, ``Z``), ``command``, ``config``, ``config_hash``, ``inputs``, ``seeds``,
        ``timings_s``, ``dependencies`` (distribution → version or None if not installed),
        ``platform`` (``python``, ``implementation``, ``platform``, ``machine``, ``cpu_count`` and
        ``NUMBA_NUM_THREADS`` when that variable is set), ``extra``.

    Raises
    ------
    InputError
        If an input file is missing or unreadable (the message names it).
    TypeError
        If ``inputs`` is a single path rather than a list of paths, or ``command`` is neither a string
        nor a list.
    ValueError
        If a value cannot be written as strict JSON (NaN in ``timings_s``, ...), naming the key path.
    """
    if isinstance(inputs, (str, bytes, os.PathLike)):
        shown = os.fsdecode(inputs)
        raise TypeError(f"inputs must be a list of paths, got a single path {shown!r}; wrap it in a list")
    if isinstance(command, str):
        cmd: str | list[str] = command
    elif isinstance(command, (list, tuple)):
        cmd = [os.fsdecode(c) if isinstance(c, (bytes, os.PathLike)) else str(c) for c in command]
    else:
        raise TypeError(f"command must be a string or a list of strings, got {type(command).__name__}")

    config_json: Any = None
    digest: str | None = None
    if config is not None:
        from .config import config_hash  # pydantic-based; imported only when needed

        if hasattr(config, "model_dump") and not isinstance(config, type):
            config_json = config.model_dump(mode="json")
        else:
            config_json = config
        config_json = to_jsonable(config_json)  # refuses NaN, naming the key
        digest = config_hash(config)

    records = []
    for item in inputs:
        sha, size = file_sha256(item)
        records.append({"path": os.fsdecode(item), "sha256": sha, "bytes": size})

    manifest = {
        "manifest_version": MANIFEST_VERSION,
        "rockmass_version": _rockmass_version(),
        "created_utc": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "command": cmd,
        "config": config_json,
        "config_hash": digest,
        "inputs": records,
        "seeds": None if seeds is None else dict(seeds),
        "timings_s": None if timings_s is None else dict(timings_s),
        "dependencies": {name: _dist_version(name) for name in TRACKED_DISTRIBUTIONS},
        "platform": _platform(),
        "extra": None if extra is None else dict(extra),
    }
    return to_jsonable(manifest)


def write_manifest(out_dir: str | os.PathLike, **kwargs: Any) -> Path:
    """Build a manifest (same keyword arguments as :func:`build_manifest`) and write it atomically.

    Parameters
    ----------
    out_dir : str or path-like
        Output folder (created if missing); the file is ``out_dir / "manifest.json"``.
    **kwargs
        Passed to :func:`build_manifest`.

    Returns
    -------
    pathlib.Path
        Path of the written ``manifest.json``.
    """
    manifest = build_manifest(**kwargs)
    return atomic_write_json(Path(out_dir) / MANIFEST_NAME, manifest)
