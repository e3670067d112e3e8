"""Config sections take their parameters from the library types: declared once, checked the same."""

import dataclasses
import pickle
from typing import Annotated

import pytest
from pydantic import Field, ValidationError

from rockmass.blockgen import JointSet
from rockmass.dfn.specs import spec
from rockmass.config import load_config
from rockmass.errors import ConfigError
from rockmass.solve_config import SolveConfig, StageConfig
from rockmass.solver import (ContinuouslyYielding, Coulomb, Monitor, Settings, Sine, Stage,
                             VelocityInput)
from rockmass.strict import ConfigFile, StrictModel, config_file, file_fields, library_section
from rockmass.study_config import StudyCase, standalone_config


def test_solve_section_has_every_settings_field_and_blocks_file():
    library = set(Settings.__pydantic_fields__)
    assert set(SolveConfig.model_fields) == library | {"blocks_file"}
    assert set(StageConfig.model_fields) == set(Stage.__pydantic_fields__)


def test_defaults_are_the_library_defaults():
    cy = ContinuouslyYielding(1e9, 1e9)
    section = SolveConfig.model_validate({"joints": {"default": {"model": "cy", "an_pa_m": 1e9,
                                                                 "as_pa_m": 1e9}},
                                          "stages": [{"name": "s"}]})
    assert section.joints["default"] == cy
    assert (cy.initial_friction_deg, cy.basic_friction_deg) == (59.3, 30.0)
    stage = section.stages[0].to_library(excavate=())
    assert stage == Stage("s")


@pytest.mark.parametrize("make, field", [
    (lambda: Coulomb(1e9, -1.0, 30.0), "ks_pa_m"),                   # positional: still the name
    (lambda: Coulomb(kn_pa_m=-1, ks_pa_m=1e9, friction_deg=30.0), "kn_pa_m"),
    (lambda: ContinuouslyYielding(1e9, 1e9, initial_friction_deg=20.0), "basic_friction_deg"),
    (lambda: Stage("shake", "dynamic"), "duration_s"),
    (lambda: Stage("s", max_steps=3.5), "max_steps"),
    (lambda: Monitor("m"), "point_xy_m"),
    (lambda: JointSet(0.0, 1.0, "lognormal"), "spacing_std_m"),
    (lambda: JointSet(0.0, 1.0, trace_length_m=2.0), "gap_length_m"),
])
def test_a_bad_value_from_python_is_a_value_error_naming_the_field(make, field):
    with pytest.raises(ValueError, match=field) as info:
        make()
    assert isinstance(info.value, ValidationError)
    assert info.value.errors()[0]["loc"] == (field,)


def test_the_same_rule_names_the_same_field_from_toml(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text('[solve]\n[solve.joints.default]\nmodel = "cy"\nan_pa_m = 1e9\nas_pa_m = 1e9\n'
                    'initial_friction_deg = 20.0\n[[solve.stages]]\nname = "s"\n')
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert info.value.problems == [("solve.joints.default.basic_friction_deg",
                                    "must not exceed initial_friction_deg (20.0), got 30.0")]


def test_settings_survive_pickling():
    settings = Settings(joints={"default": Coulomb(1e9, 1e9, 30.0)},
                        stages=[Stage("s"), Stage("d", "dynamic", duration_s=1.0)],
                        velocity_inputs=[VelocityInput("bottom", "x", Sine(0.1, 2.0))])
    assert pickle.loads(pickle.dumps(settings)) == settings
    assert dataclasses.replace(settings, sleep=True).sleep


def test_a_new_library_field_is_a_toml_key_without_touching_the_section():
    @spec
    class Widget:
        size_m: Annotated[float, Field(gt=0, description="size")]
        new_key: Annotated[int, Field(ge=0, description="added later")] = 3

    section = library_section(Widget)
    assert section.model_validate({"size_m": 2.0, "new_key": 5}).to_library() == Widget(2.0, 5)
    with pytest.raises(ValidationError, match="new_key"):
        section.model_validate({"size_m": 2.0, "new_key": -1})


def test_file_keys_are_found_from_their_type(tmp_path):
    class Section(StrictModel):
        data: ConfigFile
        other: list[ConfigFile] = []
        note: str = ""

    doc = Section(data="a.csv", other=["b.csv", "/abs/c.csv"], note="not a file")
    assert file_fields(doc) == [(["data"], "a.csv"), (["other", 0], "b.csv"),
                                (["other", 1], "/abs/c.csv")]
    assert config_file(tmp_path / "x.toml", "a.csv") == tmp_path / "a.csv"
    assert config_file(tmp_path / "x.toml", "/abs/c.csv").as_posix() == "/abs/c.csv"


def test_standalone_case_config_makes_every_file_key_absolute(tmp_path):
    raw = {"blocks": {"domain": {"width_m": 1.0, "height_m": 1.0}, "traces": "t.csv"},
           "solve": {"blocks_file": "b.json", "joints": {"default": {
               "model": "coulomb", "kn_pa_m": 1e9, "ks_pa_m": 1e9, "friction_deg": 30.0}},
               "stages": [{"name": "s"}],
               "velocity_inputs": [{"where": "bottom", "component": "x",
                                    "history": {"type": "csv", "file": "v.csv"}}]}}
    path = tmp_path / "study.toml"
    from rockmass.config import RockmassConfig

    case = StudyCase(0, {}, 0, 0, raw, RockmassConfig.model_validate(raw), "0" * 64)
    data = standalone_config(case, path)
    assert data["blocks"]["traces"] == str(tmp_path / "t.csv")
    assert data["solve"]["blocks_file"] == str(tmp_path / "b.json")
    assert data["solve"]["velocity_inputs"][0]["history"]["file"] == str(tmp_path / "v.csv")
    assert raw["solve"]["blocks_file"] == "b.json"  # input not modified
