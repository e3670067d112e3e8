"""Face photographs to joint traces (polylines in metres on the face frame).

- :func:`extract` — the chain of docs/imaging.md §2-§7: illumination flattening, multi-scale ridge filter
  for dark lines, hysteresis threshold, cleanup, skeleton graph, spur pruning, X-node repair, gap
  bridging, linking of pieces that continue one another (:mod:`~rockmass.imaging.link`),
  simplified polylines in metres; every setting in :class:`ExtractParams`.
- :mod:`~rockmass.imaging.face_mask` — the rock face against the image border, over-exposed
  regions, lining / shotcrete / sky and machinery (``ExtractParams.face_mask``; a ROI replaces it).
- :mod:`~rockmass.imaging.metrics` — accuracy against ground truth (buffered F1, P21 / P20, set
  angles, D_box, nodes).
- :mod:`~rockmass.imaging.synthetic` — synthetic face photographs with known traces (easy /
  moderate / hard) and the trace-network generator behind them.
- :mod:`~rockmass.imaging.synthetic_field` — field-like synthetic faces (wide shadowed joints, step
  edges, plates, rubble, crevices, oriented texture) labelled at the major joints' centre lines.
- :mod:`~rockmass.imaging.learned` — the learned joint detector (``ExtractParams(detector=
  "learned")``): per-pixel features (:mod:`~rockmass.imaging.features`) and the shipped classifier;
  trained by :mod:`~rockmass.imaging.train_pixel_model` on synthetic faces only.
- :mod:`~rockmass.imaging.joint_net` — a convolutional joint detector (``pixel_model = "cnn"``,
  and among "auto"'s candidates by default, ``auto_network_ratio``), run by OpenCV from an ONNX
  file; trained by :mod:`~rockmass.imaging.train_joint_net` (PyTorch, training only) on synthetic
  faces and on joints drawn over the random textures of :mod:`~rockmass.imaging.rock_textures`.
- :mod:`~rockmass.imaging.frame` — pixel (row, col) <-> face frame (u, v) metres, the one place the
  conversion happens.
"""

from .enhance import flatten_illumination, read_photo, to_grey
from .extract import ExtractParams, Extraction, ScaleInfo, extract, scale_from_control_points
from .face_mask import FaceMaskParams, face_mask, face_mask_cues
from .frame import rc_to_uv, uv_to_rc
from .learned import joint_probability, load_model
from .link import extend_to_border, link_traces
from .metrics import (Accuracy, buffered_match, count_nodes, raster_match, render_traces,
                      set_mean_angles, trace_accuracy)
from .ridges import ridge_response, ridge_sigmas
from .segment import hysteresis_mask, robust_thresholds, roi_mask, segment_ridges
from .skeleton_graph import (SkeletonGraph, bridge_gaps, build_graph, chain_traces, prune_spurs,
                             repair_crossings, skeletonize)
from .synthetic import (DIFFICULTIES, FaceStyle, JointSetSpec, SyntheticFace, joints_on_photo,
                        save_synthetic_face, synthetic_face, synthetic_network)
from .synthetic_field import FieldStyle, field_face
from .vectorize import axial_angle_deg, simplify_polylines, to_trace_map

__all__ = [
    "extract", "ExtractParams", "Extraction", "ScaleInfo", "scale_from_control_points",
    "read_photo", "to_grey", "flatten_illumination",
    "ridge_response", "ridge_sigmas",
    "segment_ridges", "hysteresis_mask", "roi_mask", "robust_thresholds",
    "face_mask", "face_mask_cues", "FaceMaskParams",
    "joint_probability", "load_model",
    "SkeletonGraph", "skeletonize", "build_graph", "prune_spurs", "repair_crossings", "bridge_gaps",
    "chain_traces", "link_traces", "extend_to_border",
    "to_trace_map", "axial_angle_deg", "simplify_polylines",
    "trace_accuracy", "Accuracy", "buffered_match", "raster_match", "render_traces", "count_nodes",
    "set_mean_angles",
    "rc_to_uv", "uv_to_rc",
    "DIFFICULTIES", "FaceStyle", "JointSetSpec", "SyntheticFace", "synthetic_face", "joints_on_photo",
    "synthetic_network", "save_synthetic_face", "FieldStyle", "field_face",
]
