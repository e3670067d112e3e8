"""The fracture data model and its files: trace maps, readers and writers.

Public names (each module's docstring gives the formulas and sources)
---------------------------------------------------------------------
:class:`TraceMap`
    Joint traces as polylines in metres in a named frame, with per-trace attributes and the sampling
    window polygon (:mod:`rockmass.dfn.tracemap`).
:func:`read_traces`, :func:`write_traces`
    GeoJSON or CSV by suffix (:mod:`rockmass.dfn.traceio`).
:func:`read_geojson`, :func:`write_geojson`, :func:`read_csv`, :func:`write_csv`, :func:`read_gis`, :func:`write_gis`
    The explicit readers and writers (:mod:`rockmass.dfn.geojson_io`, :mod:`rockmass.dfn.csv_io`;
    GeoPackage / Shapefile layers through the optional pyogrio, :mod:`rockmass.dfn.gis_io`).
:func:`branches_and_nodes`, :func:`validate_traces`
    fractopo's branch and node layers (:mod:`rockmass.dfn.branches`) and its trace validation
    labels (:mod:`rockmass.dfn.trace_validation`).
Frames (:mod:`rockmass.dfn.frames`)
    The CRS of a map (:func:`crs_kind`; geographic ones refused by :func:`check_crs`), the local CRS
    that names a face frame in files (:func:`local_crs_wkt`), and the convention of trace angles in
    outputs: azimuth clockwise from North on a map, counter-clockwise from +u on a face
    (:func:`angle_convention`, :func:`to_convention`).
:func:`signed_area`, :func:`polygon_area`
    The shoelace area of a polygon ring (:mod:`rockmass.dfn.polygon`), the one polygon-area formula
    of every stage that may import dfn (docs/fractures.md §1.3).
Trace-map statistics
    2D joint sets (:mod:`~rockmass.dfn.sets2d`), P20 / P21 / scanline spacing
    (:mod:`~rockmass.dfn.intensity`), Mauldon circular windows (:mod:`~rockmass.dfn.mauldon`),
    I-Y-X-E topology (:mod:`~rockmass.dfn.topology`) and the fractopo-named summary
    (:func:`trace_map_statistics`, :mod:`~rockmass.dfn.trace_stats`), with P21 per grid cell
    (:func:`p21_map`).
3D orientation and DFN primitives
    dip / dip direction, strike, trend / plunge conversions (:mod:`~rockmass.dfn.orientation`),
    Fisher sampling and fitting (:mod:`~rockmass.dfn.fisher`), stereology C13 / C23 and the P32
    solve (:mod:`~rockmass.dfn.stereology`), size distributions (:mod:`~rockmass.dfn.sizes`).
DFN generation and virtual sampling
    seeded disk networks filled to a clipped P32 (:mod:`~rockmass.dfn.generation`,
    :class:`DiskNetwork`), line and plane sampling (:mod:`~rockmass.dfn.sampling`), sections generated
    directly on a plane (:mod:`~rockmass.dfn.section`), ``fractures.csv`` / ``.vtu``
    (:mod:`~rockmass.dfn.network_io`).
Scanline surveys
    reading (:mod:`~rockmass.dfn.scanline`), 3D joint sets from poles (:mod:`~rockmass.dfn.sets3d`),
    P10, Terzaghi, spacing fits and RQD (:mod:`~rockmass.dfn.scanline_stats`), the contoured pole
    density of a stereonet (:func:`pole_density`, Kamb's kernel concentration :func:`kamb_kappa`;
    :mod:`~rockmass.dfn.stereonet`). Figures:
    :mod:`rockmass.dfn.plots` (rose, trace map) and :mod:`rockmass.dfn.stereonet`.
Fitting from field data and the closed loop
    disk radius laws from censored trace lengths (:mod:`~rockmass.dfn.size_fit`), orientation, size
    and P32 per set from scanlines and faces (:mod:`~rockmass.dfn.field_fit`), generate → sample →
    re-fit → compare (:mod:`~rockmass.dfn.validation`).

``rockmass.dfn`` depends on numpy and shapely only: it never imports the pipeline package
(``rockmass`` top-level modules) nor numba, matplotlib, OpenCV or scikit-image at import time.
The public names load on first use (PEP 562), so importing the package, or its standard-library-only
module :mod:`rockmass.dfn.atomic` (the atomic file writes that every rockmass writer shares), does
not load numpy or shapely either.
"""

from __future__ import annotations

import importlib as _importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .csv_io import read_csv, write_csv
    from .geojson_io import read_geojson, write_geojson
    from .traceio import read_traces, write_traces
    from .gis_io import read_gis, write_gis
    from .branches import BranchesAndNodes, branches_and_nodes
    from .trace_validation import TraceValidation, validate_traces
    from .tracemap import TraceMap
    from .frames import ANGLE_CONVENTIONS, DEGREE_EXTENT, MAP_FRAME, angle_convention, check_crs, crs_kind
    from .frames import default_frame, is_rockmass_local_crs, local_crs_wkt, to_convention
    from .polygon import polygon_area, signed_area
    from .sets2d import trace_angles_deg, fit_sets_2d, fit_axial_mixture, JointSets2D
    from .intensity import sampling_window, SamplingWindow, clipped_lengths_m, trace_intensity, TraceIntensity, scanline_survey, ScanlineSurvey
    from .mauldon import mauldon_from_counts, mauldon_circle, MauldonEstimate, circle_window, CircleWindow
    from .mauldon import InscribedCircles, MauldonCircles, inscribed_circles, mauldon_circles
    from .topology import trace_topology, TraceTopology
    from .trace_stats import P21_MAP_CELLS, p21_map, trace_map_statistics
    from .stereonet import equal_area_vectors, equal_area_xy, kamb_kappa, plot_pole_density, plot_stereonet, pole_density, small_circle
    from .orientation import angle_between, dip_text, dip_from_normal, dip_from_pole_trend_plunge, dip_from_strike, normal_from_dip, pole_from_dip, pole_trend_plunge, strike_from_dip, to_lower_hemisphere, trend_plunge_from_vector, vector_from_trend_plunge
    from .fisher import FisherFit, confidence_cone, fisher_angle_cdf, fisher_angle_pdf, fisher_density, fit_fisher, orientation_tensor, sample_fisher, variability_cone
    from .stereology import C13_ISOTROPIC, C23_ISOTROPIC, P32Solution, c13, c13_from_angle, c23, c23_from_angle, p10_from_p32, p21_from_p32, p32_from_p10, p32_from_p21, solve_p32, terzaghi_weights
    from .sizes import ConstantSize, ExponentialSize, LognormalSize, PowerLawSize, SizeDistribution, mean_trace_length, p20_from_p30, p30_from_p32, p32_from_p30, radius_exponent_from_trace, trace_exponent_from_radius
    from .network import DiskNetwork, disk_basis, as_box
    from .generation import BootstrapOrientation, DEFAULT_MAX_FRACTURES, FisherOrientation, FractureSetSpec, IntensityP10, IntensityP21, IntensityP32, UniformOrientation, expected_counts, generate, realization_seed, realizations, size_upper_bound
    from .sampling import LineSample, plane_frame, sample_line, sample_plane
    from .section import generate_section, size_biased_sample
    from .network_io import CSV_COLUMNS, read_fractures_csv, write_fractures_csv, write_fractures_vtu, disk_polygons
    from .network_io import FRACTURE_CELL_DATA, SECTION_CELL_DATA, clip_disk_polygons, write_section_traces_vtu
    from .scanline import Scanline, read_scanline
    from .sets3d import JointSets3D, fit_sets_3d
    from .scanline_stats import SpacingFit, fit_spacings, rqd_direct, rqd_priest_hudson, scanline_statistics
    from .size_fit import CensoredTraces, SizeFit, censored_traces, fit_sizes, trace_length_functions
    from .field_fit import FaceSurvey, FieldFit, FittedSet, assign_traces, fit_field
    from .validation import ClosedLoop, closed_loop, compare_fit, compare_with_field, section_check, virtual_face, virtual_scanline

#: Public name -> the module that defines it.
_SOURCES = {
    "TraceMap": "tracemap",
    "read_traces": "traceio",
    "write_traces": "traceio",
    "read_geojson": "geojson_io",
    "write_geojson": "geojson_io",
    "read_csv": "csv_io",
    "write_csv": "csv_io",
    "read_gis": "gis_io",
    "write_gis": "gis_io",
    "BranchesAndNodes": "branches",
    "branches_and_nodes": "branches",
    "TraceValidation": "trace_validation",
    "validate_traces": "trace_validation",
    "trace_angles_deg": "sets2d",
    "fit_sets_2d": "sets2d",
    "fit_axial_mixture": "sets2d",
    "JointSets2D": "sets2d",
    "sampling_window": "intensity",
    "SamplingWindow": "intensity",
    "clipped_lengths_m": "intensity",
    "trace_intensity": "intensity",
    "TraceIntensity": "intensity",
    "scanline_survey": "intensity",
    "ScanlineSurvey": "intensity",
    "mauldon_from_counts": "mauldon",
    "mauldon_circle": "mauldon",
    "MauldonEstimate": "mauldon",
    "circle_window": "mauldon",
    "CircleWindow": "mauldon",
    "InscribedCircles": "mauldon",
    "MauldonCircles": "mauldon",
    "inscribed_circles": "mauldon",
    "mauldon_circles": "mauldon",
    "trace_topology": "topology",
    "TraceTopology": "topology",
    "trace_map_statistics": "trace_stats",
    "P21_MAP_CELLS": "trace_stats",
    "p21_map": "trace_stats",
    "equal_area_vectors": "stereonet",
    "equal_area_xy": "stereonet",
    "kamb_kappa": "stereonet",
    "plot_pole_density": "stereonet",
    "plot_stereonet": "stereonet",
    "pole_density": "stereonet",
    "small_circle": "stereonet",
    "angle_between": "orientation",
    "dip_text": "orientation",
    "ANGLE_CONVENTIONS": "frames",
    "DEGREE_EXTENT": "frames",
    "MAP_FRAME": "frames",
    "angle_convention": "frames",
    "check_crs": "frames",
    "crs_kind": "frames",
    "default_frame": "frames",
    "is_rockmass_local_crs": "frames",
    "local_crs_wkt": "frames",
    "to_convention": "frames",
    "dip_from_normal": "orientation",
    "dip_from_pole_trend_plunge": "orientation",
    "dip_from_strike": "orientation",
    "normal_from_dip": "orientation",
    "pole_from_dip": "orientation",
    "pole_trend_plunge": "orientation",
    "strike_from_dip": "orientation",
    "to_lower_hemisphere": "orientation",
    "trend_plunge_from_vector": "orientation",
    "vector_from_trend_plunge": "orientation",
    "FisherFit": "fisher",
    "confidence_cone": "fisher",
    "fisher_angle_cdf": "fisher",
    "fisher_angle_pdf": "fisher",
    "fisher_density": "fisher",
    "fit_fisher": "fisher",
    "orientation_tensor": "fisher",
    "sample_fisher": "fisher",
    "variability_cone": "fisher",
    "C13_ISOTROPIC": "stereology",
    "C23_ISOTROPIC": "stereology",
    "P32Solution": "stereology",
    "c13": "stereology",
    "c13_from_angle": "stereology",
    "c23": "stereology",
    "c23_from_angle": "stereology",
    "p10_from_p32": "stereology",
    "p21_from_p32": "stereology",
    "p32_from_p10": "stereology",
    "p32_from_p21": "stereology",
    "solve_p32": "stereology",
    "terzaghi_weights": "stereology",
    "ConstantSize": "sizes",
    "ExponentialSize": "sizes",
    "LognormalSize": "sizes",
    "PowerLawSize": "sizes",
    "SizeDistribution": "sizes",
    "mean_trace_length": "sizes",
    "p20_from_p30": "sizes",
    "p30_from_p32": "sizes",
    "p32_from_p30": "sizes",
    "radius_exponent_from_trace": "sizes",
    "trace_exponent_from_radius": "sizes",
    "polygon_area": "polygon",
    "signed_area": "polygon",
    "DiskNetwork": "network",
    "disk_basis": "network",
    "as_box": "network",
    "BootstrapOrientation": "generation",
    "DEFAULT_MAX_FRACTURES": "generation",
    "FisherOrientation": "generation",
    "FractureSetSpec": "generation",
    "expected_counts": "generation",
    "IntensityP10": "generation",
    "IntensityP21": "generation",
    "IntensityP32": "generation",
    "UniformOrientation": "generation",
    "generate": "generation",
    "realization_seed": "generation",
    "realizations": "generation",
    "size_upper_bound": "generation",
    "LineSample": "sampling",
    "plane_frame": "sampling",
    "sample_line": "sampling",
    "sample_plane": "sampling",
    "generate_section": "section",
    "size_biased_sample": "section",
    "CSV_COLUMNS": "network_io",
    "read_fractures_csv": "network_io",
    "write_fractures_csv": "network_io",
    "write_fractures_vtu": "network_io",
    "disk_polygons": "network_io",
    "FRACTURE_CELL_DATA": "network_io",
    "SECTION_CELL_DATA": "network_io",
    "clip_disk_polygons": "network_io",
    "write_section_traces_vtu": "network_io",
    "Scanline": "scanline",
    "read_scanline": "scanline",
    "JointSets3D": "sets3d",
    "fit_sets_3d": "sets3d",
    "SpacingFit": "scanline_stats",
    "fit_spacings": "scanline_stats",
    "rqd_direct": "scanline_stats",
    "rqd_priest_hudson": "scanline_stats",
    "scanline_statistics": "scanline_stats",
    "CensoredTraces": "size_fit",
    "SizeFit": "size_fit",
    "censored_traces": "size_fit",
    "fit_sizes": "size_fit",
    "trace_length_functions": "size_fit",
    "FaceSurvey": "field_fit",
    "FieldFit": "field_fit",
    "FittedSet": "field_fit",
    "assign_traces": "field_fit",
    "fit_field": "field_fit",
    "ClosedLoop": "validation",
    "closed_loop": "validation",
    "compare_fit": "validation",
    "compare_with_field": "validation",
    "section_check": "validation",
    "virtual_face": "validation",
    "virtual_scanline": "validation",
}

__all__ = list(_SOURCES)


def __getattr__(name: str) -> object:
    """Import a public name's module on first access and cache the name here."""
    source = _SOURCES.get(name)
    if source is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(_importlib.import_module(f".{source}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
