"""Regenerate the field inputs of ``samples/quickstart.toml`` (deterministic: the same files on every
machine with the same library versions).

    python samples/make_quickstart.py

Two synthetic field records of a tunnel heading north (+y) whose face is the vertical plane y = 0:

- ``quickstart_face.png`` (+ ``quickstart_face_truth.geojson``, ``quickstart_face_meta.json``): a
  12 m x 8 m face photographed at 0.02 m/px (600 x 400 px), rendered by
  :func:`rockmass.imaging.synthetic.synthetic_face` ("easy" style) from the traces realization 0 of
  the 3D network :data:`TRUTH` leaves on the face (:func:`rockmass.dfn.sample_plane`); the
  ground-truth traces are written beside it. The face frame (u right, v up, origin at the photo's
  bottom-left) is the plane frame of a face looking North (:func:`rockmass.dfn.plane_frame`: u =
  West, v = up) with its origin at (6, 0, -4) m, so the photo shows x = 6 ... -6 m, z = -4 ... 4 m.
- ``quickstart_scanline.csv``: a virtual scanline along the tunnel wall, (-3, 0.5, 0) to
  (-3, 30.5, 0) m (trend 0, plunge 0, 30 m), through the same realization
  (:func:`rockmass.dfn.validation.virtual_scanline`).

Ground truth: set A dip 70 / dip direction 030, set B 60 / 200, Fisher kappa 40, P32 0.5 m²/m³
each, power-law radii (alpha 2.5, 1.5 to 20 m). The face and the scanline are two samples of one
realization, so they agree with each other and with the truth up to the sampling error of one
12 m x 8 m face and one 30 m line. (Before session 24 the face was drawn from a 2D network of its
own, about 2.5 times denser on the face than this 3D network, and the fit could not agree with both.)
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SEED = 7
M_PER_PX = 0.02
SHAPE_PX = (400, 600)
FACE_POINT_M = (6.0, 0.0, -4.0)
FACE_NORMAL = (0.0, 1.0, 0.0)  # a face looking North: dip 90, dip direction 000
SCANLINE = ((-3.0, 0.5, 0.0), (-3.0, 30.5, 0.0))
#: The 3D network the field data are drawn from (a ``[dfn]`` section).
TRUTH = {
    "seed": SEED,
    "domain": {"min_m": [-12.0, -2.0, -12.0], "max_m": [12.0, 33.0, 12.0]},
    "sets": [
        {"name": "A", "orientation": {"distribution": "fisher", "dip_deg": 70.0,
                                      "dip_direction_deg": 30.0, "kappa": 40.0},
         "size": {"distribution": "power_law", "r_min_m": 1.5, "r_max_m": 20.0, "alpha": 2.5},
         "intensity": {"measure": "P32", "value": 0.5}},
        {"name": "B", "orientation": {"distribution": "fisher", "dip_deg": 60.0,
                                      "dip_direction_deg": 200.0, "kappa": 40.0},
         "size": {"distribution": "power_law", "r_min_m": 1.5, "r_max_m": 20.0, "alpha": 2.5},
         "intensity": {"measure": "P32", "value": 0.5}},
    ],
}


def trace_angle_deg(dip_deg: float, dip_direction_deg: float) -> float:
    """Angle (0-180°, counter-clockwise from +u) of the traces a plane leaves on the face."""
    from rockmass.dfn.orientation import normal_from_dip
    from rockmass.dfn.sampling import plane_frame

    u, v, m = plane_frame(FACE_NORMAL)
    d = np.cross(normal_from_dip(dip_deg, dip_direction_deg), m)
    return math.degrees(math.atan2(float(d @ v), float(d @ u))) % 180.0


def realization():
    """Realization 0 of :data:`TRUTH` (the disks both field records sample)."""
    from rockmass.dfn.generation import generate
    from rockmass.dfn_config import DFNConfig

    cfg = DFNConfig.model_validate(TRUTH)
    return generate([s.to_spec() for s in cfg.sets], cfg.domain_m(), seed=cfg.seed, realization=0)


def face():
    """The synthetic face photo of the realization's traces on the face."""
    from rockmass.dfn import sample_plane
    from rockmass.imaging.synthetic import synthetic_face

    h, w = SHAPE_PX
    window = [(0.0, 0.0), (w * M_PER_PX, 0.0), (w * M_PER_PX, h * M_PER_PX), (0.0, h * M_PER_PX)]
    traces = sample_plane(realization(), FACE_POINT_M, FACE_NORMAL, window)
    return synthetic_face("easy", seed=SEED, shape_px=SHAPE_PX, m_per_px=M_PER_PX, traces=traces)


def scanline_csv() -> str:
    """The virtual scanline survey through realization 0 of :data:`TRUTH`."""
    from rockmass.dfn.validation import virtual_scanline

    survey = virtual_scanline(realization(), *SCANLINE)
    lines = ["# Virtual scanline along the quickstart tunnel's wall through one realization of the",
             "# 3D network of samples/make_quickstart.py (TRUTH); written by that script.",
             f"# trend: {survey.trend_deg:.6f}", f"# plunge: {survey.plunge_deg + 0.0:.6f}",
             f"# length: {survey.length_m:.6f}",
             "# start: " + ", ".join(f"{v:g}" for v in SCANLINE[0]),
             "distance_m,dip_deg,dip_direction_deg"]
    lines += [f"{d:.4f},{a:.2f},{b:.2f}" for d, a, b in
              zip(survey.distance_m, survey.dip_deg, survey.dip_direction_deg)]
    return "\n".join(lines) + "\n"


def main(directory: Path = HERE) -> None:
    """Write the quickstart's input files into ``directory``."""
    import cv2
    from rockmass.atomic import atomic_path, atomic_write_json, atomic_write_text
    from rockmass.dfn import write_traces

    f = face()
    with atomic_path(directory / "quickstart_face.png") as tmp:
        if not cv2.imwrite(str(tmp), f.image):
            raise OSError("could not write quickstart_face.png")
    write_traces(f.truth, directory / "quickstart_face_truth.geojson")
    atomic_write_json(directory / "quickstart_face_meta.json", {
        "m_per_px": f.m_per_px, "difficulty": f.difficulty, "seed": f.seed, "shape_px": list(SHAPE_PX),
        "face_point_m": list(FACE_POINT_M), "face_normal": list(FACE_NORMAL),
        "trace_angles_deg": [trace_angle_deg(s["orientation"]["dip_deg"],
                                             s["orientation"]["dip_direction_deg"]) for s in TRUTH["sets"]],
        "truth_3d": TRUTH})
    atomic_write_text(directory / "quickstart_scanline.csv", scanline_csv())


if __name__ == "__main__":
    main()
