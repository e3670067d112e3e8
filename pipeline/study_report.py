"""``report.html`` of a study: one self-contained page (PNG images embedded as base64, no script,
no network). Only cases in equilibrium are compared: every statistic (means, ± spread) and the main
series of the plots use the cases whose outcome is ``ok`` (:data:`rockmass.study.OUTCOMES`); cases
whose blocks failed are shown apart, and the others are listed with their reason. The page has

- a summary line ("N of M cases in equilibrium; K with failed blocks (fall a, slide b); ...") and
  the number of cases per outcome;
- D_box against the maximum displacement, one colour per value of the colouring field (θ, as in
  Jiang et al., Figs. 7–8; docs/sources.md §1): every ``ok`` realization as a dot, the mean of each parameter
  combination with ± one standard deviation over its ``ok`` realizations in both directions; the
  ``failed_blocks`` cases as crosses at the displacement of the blocks left in equilibrium
  (labelled "blocks failed"; never averaged); cases not in equilibrium are not plotted;
- the spread over realizations: D_box and displacement of every combination;
- the cases with failed blocks (count, area, mechanisms), the cases not in equilibrium
  (not_converged, unstable, overlap, error) with the solver's diagnostic or the error;
- a summary table per combination (mean ± sd and n over its ``ok`` cases, its other outcomes) and
  the table of every case (as results.csv).

:func:`report_data` returns the numbers the page shows, as plain data.
"""

from __future__ import annotations

import base64
import html
import json
import math
from collections import OrderedDict

from .html_report import BASE_CSS, figure, pyplot
from .html_report import fmt as _fmt
from .html_report import png_base64 as _png
from .html_report import table as _table

__all__ = ["write_report", "report_data", "colour_field", "groups"]

#: What each outcome means, for the report's outcome table.
OUTCOME_MEANING = {
    "ok": "every static stage reached equilibrium, no block failed: compared and averaged",
    "failed_blocks": "blocks kept moving (fall, slide, rotation) and were taken out; the rest "
                     "reached equilibrium: shown apart (crosses), never averaged",
    "not_converged": "a static stage reached max_steps without equilibrium: listed, not plotted",
    "unstable": "the solver stopped the run (energy ledger or time step): listed, not plotted",
    "overlap": "the solver stopped the run (blocks overlapping): listed, not plotted",
    "error": "an exception (missing file, bad model, lost worker): listed; a re-run retries it",
}


def colour_field(study, cases) -> str | None:
    """The field that colours the plots: ``study.colour_by``, else θ when it varies, else the
    first varying field."""
    if study.colour_by:
        return study.colour_by
    varying = []
    for c in cases:
        for p in c.params:
            if p not in varying:
                varying.append(p)
    for p in varying:
        if p.endswith("theta_deg"):
            return p
    return varying[0] if varying else None


def _value(case, path):
    from .study_config import get_path

    if path in case.params:
        return case.params[path]
    return get_path(case.raw, path)


def _label(value) -> str:
    if isinstance(value, float) and value.is_integer():
        return f"{value:g}"
    return json.dumps(value) if isinstance(value, (list, dict)) else str(value)


def groups(cases, records: dict) -> "OrderedDict[str, list]":
    """Parameter combination (the case's params as text) -> [(case, record)] over realizations
    (every outcome; the statistics pick the ``ok`` ones)."""
    out: OrderedDict[str, list] = OrderedDict()
    for c in cases:
        rec = records.get(c.case_id)
        if rec is None:
            continue
        key = json.dumps(c.params, sort_keys=True)
        out.setdefault(key, []).append((c, rec))
    return out


def _mean_sd(values):
    """(mean, sample standard deviation, n) of the finite values; (None, None, 0) without any."""
    vals = [v for v in values if v is not None and math.isfinite(v)]
    if not vals:
        return None, None, 0
    m = sum(vals) / len(vals)
    sd = math.sqrt(sum((v - m) ** 2 for v in vals) / (len(vals) - 1)) if len(vals) > 1 else 0.0
    return m, sd, len(vals)


def _reason(rec) -> str:
    """Why a case is not compared: its failed blocks' mechanisms, or its diagnostic / error."""
    if rec.get("status") == "failed_blocks":
        return (f"{rec.get('failed_blocks')} blocks failed ({rec.get('failed_mechanisms') or '-'}), "
                f"{_fmt(rec.get('failed_area_m2'))} m²")
    return str(rec.get("error") or "")


def report_data(study, cases, records: dict) -> dict:
    """The numbers of the report, as plain data.

    Parameters
    ----------
    study : StudyConfig
        ``[study]`` (``displacement`` chooses the boundary or overall displacement).
    cases : list of StudyCase
    records : dict
        Case id -> case record (every outcome; cases without a record are "not run").

    Returns
    -------
    dict
        ``outcomes`` (cases per outcome), ``summary`` (:func:`rockmass.study.outcome_summary`),
        ``groups``: per
        parameter combination ``params``, ``n`` (cases with a record), ``outcomes``, and over its
        ``ok`` cases only ``n_ok``, ``d_box``, ``d_box_r2``, ``p21_per_m``, ``n_blocks``,
        ``displacement_m`` (each ``{"mean", "sd", "n"}``, sample sd); ``failed_block_cases``
        (case, params, realization, d_box, ``displacement_m`` of the blocks left in equilibrium,
        failed_blocks, failed_area_m2, failed_mechanisms) and ``not_in_equilibrium`` (case,
        params, realization, status, reason).
    """
    from .study import displacement_m, outcome_counts, outcome_summary

    recs = [records[c.case_id] for c in cases if c.case_id in records]
    out = {"outcomes": outcome_counts(recs), "summary": outcome_summary(recs, len(cases)),
           "groups": [],
           "failed_block_cases": [], "not_in_equilibrium": []}
    for members in groups(cases, records).values():
        c0 = members[0][0]
        ok = [r for _, r in members if r.get("status") == "ok"]
        entry = {"params": c0.text, "n": len(members), "n_ok": len(ok),
                 "outcomes": outcome_counts(r for _, r in members)}
        for k in ("d_box", "d_box_r2", "p21_per_m", "n_blocks"):
            m, sd, n = _mean_sd([r.get(k) for r in ok])
            entry[k] = {"mean": m, "sd": sd, "n": n}
        m, sd, n = _mean_sd([displacement_m(r, study.displacement) for r in ok])
        entry["displacement_m"] = {"mean": m, "sd": sd, "n": n}
        out["groups"].append(entry)
    for c in cases:
        rec = records.get(c.case_id)
        if rec is None or rec.get("status") == "ok":
            continue
        base = {"case": c.index, "params": c.text,
                "realization": c.realization}
        if rec.get("status") == "failed_blocks":
            out["failed_block_cases"].append({
                **base, "d_box": rec.get("d_box"),
                "displacement_m": displacement_m(rec, study.displacement),
                "failed_blocks": rec.get("failed_blocks"),
                "failed_area_m2": rec.get("failed_area_m2"),
                "failed_mechanisms": rec.get("failed_mechanisms")})
        else:
            out["not_in_equilibrium"].append({**base, "status": rec.get("status"),
                                              "reason": _reason(rec)})
    return out


def _figures(study, cases, records) -> list[tuple[str, str]]:
    from .study import displacement_m

    plt = pyplot()
    figs = []
    cfield = colour_field(study, cases)
    grouped = groups(cases, records)
    has_disp = any(displacement_m(r, study.displacement) is not None for r in records.values())

    def y_of(rec):
        """The plotted value (mm, or P21 without [solve]): None when the case is not plotted."""
        if has_disp:
            d = displacement_m(rec, study.displacement)
            return None if d is None else d * 1e3
        return rec.get("p21_per_m") if rec.get("status") == "ok" else None

    colour_values = []
    for c in cases:
        v = _label(_value(c, cfield)) if cfield else "all"
        if v not in colour_values:
            colour_values.append(v)
    cmap = plt.get_cmap("tab10")
    colours = {v: cmap(i % 10) for i, v in enumerate(colour_values)}
    cname = (cfield or "").rsplit(".", 1)[-1]
    symbol = "θ" if cname == "theta_deg" else cname
    plotted = [y for r in records.values() if r.get("d_box") is not None
               for y in [y_of(r)] if y is not None]
    positive = [y for y in plotted if y > 0]
    log_y = bool(positive) and max(positive) > 100 * min(positive)

    # 1. D_box vs maximum displacement (Jiang et al., Figs. 7–8): ok cases; failed blocks apart
    fig, ax = plt.subplots(figsize=(7.0, 5.0))
    where = " around the excavation" if study.displacement == "boundary" else ""
    ylab = f"maximum displacement{where} (mm)\nblocks in equilibrium"
    series: dict[str, list] = {}
    shown: list[str] = []  # colour values with a point (a series or a cross), legend order
    crosses = False
    for members in grouped.values():
        c0 = members[0][0]
        cv = _label(_value(c0, cfield)) if cfield else "all"
        pts = [(r["d_box"], y_of(r)) for _, r in members
               if r.get("status") == "ok" and r.get("d_box") is not None and y_of(r) is not None]
        fails = [(r["d_box"], y_of(r)) for _, r in members
                 if r.get("status") == "failed_blocks" and r.get("d_box") is not None
                 and y_of(r) is not None]
        if (fails or pts) and cv not in shown:
            shown.append(cv)
        if fails:
            crosses = True
            ax.scatter([p[0] for p in fails], [p[1] for p in fails], marker="x", s=40,
                       color=colours[cv], linewidths=1.5)
        if not pts:
            continue
        ax.scatter([p[0] for p in pts], [p[1] for p in pts], s=16, alpha=0.5, color=colours[cv],
                   linewidths=0)
        md, sd_d, _ = _mean_sd([p[0] for p in pts])
        my, sd_y, _ = _mean_sd([p[1] for p in pts])
        yerr = None
        if sd_y:  # on a log axis the bar stops short of zero
            yerr = [[min(sd_y, 0.9 * my) if log_y else sd_y], [sd_y]]
        ax.errorbar(md, my, xerr=sd_d or None, yerr=yerr, fmt="o", ms=6,
                    color=colours[cv], capsize=3)
        series.setdefault(cv, []).append((md, my))
    for cv in shown:  # a colour whose cases all failed blocks has no line, but a legend entry
        pts = sorted(series.get(cv, []))
        ax.plot([p[0] for p in pts], [p[1] for p in pts], "-", color=colours[cv], lw=1.2,
                label=f"{symbol} = {cv}" + ("°" if cname.endswith("_deg") else ""))
    if crosses:
        ax.scatter([], [], marker="x", s=40, color="0.3", linewidths=1.5, label="blocks failed")
    if log_y:
        ax.set_yscale("log")
    ax.set_xlabel("fractal dimension D_box (360 × 360 box counting)")
    ax.set_ylabel(ylab if has_disp else "P21 (m/m²)")
    ax.set_title("Maximum displacement versus fractal dimension" if has_disp
                 else "Joint intensity versus fractal dimension (no [solve] section)")
    if shown:
        ax.legend(title=None, frameon=False)
    ax.grid(alpha=0.3)
    figs.append(("D_box versus maximum displacement of the blocks in equilibrium, coloured by "
                 + (cfield or "case") + "; dots: realizations in equilibrium (ok), markers: their "
                 "mean ± sd; crosses: blocks failed (the displacement of the blocks left in "
                 "equilibrium, never averaged); cases not in equilibrium are not plotted"
                 if has_disp else "D_box versus P21 (the base config has no [solve] section)",
                 _png(fig)))
    plt.close(fig)

    # 2. spread over realizations, per combination
    labels, dvals, yvals, xd, xy, cols = [], [], [], [], [], []
    for members in grouped.values():
        c0 = members[0][0]
        ok = [r for _, r in members if r.get("status") == "ok"]
        labels.append(c0.text)
        dvals.append([r["d_box"] for r in ok if r.get("d_box") is not None])
        yvals.append([y_of(r) for r in ok if y_of(r) is not None] if has_disp else [])
        fails = [r for _, r in members if r.get("status") == "failed_blocks"]
        xd.append([r["d_box"] for r in fails if r.get("d_box") is not None])
        xy.append([y_of(r) for r in fails if y_of(r) is not None] if has_disp else [])
        cols.append(colours[_label(_value(c0, cfield)) if cfield else "all"])
    if labels:
        panels = 2 if has_disp else 1
        fig, axes = plt.subplots(panels, 1, figsize=(max(6.0, 0.45 * len(labels) + 2), 2.6 * panels + 1),
                                 sharex=True, squeeze=False)
        for ax, vals, xvals, name in zip(axes[:, 0], (dvals, yvals), (xd, xy),
                                         ("D_box", "max displacement (mm)")):
            disp = name.startswith("max")
            for i, (v, col) in enumerate(zip(vals, cols)):
                ax.scatter([i] * len(v), v, s=14, color=col, alpha=0.7, linewidths=0)
                if xvals[i]:
                    ax.scatter([i] * len(xvals[i]), xvals[i], marker="x", s=30, color=col)
                m, sd, n = _mean_sd(v)
                if m is not None:
                    err = None
                    if sd:
                        err = [[min(sd, 0.9 * m) if (log_y and disp) else sd], [sd]]
                    ax.errorbar(i + 0.18, m, yerr=err, fmt="_", ms=10, color="k", capsize=3)
            ax.set_ylabel(name)
            if log_y and disp:
                ax.set_yscale("log")
            ax.grid(alpha=0.3)
        axes[-1, 0].set_xticks(range(len(labels)))
        axes[-1, 0].set_xticklabels(labels, rotation=60, ha="right", fontsize=7)
        figs.append(("Spread over realizations for every parameter combination: dots, cases in "
                     "equilibrium (ok), with their mean ± sd (black); crosses: blocks failed",
                     _png(fig)))
        plt.close(fig)
    return figs


def _model_thumbnails(study, cases, records, config_path, limit: int = 6) -> list[tuple[str, str]]:
    """Block plots of representative cases: for each colour value, the realization-0 cases with
    the smallest and the largest D_box (models rebuilt from their configs, a second or so each)."""
    import tempfile
    from pathlib import Path

    from .blockgen import plot_blocks
    from .study import _build_model, displacement_m

    cfield = colour_field(study, cases)
    picks: dict[str, list] = {}
    for c in cases:
        rec = records.get(c.case_id)
        if rec is None or rec.get("d_box") is None or c.realization != 0:
            continue
        picks.setdefault(_label(_value(c, cfield)) if cfield else "all", []).append((c, rec))
    chosen = []
    for members in picks.values():
        members.sort(key=lambda m: m[1]["d_box"])
        for m in (members[0], members[-1]):
            if m not in chosen:
                chosen.append(m)
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for i, (c, rec) in enumerate(chosen[:limit]):
            try:
                model = _build_model(c.document, config_path)
                path = plot_blocks(model, Path(tmp) / f"case{i}.png", dpi=50)
            except Exception:  # noqa: BLE001 - a missing thumbnail must not stop the report
                continue
            disp = displacement_m(rec, study.displacement)
            cap = (f"case {c.index}: {c.text}; D_box "
                   f"{rec['d_box']:.3f}, {model.n_blocks} blocks"
                   + (f", max displacement {disp * 1e3:.3g} mm" if disp is not None else "")
                   + (f"; {rec.get('status')}: {_reason(rec)}" if rec.get("status") != "ok"
                      else ""))
            out.append((cap, base64.b64encode(path.read_bytes()).decode("ascii")))
    return out


def _pm(stat: dict, scale: float = 1.0) -> str:
    """``mean ± sd`` of a :func:`report_data` statistic (empty without a value)."""
    if stat["mean"] is None:
        return ""
    return f"{stat['mean'] * scale:.4g} ± {stat['sd'] * scale:.2g}"


def write_report(path, document, cases, finished: dict, failed: dict, summary: dict,
                 config_path) -> None:
    """Write ``report.html`` (atomically). ``finished``: the records of every case with an outcome
    other than error; ``failed``: the error records (both case id -> record)."""
    from .atomic import atomic_write_text
    from .study import OUTCOMES, results_rows

    study = document.study
    records = {**finished, **failed}
    data = report_data(study, cases, records)
    figs = _figures(study, cases, records) if records else []
    srows = []
    for g in data["groups"]:
        others = ", ".join(f"{o} {n}" for o, n in g["outcomes"].items() if n and o != "ok")
        srows.append([g["params"], str(g["n"]), str(g["n_ok"]), _pm(g["d_box"]),
                      _pm(g["d_box_r2"]), _pm(g["p21_per_m"]), _pm(g["n_blocks"]),
                      _pm(g["displacement_m"], 1e3), others])
    sheader = ["parameters", "cases", "ok (n)", "D_box", "R²", "P21 (1/m)", "blocks",
               "max displacement (mm)", "other outcomes"]
    oheader = ["outcome", "cases", "meaning"]
    orows = [[o, str(data["outcomes"][o]), OUTCOME_MEANING[o]] for o in OUTCOMES]
    fheader = ["case", "parameters", "realization", "D_box",
               "max displacement of the blocks in equilibrium (mm)", "failed blocks",
               "failed area (m²)", "mechanisms"]
    frows = [[str(f["case"]), f["params"], str(f["realization"]), _fmt(f["d_box"]),
              _fmt(None if f["displacement_m"] is None else f["displacement_m"] * 1e3),
              _fmt(f["failed_blocks"]), _fmt(f["failed_area_m2"]), f["failed_mechanisms"] or ""]
             for f in data["failed_block_cases"]]
    nheader = ["case", "parameters", "realization", "status", "reason"]
    nrows = [[str(f["case"]), f["params"], str(f["realization"]), str(f["status"]), f["reason"]]
             for f in data["not_in_equilibrium"]]
    header, rows = results_rows(cases, records, study.displacement)
    rows = [[_fmt(float(x)) if _is_float(x) else x for x in r] for r in rows]
    try:
        thumbs = _model_thumbnails(study, cases, records, config_path) if records else []
    except Exception:  # noqa: BLE001
        thumbs = []
    thumbs_html = "".join(figure(cap, b64, "thumb") for cap, b64 in thumbs)
    images = "".join(figure(cap, b64) for cap, b64 in figs)
    info = (f"{summary['finished']} of {summary['cases']} cases finished, {summary['failed']} "
            f"failed with an error, {summary['skipped']} reused from an earlier run; executor: "
            f"{summary['executor']}; status: {summary['status']}")
    grid = document.fractal.grid if document.fractal else 360
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>rockmass study report</title>
<style>
{BASE_CSS}.thumbs {{ display: flex; flex-wrap: wrap; gap: 1em; }}
figure.thumb {{ width: 360px; margin: 0; }}
#outcomes td:last-child, #not-in-equilibrium td:last-child {{ text-align: left; }}
</style></head><body>
<h1>rockmass study</h1>
<p id="outcome-summary"><strong>{html.escape(data['summary'])}.</strong></p>
<p>Config: <code>{html.escape(str(config_path))}</code>. {html.escape(info)}.</p>
<p>D_box: box counting of the joint network (joint sets and traces clipped to the domain, without
excavation outlines or dangling-end extensions) rasterised on a {grid} × {grid} grid (Jiang et al.
§4.1). Maximum displacement: {'of the blocks on the excavation boundary' if study.displacement ==
'boundary' else 'of any block'} that stay in equilibrium (failed blocks and slivers left out), after
the last DEM stage, from the initial equilibrium. Means, spreads and the plotted series use the cases
in equilibrium (ok) only; a case whose blocks failed is shown apart, never averaged.</p>
<h2>Outcomes</h2>
{_table(oheader, orows, "outcomes")}
<h2>Plots</h2>
{images or '<p>No finished case yet.</p>'}
<h2>Cases with failed blocks</h2>
{_table(fheader, frows, "failed-blocks") if frows else '<p>None.</p>'}
<h2>Cases not in equilibrium</h2>
{_table(nheader, nrows, "not-in-equilibrium") if nrows else '<p>None.</p>'}
<h2>Block models</h2>
<p>For each {html.escape(colour_field(study, cases) or 'case')} value, the realization-0 cases with the
smallest and largest D_box (excavation stages shaded; edges coloured by joint set).</p>
<div class="thumbs">{thumbs_html or '<p>None.</p>'}</div>
<h2>Per parameter combination (mean ± sd over the realizations in equilibrium)</h2>
{_table(sheader, srows, "combinations")}
<h2>All cases (results.csv)</h2>
{_table(header, rows, "cases")}
</body></html>
"""
    atomic_write_text(path, page)


def _is_float(text: str) -> bool:
    if not text or not any(ch in text for ch in ".e") or text.startswith(("[", "{")):
        return False
    try:
        float(text)
    except ValueError:
        return False
    return True
