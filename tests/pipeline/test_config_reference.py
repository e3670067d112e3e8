"""The configuration reference is generated from the config types and kept in step with them."""

from pathlib import Path

from rockmass.config_reference import config_keys, config_reference

DOC = Path(__file__).resolve().parents[2] / "docs" / "config.md"


def test_docs_config_md_is_the_generated_reference():
    # regenerate with: python -m rockmass.config_reference docs/config.md
    assert DOC.read_text(encoding="utf-8") == config_reference()


def test_every_key_has_a_description():
    missing = [f"{k.table} {k.name}" for k in config_keys() if not k.description]
    assert not missing, missing


def test_solver_keys_take_units_defaults_and_ranges_from_the_solver_types():
    keys = {(k.table, k.name): k for k in config_keys()}
    cy = keys[('[solve.joints.<label>] (model = "cy")', "initial_friction_deg")]
    assert (cy.unit, cy.default, cy.range) == ("°", "59.3", "0 <= x < 90")
    kn = keys[('[solve.joints.<label>] (model = "coulomb")', "kn_pa_m")]
    assert (kn.unit, kn.default, kn.range) == ("Pa/m", "required", "0 < x <= 1e16")


def test_file_keys_are_typed_as_files():
    files = {(k.table, k.name) for k in config_keys() if k.type == "file"}
    assert {("[solve]", "blocks_file"), ("[blocks]", "traces"), ("[run]", "photo"),
            ('[solve.velocity_inputs[].history] (type = "csv")', "file")} <= files
