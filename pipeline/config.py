"""Strict TOML configuration (docs/design.md §4): unknown keys are errors, every number is range-checked.

A config file is read with :mod:`tomllib` and validated by a pydantic model. Every problem in the
file is reported at once, each as ``(field, message)`` with the field as a dotted key path (list
indices in brackets) and a message that says what was wrong, what is expected and what was found::

    site.toml: fractal.gridd: unknown key (allowed: grid, method, range_px, n_offsets, line_rule, skeletonize, threshold, invert); did you mean "grid"?
    site.toml: fractal.grid: must be >= 8, got 0 (allowed: 8 <= grid <= 16384)
    site.toml: fractal.n_offsets: must be an integer, got 3.5 (a float)

Adding a section, adding a key
------------------------------
A parameter is declared once, where it is used: a library parameter on the library's dataclass
(:mod:`rockmass.solver.settings`, :class:`rockmass.blockgen.JointSet`; type, range, default and
``description`` in the annotation, cross-field rules as validators), which the section uses as its
field type or generates itself from (:func:`rockmass.strict.library_section`). A TOML-only key
(a file name, a stage name) goes on the section, typed :data:`rockmass.strict.ConfigFile` when it
names a file. Then regenerate ``docs/config.md`` (:mod:`rockmass.config_reference`); a test fails
until you do, and when a key has no description.

A new section: ``class XyzConfig(StrictModel): ...`` in its own module ``xyz_config.py`` (importing
from :mod:`rockmass.strict`, never from here) and one line in :class:`RockmassConfig`:
``xyz: Stage("xyz_config", "XyzConfig") = None``.

Stage sections (``[dfn]``, ``[blocks]``) are resolved lazily: their module is imported only when
the document has that section, so ``import rockmass.config`` (and ``RockmassConfig()``) stays free
of numpy. Validation and error messages are the same as for a section typed directly.

Typing rules (why :class:`StrictModel` is strict)
-------------------------------------------------
pydantic's default "lax" mode would turn ``grid = 3.7`` into 3 or ``grid = "360"`` into 360, hiding a
typo in a number that decides the result. :class:`StrictModel` therefore validates in strict mode:

- an ``int`` field accepts only a TOML integer (not a float, string or boolean);
- a ``float`` field accepts a TOML float or integer (``grid_m = 2`` means 2.0), stored as float;
- a ``bool`` field accepts only ``true``/``false``;
- every float must be finite (TOML allows ``nan`` and ``inf``; we do not).

TOML arrays arrive as Python lists, which strict mode refuses for ``tuple`` fields (and strings are
refused for ``Path`` fields). Annotate such fields with ``Field(strict=False)`` as ``range_px`` does;
the items inside stay strict.

Cross-field checks go in a ``model_validator(mode="after")`` that calls :func:`field_problem`, so the
error still names the field (``fractal.range_px``), not the section.
"""

from __future__ import annotations

import difflib
import json
import math
import os
import re
import tomllib
import types
import typing
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import (AfterValidator, AllowInfNan, BaseModel, Field, ValidationError,
                      field_serializer, field_validator, model_serializer, model_validator)

from .canonical import canonical_json, config_hash  # here too: their home before they moved
from .errors import ConfigError
from .strict import StrictModel, field_problem

__all__ = [
    "StrictModel",
    "FractalConfig",
    "RockmassConfig",
    "load_config",
    "problems_from_validation_error",
    "field_problem",
    "Stage",
    "canonical_json",
    "config_hash",
]


# ----------------------------------------------------------------------------------------- sections


class FractalConfig(StrictModel):
    """``[fractal]``: box-counting fractal dimension of a trace map or binary image.

    Parameters
    ----------
    grid : int, default 360
        Side of the square raster grid in pixels, 8 <= grid <= 16384.
    method : {"raster", "vector"}, default "raster"
        Count boxes on a rasterised grid, or exactly on the vector traces.
    range_px : (float, float) or None, default None
        Fit range of box sizes ``[min, max]`` in grid pixels, 1 <= min < max <= grid. None means the
        default range, 1 to grid/4.
    n_offsets : int, default 8
        Number of grid offsets (1..64) whose spread gives the uncertainty of D.
    line_rule : {"supercover", "bresenham"}, default "supercover"
        How vector traces are rasterised: every pixel a segment touches, or one pixel per step.
    skeletonize : {"auto", "always", "never"}, default "auto"
        Thin image traces to one pixel width before counting; "auto" thins when traces are thicker
        than one pixel.
    threshold : float or None, default None
        Grey level above which a pixel is a trace, for non-binary images (finite). None: the image
        must already be binary.
    invert : bool, default False
        Dark traces on a light background.
    """

    grid: int = Field(360, ge=8, le=16384)
    method: Literal["raster", "vector"] = "raster"
    range_px: Annotated[tuple[Annotated[float, Field(ge=1)], float], Field(strict=False)] | None = None
    n_offsets: int = Field(8, ge=1, le=64)
    line_rule: Literal["supercover", "bresenham"] = "supercover"
    skeletonize: Literal["auto", "always", "never"] = "auto"
    threshold: float | None = None
    invert: bool = False

    @field_validator("range_px")
    @classmethod
    def _range_increasing(cls, value: tuple[float, float] | None) -> tuple[float, float] | None:
        if value is not None and not value[0] < value[1]:
            raise ValueError(f"must be [min, max] with min < max, got [{value[0]!r}, {value[1]!r}]")
        return value

    @model_validator(mode="after")
    def _range_within_grid(self) -> FractalConfig:
        if self.range_px is not None and self.range_px[1] > self.grid:
            low, high = self.range_px
            message = f"max box size must be <= grid ({self.grid}), got [{low!r}, {high!r}]"
            raise field_problem(self, "range_px", message, [low, high])
        return self


class ImagingConfig(StrictModel):
    """``[imaging]``: photo -> traces (:func:`rockmass.imaging.extract`).

    Parameters
    ----------
    m_per_px : float, optional
        Scale, metres per input pixel, > 0. Without it (and without control points on the command
        line) the traces are in pixels and every output says so.
    joint_width_px : float, optional
        Expected joint width in input pixels, > 0; sets the ridge filter scales (the learned
        detector caps it at the default, and warns). Default: 3 pixels
        of the working grid (the photo down-sampled to ``params.max_megapixels``), the same view of
        a joint at any photo size.
    joint_width_m : float, optional
        Instead of ``joint_width_px``: the expected joint width in metres on the face, > 0 (needs a
        scale: ``m_per_px`` or control points).
    face_dip_deg, face_dip_direction_deg : float, optional
        Orientation of the face plane (0-90°, 0-360°), recorded for placing traces in 3D.
    params : table, optional
        Any field of :class:`rockmass.imaging.ExtractParams` (``low_k = 2.0``,
        ``max_megapixels = 8.0``, ...); unknown keys and out-of-range values are errors.
        Infinities are allowed here (``min_trace_contrast = -inf`` turns the contrast filter off,
        ``face_contrast_share = inf`` keeps the fixed floor); ExtractParams refuses them, and NaN,
        where they make no sense. In the config's JSON form (its canonical text and hash) they
        are the strings "inf" / "-inf".
    """

    m_per_px: float | None = Field(None, gt=0)
    joint_width_px: float | None = Field(None, gt=0)
    joint_width_m: float | None = Field(None, gt=0)
    face_dip_deg: float | None = Field(None, ge=0, le=90)
    face_dip_direction_deg: float | None = Field(None, ge=0, lt=360)
    params: dict[str, bool | int | Annotated[float, AllowInfNan(True)] | str | list[int]] = Field(
        default_factory=dict)

    @field_validator("params")
    @classmethod
    def _known_extract_params(cls, value: dict) -> dict:
        import dataclasses

        from rockmass.imaging.extract import ExtractParams  # lazy: only when a file has the key

        allowed = [f.name for f in dataclasses.fields(ExtractParams)]
        unknown = sorted(set(value) - set(allowed))
        if unknown:
            raise ValueError(f"unknown key(s) {', '.join(unknown)} (allowed: {', '.join(allowed)})")
        ExtractParams(**value)  # its own range checks; the message names the key
        return value

    @field_serializer("params", when_used="json")
    def _infinities_as_text(self, value: dict) -> dict:
        """JSON has no infinity (:func:`rockmass.imaging.extract.infinities_as_text`)."""
        from rockmass.imaging.extract import infinities_as_text

        return infinities_as_text(value)

    @model_validator(mode="after")
    def _one_joint_width(self) -> ImagingConfig:
        if self.joint_width_px is not None and self.joint_width_m is not None:
            raise field_problem(self, "joint_width_m", "give either joint_width_px or joint_width_m, "
                                "not both", self.joint_width_m)
        return self


class _LazySection:
    """Marker in ``Annotated[Any, _LazySection(...)]``: the section class ``rockmass.<module>.<name>``.

    The class is imported on first use (:meth:`resolve`), i.e. when a document has the section or
    when an error inside it is being described.
    """

    __slots__ = ("module", "name")

    def __init__(self, module: str, name: str) -> None:
        self.module = module
        self.name = name

    def resolve(self) -> type[BaseModel]:
        import importlib

        return getattr(importlib.import_module(f"{__package__}.{self.module}"), self.name)

    def validate(self, value: Any) -> Any:
        """``None`` passes; anything else is validated by the section class (errors keep their
        location below the section, e.g. ``blocks.domain.width_m``)."""
        return None if value is None else self.resolve().model_validate(value)

    def __repr__(self) -> str:
        return f"Stage({self.module!r}, {self.name!r})"


def Stage(module: str, name: str) -> Any:  # noqa: N802 (reads as a type in a field annotation)
    """Annotation of an optional stage section validated by ``rockmass.<module>.<name>``, imported lazily.

    Examples
    --------
    >>> class Doc(StrictModel):
    ...     blocks: Stage("blocks_config", "BlocksConfig") = None
    >>> Doc().blocks is None
    True
    """
    marker = _LazySection(module, name)
    return Annotated[Any, marker, AfterValidator(marker.validate)]


DFNSection = Stage("dfn_config", "DFNConfig")
BlocksSection = Stage("blocks_config", "BlocksConfig")
SolveSection = Stage("solve_config", "SolveConfig")
Blocks3DSection = Stage("blocks3d_config", "Blocks3DConfig")


#: Sections added after config hashes were first recorded: dumped (and hashed) only when present,
#: so that adding one changes no existing config's hash and studies keep resuming.
SECTIONS_ADDED_LATER = ("blocks3d",)


class RockmassConfig(StrictModel):
    """The whole configuration document. Every section is optional: a stage runs only if asked for.

    One file can hold several stages; each command reads its own section (``rockmass dfn`` reads
    ``[dfn]``, ``rockmass blocks`` reads ``[blocks]``).

    Parameters
    ----------
    imaging : ImagingConfig or None
        ``[imaging]`` section.
    fractal : FractalConfig or None
        ``[fractal]`` section.
    dfn : rockmass.dfn_config.DFNConfig or None
        ``[dfn]`` section (disk fracture network generation).
    blocks : rockmass.blocks_config.BlocksConfig or None
        ``[blocks]`` section (block model of a 2D section).
    blocks3d : rockmass.blocks3d_config.Blocks3DConfig or None
        ``[blocks3d]`` section (3D blocks, keyblocks and block sizes); left out of dumps and hashes
        when absent, so adding it changed no existing config hash.
    solve : rockmass.solve_config.SolveConfig or None
        ``[solve]`` section (DEM run of a block model).
    run : rockmass.run_config.RunConfig or None
        ``[run]`` section (field inputs and wanted stages of ``rockmass run``); not in
        ``model_dump`` (nor so in :func:`config_hash`): ``rockmass run`` records and hashes it.
    """

    imaging: ImagingConfig | None = None
    fractal: FractalConfig | None = None
    dfn: DFNSection = None
    blocks: BlocksSection = None
    blocks3d: Blocks3DSection = None
    solve: SolveSection = None
    # left out of dumps and hashes (exclude=True): it names the inputs of ``rockmass run``, which
    # hashes them itself, so adding it changed no existing config hash (study resume keeps working)
    run: Annotated[Stage("run_config", "RunConfig"), Field(exclude=True)] = None

    @model_serializer(mode="wrap")
    def _sections_added_later_only_when_present(self, handler):
        dumped = handler(self)
        if isinstance(dumped, dict):
            for name in SECTIONS_ADDED_LATER:
                if name in dumped and dumped[name] is None:
                    del dumped[name]
        return dumped


# ------------------------------------------------------------------------------------------ loading

_TOML_LINE_COL = re.compile(r"at line (\d+), column (\d+)")


def required_section(document: BaseModel, name: str, config_path: str | os.PathLike) -> Any:
    """The ``[name]`` section of ``document``; a :class:`ConfigError` naming it when it is absent
    (the command ``rockmass <name>`` reads that section)."""
    section = getattr(document, name)
    if section is None:
        raise ConfigError(config_path, [(name, f"required section is missing (rockmass {name} reads "
                                               f"the [{name}] section)")])
    return section


def load_config(path: str | os.PathLike, model: type[BaseModel] = RockmassConfig) -> BaseModel:
    """Read and validate a TOML configuration file.

    Parameters
    ----------
    path : str or path-like
        The ``.toml`` file (UTF-8, a byte-order mark is tolerated).
    model : pydantic model class, default RockmassConfig
        The model the document must satisfy.

    Returns
    -------
    model
        The validated, frozen configuration with defaults filled in.

    Raises
    ------
    ConfigError
        With ``path`` and every problem found. ``problems`` holds ``(field, message)`` pairs; the
        field is ``"<file>"`` when the file cannot be read or is not valid TOML, otherwise a dotted
        key path such as ``fractal.grid`` or ``dfn.sets[1].kappa``. Message formats::

            <file>: cannot read: No such file or directory
            <file>: invalid TOML: Invalid value (at line 3, column 8); line 3 is: grid = = 5
            fractal.gridd: unknown key (allowed: grid, method, ...); did you mean "grid"?
            fractal.grid: must be >= 8, got 0 (allowed: 8 <= grid <= 16384)
            fractal.grid: must be an integer, got "360" (a string)
            fractal.method: must be one of "raster", "vector"; got "rastr" (a string)
            fractal.range_px: max box size must be <= grid (360), got [1.0, 400.0]

    Examples
    --------
    >>> import tempfile, pathlib
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "site.toml"
    >>> _ = f.write_text("[fractal]\\ngrid = 512\\n")
    >>> load_config(f).fractal.grid
    512
    >>> _ = f.write_text("[fractal]\\ngrid = 4\\n")
    >>> load_config(f)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    rockmass.errors.ConfigError: .../site.toml: fractal.grid: must be >= 8, got 4 (allowed: 8 <= grid <= 16384)
    """
    shown = os.fspath(path)
    try:
        raw = Path(path).read_bytes()
    except OSError as exc:
        raise ConfigError(shown, [("<file>", f"cannot read: {exc.strerror or exc}")]) from exc
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        where = f"byte 0x{raw[exc.start]:02x} at offset {exc.start}"
        raise ConfigError(shown, [("<file>", f"cannot read: not UTF-8 text ({where})")]) from exc
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        message = f"invalid TOML: {exc}"
        match = _TOML_LINE_COL.search(str(exc))
        if match:
            lines = text.splitlines()
            lineno = int(match.group(1))
            if 1 <= lineno <= len(lines):
                message += f"; line {lineno} is: {lines[lineno - 1].strip()[:80]}"
        raise ConfigError(shown, [("<file>", message)]) from exc
    except RecursionError as exc:  # arrays or tables nested thousands deep (issue 18)
        raise ConfigError(shown, [("<file>", "invalid TOML: nested too deeply to be read")]) from exc
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(shown, problems_from_validation_error(exc, model, data)) from exc


# ----------------------------------------------------------------- pydantic errors -> (field, message)


def _toml(value: Any, limit: int = 60) -> str:
    """A value as it would look in the TOML file."""
    if isinstance(value, bool):
        text = "true" if value else "false"
    elif isinstance(value, str):
        text = json.dumps(value, ensure_ascii=False)
    elif isinstance(value, float):
        if math.isfinite(value):
            text = repr(value)
        else:
            text = "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    elif isinstance(value, (list, tuple)):
        text = "[" + ", ".join(_toml(v, limit) for v in value) + "]"
    elif isinstance(value, dict):
        text = "{" + ", ".join(f"{k} = {_toml(v, limit)}" for k, v in value.items()) + "}"
    elif value is None:
        text = "nothing"
    elif hasattr(value, "isoformat"):
        text = value.isoformat()
    else:
        text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _bound(value: Any) -> str:
    """A bound as written in the model: ``0`` rather than pydantic's ``0.0`` for ``ge=0``."""
    if isinstance(value, float) and value.is_integer():
        return str(int(value))
    return _toml(value)


def _toml_kind(value: Any) -> str:
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, int):
        return "an integer"
    if isinstance(value, float):
        return "a float"
    if isinstance(value, str):
        return "a string"
    if isinstance(value, (list, tuple)):
        return "an array"
    if isinstance(value, dict):
        return "a table"
    if hasattr(value, "isoformat"):
        return "a date/time"
    return f"a {type(value).__name__}"


def _got(value: Any) -> str:
    return f"got {_toml(value)} ({_toml_kind(value)})"


def _unwrap(annotation: Any) -> list[Any]:
    """The concrete types an annotation admits (Optional, unions and Annotated removed)."""
    origin = typing.get_origin(annotation)
    if origin is Annotated:
        lazy = [m for m in annotation.__metadata__ if isinstance(m, _LazySection)]
        if lazy:
            return [lazy[0].resolve()]
        return _unwrap(typing.get_args(annotation)[0])
    if origin in (typing.Union, types.UnionType):
        return [t for arg in typing.get_args(annotation) for t in _unwrap(arg) if t is not type(None)]
    return [annotation]


def _field_types(info: Any) -> list[Any]:
    """Types a model field admits; a lazy stage section (:func:`Stage`) gives its section class."""
    lazy = [m for m in info.metadata if isinstance(m, _LazySection)]
    return [lazy[0].resolve()] if lazy else _unwrap(info.annotation)


def _section_fields(ann: Any) -> dict[str, Any]:
    """The fields of a table type (a pydantic model or pydantic dataclass), else ``{}``."""
    return getattr(ann, "__pydantic_fields__", {}) if isinstance(ann, type) else {}


def _annotation_at(model: type[BaseModel], keys: list[str | int]) -> list[Any]:
    """Types admitted at key path ``keys`` below ``model`` (empty list if the path is unknown)."""
    current: list[Any] = [model]
    for key in keys:
        following: list[Any] = []
        for ann in current:
            if _section_fields(ann) and isinstance(key, str):
                for name, info in _section_fields(ann).items():
                    if key in (name, info.alias):
                        following.extend(_field_types(info))
            elif isinstance(key, int):
                args = typing.get_args(ann)
                origin = typing.get_origin(ann)
                if origin in (list, set, frozenset) and args:
                    following.extend(_unwrap(args[0]))
                elif origin is tuple and args:
                    if len(args) == 2 and args[1] is Ellipsis:
                        following.extend(_unwrap(args[0]))
                    elif key < len(args):
                        following.extend(_unwrap(args[key]))
            elif isinstance(key, str) and typing.get_origin(ann) is dict:
                args = typing.get_args(ann)
                if len(args) == 2:
                    following.extend(_unwrap(args[1]))
        current = following
    return current


def _allowed_keys(model: type[BaseModel], keys: list[str | int]) -> list[str]:
    allowed: list[str] = []
    for ann in _annotation_at(model, keys):
        if _section_fields(ann):
            for name, info in _section_fields(ann).items():
                key = info.alias or name
                if key not in allowed:
                    allowed.append(key)
    return allowed


def _literal_choices(model: type[BaseModel], keys: list[str | int]) -> list[Any]:
    choices: list[Any] = []
    for ann in _annotation_at(model, keys):
        if typing.get_origin(ann) is Literal:
            choices.extend(typing.get_args(ann))
    return choices


def _data_path(loc: tuple[str | int, ...], data: Any) -> list[str | int]:
    """The key path in the user's document, dropping pydantic's union-member tags from ``loc``.

    A location element is kept if it is a key (or index) of the data at that point, or if it is the
    last element (a missing key is not in the data).
    """
    keys: list[str | int] = []
    node = data
    for i, part in enumerate(loc):
        last = i == len(loc) - 1
        if isinstance(node, dict) and part in node:
            keys.append(part)
            node = node[part]
        elif isinstance(node, (list, tuple)) and isinstance(part, int) and 0 <= part < len(node):
            keys.append(part)
            node = node[part]
        elif last:
            keys.append(part)
            node = None
        # else: a tag pydantic adds for a union member; not part of the document
    return keys


def _dotted(keys: list[str | int]) -> str:
    out = ""
    for key in keys:
        if isinstance(key, int):
            out += f"[{key}]"
        else:
            key = str(key)
            shown = key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else json.dumps(key, ensure_ascii=False)
            out = f"{out}.{shown}" if out else shown
    return out or "<document>"


_OPERATORS = {"greater_than_equal": ">=", "greater_than": ">", "less_than_equal": "<=", "less_than": "<"}


def _message(error: dict[str, Any], model: type[BaseModel], keys: list[str | int]) -> str:
    kind = error["type"]
    value = error.get("input")
    ctx = error.get("ctx") or {}

    if kind in ("extra_forbidden", "unexpected_keyword_argument"):
        allowed = _allowed_keys(model, keys[:-1])
        if not allowed:
            return "unknown key (this section takes no keys)" if keys[:-1] else "unknown key"
        text = f"unknown key (allowed: {', '.join(allowed)})"
        close = difflib.get_close_matches(str(keys[-1]), allowed, n=1)
        return text + (f'; did you mean "{close[0]}"?' if close else "")
    if kind in ("missing", "missing_argument"):
        if keys and isinstance(keys[-1], int):
            return "missing array item (the array is too short)"
        return "required key is missing"
    if kind in ("greater_than_equal", "greater_than", "less_than_equal", "less_than"):
        op = _OPERATORS[kind]
        bound = next(iter(ctx.values())) if ctx else "?"
        # the other bound of the same field, so the message gives the whole allowed range
        text = f"must be {op} {_bound(bound)}, got {_toml(value)}"
        return text + _allowed_range(model, keys)
    if kind in ("int_type", "int_parsing", "int_from_float"):
        return f"must be an integer, {_got(value)}"
    if kind in ("float_type", "float_parsing"):
        return f"must be a number, {_got(value)}"
    if kind == "finite_number":
        return f"must be a finite number, got {_toml(value)}"
    if kind in ("bool_type", "bool_parsing"):
        return f"must be true or false, {_got(value)}"
    if kind in ("string_type", "str_type"):
        return f"must be a string, {_got(value)}"
    if kind in ("literal_error", "enum"):
        choices = _literal_choices(model, keys)
        expected = ", ".join(_toml(c) for c in choices) if choices else ctx.get("expected", "?")
        return f"must be one of {expected}; {_got(value)}"
    if kind in ("model_type", "model_attributes_type", "dict_type", "dataclass_type",
                "dataclass_args_type"):
        return f"must be a table ([section] or {{key = value}}), {_got(value)}"
    if kind in ("tuple_type", "list_type", "set_type", "frozen_set_type", "iterable_type"):
        return f"must be an array, {_got(value)}"
    if kind in ("too_short", "too_long"):
        n_min, n_max = ctx.get("min_length"), ctx.get("max_length")
        actual = ctx.get("actual_length")
        if kind == "too_long" and n_max is not None:
            want = f"at most {n_max} items"
        else:
            want = f"at least {n_min} items"
        return f"must have {want}, got {actual if actual is not None else '?'}: {_toml(value)}"
    if kind == "rockmass_field":
        return str(ctx.get("message", error["msg"]))
    if kind == "value_error":
        msg = str(error["msg"])
        return msg.removeprefix("Value error, ")
    if kind == "assertion_error":
        return str(error["msg"]).removeprefix("Assertion failed, ")
    # anything else: pydantic's own wording, lower-cased start, with the value
    msg = str(error["msg"])
    msg = msg[:1].lower() + msg[1:]
    return f"{msg}, {_got(value)}"


def _allowed_range(model: type[BaseModel], keys: list[str | int]) -> str:
    """`` (allowed: 1 <= n_offsets <= 64)`` when the field has both bounds, else empty."""
    if not keys or not isinstance(keys[-1], str):
        return ""
    for ann in _annotation_at(model, keys[:-1]):
        for name, info in _section_fields(ann).items():
            if keys[-1] not in (name, info.alias):
                continue
            lower = upper = ""
            for meta in info.metadata:
                if getattr(meta, "ge", None) is not None:
                    lower = f"{_bound(meta.ge)} <= "
                if getattr(meta, "gt", None) is not None:
                    lower = f"{_bound(meta.gt)} < "
                if getattr(meta, "le", None) is not None:
                    upper = f" <= {_bound(meta.le)}"
                if getattr(meta, "lt", None) is not None:
                    upper = f" < {_bound(meta.lt)}"
            if lower and upper:
                return f" (allowed: {lower}{keys[-1]}{upper})"
    return ""


def _fixed_length_problem(
    error: dict[str, Any], model: type[BaseModel], keys: list[str | int], data: Any
) -> tuple[str, str] | None:
    """Report a wrong-length array for a fixed-length tuple field at the field itself.

    pydantic says "missing" at ``range_px[1]`` for a short array and "at most 2 items" for a long one;
    the user needs "exactly 2 items".
    """
    kind = error["type"]
    if kind == "missing" and keys and isinstance(keys[-1], int):
        field = keys[:-1]
    elif kind in ("too_short", "too_long"):
        field = keys
    else:
        return None
    sizes = {
        len(typing.get_args(ann))
        for ann in _annotation_at(model, field)
        if typing.get_origin(ann) is tuple and Ellipsis not in typing.get_args(ann)
    }
    if len(sizes) != 1:
        return None
    node = data
    try:
        for key in field:
            node = node[key]
    except (KeyError, IndexError, TypeError):
        return None
    shown = f"got {len(node)}: {_toml(node)}" if isinstance(node, (list, tuple)) else _got(node)
    return _dotted(field), f"must be an array of exactly {sizes.pop()} items, {shown}"


def problems_from_validation_error(
    exc: ValidationError, model: type[BaseModel], data: Any
) -> list[tuple[str, str]]:
    """Turn a pydantic ``ValidationError`` into ``(field, message)`` pairs, one per problem.

    Parameters
    ----------
    exc : pydantic.ValidationError
        From ``model.model_validate(data)``.
    model : pydantic model class
        The model that was validated (used to list allowed keys and choices).
    data : object
        The validated document (used to drop pydantic's union tags from locations).

    Returns
    -------
    list of (str, str)
        Field as a dotted key path with list indices in brackets, and a message with the expected
        form and the bad value, in the order pydantic found them.
    """
    problems: list[tuple[str, str]] = []
    for error in exc.errors(include_url=False):
        keys = _data_path(tuple(error["loc"]), data)
        fixed = _fixed_length_problem(error, model, keys, data)
        problem = fixed or (_dotted(keys), _message(error, model, keys))
        if problem not in problems:
            problems.append(problem)
    return problems
