"""The strict base of every config section (:class:`StrictModel`) and the cross-field error helper.

Kept apart from :mod:`rockmass.config` so that stage-section modules (``dfn_config``,
``blocks_config``, ...) can import it while :mod:`rockmass.config` imports them: the typing rules
are described in :mod:`rockmass.config`.
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ConfigDict, ValidationError
from pydantic_core import InitErrorDetails, PydanticCustomError

__all__ = ["StrictModel", "field_problem"]


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


def field_problem(
    model: type[BaseModel] | BaseModel, field: str, message: str, value: Any
) -> ValidationError:
    """A validation error attached to ``field`` of ``model``, for cross-field checks.

    Raise the returned error from a ``model_validator(mode="after")``: pydantic then reports it at the
    field's own location (``fractal.range_px``) rather than at the section.

    Parameters
    ----------
    model : pydantic model class or instance
        The model being validated (used for the error title).
    field : str
        Name of the offending field in that model.
    message : str
        What is wrong and what is expected, including the bad value.
    value : object
        The offending value.

    Returns
    -------
    pydantic.ValidationError
    """
    title = model.__name__ if isinstance(model, type) else type(model).__name__
    detail = InitErrorDetails(
        type=PydanticCustomError("rockmass_field", "{message}", {"message": message}),
        loc=(field,),
        input=value,
    )
    return ValidationError.from_exception_data(title, [detail])
