"""The DFN section of ``report.html`` (:mod:`rockmass.run_report`): the realizations of the run,
each set's orientation and size law, P32 target and achieved, the validation against the field data
and the contoured disk poles of the first realization.
"""

from __future__ import annotations

import html
from typing import TYPE_CHECKING

from .html_report import figure, fmt, note, png_base64, table
from .report_files import _Note, _rel

if TYPE_CHECKING:
    from .run_report import _Run

__all__: list[str] = []  # private to rockmass.run_report


def _realizations(run: _Run) -> tuple[list[tuple[int, dict]], list[str]]:
    """(index, summary.json) of every ``dfn/realization_NNNN`` folder, in order, and the notes of
    those whose summary cannot be read."""
    out, notes = [], []
    folders = [f for f in sorted(run.dirs["dfn"].glob("realization_*"))
               if f.is_dir() and f.name[12:].isdigit()]
    if not folders:
        raise _Note(f"{_rel(run.dirs['dfn'], run.out)} holds no realization_NNNN folder")
    for folder in folders:
        try:
            out.append((int(folder.name[12:]), run.read(folder / "summary.json")))
        except _Note as exc:
            notes.append(f"{exc}.")
    return out, notes


def _set_laws(run: _Run) -> dict[str, tuple[str, str, str]]:
    """Set name -> (source, orientation text, size-law text), from fitted.json then the config."""
    laws = {}
    try:
        config = (run.json("dfn", "manifest.json").get("config") or {}).get("dfn") or {}
    except _Note:
        config = {}
    for s in config.get("sets") or []:
        o, size = s.get("orientation") or {}, dict(s.get("size") or {})
        law = _size_text(size.pop("distribution", ""), size)
        laws[s.get("name")] = ("config", _orientation_text(o), law)
    if (run.dirs["dfn"] / "fitted.json").exists():
        for s in run.json("dfn", "fitted.json").get("sets") or []:
            size = s.get("size") or {}
            law = (_size_text(size.get("family", ""), size.get("params") or {}) if size.get("ok", True)
                   else f"none ({size.get('reason', '')})")
            if size.get("ok", True) and size.get("note"):  # e.g. an exponent the traces do not bound
                law += f" (note: {size['note']})"
            laws[s.get("name")] = ("fitted", _orientation_text(s.get("orientation") or {}), law)
    return laws


def _orientation_text(o: dict) -> str:
    from .dfn.orientation import dip_text

    # dip/dip direction as the command line prints them (issue 19: the report said 69/29)
    text = f"{o.get('distribution', '')} {dip_text(o.get('dip_deg'), o.get('dip_direction_deg'))}"
    return text + (f", κ {fmt(o.get('kappa'), 3)}" if o.get("kappa") is not None else "")


def _size_text(family: str, params: dict) -> str:
    return f"{family} " + ", ".join(f"{k} {fmt(v, 4)}" for k, v in params.items())


def _section_dfn(run: _Run) -> str:
    """Per set: orientation and size law (fitted or given), P32 target and achieved per realization."""
    realizations, notes = run.realizations()
    try:
        laws = _set_laws(run)
        law_note = ""
    except _Note as exc:
        laws, law_note = {}, note(f"{exc}.")
    rows = []
    for i, summary in realizations:
        for s in summary.get("sets") or []:
            source, orient, size = laws.get(s.get("name"), ("", "", ""))
            rows.append([str(i), str(s.get("name", s.get("set"))), source, orient, size,
                         fmt(s.get("target_p32")), fmt(s.get("achieved_p32")), fmt(s.get("count"))])
    head = ["realization", "set", "from", "orientation (dip/dip dir.)", "size law (radius)",
            "P32 target (m²/m³)", "P32 achieved (m²/m³)", "disks"]
    try:
        density = _dfn_pole_density(run, realizations[0][0]) if realizations else ""
    except _Note as exc:
        density = note(f"{exc}.")
    return (table(head, rows, "t-dfn") + _dfn_validation(run, [i for i, _ in realizations]) + law_note
            + "".join(note(n) for n in notes) + density)


#: Disks of a realization drawn in its pole density at most (every k-th beyond: the density of a few
#: thousand poles is already smooth, and the plot stays about a second).
_MAX_DENSITY_POLES = 5000


def _dfn_pole_density(run: _Run, index: int) -> str:
    """Contoured stereonet of the disk poles of realization ``index`` (its fractures.csv), with the
    set mean poles the DFN was generated from (fitted.json, else the config)."""
    import numpy as np

    from .dfn.orientation import normal_from_dip
    from .dfn.stereonet import kamb_kappa, plot_pole_density

    path = run.dirs["dfn"] / f"realization_{index:04d}" / "fractures.csv"
    try:
        with path.open(encoding="utf-8") as fh:
            header = fh.readline().strip().split(",")
            columns = [header.index(c) for c in ("nx", "ny", "nz")]
            normals = np.loadtxt(fh, delimiter=",", usecols=columns, ndmin=2)
    except FileNotFoundError:
        raise _Note(f"{_rel(path, run.out)} is missing") from None
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise _Note(f"{_rel(path, run.out)} is not a readable fracture table ({exc})") from None
    if normals.shape[0] == 0:
        return note(f"{_rel(path, run.out)} holds no disk: no pole density to draw.")
    step = -(-normals.shape[0] // _MAX_DENSITY_POLES)
    poles = normals[::step]
    kappa = min(kamb_kappa(poles.shape[0]), 100.0)
    sets = []
    if (run.dirs["dfn"] / "fitted.json").exists():
        sets = [s.get("orientation") or {} for s in run.json("dfn", "fitted.json").get("sets") or []]
    else:
        config = ((run.json("dfn", "manifest.json").get("config") or {}).get("dfn") or {}).get("sets") or []
        sets = [s.get("orientation") or {} for s in config]
    means = [normal_from_dip(o["dip_deg"], o["dip_direction_deg"]) for o in sets
             if isinstance(o.get("dip_deg"), (int, float)) and isinstance(o.get("dip_direction_deg"), (int, float))]
    fig = plot_pole_density(poles, kappa=kappa, set_means=means or None,
                            title=f"Realization {index}: disk poles (lower hemisphere, equal area)")
    every = f", every {step}th of {normals.shape[0]} disks" if step > 1 else ""
    caption = (f"Density of the poles of the {poles.shape[0]} disks of realization {index}{every}, in "
               f"multiples of a uniform density (lower hemisphere, equal area; Fisher kernel k = "
               f"{fmt(kappa, 3)}: Kamb's 3 σ circle in Vollmer's form, at most 100, a cone of about 8°); "
               "squares: the set mean poles it was generated from. Disks are counted, not weighted by area")
    return figure(caption, png_base64(fig), "small")


def _dfn_validation(run: _Run, indices: list[int]) -> str:
    """One line per realization re-sampled with the field geometry (validation.json, with
    ``[dfn.fit] validate = true``): how many measured quantities it reproduces within tolerance."""
    lines = []
    for i in indices:
        path = run.dirs["dfn"] / f"realization_{i:04d}" / "validation.json"
        if not path.exists():
            continue
        try:
            rows = run.read(path).get("rows") or []
            ok = sum(1 for r in rows if r.get("ok"))
            lines.append(f"realization {i}: {ok} of {len(rows)} field measures within tolerance")
        except (_Note, AttributeError) as exc:
            lines.append(f"realization {i}: {exc}")
    if not lines:
        return ""
    return f'<p id="dfn-validation">Validation against the field data: {html.escape("; ".join(lines))}.</p>'

