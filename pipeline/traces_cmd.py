"""``rockmass traces FILE``: statistics of a digitised trace map.

Reads traces (GeoJSON, CSV, GeoPackage or Shapefile), computes the trace-map statistics of
:func:`rockmass.dfn.trace_map_statistics` (joint sets, P20, P21, trace lengths with censoring,
Mauldon estimators on the window when it is a circle, else on disjoint circles placed inside it,
I-Y-X-E topology) and the box-counting dimension of
:func:`rockmass.fractal.box_count` over the same window, and writes under ``--out DIR``:
``summary.json``, ``rose.png`` (length-weighted, equal-area, axial), ``traces.png`` (the map by set)
and ``manifest.json`` — all of them or none. ``--json`` prints the summary to stdout. ``--gis gpkg``
(or ``shp``) also writes the map as GIS layers with fractopo's field names: ``traces.gpkg`` with
the layers ``traces``, ``area``, ``nodes`` and ``branches`` (or ``traces.shp``, ``traces_area.shp``,
``traces_nodes.shp``, ``traces_branches.shp``; :func:`rockmass.traces_stage.gis_layers`). GeoPackage
and Shapefile need the optional pyogrio (``pip install 'rockmass[gis]'``).

Zero-length traces are dropped with a warning and counted (``input.dropped_zero_length``); a map of
more than ``--max-traces`` traces (default 200 000, or ``ROCKMASS_MAX_TRACES``) is refused before
its statistics start (exit 2; :func:`rockmass.budgets.check_traces`).
"""

from __future__ import annotations

import argparse

from .budgets import DEFAULT_MAX_TRACES, MAX_TRACES_ENV, TRACE_SECONDS, trace_limit_arg
from .outputs import print_summary
from .traces_stage import GIS_FORMATS, produce

__all__ = ["add_parser", "run"]


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register the ``traces`` subcommand."""
    p = subparsers.add_parser(
        "traces", help="statistics of a digitised trace map (sets, P20, P21, topology, D)",
        description="Joint sets, intensities (P20, P21), trace lengths with censoring, Mauldon "
                    "estimators, topology and the box-counting dimension of a trace map.")
    p.add_argument("file", help="traces (.geojson, .json, .csv, .gpkg or .shp)")
    p.add_argument("--layer", help="the traces layer of a GeoPackage with several line layers (default: "
                                   "the only line layer, else the one named 'traces')")
    p.add_argument("--area", metavar="POLYGON.geojson|bbox|hull",
                   help="the mapped area: a GeoJSON, GeoPackage or Shapefile with one polygon (in "
                        "the map's CRS; a GeoPackage of traces may hold it as its polygon layer), or "
                        "'bbox' / 'hull' to take the traces' bounding box / convex hull, named in "
                        "every output (default: the map's own window polygon; a map without one "
                        "needs --area)")
    p.add_argument("--sets", type=int, dest="n_sets",
                   help="number of joint sets (default: chosen by BIC over 1-5)")
    p.add_argument("--snap-tolerance", type=float, dest="snap_tolerance_m",
                   help="topology snap tolerance in metres (default 1e-4 x window diameter)")
    p.add_argument("--max-traces", type=trace_limit_arg, dest="max_traces", metavar="N",
                   help=f"refuse a map of more than N traces before the statistics start (default "
                        f"{DEFAULT_MAX_TRACES}, or the environment variable {MAX_TRACES_ENV}; "
                        f"about {TRACE_SECONDS:.1e} s a trace)")
    p.add_argument("--gis", choices=GIS_FORMATS,
                   help="also write the traces, area, nodes and branches as GIS layers with "
                        "fractopo's field names under --out: traces.gpkg, or traces*.shp "
                        "(needs pyogrio: pip install 'rockmass[gis]')")
    p.add_argument("--out", help="write summary.json, rose.png, traces.png and manifest.json here")
    p.add_argument("--json", action="store_true", help="print the summary as JSON on stdout")
    p.set_defaults(handler=run)
    return p


#: A fitted set whose circular spread exceeds this (degrees) is named broad in the printed summary:
#: its mean resultant length on doubled angles is then under 0.38 (spread = ½√(−2 ln R̄),
#: docs/fractures.md §3.2), closer to scattered directions than to one joint set (the two clear
#: sets of the public KB11 map spread 6°, the quickstart photo's traces of a Fisher κ = 40 set 11°).
BROAD_SET_SPREAD_DEG = 40.0


def summary_text(summary: dict) -> str:
    """A few human-readable lines: counts, intensities (with their units), sets and D."""
    def value(key, fmt=".4g"):
        q = summary[key]
        text = "undefined" if q["value"] is None else format(q["value"], fmt)
        return text if q.get("unit") in (None, "-") else f"{text} {q['unit']}"

    area = summary.get("input", {}).get("area") or {}
    lines = [f"{value('Number of Traces', 'd')} traces, P20 = {value('Areal Frequency P20')}, "
             f"P21 = {value('Fracture Intensity P21')}, mean length {value('Trace Mean Length')}, "
             f"D_box = {value('Box-counting Dimension', '.4f')}"]
    if area:
        lines.append(f"  area {value('Area')}: {area['text']}")
    checked = summary.get("validation") or {}
    if checked:
        flagged = ", ".join(f"{label} {n}" for label, n in checked["errors"].items() if n)
        lines.append(f"  fractopo validation: {checked['traces_flagged']} of "
                     f"{summary['Number of Traces']['value']} traces flagged" + (f" ({flagged})" if flagged else ""))
    dropped = summary.get("input", {}).get("dropped_zero_length") or {}
    if dropped.get("count"):
        lines.append(f"  {dropped['count']} zero-length traces dropped (not counted)")
    azimuth = summary.get("angle_convention") == "azimuth"
    crs = summary.get("crs")
    lines.append(f"  angles: {summary.get('angle_convention_text', '')}"
                 + (f"; crs {crs}" if crs else f"; {summary.get('frame', 'face')} frame, no CRS"))
    for s in summary["sets"]:
        spread = s["Circular Spread"]["value"]
        mean = s["Mean Angle"]["value"]
        mean_text = f"azimuth {mean:05.1f}°" if azimuth else f"mean angle {mean:.1f}°"
        lines.append(f"  set {s['Set']}: {mean_text}, spread "
                     f"{'undefined' if spread is None else format(spread, '.1f') + '°'}, "
                     f"{s['Number of Traces']['value']} traces")
    broad = [s["Set"] for s in summary["sets"] if s["Circular Spread"]["value"] is None
             or s["Circular Spread"]["value"] > BROAD_SET_SPREAD_DEG]
    if broad and len(summary["sets"]) > 1:
        lines.append(f"  note: set{'s' if len(broad) > 1 else ''} {', '.join(map(str, broad))} "
                     f"spread{'' if len(broad) > 1 else 's'} over {BROAD_SET_SPREAD_DEG:g}°: traces "
                     "of scattered directions more than a joint set; --sets N fixes the number of sets")
    return "\n".join(lines)


def run(args) -> int:
    """Handler of ``rockmass traces``."""
    if args.gis and not args.out:
        from .errors import InputError

        raise InputError(f"--gis {args.gis} writes its layers under --out DIR; give --out")
    print_summary(produce(args, args.out), args.json, summary_text)
    return 0
