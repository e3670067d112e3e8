"""Parameter dataclasses declared once: :func:`spec` and :func:`field_error`.

A parameter type of the library (a joint set, a joint model, a solver stage) is a frozen pydantic
dataclass whose annotations carry each field's type, range and description, so the same
declaration validates Python calls and TOML tables (the ``rockmass`` config sections use these
classes as their field types) and writes the configuration reference. This module holds the pieces
they share. It lives in ``rockmass.dfn``, the base of the stages' dependency direction
(docs/design.md §1), so that every stage and the config layer can use it; it imports pydantic and
the standard library only, so the command line can load it without numpy.
"""

from __future__ import annotations

import functools
import numbers
from typing import Annotated, Any

from pydantic import BeforeValidator, ConfigDict, Field, Strict, ValidationError
from pydantic.dataclasses import dataclass
from pydantic_core import InitErrorDetails, PydanticCustomError

__all__ = ["SPEC_CONFIG", "spec", "field_error", "Float", "FloatOrInf", "Int", "Bool"]

#: Validation of every spec: unknown keys refused, defaults checked like values, no NaN or
#: infinity (a field may allow infinity itself with ``Field(allow_inf_nan=True)``). Scalars are
#: made strict per field (``Annotated[float, Strict()]``), so that sequences still accept lists.
#: A field whose config key differs from its Python name has that key as ``alias``: tables and
#: dumps use the key, Python calls the name (:func:`spec` translates).
SPEC_CONFIG = ConfigDict(extra="forbid", validate_default=True, allow_inf_nan=False,
                         serialize_by_alias=True)


def _plain_number(value: Any) -> Any:
    """numpy scalars as Python numbers (strict fields refuse ``np.float32`` or ``np.int64``); numpy
    registers its scalar types with :mod:`numbers`, so no numpy import is needed to see them."""
    if getattr(value, "shape", None) == () and hasattr(value, "item"):
        value = value.item()          # a 0-d array
    if type(value) in (bool, int, float) or not isinstance(value, numbers.Real):
        return value
    return int(value) if isinstance(value, numbers.Integral) else float(value)


# strict scalars: a float field takes a float or an integer, an int field only an integer (numpy's
# too), a bool field only true/false (lax mode would turn 3.7 into 3 or "1e9" into 1e9)
Float = Annotated[float, BeforeValidator(_plain_number), Strict()]
Int = Annotated[int, BeforeValidator(_plain_number), Strict()]
Bool = Annotated[bool, Strict()]
#: a Float that may be infinite (e.g. "no upper limit"); NaN passes too, so its rule must refuse it
FloatOrInf = Annotated[float, Field(allow_inf_nan=True), BeforeValidator(_plain_number), Strict()]


def spec(cls: type | None = None, *, key: str = "", type_errors: bool = False) -> Any:
    """Make ``cls`` a frozen pydantic dataclass with :data:`SPEC_CONFIG`.

    Positional arguments are passed on by name, so that an error names the field
    (``JointSet(0, -1.0)``: ``spacing_m``) where pydantic would name the argument's index.
    Pickling, :func:`dataclasses.replace` and validation from a mapping are unchanged.

    A Python call that fails raises the ``ValidationError`` with each problem restated on its
    first line as ``key + field`` and the message (``Cracks: cracks.size_m Input should be
    greater than 0``), so that a message can be matched on ``field must ...`` whatever pydantic's
    layout. Validation inside a config section does not go through ``__init__`` and keeps its
    ``file: section.key: message`` form.

    Parameters
    ----------
    key : str, default ""
        Prefix of the field names in those first lines (``"cracks."``).
    type_errors : bool, default False
        Raise ``TypeError`` (naming the field) when every problem is a value of the wrong type,
        for library types whose callers rely on that convention (the size distributions).
    """
    if cls is None:
        return functools.partial(spec, key=key, type_errors=type_errors)
    cls = dataclass(frozen=True, config=SPEC_CONFIG)(cls)
    names = [name for name, info in cls.__pydantic_fields__.items() if info.init is not False]
    keys = {name: info.alias for name, info in cls.__pydantic_fields__.items() if info.alias}
    validate = cls.__init__

    @functools.wraps(validate)
    def __init__(self, *args: Any, **kwargs: Any) -> None:
        if len(args) > len(names):
            raise TypeError(f"{cls.__name__} takes at most {len(names)} positional arguments, "
                            f"got {len(args)}")
        for name, value in zip(names, args):
            if name in kwargs:
                raise TypeError(f"{cls.__name__} got two values for {name!r}")
            kwargs[name] = value
        for name, alias in keys.items():
            if name in kwargs:
                if alias in kwargs:
                    raise TypeError(f"{cls.__name__} got two values for {name!r}")
                kwargs[alias] = kwargs.pop(name)
        try:
            validate(self, **kwargs)
        except ValidationError as exc:
            raise _restated(exc, cls.__name__, key, type_errors,
                            {alias: name for name, alias in keys.items()}) from None

    cls.__init__ = __init__
    return cls


def _restated(exc: ValidationError, title: str, key: str, type_errors: bool,
              names: dict[str, str]) -> Exception:
    """``exc`` with every problem also stated as ``key + field message`` in its title line, and
    located at the Python names of fields that have a config alias (``names``: alias to name)."""
    errors = exc.errors(include_url=False)
    for e in errors:
        if e["loc"] and e["loc"][0] in names:
            e["loc"] = (names[e["loc"][0]], *e["loc"][1:])
    lines = "; ".join(f"{key}{'.'.join(map(str, e['loc']))} {e['msg']}" for e in errors)
    if type_errors and all(e["type"].endswith("_type") for e in errors):
        return TypeError(f"{title}: {lines}, got {', '.join(repr(e['input']) for e in errors)}")
    details = [InitErrorDetails(
        type=PydanticCustomError(e["type"], "{message}", {"message": e["msg"]}),
        loc=e["loc"], input=e["input"]) for e in errors]
    return ValidationError.from_exception_data(f"{title}: {lines}", details)


def field_error(owner: Any, field: str, message: str, value: Any) -> ValidationError:
    """A ``ValidationError`` located at ``field`` of ``owner`` (a class or instance).

    Raise it from a ``model_validator(mode="after")`` for a rule between fields, so that the error
    names the field (and, read from TOML, its key path ``solve.monitors[1].point_xy_m``) rather
    than the whole table.
    """
    title = owner.__name__ if isinstance(owner, type) else type(owner).__name__
    detail = InitErrorDetails(
        type=PydanticCustomError("rockmass_field", "{message}", {"message": message}),
        loc=(field,), input=value)
    return ValidationError.from_exception_data(title, [detail])
