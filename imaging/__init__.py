"""Face photographs to joint traces (polylines in metres on the face frame).

Available now:

- :mod:`rockmass.imaging.frame` — pixel (row, col) <-> face frame (u, v) metres, the one place the
  conversion happens;
- :mod:`rockmass.imaging.synthetic` — synthetic face photographs with known traces (difficulty
  levels easy / moderate / hard) and the trace-network generator behind them.

The extraction chain (issue "Traces from face photographs") comes next.
"""

from .frame import rc_to_uv, uv_to_rc
from .synthetic import (DIFFICULTIES, FaceStyle, JointSetSpec, SyntheticFace, save_synthetic_face,
                        synthetic_face, synthetic_network)

__all__ = ["rc_to_uv", "uv_to_rc", "DIFFICULTIES", "FaceStyle", "JointSetSpec", "SyntheticFace",
           "synthetic_face", "synthetic_network", "save_synthetic_face"]
