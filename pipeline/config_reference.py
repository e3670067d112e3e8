"""The configuration reference (``docs/config.md``), written from the config types themselves.

Every key of every section is listed with its type, unit, default, allowed range and description,
all read from the declarations: the pydantic sections of :mod:`rockmass.config` and the library
dataclasses they use (:mod:`rockmass.solver.settings`). The unit comes from the key's suffix (the
naming rule of docs/design.md §3.1: ``_pa_m`` is Pa/m, ``_deg`` degrees, ...); the description is the field's
``description``, or else its entry in the Parameters section of the class docstring.
``tests/pipeline/test_config_reference.py`` regenerates the file and fails when it differs, and
when a key has no description. Regenerate with::

    python -m rockmass.config_reference docs/config.md
"""

from __future__ import annotations

import dataclasses
import inspect
import math
import re
import sys
import types
import typing
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic_core import PydanticUndefined

from .strict import names_file

__all__ = ["UNITS", "Key", "config_keys", "config_reference", "write_config_reference"]

#: Unit of a key, by suffix (longest first): the naming rule that puts the unit in the name.
UNITS = (("m_per_px", "m/px"), ("_kg_m3", "kg/m³"), ("_m_s2", "m/s²"), ("_pa_m", "Pa/m"),
         ("_n_m2", "N/m²"), ("_n_m", "N/m"), ("_n", "N"), ("_m2", "m²"), ("_m3", "m³"), ("_m_s", "m/s"), ("_pa", "Pa"), ("_deg", "°"), ("_hz", "Hz"),
         ("_px", "px"), ("_s", "s"), ("_m", "m"))

_TITLE = "rockmass configuration reference"


@dataclasses.dataclass(frozen=True)
class Key:
    """One key of the configuration: where it is, its type, unit, default, range and description."""

    table: str          # "[solve.joints.<label>] (model = \"cy\")"
    name: str
    type: str
    unit: str
    default: str
    range: str
    description: str


def _unit(name: str) -> str:
    return next((unit for suffix, unit in UNITS if name.endswith(suffix)), "")


def _fields(cls: Any) -> dict[str, Any]:
    return getattr(cls, "__pydantic_fields__", {}) if isinstance(cls, type) else {}


def _strip(annotation: Any) -> tuple[Any, list[Any]]:
    """(bare type, metadata) of an ``Annotated`` annotation, nested ones flattened."""
    metadata: list[Any] = []
    while typing.get_origin(annotation) is Annotated:
        metadata = [*annotation.__metadata__, *metadata]
        annotation = typing.get_args(annotation)[0]
    return annotation, metadata


def _members(annotation: Any) -> list[Any]:
    """The non-None members of a union (the annotation itself otherwise)."""
    annotation, _ = _strip(annotation)
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        return [a for a in typing.get_args(annotation) if a is not type(None)]
    return [annotation]


def _lazy_section(metadata: list[Any]) -> Any:
    marker = next((m for m in metadata if hasattr(m, "resolve") and hasattr(m, "module")), None)
    return None if marker is None else marker.resolve()


def _type_name(annotation: Any, outer: list[Any] = ()) -> str:
    if names_file(annotation, outer):
        return "file"
    bare, _ = _strip(annotation)
    origin = typing.get_origin(bare)
    if origin in (typing.Union, types.UnionType):
        names = [_type_name(a) for a in typing.get_args(bare) if a is not type(None)]
        return " or ".join(dict.fromkeys(names))
    if origin is Literal:
        return " | ".join(f'"{v}"' if isinstance(v, str) else str(v) for v in typing.get_args(bare))
    if origin in (list, tuple):
        args = typing.get_args(bare)
        if origin is tuple and args and args[-1] is not Ellipsis:
            return "[" + ", ".join(_type_name(a) for a in args) + "]"
        item = _type_name(args[0]) if args else ""
        return "array of tables" if item == "table" else (f"array of {item}" if item else "array")
    if origin is dict:
        item = _type_name(typing.get_args(bare)[1])
        return "table of tables" if item == "table" else f"table of {item}"
    if _fields(bare):
        return "table"
    if bare is Any:
        return "table"
    if callable(bare) and typing.get_origin(bare) is None and isinstance(bare, type):
        return {"float": "float", "int": "integer", "bool": "boolean", "str": "string"}.get(
            bare.__name__, bare.__name__)
    return str(bare).replace("typing.", "")


def _bounds(annotation: Any, metadata: list[Any]) -> str:
    """``0 < x <= 1e16``, ``1-64 items``, ``pattern ...`` from the constraints of a field."""
    found: list[Any] = list(metadata)
    for member in _members(annotation):
        found += _strip(member)[1]
    found += [m for info in found for m in getattr(info, "metadata", ())]  # FieldInfo in Annotated
    low = high = length = pattern = ""
    lo_n = hi_n = None
    for m in found:
        for attr, op in (("ge", ">="), ("gt", ">")):
            if getattr(m, attr, None) is not None:
                low = f"{_number(getattr(m, attr))} {'<=' if op == '>=' else '<'} "
        for attr, op in (("le", "<="), ("lt", "<")):
            if getattr(m, attr, None) is not None:
                high = f" {op} {_number(getattr(m, attr))}"
        lo_n = getattr(m, "min_length", None) if getattr(m, "min_length", None) is not None else lo_n
        hi_n = getattr(m, "max_length", None) if getattr(m, "max_length", None) is not None else hi_n
        if getattr(m, "pattern", None):
            pattern = f"matches `{m.pattern}`"
    if lo_n is not None or hi_n is not None:
        length = f"length {lo_n or 0}–{hi_n if hi_n is not None else '∞'}"
    value = f"{low}x{high}" if low or high else ""
    return "; ".join(p for p in (value, length, pattern) if p)


def _number(value: Any) -> str:
    """A number as short as it is exact: ``2700``, ``1e16``, ``1e-5``, ``59.3``."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) < 10 ** 6:
        return str(value)
    text = f"{value:g}"
    if float(text) != value:
        return repr(value)
    return re.sub(r"e\+?(-?)0*(\d)", r"e\1\2", text)


def _default(info: Any) -> str:
    if info.default_factory is not None:
        value = info.default_factory()
    elif info.default is PydanticUndefined:
        return "required"
    else:
        value = info.default
    if value is None:
        return "none"
    if _fields(type(value)):
        return "(its defaults)"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "inf" if math.isinf(value) else _number(value)
    if isinstance(value, int):
        return _number(value)
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, (list, tuple, dict)):
        return "[]" if not value else ("[" + ", ".join(_number(v) for v in value) + "]"
                                       if isinstance(value, (list, tuple)) else "{}")
    return repr(value)


def _docstring_entries(cls: type) -> dict[str, str]:
    """``name -> text`` from the numpydoc Parameters sections of ``cls`` and its bases (a line
    ``a, b : type`` followed by indented text describes both)."""
    entries: dict[str, str] = {}
    for base in reversed(cls.__mro__):
        entries.update({k: v for k, v in _parameters(base.__dict__.get("__doc__")).items() if v})
    return entries


def _parameters(doc: str | None) -> dict[str, str]:
    doc = inspect.cleandoc(doc or "")
    match = re.search(r"^Parameters\n-+\n(.*?)(?:\n\S[^\n]*\n-+\n|\Z)", doc, re.S | re.M)
    if not match:
        return {}
    entries: dict[str, str] = {}
    names: list[str] = []
    for line in match.group(1).splitlines():
        if line and not line[0].isspace():
            names = [n.strip() for n in line.split(" : ")[0].split(",")]
            for n in names:
                entries[n] = ""
        elif line.strip():
            for n in names:
                entries[n] += " " + line.strip()
    return {n: re.sub(r"\s+", " ", t).strip() for n, t in entries.items()}


def _description(cls: type, name: str, info: Any, entries: dict[str, str]) -> str:
    text = info.description or entries.get(info.alias or name, "") or entries.get(name, "")
    text = re.sub(r":\w+:`~?", "`", text.replace("``", "`"))  # reST roles and literals -> Markdown
    return re.sub(r"\s+", " ", text).replace("|", "\\|").strip()


def _tables(annotation: Any, metadata: list[Any]) -> list[type]:
    """Table types found in an annotation (a section, an array of tables, a table of tables)."""
    lazy = _lazy_section(metadata) or _lazy_section(_strip(annotation)[1])
    if lazy is not None:
        return [lazy]
    out: list[type] = []
    for member in _members(annotation):
        bare, _ = _strip(member)
        origin = typing.get_origin(bare)
        if _fields(bare):
            out.append(bare)
        elif origin in (list, tuple, dict):
            args = typing.get_args(bare)
            item = args[-1] if origin is dict else (args[0] if args else Any)
            out += _tables(item, [])
    return out


def _suffix(annotation: Any) -> str:
    """``[]`` for an array of tables, ``.<label>`` for a table of tables."""
    bare = _members(annotation)[0] if _members(annotation) else annotation
    bare, _ = _strip(bare)
    origin = typing.get_origin(bare)
    if origin in (list, tuple):
        return "[]"
    if origin is dict:
        return ".<label>"
    return ""


def _tag(cls: type, siblings: list[type]) -> str:
    """`` (model = "cy")`` when ``cls`` is one of several tables allowed at one place."""
    if len(siblings) < 2:
        return ""
    for name, info in _fields(cls).items():
        bare, _ = _strip(info.annotation)
        if typing.get_origin(bare) is Literal and len(typing.get_args(bare)) == 1:
            return f' ({name} = "{typing.get_args(bare)[0]}")'
    return f" ({cls.__name__})"


def config_keys(model: type | None = None, path: str = "") -> list[Key]:
    """Every key below ``model`` (default: the whole document with the ``[study]`` section), tables
    before the tables they contain.

    Examples
    --------
    >>> keys = config_keys()
    >>> next(k for k in keys if k.name == "friction_deg" and k.table.startswith("[solve"))  # doctest: +NORMALIZE_WHITESPACE
    Key(table='[solve.joints.<label>] (model = "coulomb")', name='friction_deg', type='float',
        unit='°', default='required', range='0 <= x < 90', description='friction angle φ')
    """
    if model is None:
        from .study_config import StudyDocument

        model = StudyDocument
    return _walk(model, path, "")


def _walk(cls: type, path: str, tag: str) -> list[Key]:
    entries = _docstring_entries(cls)
    own: list[Key] = []
    nested: list[Key] = []
    table = f"[{path}]{tag}" if path else "(top level)"
    for name, info in _fields(cls).items():
        key = info.alias or name
        tables = _tables(info.annotation, info.metadata)
        type_name = _type_name(info.annotation, info.metadata)
        if tables and type_name == "table":
            type_name = "table" if len(tables) == 1 else "table (one of several kinds)"
        own.append(Key(table, key, type_name, _unit(key), _default(info),
                       _bounds(info.annotation, info.metadata),
                       _description(cls, name, info, entries)))
        below = f"{path}.{key}" if path else key
        below += _suffix(info.annotation) if tables else ""
        for sub in tables:
            nested += _walk(sub, below, _tag(sub, tables))
    return own + nested


def config_reference() -> str:
    """The Markdown text of ``docs/config.md``."""
    lines = [f"# {_TITLE}", "",
             "Generated from the code by `python -m rockmass.config_reference docs/config.md`; do",
             "not edit by hand. Every section is optional; each command reads its own. File keys",
             "are relative to the config file. `x` in a range stands for the key's value; `[]`",
             "after a table name means an array of tables (`[[...]]` in TOML), `<label>` a key",
             "you choose.", ""]
    current = None
    for key in config_keys():
        if key.table != current:
            current = key.table
            lines += ["", f"## {key.table}", "",
                      "| key | type | unit | default | range | description |",
                      "|---|---|---|---|---|---|"]
        cells = [f"`{key.name}`", key.type.replace("|", "\\|"), key.unit, key.default,
                 key.range.replace("|", "\\|"), key.description]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def write_config_reference(path: str | Path) -> None:
    """Write :func:`config_reference` to ``path`` (UTF-8)."""
    Path(path).write_text(config_reference(), encoding="utf-8")


if __name__ == "__main__":  # python -m rockmass.config_reference docs/config.md
    write_config_reference(sys.argv[1] if len(sys.argv) > 1 else "docs/config.md")
