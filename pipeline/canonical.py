"""The canonical text and hash of a configuration (:func:`canonical_json`, :func:`config_hash`).

Kept apart from :mod:`rockmass.config` (which re-exports both), so that writing a manifest
(:mod:`rockmass.manifest`) does not import pydantic: ``rockmass extract`` without ``--config``
then never does. Only the standard library and
:mod:`rockmass.atomic` are imported here.
"""

from __future__ import annotations

import hashlib
import json
import sys
from typing import Any

from .atomic import to_jsonable

__all__ = ["canonical_json", "config_hash"]


def canonical_json(obj: Any) -> str:
    """Canonical JSON text of a configuration: sorted keys, no whitespace, floats by ``repr``.

    Parameters
    ----------
    obj : pydantic model, mapping, dataclass or JSON-like value
        A pydantic model is dumped with ``model_dump(mode="json")``, i.e. *resolved*: defaults are
        filled in, so a file that spells out a default and one that omits it give the same text.
        NaN and ±Infinity are refused (:func:`rockmass.atomic.to_jsonable`).

    Returns
    -------
    str

    Notes
    -----
    ``1`` and ``1.0`` are different texts; for a validated model this cannot happen, because each field
    has one type (a float field stores ``2`` as ``2.0``). Adding a section to
    :class:`~rockmass.config.RockmassConfig` adds ``"section":null`` to every canonical text, so
    hashes are comparable only between the same rockmass version (which the manifest records).

    Examples
    --------
    >>> canonical_json({"b": 1, "a": [1.5, None]})
    '{"a":[1.5,null],"b":1}'
    """
    pydantic = sys.modules.get("pydantic")  # a model exists only once pydantic is imported
    if pydantic is not None and isinstance(obj, pydantic.BaseModel):
        obj = obj.model_dump(mode="json")
    plain = to_jsonable(obj)
    return json.dumps(plain, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=False)


def config_hash(obj: Any) -> str:
    """SHA-256 hex digest of :func:`canonical_json` of ``obj`` (UTF-8).

    Examples
    --------
    >>> from rockmass.config import RockmassConfig
    >>> empty = {"imaging": None, "fractal": None, "dfn": None, "blocks": None, "solve": None}
    >>> config_hash(RockmassConfig()) == config_hash(empty)
    True
    """
    return hashlib.sha256(canonical_json(obj).encode("utf-8")).hexdigest()
