"""Provenance: ``manifest.json`` records what produced a run's outputs.

A manifest answers "could I reproduce this folder?": the rockmass version and the versions of the
libraries that decide numerical results, the machine, the exact command, the resolved configuration
and its hash, the SHA-256 of every input file, the seeds, and how long each step took.

Library versions come from :mod:`importlib.metadata`, so none of those libraries is imported (the CLI
stays fast, and a manifest can be written before anything heavy is loaded).
"""

from __future__ import annotations

import contextlib
import contextvars
import datetime as _dt
import hashlib
import os
import platform
from collections.abc import Iterable, Iterator, Mapping
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

from .atomic import atomic_write_json, to_jsonable
from .errors import InputError

__all__ = ["MANIFEST_NAME", "TRACKED_DISTRIBUTIONS", "build_manifest", "digest_cache", "file_sha256",
           "write_manifest", "portable_paths", "portable_config_paths"]

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

#: The digest cache of :func:`digest_cache` in force (None: every call reads its file).
_DIGESTS: contextvars.ContextVar[dict | None] = contextvars.ContextVar("rockmass_digests", default=None)
#: ``(base, run folder)`` of :func:`portable_config_paths` in force (None: paths as they are).
_PORTABLE: contextvars.ContextVar[tuple[Path, Path] | None] = contextvars.ContextVar(
    "rockmass_portable_paths", default=None)


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
    cache = _DIGESTS.get()
    key = _cache_key(path) if cache is not None else None
    if key is not None and key in cache:
        return cache[key]
    result = _read_sha256(path)
    if key is not None:
        cache[key] = result
    return result


@contextlib.contextmanager
def digest_cache(cache: dict) -> Iterator[dict]:
    """Within the block, :func:`file_sha256` keeps each file's digest in ``cache`` and reads a file
    again only when it changed.

    A file is the same file while its resolved path, device, inode, size and modification time
    (ns) are, so a file rewritten or replaced in between is read again. Meant for one command (one
    ``rockmass run`` hashes each input for its stage hashes, the stage manifests and the run's
    manifest); pass the same dict to several blocks to share it between them.
    """
    token = _DIGESTS.set(cache)
    try:
        yield cache
    finally:
        _DIGESTS.reset(token)


def portable_paths(obj: Any, base: str | os.PathLike, out_dir: str | os.PathLike) -> Any:
    """``obj`` (JSON-like) with its absolute paths written so that they do not depend on where the
    project or the run folder is: a path inside ``out_dir`` (a run's own output, such as the
    ``"@traces"`` of a photo) as ``<run>/<stage>/<file>``, any other relative to ``base`` (the
    config's folder, as the config would name it). File contents are hashed apart.

    >>> portable_paths({"traces": "/p/out/extract/t.geojson", "f": ["/p/data/s.csv", "x.csv"]},
    ...                "/p", "/p/out")
    {'traces': '<run>/extract/t.geojson', 'f': ['data/s.csv', 'x.csv']}
    """
    base, out_dir = Path(base), Path(out_dir)
    if isinstance(obj, dict):
        return {k: portable_paths(v, base, out_dir) for k, v in obj.items()}
    if isinstance(obj, list):
        return [portable_paths(v, base, out_dir) for v in obj]
    if isinstance(obj, str) and os.path.isabs(obj):
        path = Path(obj)
        if path.is_relative_to(out_dir):
            return "<run>/" + path.relative_to(out_dir).as_posix()
        return os.path.relpath(path, base)
    return obj


def local_path(portable: str, base: str | os.PathLike, out_dir: str | os.PathLike) -> Path:
    """The path a :func:`portable_paths` entry names: ``<run>/...`` inside ``out_dir``, another
    relative path against ``base`` (the config's folder), an absolute one as it is.

    >>> local_path("<run>/extract/t.geojson", "/p", "/p/out").as_posix()
    '/p/out/extract/t.geojson'
    >>> local_path("data/s.csv", "/p", "/p/out").as_posix()
    '/p/data/s.csv'
    """
    if portable.startswith("<run>/"):
        return Path(out_dir) / portable[len("<run>/"):]
    return Path(base) / portable


@contextlib.contextmanager
def portable_config_paths(base: str | os.PathLike, out_dir: str | os.PathLike) -> Iterator[None]:
    """Within the block, :func:`build_manifest` records and hashes its config with
    :func:`portable_paths` (``rockmass run`` around its stages: a stage's ``config_hash`` is then
    the same whatever --out the run writes to, issue 18)."""
    token = _PORTABLE.set((Path(base).resolve(), Path(out_dir).resolve()))
    try:
        yield
    finally:
        _PORTABLE.reset(token)


def _cache_key(path) -> tuple | None:
    """(resolved path, device, inode, size, mtime ns) of a file, or None if it cannot be stat'ed
    (then it is read, and the read reports the problem)."""
    try:
        st = os.stat(path)
        return (os.path.realpath(path), st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns)
    except (OSError, ValueError):
        return None


def _read_sha256(path) -> tuple[str, int]:
    """SHA-256 hex digest and size of a file, read in chunks (errors as :func:`file_sha256`)."""
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
        ``model_dump(mode="json")``; ``config_hash`` is :func:`rockmass.config.config_hash` of it
        (within :func:`portable_config_paths`, of it with :func:`portable_paths`).
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
        from .canonical import config_hash  # no pydantic (rockmass extract without --config)

        if hasattr(config, "model_dump") and not isinstance(config, type):
            config_json = config.model_dump(mode="json")
        else:
            config_json = config
        config_json = to_jsonable(config_json)  # refuses NaN, naming the key
        portable = _PORTABLE.get()
        if portable is not None:
            config_json = portable_paths(config_json, *portable)
        digest = config_hash(config_json)

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
