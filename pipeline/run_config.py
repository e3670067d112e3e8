"""``[run]``: the field inputs of ``rockmass run`` and the stages wanted.

The stages themselves are configured by the sections the single-stage subcommands read
(``[imaging]``, ``[fractal]``, ``[dfn]``, ``[blocks]``, ``[solve]``); ``[run]`` only names the field
data the chain starts from and, optionally, which stages' outputs are wanted.

How a stage feeds the next (the one rule)
-----------------------------------------
Every stage reads the files its own section names, as its subcommand does, except where the run
makes the data itself: a file key of a stage section (``dfn.fit.scanlines[i]``,
``dfn.fit.faces[i].file``, ``blocks.traces``) may be ``"@traces"`` (the run's trace map: the
``extract`` stage's ``traces.geojson`` when ``photo`` is given, else the ``traces`` file) or
``"@scanline"`` (the ``scanline`` file); ``[blocks.dfn_section]`` is cut from the run's own DFN
realization (``dfn/realization_NNNN/fractures.csv``, by :func:`rockmass.dfn.sample_plane`); and
``[solve]`` without ``blocks_file`` solves the run's ``blocks`` stage. A reference to data the run
does not have is bad input (exit 2) before any stage runs.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field, Strict, field_validator

from .strict import ConfigFile, StrictModel, config_file

__all__ = ["REFERENCES", "STAGES", "RunConfig"]

#: Every stage of a run, in the order they run; also the names of their output folders.
STAGES = ("extract", "traces", "boxcount", "scanline", "dfn", "blocks", "solve")

#: ``"@name"`` file references a stage section may use in a run, and what each one names.
REFERENCES = {"@traces": "the run's trace map (extract's traces.geojson, or [run] traces)",
              "@scanline": "the [run] scanline file"}

StageName = Literal["extract", "traces", "boxcount", "scanline", "dfn", "blocks", "solve"]


class RunConfig(StrictModel):
    """``[run]``: field inputs of ``rockmass run`` (paths relative to the config file).

    Parameters
    ----------
    photo : str, optional
        Face photograph (JPEG, PNG, TIFF): the ``extract`` stage, scale and face orientation from
        ``[imaging]``. Its traces are the run's trace map.
    traces : str, optional
        A digitised trace map (GeoJSON / CSV) instead of a photo; not together with ``photo``.
    scanline : str, optional
        A scanline survey CSV (``rockmass scanline``): the ``scanline`` stage and ``"@scanline"``.
    stages : list of str, optional
        Stages whose outputs are wanted (names from :data:`STAGES`); the stages they read run too.
        Default: every stage the inputs and sections allow.
    trace_sets, scanline_sets : int, optional
        Number of joint sets (1-5) of the trace and scanline statistics; default chosen by BIC.
    area : str, optional
        The mapped area of the trace statistics (``rockmass traces --area``): a GeoJSON file with
        one polygon (relative to the config file, in the trace map's CRS), or ``"bbox"`` /
        ``"hull"`` for the traces' bounding box / convex hull, named in the outputs. Default: the
        trace map's own window polygon (a photo's traces always have one: the image or the ROI); a
        ``traces`` file without a window needs ``area`` (issue 19: never a silent bounding box).
    """

    photo: ConfigFile | None = None
    traces: ConfigFile | None = None
    scanline: ConfigFile | None = None
    stages: Annotated[list[StageName], Field(min_length=1, max_length=len(STAGES))] | None = None
    trace_sets: int | None = Field(None, ge=1, le=5)
    scanline_sets: int | None = Field(None, ge=1, le=5)
    # a file or "bbox" / "hull": not a ConfigFile (the choices are not files)
    area: Annotated[str, Strict(), Field(min_length=1, max_length=4096)] | None = None

    @field_validator("stages")
    @classmethod
    def _unique(cls, value: list[str] | None) -> list[str] | None:
        if value is not None and len(set(value)) != len(value):
            twice = sorted({s for s in value if value.count(s) > 1})
            raise ValueError(f"each stage at most once, got {', '.join(twice)} twice")
        return value

    def area_value(self, config_path) -> str | None:
        """``area`` for the traces stage: ``"bbox"`` / ``"hull"`` as written, a file resolved
        against the config's folder, or None."""
        from .traces_stage import AREA_CHOICES

        if self.area is None or self.area in AREA_CHOICES:
            return self.area
        return str(config_file(config_path, self.area))

    def path(self, key: str, config_path) -> Path | None:
        """The file of ``key`` (``photo``, ``traces``, ``scanline``) resolved against the config's
        folder, or None."""
        return config_file(config_path, getattr(self, key))
