"""The building blocks of every config section.

- :class:`StrictModel`, the strict base of a section, and :func:`field_problem` for cross-field
  errors that name the field;
- :func:`library_section`: a section generated from a library dataclass (its fields, ranges,
  defaults, descriptions and cross-field rules), for tables whose TOML form differs from the
  library type in a few fields only (``[solve]``, ``[[solve.stages]]``); a table whose form is the
  same uses the library type itself as its field type;
- :data:`ConfigFile`, the one type of a file key, :func:`config_file` that resolves it against the
  config file's folder, and :func:`file_fields` that finds every file key of a document from the
  types.

Kept apart from :mod:`rockmass.config` so that stage-section modules (``dfn_config``,
``blocks_config``, ...) can import it while :mod:`rockmass.config` imports them: the typing rules
are described in :mod:`rockmass.config`. Nothing here imports numpy.
"""

from __future__ import annotations

import copy
import os
import types
import typing
from pathlib import Path
from typing import Annotated, Any, ClassVar

from pydantic import BaseModel, ConfigDict, Field, Strict, create_model, model_validator

from .dfn.specs import field_error

__all__ = ["StrictModel", "LibrarySection", "library_section", "field_problem", "ConfigFile",
           "config_file", "in_folder", "file_fields", "names_file"]


class StrictModel(BaseModel):
    """Base class of every config section: unknown keys forbidden, frozen, strict types.

    ``extra="forbid"`` makes a misspelt key an error; ``frozen=True`` makes a loaded config immutable
    (and hashable); ``validate_default=True`` checks defaults against the same bounds as user values;
    ``strict=True`` and ``allow_inf_nan=False`` implement the typing rules in the module docstring.
    """

    model_config = ConfigDict(
        extra="forbid",
        frozen=True,
        validate_default=True,
        strict=True,
        allow_inf_nan=False,
    )


#: A validation error attached to one field, for rules between fields (the one implementation lives
#: with the library's parameter types, :func:`rockmass.dfn.specs.field_error`).
field_problem = field_error


# -------------------------------------------------------------------------- library sections


class LibrarySection(StrictModel):
    """Base of a section generated from a library dataclass by :func:`library_section`.

    Not strict as a whole: the library's scalar types carry their own ``Strict()`` (an ``int``
    takes no float), while its tuples must take TOML arrays. Fields a section adds or replaces use
    strict types too (:data:`ConfigFile`).
    """

    model_config = ConfigDict(StrictModel.model_config, strict=False)
    __library__: ClassVar[type]

    def to_library(self, **values: Any) -> Any:
        """The library object: this section's values of the library's fields, ``values`` added (the
        fields the section replaced, converted by the caller). Raises the library's
        ``ValueError`` (``pydantic.ValidationError``) naming the field."""
        names = [n for n in self.__library__.__pydantic_fields__ if n in type(self).model_fields]
        return self.__library__(**{n: getattr(self, n) for n in names if n not in values}, **values)


def library_section(library: type, **replace: Any) -> type[LibrarySection]:
    """A config section with the fields of the pydantic dataclass ``library``.

    Each field keeps the library's annotation (type, range, description) and default, in the
    library's order, and the library's ``model_validator``\\ s (its cross-field rules) run on the
    section too, so a parameter and its rules are declared once, on the library type. (Field
    validators are not copied: a rule that a generated section needs is a model validator.) Subclass the
    result to add TOML-only keys (file names) and methods; :meth:`LibrarySection.to_library` builds
    the library object.

    Parameters
    ----------
    library : pydantic dataclass
        E.g. :class:`rockmass.solver.Stage`.
    **replace : annotation, (annotation, FieldInfo) or None
        Fields whose TOML form differs: a new annotation alone keeps the library's default, range
        and description (``stages=list[StageConfig]``); with a ``Field`` it replaces them too
        (``excavate`` takes names where the library takes region numbers); None leaves the field
        out.
    """
    fields: dict[str, Any] = {}
    for name, info in library.__pydantic_fields__.items():
        new = replace.get(name, info.annotation)
        if new is not None:
            fields[name] = new if isinstance(new, tuple) else (new, copy.copy(info))
    validators = {name: model_validator(mode=d.info.mode)(d.func)
                  for name, d in library.__pydantic_decorators__.model_validators.items()}
    section = create_model(f"{library.__name__}Section", __base__=LibrarySection,
                           __validators__=validators, **fields)
    section.__library__ = library
    return section


# ----------------------------------------------------------------------------------- file fields


class _FileMarker:
    """Metadata of :data:`ConfigFile`: the string names a file relative to the config file."""

    def __repr__(self) -> str:
        return "ConfigFile"


_FILE = _FileMarker()

#: The type of every file key: a path as written in the TOML file, relative to the file's folder
#: (:func:`config_file` resolves it). Kept as written, so a config's hash does not depend on
#: where the file sits; :func:`file_fields` finds every such key of a validated document.
ConfigFile = Annotated[str, Strict(), Field(min_length=1, max_length=4096), _FILE]


def config_file(config_path: str | os.PathLike, name: str | None) -> Path | None:
    """File key ``name`` resolved against the folder of ``config_path`` (absolute names are kept);
    None stays None.

    >>> config_file("site/run.toml", "data/traces.csv").as_posix()
    'site/data/traces.csv'
    """
    return None if name is None else in_folder(Path(config_path).parent, name)


def in_folder(folder: str | os.PathLike, name: str) -> Path:
    """``name`` relative to ``folder`` (an absolute name is kept): the one rule for file keys."""
    path = Path(name)
    return path if path.is_absolute() else Path(folder) / path


def names_file(annotation: Any, metadata: Any = ()) -> bool:
    """Whether a field of this annotation (and field metadata) is a :data:`ConfigFile`."""
    if _FILE in metadata:
        return True
    origin = typing.get_origin(annotation)
    if origin is Annotated:
        return names_file(typing.get_args(annotation)[0], annotation.__metadata__)
    if origin in (typing.Union, types.UnionType):
        return any(names_file(arg) for arg in typing.get_args(annotation))
    return False


def _item_type(annotation: Any, key: Any) -> Any:
    """The annotation of item ``key`` of a list/tuple/dict annotation (Any when unknown)."""
    while typing.get_origin(annotation) is Annotated:
        annotation = typing.get_args(annotation)[0]
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        members = [a for a in typing.get_args(annotation) if a is not type(None)]
        annotation = members[0] if len(members) == 1 else Any
    args = typing.get_args(annotation)
    origin = typing.get_origin(annotation)
    if origin is dict and len(args) == 2:
        return args[1]
    if origin in (list, tuple) and args:
        return args[0] if len(args) == 1 or args[1] is Ellipsis else args[min(key, len(args) - 1)]
    return Any


def file_fields(value: Any, keys: tuple = (), annotation: Any = Any,
                metadata: Any = ()) -> list[tuple[list[str | int], str]]:
    """Every file key (typed :data:`ConfigFile`) set in a validated config, as ``(key path, name)``.

    The key path is a list such as ``["solve", "velocity_inputs", 0, "history", "file"]``, in
    document order. Which keys are files is read from the types, so a new file key is found
    without being listed anywhere.
    """
    fields = getattr(type(value), "__pydantic_fields__", None)
    if fields is not None and not isinstance(value, type):
        found = []
        for name, info in fields.items():
            found += file_fields(getattr(value, name), (*keys, info.alias or name),
                                 info.annotation, info.metadata)
        return found
    if isinstance(value, str):
        return [(list(keys), value)] if names_file(annotation, metadata) else []
    if isinstance(value, dict):
        return [f for k, v in value.items()
                for f in file_fields(v, (*keys, k), _item_type(annotation, k))]
    if isinstance(value, (list, tuple)):
        return [f for i, v in enumerate(value)
                for f in file_fields(v, (*keys, i), _item_type(annotation, i))]
    return []
