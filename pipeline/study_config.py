"""``[study]``: a base config (the stage sections of the same file) and the cases derived from it.

A study file is an ordinary rockmass config (``[blocks]``, ``[solve]``, ``[fractal]``, ...: the
*base*) plus a ``[study]`` section that says which fields vary::

    [study]
    realizations = 3                   # seeds per parameter combination
    seed = 0                           # root seed of the realizations

    [study.grid]                       # cartesian product over these fields (dotted paths)
    blocks.two_sets.theta_deg = [40.0, 60.0, 90.0]
    blocks.two_sets.spacing_m = [[4.0, 6.0], [6.0, 8.0]]

    [[study.cases]]                    # and/or an explicit list of override sets
    "blocks.two_sets.alpha_deg" = 0.0

Field paths are dotted key paths into the document, with list indices in brackets
(``blocks.excavations[0].span_m``, ``solve.joints.default.friction_deg``); in ``[study.grid]`` and
``[[study.cases]]`` they may be written as nested TOML keys (unquoted dots) or as one quoted key.
The cases are every ``[[study.cases]]`` entry (or the base alone when there is none) combined with
every point of the grid, each run ``realizations`` times. Realization ``r`` writes the seed
``realization_seed(seed, r)`` into every field of ``seed_fields`` (default ``blocks.seed``, plus
``dfn.seed`` when the base has a ``[dfn]`` section), so every parameter combination sees the same
seeds (common random numbers: differences between combinations are not sampling noise).

Every case is validated as a whole document *before any case runs*; a problem names the study field
that caused it and the case. A case's id is the SHA-256 of its resolved config (defaults filled in,
:func:`rockmass.config.config_hash`) and of the files it reads, so a finished case is recognised
whatever the order of the grid, and changing one value re-runs only the cases it touches.
"""

from __future__ import annotations

import copy
import hashlib
import itertools
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import Field, ValidationError, model_validator

from .config import RockmassConfig, canonical_json, problems_from_validation_error
from .errors import ConfigError
from .strict import StrictModel, config_file, field_problem, file_fields, in_folder

__all__ = ["StudyConfig", "StudyDocument", "StudyCase", "load_study", "expand_cases",
           "realization_seed", "parse_path", "set_path", "get_path", "flatten_overrides",
           "toml_text", "standalone_config", "input_records", "params_text"]

MAX_CASES = 100_000
_PATH_TOKEN = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)|\[(\d+)\]")
_PATH = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\[\d+\])*(\.[A-Za-z_][A-Za-z0-9_]*(\[\d+\])*)*$")


#: The key of a ``[[study.cases]]`` table that names its cases rather than overriding a field.
LABEL_KEY = "label"
#: Longest case label (characters).
MAX_LABEL = 60


def case_overrides(entry: dict) -> dict:
    """A ``[[study.cases]]`` table without its :data:`LABEL_KEY`: the field overrides alone."""
    return {k: v for k, v in entry.items() if k != LABEL_KEY}


class StudyConfig(StrictModel):
    """``[study]``: what varies across the cases of a study.

    Parameters
    ----------
    grid : table of field path -> list of values, default {}
        Cartesian product over the fields (each list non-empty, values as the field expects them).
    cases : list of tables of field path -> value, default []
        Explicit override sets; combined with every grid point. A ``label`` key (a line of text of
        at most 60 characters, :data:`MAX_LABEL`) names its cases in results.csv (``label`` column), ``--list``,
        the progress lines and the report, in place of their field values; it is not part of the
        config, so it changes no case id.
    realizations : int, default 1
        Seeds per parameter combination, 1..10000.
    seed : int, default 0
        Root seed; realization r uses :func:`realization_seed` (seed, r).
    seed_fields : list of str or None, default None
        Fields that receive the realization's seed; None: ``blocks.seed`` (and ``dfn.seed`` when the
        base has ``[dfn]``).
    colour_by : str or None, default None
        Field whose value colours the report's plots; None: ``blocks.two_sets.theta_deg`` when it
        varies, else the first varying field.
    displacement : {"boundary", "overall"}, default "boundary"
        The report's maximum displacement (results.csv ``max_displacement_m``): of the blocks on
        the excavation boundary (around the opening, as Jiang et al.) or of any block, after the
        last stage, over the blocks that stay in equilibrium (failed blocks left out). Both are in
        results.csv.
    """

    grid: dict[str, Any] = Field(default_factory=dict)
    cases: Annotated[list[dict[str, Any]], Field(max_length=MAX_CASES)] = Field(default_factory=list)
    realizations: int = Field(1, ge=1, le=10_000)
    seed: int = Field(0, ge=0, lt=2 ** 63)
    seed_fields: Annotated[list[str], Field(max_length=16)] | None = None
    colour_by: str | None = None
    displacement: Literal["boundary", "overall"] = "boundary"

    @model_validator(mode="after")
    def _shapes(self):
        for name in ("grid",):
            try:
                flat = flatten_overrides(self.grid)
            except ValueError as exc:
                raise field_problem(self, name, str(exc), self.grid) from None
            for path, values in flat.items():
                if not isinstance(values, list):
                    raise field_problem(self, name, f"{path}: must be a list of values (one per "
                                        f"grid point), got {values!r}", values)
                if not values:
                    raise field_problem(self, name, f"{path}: empty list (a grid needs at least "
                                        "one value per field)", values)
        for i, entry in enumerate(self.cases):
            label = entry.get(LABEL_KEY)
            if label is not None and not (isinstance(label, str) and 0 < len(label.strip()) and
                                          len(label) <= MAX_LABEL and label.isprintable()):
                raise field_problem(self, "cases", f"[{i}].{LABEL_KEY}: must be a line of text of 1 to "
                                    f"{MAX_LABEL} characters, got {label!r}", label)
            try:
                flat = flatten_overrides(case_overrides(entry))
            except ValueError as exc:
                raise field_problem(self, "cases", f"[{i}]: {exc}", entry) from None
            if not flat:
                raise field_problem(self, "cases", f"[{i}]: empty table (give at least one field "
                                    "path = value)", entry)
        for path in [*(self.seed_fields or []), *([self.colour_by] if self.colour_by else [])]:
            if not _PATH.match(path):
                raise field_problem(self, "seed_fields", f"not a field path: {path!r} (expected "
                                    "e.g. blocks.seed)", path)
        return self


class StudyDocument(RockmassConfig):
    """A study file: every stage section of :class:`RockmassConfig` plus ``[study]``.

    Parameters
    ----------
    study : StudyConfig
        ``[study]`` section (the cases of ``rockmass study``; required in a study file).
    """

    study: StudyConfig


# ------------------------------------------------------------------------------------- paths


def parse_path(path: str) -> list[str | int]:
    """``"blocks.excavations[0].span_m"`` -> ``["blocks", "excavations", 0, "span_m"]``.

    >>> parse_path("blocks.excavations[0].span_m")
    ['blocks', 'excavations', 0, 'span_m']
    """
    if not _PATH.match(path):
        raise ValueError(f"not a field path: {path!r} (expected dotted keys with [index] for "
                         "list items, e.g. blocks.two_sets.theta_deg)")
    return [name if name else int(index) for name, index in _PATH_TOKEN.findall(path)]


def flatten_overrides(table: dict, prefix: str = "") -> dict[str, Any]:
    """Nested TOML tables of overrides -> ``{dotted path: value}`` (a leaf is any non-table value).

    >>> flatten_overrides({"blocks": {"two_sets": {"theta_deg": [40, 60]}}, "solve.sleep": [True]})
    {'blocks.two_sets.theta_deg': [40, 60], 'solve.sleep': [True]}
    """
    out: dict[str, Any] = {}
    for key, value in table.items():
        path = f"{prefix}.{key}" if prefix else str(key)
        if isinstance(value, dict):
            out.update(flatten_overrides(value, path))
        else:
            parse_path(path)
            if path in out:
                raise ValueError(f"{path}: given twice")
            out[path] = value
    return out


def get_path(doc: Any, path: str) -> Any:
    """The value at ``path`` in nested dicts/lists, or None when a part is missing."""
    node = doc
    for key in parse_path(path):
        if isinstance(key, int):
            if not isinstance(node, list) or key >= len(node):
                return None
        elif not isinstance(node, dict) or key not in node:
            return None
        node = node[key]
    return node


def set_path(doc: dict, path: str, value: Any) -> None:
    """Write ``value`` at ``path`` in nested dicts/lists (missing tables are created).

    Raises
    ------
    ValueError
        When the path goes through a value that is not a table, or indexes past the end of a list.
    """
    keys = parse_path(path)
    node: Any = doc
    for depth, key in enumerate(keys):
        last = depth == len(keys) - 1
        here = _show(keys[:depth + 1])
        if isinstance(key, int):
            if not isinstance(node, list):
                raise ValueError(f"{here}: {_show(keys[:depth]) or 'the document'} is not a list")
            if key >= len(node):
                raise ValueError(f"{here}: index out of range (the base config has {len(node)} "
                                 f"entries in {_show(keys[:depth])})")
        else:
            if not isinstance(node, dict):
                raise ValueError(f"{here}: {_show(keys[:depth])} is not a table")
            if not last and key not in node:
                node[key] = {} if isinstance(keys[depth + 1], str) else []
        if last:
            node[key] = copy.deepcopy(value)
        else:
            node = node[key]


def _show(keys: list[str | int]) -> str:
    out = ""
    for k in keys:
        out += f"[{k}]" if isinstance(k, int) else (f".{k}" if out else k)
    return out


# ------------------------------------------------------------------------------------- seeds


def realization_seed(root: int, realization: int) -> int:
    """Seed of realization ``r``: 63 bits of the child with spawn key ``(r,)`` of
    ``SeedSequence(root)`` (docs/design.md §3.5), the same whichever case, order or worker runs it.

    >>> realization_seed(0, 0) == realization_seed(0, 0) != realization_seed(0, 1)
    True
    """
    import numpy as np

    words = np.random.SeedSequence(root, spawn_key=(realization,)).generate_state(2, np.uint32)
    return int((int(words[0]) << 31) ^ int(words[1])) & (2 ** 63 - 1)


# ------------------------------------------------------------------------------------- cases


@dataclass(frozen=True)
class StudyCase:
    """One case of a study: its overrides, realization, seed, resolved document and id."""

    index: int
    params: dict            # field path -> value (grid and list overrides, in the study's order)
    realization: int
    seed: int
    raw: dict               # the case's config as TOML data (base + overrides), without [study]
    document: Any           # validated RockmassConfig
    case_id: str            # 64 hex digits
    inputs: dict = field(default_factory=dict)  # files read by the case -> sha256
    label: str = ""         # the ``label`` of its [[study.cases]] table, if any
    grid_paths: tuple = ()  # the fields of ``params`` set by study.grid

    @property
    def short_id(self) -> str:
        return self.case_id[:16]

    @property
    def text(self) -> str:
        """How the case is named to the user: its label (with the grid's values, when it also has
        grid fields), else its field values (:func:`params_text`), else ``base config``."""
        if self.label:
            grid = params_text({k: v for k, v in self.params.items() if k in self.grid_paths})
            return f"{self.label} ({grid})" if grid else self.label
        return params_text(self.params) or "base config"


def load_study(config_path: str | os.PathLike) -> tuple[StudyDocument, dict]:
    """Load and validate a study file; return (document, raw TOML data)."""
    import tomllib

    from .config import load_config

    document = load_config(config_path, StudyDocument)
    # load_config validated the text; read the raw data again to build the cases from
    raw = tomllib.loads(Path(config_path).read_bytes().decode("utf-8-sig"))
    return document, raw


def _seed_fields(study: StudyConfig, base: dict) -> list[str]:
    if study.seed_fields is not None:
        return list(study.seed_fields)
    fields = ["blocks.seed"]
    if "dfn" in base:
        fields.append("dfn.seed")
    return fields


def _hash_once(path, digests: dict) -> str:
    """SHA-256 of ``path`` ("missing" when it cannot be read), hashed once per distinct path:
    ``digests`` maps path -> (sha256, bytes), or None for a file that is missing or unreadable."""
    from .errors import InputError
    from .manifest import file_sha256

    key = os.fspath(path)
    if key not in digests:
        try:
            digests[key] = file_sha256(path)
        except InputError:
            digests[key] = None
    found = digests[key]
    return "missing" if found is None else found[0]


def _input_files(document, config_path, digests: dict) -> dict[str, str]:
    """Files a case reads besides the config -> sha256 or "missing" (their content is part of the
    case id; a missing file fails its case when it runs, not the study). They are the file keys
    (:data:`rockmass.strict.ConfigFile`) of the sections a case runs, ``[blocks]`` and ``[solve]``.
    ``digests``: see :func:`_hash_once`."""
    paths = [config_file(config_path, name) for _, name in _case_files(document)]
    return {os.fspath(p): _hash_once(p, digests) for p in paths}


def _case_files(document) -> list[tuple[list[str | int], str]]:
    """(key path, name) of every file key of the ``[blocks]`` and ``[solve]`` sections."""
    return [([section, *keys], name) for section in ("blocks", "solve")
            for keys, name in file_fields(getattr(document, section))]


def input_records(digests: dict) -> list[dict]:
    """Manifest ``inputs`` records of the files the cases read, from the digests taken when the
    cases were expanded (:func:`expand_cases`; nothing is hashed again): ``{"path", "sha256",
    "bytes"}`` sorted by path, and ``"missing": true`` with null hash and size for a file that could
    not be read."""
    records = []
    for path in sorted(digests):
        found = digests[path]
        if found is None:
            records.append({"path": path, "sha256": None, "bytes": None, "missing": True})
        else:
            records.append({"path": path, "sha256": found[0], "bytes": found[1]})
    return records


def expand_cases(document: StudyDocument, raw: dict, config_path,
                 digests: dict | None = None) -> list[StudyCase]:
    """Every case of the study, validated; raises :class:`ConfigError` (exit 2) naming the study
    field and the case before anything runs.

    ``digests``: a dict filled with path -> (sha256, bytes), or None when missing, for every file a
    case reads, each distinct path hashed once (pass one to record the inputs in a manifest with
    :func:`input_records` without hashing them again)."""
    from .config import config_hash

    shown = os.fspath(config_path)
    study = document.study
    base = {k: v for k, v in raw.items() if k != "study"}
    if document.blocks is None:
        raise ConfigError(shown, [("blocks", "a study builds a block model per case: the base "
                                   "config needs a [blocks] section")])
    grid = flatten_overrides(study.grid)
    listed = [flatten_overrides(case_overrides(entry)) for entry in study.cases] or [{}]
    labels = [entry.get(LABEL_KEY, "") for entry in study.cases] or [""]
    seed_fields = _seed_fields(study, base)
    problems: list[tuple[str, str]] = []
    for path in seed_fields:
        if path in grid or any(path in entry for entry in listed):
            problems.append(("study.seed_fields", f"{path} is set by the realizations and also "
                             "varied by study.grid / study.cases; vary one or the other"))
    for path in grid:
        if any(path in entry for entry in listed):
            problems.append((f"study.grid.{path}", "also set in study.cases; give each field in "
                             "one place"))
    problems += _colour_by_problems(study.colour_by, grid, listed, seed_fields, base)
    if problems:
        raise ConfigError(shown, problems)
    n = len(listed) * study.realizations
    for values in grid.values():
        n *= len(values)
    if n > MAX_CASES:
        raise ConfigError(shown, [("study", f"{n} cases; at most {MAX_CASES} per study (split it)")])

    digests = {} if digests is None else digests
    cases: list[StudyCase] = []
    seen: dict[str, int] = {}
    grid_paths = list(grid)
    for entry_index, entry in enumerate(listed):
        for point in itertools.product(*grid.values()):
            params = {**entry, **dict(zip(grid_paths, point))}
            for r in range(study.realizations):
                seed = realization_seed(study.seed, r)
                data = copy.deepcopy(base)
                for path, value in params.items():
                    where = (f"study.cases[{entry_index}].{path}" if path in entry
                             else f"study.grid.{path}")
                    try:
                        set_path(data, path, value)
                    except ValueError as exc:
                        raise ConfigError(shown, [(where, str(exc))]) from None
                for path in seed_fields:
                    try:
                        set_path(data, path, seed)
                    except ValueError as exc:
                        raise ConfigError(shown, [("study.seed_fields", str(exc))]) from None
                index = len(cases)
                try:
                    doc = RockmassConfig.model_validate(data)
                except ValidationError as exc:
                    raise ConfigError(shown, _case_problems(exc, data, params, entry, index,
                                                            entry_index, seed_fields)) \
                        from None
                if doc.solve is not None and doc.solve.blocks_file is not None:
                    raise ConfigError(shown, [("solve.blocks_file", "a study builds each case's "
                                               "blocks from its [blocks] section and does not "
                                               "read blocks_file: remove it (rockmass solve "
                                               "solves a blocks.json)")])
                inputs = _input_files(doc, config_path, digests)
                digest = hashlib.sha256(canonical_json(
                    {"config_hash": config_hash(doc), "inputs": inputs}).encode()).hexdigest()
                if digest in seen:
                    raise ConfigError(shown, [("study", f"cases {seen[digest]} and {index} are the "
                                               f"same config ({params_text(params) or 'the base config'}); a study "
                                               "runs each config once")])
                seen[digest] = index
                cases.append(StudyCase(index, params, r, seed, data, doc, digest, inputs,
                                       label=labels[entry_index], grid_paths=tuple(grid_paths)))
    return cases


def _colour_by_problems(colour_by, grid: dict, listed: list[dict], seed_fields: list[str],
                        base: dict) -> list[tuple[str, str]]:
    """``study.colour_by`` must name a field whose value the report can read from each case: one
    the study varies (grid, cases, seed fields) or a value of the base config (not a table);
    otherwise the plots would silently go uncoloured. The problem lists the varying fields."""
    if not colour_by:
        return []
    varying = list(dict.fromkeys([*grid, *(p for entry in listed for p in entry), *seed_fields]))
    value = get_path(base, colour_by)
    if colour_by in varying or (value is not None and not isinstance(value, dict)):
        return []
    what = "is a table, not a field" if isinstance(value, dict) else "names no field of the cases"
    return [("study.colour_by", f"{colour_by!r} {what}; give one of the fields the study varies "
             f"({', '.join(varying)}) or a field set in the base config")]


def params_text(params: dict) -> str:
    """A case's parameters as ``theta_deg=60.0, ...`` (empty for the base config): the last part of
    each field path, or the whole path when two fields share it.

    >>> params_text({"blocks.two_sets.theta_deg": 60.0, "dfn.sets[0].intensity.value": 1.0,
    ...              "dfn.sets[1].intensity.value": 2.0})
    'theta_deg=60.0, dfn.sets[0].intensity.value=1.0, dfn.sets[1].intensity.value=2.0'
    """
    last = [k.rsplit(".", 1)[-1] for k in params]
    return ", ".join(f"{k if last.count(n) > 1 else n}={v}" for k, n, v in
                     zip(params, last, params.values()))


def _case_problems(exc: ValidationError, data: dict, params: dict, entry: dict, index: int,
                   entry_index: int = 0, seed_fields=()):
    """(field, message) problems of a case that fails validation, each charged to the study field
    that set the value when one did (``study.cases[entry_index]``, ``study.grid`` or
    ``study.seed_fields``), naming the case and its parameters."""
    case = f"study case {index}: {params_text(params) or 'the base config'}"
    problems = []
    for fld, message in problems_from_validation_error(exc, RockmassConfig, data):
        culprit = next((p for p in params if fld == p or fld.startswith(p + ".")
                        or fld.startswith(p + "[") or p.startswith(fld + ".")), None)
        if culprit is not None:
            where = (f"study.cases[{entry_index}].{culprit}" if culprit in entry
                     else f"study.grid.{culprit}")
            message = f"{fld}: {message} ({case})"
            problems.append((where, message))
        elif fld in seed_fields:  # a seed field that names no field of the config
            problems.append(("study.seed_fields", f"{fld}: {message} ({case})"))
        else:
            problems.append((fld, f"{message} ({case})"))
    return problems


# ------------------------------------------------------------------------------------- TOML out

_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")


def _key(key: str) -> str:
    import json

    return key if _BARE_KEY.match(key) else json.dumps(key, ensure_ascii=False)


def _inline(value: Any) -> str:
    import json
    import math

    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"TOML config values must be finite, got {value!r}")
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_inline(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_inline(v)}" for k, v in value.items()) + " }"
    raise TypeError(f"cannot write {type(value).__name__} as TOML")


def _is_table_array(value: Any) -> bool:
    return isinstance(value, list) and bool(value) and all(isinstance(v, dict) for v in value)


def _emit(table: dict, prefix: list[str], lines: list[str]) -> None:
    for k, v in table.items():
        if not isinstance(v, dict) and not _is_table_array(v):
            lines.append(f"{_key(k)} = {_inline(v)}")
    for k, v in table.items():
        if isinstance(v, dict):
            lines.extend(["", "[" + ".".join(map(_key, [*prefix, k])) + "]"])
            _emit(v, [*prefix, k], lines)
        elif _is_table_array(v):
            for item in v:
                lines.extend(["", "[[" + ".".join(map(_key, [*prefix, k])) + "]]"])
                _emit(item, [*prefix, k], lines)


def toml_text(data: dict) -> str:
    """TOML text of a config document (tables, arrays of tables, scalars and arrays), such that
    ``tomllib.loads(toml_text(d)) == d``.

    >>> print(toml_text({"blocks": {"seed": 1, "two_sets": {"spacing_m": [6.0, 8.0]},
    ...                  "excavations": [{"shape": "circle"}]}}), end="")
    <BLANKLINE>
    [blocks]
    seed = 1
    <BLANKLINE>
    [blocks.two_sets]
    spacing_m = [6.0, 8.0]
    <BLANKLINE>
    [[blocks.excavations]]
    shape = "circle"
    """
    lines: list[str] = []
    _emit(data, [], lines)
    return "\n".join(lines) + "\n"


def standalone_config(case: StudyCase, config_path) -> dict:
    """The case's config as a file of its own: the TOML data with the files it names made absolute
    (they were relative to the study's config), ready for ``rockmass blocks`` / ``rockmass solve``."""
    data = copy.deepcopy(case.raw)
    base = Path(os.path.abspath(config_path)).parent
    for keys, name in _case_files(case.document):
        path = _show(keys)
        if get_path(data, path) == name:
            set_path(data, path, str(in_folder(base, name)))
    return data
