"""Atomic outputs of a command (docs/design.md §3.7): a killed run never leaves a truncated file that looks complete.

The file mechanics (a temporary file beside the target, fsync, permissions, rename, clean-up on any
failure, ``.tmp-`` names that keep the target's suffix) are :mod:`rockmass.dfn.atomic`, the one
implementation every stage's writer uses; see it for the guarantees. This module is the layer a
command writes through: it creates the target's folder, and adds bytes, text and JSON entry points
and the JSON conversion. A command's set of outputs (all files or none) is made of these writers
inside :func:`rockmass.outputs.output_folder`.

JSON output is strict: NaN and ±Infinity are not JSON, so :func:`atomic_write_json` refuses them with
a message that names the key path (``result.local_slopes[3] is NaN; JSON has no NaN``) unless the
caller says that "undefined" is legitimate there (``nan_as_null=True``, which writes ``null``).

It imports nothing heavy: numpy values are recognised only if numpy is already imported.
"""

from __future__ import annotations

import contextlib
import dataclasses
import datetime as _dt
import enum
import json
import math
import os
import sys
from collections.abc import Iterator, Mapping
from pathlib import Path, PurePath
from typing import Any

from .dfn import atomic as _file

__all__ = [
    "atomic_write_bytes",
    "atomic_write_text",
    "atomic_write_json",
    "atomic_path",
    "to_jsonable",
]


def _prepare(path: str | os.PathLike) -> Path:
    target = Path(path)
    if not target.name:
        raise ValueError(f"path must name a file, got {os.fspath(path)!r}")
    target.parent.mkdir(parents=True, exist_ok=True)
    return target


def atomic_write_bytes(path: str | os.PathLike, data: bytes | bytearray | memoryview) -> Path:
    """Write ``data`` to ``path`` atomically.

    Parameters
    ----------
    path : str or path-like
        Target file. Its parent folder is created if missing. An existing file is replaced only once
        the new content is complete and on disk; a symbolic link at ``path`` is replaced by the file
        (the link target is not written).
    data : bytes-like
        The complete file content.

    Returns
    -------
    pathlib.Path
        ``path`` as a :class:`~pathlib.Path`.

    Raises
    ------
    OSError
        If the folder cannot be created or written. The temporary file is removed and any existing
        file at ``path`` is left as it was.

    Notes
    -----
    Permissions are those a plain ``open(path, "wb")`` would give (:mod:`rockmass.dfn.atomic`).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> atomic_write_bytes(d / "a.bin", b"abc").read_bytes()
    b'abc'
    """
    target = _prepare(path)
    with _file.atomic_open(target, "wb") as handle:
        handle.write(data)
    return target


def atomic_write_text(path: str | os.PathLike, text: str, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` atomically (see :func:`atomic_write_bytes`).

    Parameters
    ----------
    path : str or path-like
        Target file; parent folder created if missing.
    text : str
        The complete file content. Newlines are written as given (no platform translation).
    encoding : str, default "utf-8"
        Text encoding. The text is encoded before any file is created, so an encoding error leaves
        the folder untouched.

    Returns
    -------
    pathlib.Path
        ``path`` as a :class:`~pathlib.Path`.
    """
    if not isinstance(text, str):
        raise TypeError(f"text must be str, got {type(text).__name__}")
    return atomic_write_bytes(path, text.encode(encoding))


def atomic_write_json(
    path: str | os.PathLike, obj: Any, *, indent: int | None = 2, nan_as_null: bool = False
) -> Path:
    """Write ``obj`` as strict JSON (UTF-8, trailing newline) to ``path`` atomically.

    Parameters
    ----------
    path : str or path-like
        Target file; parent folder created if missing.
    obj : object
        Anything :func:`to_jsonable` accepts: dicts (keys kept in the order given, not sorted), lists,
        tuples, str, int, float, bool, None, numpy scalars and arrays, dataclasses, pydantic models,
        :class:`pathlib.Path`, enums and dates.
    indent : int or None, default 2
        Indentation as in :func:`json.dumps`; ``None`` writes one line.
    nan_as_null : bool, default False
        Write NaN and ±Infinity as ``null``. Use only where "undefined" is a legitimate value (a slope
        that cannot be fitted), never to hide a numerical failure.

    Returns
    -------
    pathlib.Path
        ``path`` as a :class:`~pathlib.Path`.

    Raises
    ------
    ValueError
        If ``obj`` holds NaN or ±Infinity (and ``nan_as_null`` is False), naming the key path:
        ``result.local_slopes[3] is NaN; JSON has no NaN``. Nothing is written.
    TypeError
        If ``obj`` holds a value JSON cannot represent, naming the key path. Nothing is written.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> print(atomic_write_json(d / "r.json", {"D": 1.5, "ok": True}, indent=None).read_text(), end="")
    {"D": 1.5, "ok": true}
    """
    plain = to_jsonable(obj, nan_as_null=nan_as_null)
    text = json.dumps(plain, indent=indent, ensure_ascii=False, allow_nan=False)
    return atomic_write_text(path, text + "\n", encoding="utf-8")


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Context manager giving a temporary path that is renamed onto ``path`` on success.

    Use it for writers that want a file name rather than bytes (``savefig``, ``meshio.write``,
    ``cv2.imwrite``). The temporary path is in the same folder and ends with the target's full name,
    so format detection by suffix still works. It does not exist yet when the block starts.

    Parameters
    ----------
    path : str or path-like
        Target file; parent folder created if missing.

    Yields
    ------
    pathlib.Path
        The temporary path to write to.

    Raises
    ------
    FileNotFoundError
        If the block finished without creating the temporary file (nothing is renamed, an existing
        file at ``path`` is kept).

    Notes
    -----
    :func:`rockmass.dfn.atomic.atomic_path` with the folder created first: if the block raises,
    the temporary file is deleted and an existing file at ``path`` is left untouched.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> with atomic_path(d / "plot.png") as tmp:
    ...     _ = tmp.write_bytes(b"PNG...")
    ...     tmp.suffix
    '.png'
    >>> sorted(p.name for p in d.iterdir())
    ['plot.png']
    """
    with _file.atomic_path(_prepare(path)) as tmp:
        yield tmp


# --------------------------------------------------------------------------------------- JSON values


def _child(path: str, key: Any) -> str:
    """Key path of ``key`` inside ``path``: ``a.b``, ``a[3]``, ``a["odd key"]``."""
    if isinstance(key, int):
        return f"{path}[{key}]"
    if key.isidentifier():
        return f"{path}.{key}" if path else key
    return f"{path}[{json.dumps(key, ensure_ascii=False)}]"


def _where(path: str) -> str:
    return path or "the value"


def _float(x: float, path: str, nan_as_null: bool) -> float | None:
    if math.isfinite(x):
        return float(x)
    if nan_as_null:
        return None
    what = "NaN" if math.isnan(x) else ("Infinity" if x > 0 else "-Infinity")
    raise ValueError(
        f"{_where(path)} is {what}; JSON has no {what.lstrip('-')} "
        "(pass nan_as_null=True where an undefined value is legitimate)"
    )


def _key(key: Any, path: str) -> str:
    if isinstance(key, enum.Enum):
        return _key(key.value, path)
    if isinstance(key, str):
        return str(key)
    if isinstance(key, bool):  # before int: bool is an int
        return "true" if key else "false"
    if isinstance(key, int):
        return str(key)
    np = sys.modules.get("numpy")
    if np is not None and isinstance(key, np.integer):
        return str(int(key))
    if isinstance(key, PurePath):
        return str(key)
    raise TypeError(f"{_where(path)} has a key of type {type(key).__name__} ({key!r}); JSON keys are strings")


def _ndarray(a: Any, path: str, nan_as_null: bool, seen: set[int]) -> Any:
    np = sys.modules["numpy"]
    kind = a.dtype.kind
    if kind in "biu":
        return a.tolist()
    if kind == "f":
        finite = np.isfinite(a)
        if finite.all():
            return a.tolist()
        if nan_as_null:
            out = a.astype(object)
            out[~finite] = None
            return out.tolist()
        index = tuple(int(i) for i in np.argwhere(~finite)[0])
        where = path + "".join(f"[{i}]" for i in index)
        return _float(float(a[index]), where, nan_as_null)  # raises
    return _convert(a.tolist(), path, nan_as_null, seen)


def _convert(obj: Any, path: str, nan_as_null: bool, seen: set[int]) -> Any:
    if obj is None:
        return None
    if isinstance(obj, enum.Enum):  # before str and int: str- and int-valued enums are both
        return _convert(obj.value, path, nan_as_null, seen)
    if isinstance(obj, bool):  # before int: bool is an int
        return bool(obj)
    if isinstance(obj, str):
        return str(obj)
    if isinstance(obj, int):
        return int(obj)
    if isinstance(obj, float):
        return _float(obj, path, nan_as_null)
    np = sys.modules.get("numpy")
    if np is not None:
        if isinstance(obj, np.ndarray):
            return _ndarray(obj, path, nan_as_null, seen)
        if isinstance(obj, np.generic):
            if isinstance(obj, np.floating):
                return _float(float(obj), path, nan_as_null)
            return _convert(obj.item(), path, nan_as_null, seen)
    if isinstance(obj, PurePath):
        return str(obj)
    if isinstance(obj, (_dt.datetime, _dt.date, _dt.time)):
        return obj.isoformat()

    # containers: guard against cycles on the current branch
    marker = id(obj)
    if marker in seen:
        raise ValueError(f"{_where(path)} refers back to one of its own containers (circular reference)")
    seen.add(marker)
    try:
        if isinstance(obj, Mapping):
            out: dict[str, Any] = {}
            for k, v in obj.items():
                key = _key(k, path)
                if key in out:
                    raise ValueError(f"{_where(path)} has two keys that both become {key!r} in JSON")
                out[key] = _convert(v, _child(path, key), nan_as_null, seen)
            return out
        if isinstance(obj, (list, tuple)):
            return [_convert(v, _child(path, i), nan_as_null, seen) for i, v in enumerate(obj)]
        if isinstance(obj, (set, frozenset)):
            try:
                items = sorted(obj)
            except TypeError:
                raise TypeError(
                    f"{_where(path)} is a set of unorderable items; JSON needs a stable order, pass a list"
                ) from None
            return [_convert(v, _child(path, i), nan_as_null, seen) for i, v in enumerate(items)]
        if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
            return {
                f.name: _convert(getattr(obj, f.name), _child(path, f.name), nan_as_null, seen)
                for f in dataclasses.fields(obj)
            }
        dump = getattr(obj, "model_dump", None)  # pydantic v2 model, without importing pydantic
        if callable(dump) and not isinstance(obj, type):
            return _convert(dump(mode="python"), path, nan_as_null, seen)
    finally:
        seen.discard(marker)
    raise TypeError(f"{_where(path)} is of type {type(obj).__name__}, which JSON cannot represent")


def to_jsonable(obj: Any, *, nan_as_null: bool = False) -> Any:
    """Convert ``obj`` to plain JSON types (dict, list, str, int, float, bool, None).

    Parameters
    ----------
    obj : object
        Mappings (key order kept; int, bool, enum and path keys become strings), lists and tuples,
        sets (sorted), str, int, float, bool, None, enums (their value), numpy scalars and arrays (as
        nested lists), dataclass instances (fields in declaration order), pydantic v2 models
        (``model_dump``), :class:`pathlib.PurePath` (``str``) and ``datetime``/``date``/``time``
        (ISO 8601).
    nan_as_null : bool, default False
        Turn NaN and ±Infinity into ``None`` instead of raising.

    Returns
    -------
    object
        A new structure; ``obj`` is not modified.

    Raises
    ------
    ValueError
        NaN or ±Infinity (unless ``nan_as_null``), a circular reference, or two keys that collide once
        converted to strings; the message names the key path.
    TypeError
        A value JSON cannot represent (bytes, complex, arbitrary objects); the message names the key
        path and the type.

    Examples
    --------
    >>> to_jsonable({"fit": {"slopes": [1.0, float("nan")]}})
    Traceback (most recent call last):
    ...
    ValueError: fit.slopes[1] is NaN; JSON has no NaN (pass nan_as_null=True where an undefined value is legitimate)
    >>> to_jsonable({"fit": {"slopes": [1.0, float("nan")]}}, nan_as_null=True)
    {'fit': {'slopes': [1.0, None]}}
    """
    return _convert(obj, "", nan_as_null, set())
