"""Seed 002 §4 (Varma et al. 2019, Figs. 10–19): each parameter's trend beside the paper's.

    python benchmarks/seed002_trends.py out/study_shaketable/results.csv

Reads the results of ``rockmass study samples/study_shaketable.toml`` (one parameter changed at a
time from the shake-table model) and prints, per parameter, the tunnel-wall displacement after the
shaking of each case, the direction of the trend (rising / falling / flat: the change from the
smallest to the largest value against the baseline displacement, flat within ±20 % of it) and the
direction the paper reports, with whether they agree. The paper's directions (in its words):

- lateral stress ratio K (Fig. 10): "as the lateral stress coefficient increases, the tunnel
  deformations increase" — at a fixed horizontal stress; here K scales the horizontal stress at a
  vertical stress fixed by gravity, so the two are not the same experiment;
- joint normal stiffness (Fig. 17): deformation decreases (exponentially under dynamic load);
- joint shear stiffness (Fig. 18): "no considerable differences";
- friction angle (Fig. 19): deformation decreases (linearly);
- joint angles (Figs. 11, 14, 16): sets at 40°/0° and 50°/10° stable statically but failing in
  shaking; 70°/60° only surface settlement, no tunnel deformation.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

PARAMETERS = (  # (column, label, unit factor, the paper's direction)
    ("solve.insitu.k0", "lateral stress ratio K", 1.0, "rising"),
    ("solve.joints.default.kn_pa_m", "joint normal stiffness (GPa/m)", 1e-9, "falling"),
    ("solve.joints.default.ks_pa_m", "joint shear stiffness (GPa/m)", 1e-9, "flat"),
    ("solve.joints.default.friction_deg", "friction angle (deg)", 1.0, "falling"),
)
ANGLES = ("blocks.sets[0].angle_deg", "blocks.sets[1].angle_deg")
FLAT = 0.2  # a change within ±20 % of the baseline displacement counts as flat


def read(path: Path) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def displacement_mm(row: dict) -> float:
    """The tunnel-wall displacement in mm; a case that stopped (overlap, instability: the roof
    collapsing, as the paper's UDEC runs also stopped "because of the joint overlap error") counts
    as infinitely large."""
    if row["status"] not in ("ok", "failed_blocks"):
        return float("inf")
    return float(row.get("max_displacement_m") or "nan") * 1e3


def is_baseline(row: dict) -> bool:
    """The case that changes nothing but restates K = 0.43."""
    others = [c for c, *_ in PARAMETERS[1:]] + list(ANGLES)
    return all(not row.get(c) for c in others) and row.get(PARAMETERS[0][0]) == "0.43"


def direction(points: list[tuple[float, float]], baseline: float) -> str:
    """rising / falling / flat from the smallest to the largest parameter value."""
    points = sorted(points)
    low, high = points[0][1], points[-1][1]
    if low == high:  # both stopped, or equal
        return "flat"
    change = high - low
    if abs(change) <= FLAT * baseline:
        return "flat"
    return "rising" if change > 0 else "falling"


def main(path: Path) -> None:
    rows = read(path)
    base = next(r for r in rows if is_baseline(r))
    base_mm = displacement_mm(base)
    print(f"baseline (Table 1, K = 0.43, sets +45/-45 deg): {base_mm:.3f} mm, status {base['status']}")
    print(f"\n{'parameter':34s} {'values -> tunnel-wall displacement (mm)':52s} {'here':8s} "
          f"{'paper':8s} agree")
    for column, label, unit, paper in PARAMETERS:
        mine = [r for r in rows if r.get(column) and not any(r.get(a) for a in ANGLES)]
        points = [(float(r[column]) * unit, displacement_mm(r)) for r in mine]
        points = sorted(set(points + [(_baseline_value(column) * unit, base_mm)]))
        here = direction(points, base_mm)
        values = ", ".join(f"{v:g}: " + ("stop" if d == float("inf") else f"{d:.3f}")
                           for v, d in points)
        print(f"{label:34s} {values:52s} {here:8s} {paper:8s} {'yes' if here == paper else 'NO'}")
    print("\njoint angles (first set clockwise / second anticlockwise from horizontal):")
    for r in rows:
        if r.get(ANGLES[0]):
            second, first = float(r[ANGLES[0]]), 180.0 - float(r[ANGLES[1]])
            d = displacement_mm(r)
            shown = "stopped" if d == float("inf") else f"{d:.3f} mm"
            print(f"  {first:.0f} / {second:.0f} deg: {shown}, status {r['status']}, failed blocks "
                  f"{r.get('failed_blocks') or 0}")
    print("  paper: 40/0 and 50/10 fail in shaking (keyblocks out of the wall); 70/60 surface "
          "settlement only")


def _baseline_value(column: str) -> float:
    """The baseline's value of a parameter: Table 1 of the paper, K = 0.43 (the sample's)."""
    return {"solve.insitu.k0": 0.43, "solve.joints.default.kn_pa_m": 0.7e9,
            "solve.joints.default.ks_pa_m": 0.5e9, "solve.joints.default.friction_deg": 25.56}[column]


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__.split("\n\n")[1])
    main(Path(sys.argv[1]))
