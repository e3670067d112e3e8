"""Stage sections in one document: ``[dfn]`` and ``[blocks]`` in :class:`RockmassConfig` (lazily typed)."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from rockmass import config as config_module
from rockmass import strict
from rockmass.blocks_config import BlocksConfig, BlocksDocument
from rockmass.cli import main
from rockmass.config import RockmassConfig, canonical_json, load_config
from rockmass.dfn_config import DFNConfig, DFNDocument
from rockmass.errors import ConfigError

SAMPLES = Path(__file__).resolve().parents[2] / "samples"

BLOCKS = """
[blocks]
seed = 3
[blocks.domain]
width_m = 2.0
height_m = 1.0
[[blocks.sets]]
angle_deg = 0
spacing_m = 0.5
origin_xy_m = [0.0, 0.0]
[[blocks.sets]]
angle_deg = 90
spacing_m = 0.5
origin_xy_m = [0.0, 0.0]
"""


def _write(tmp_path, text, name="site.toml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


def _problems(path, model=RockmassConfig):
    with pytest.raises(ConfigError) as info:
        load_config(path, model)
    return dict(info.value.problems)


def test_config_reexports_the_strict_helpers_unchanged():
    assert config_module.StrictModel is strict.StrictModel
    assert config_module.field_problem is strict.field_problem
    assert issubclass(BlocksConfig, strict.StrictModel) and issubclass(DFNConfig, strict.StrictModel)


def test_one_file_holds_fractal_dfn_and_blocks_each_validated_by_its_own_section(tmp_path):
    dfn_text = (SAMPLES / "dfn_seed001.toml").read_text()
    path = _write(tmp_path, "[fractal]\ngrid = 64\n" + BLOCKS + dfn_text)
    cfg = load_config(path)
    assert isinstance(cfg.blocks, BlocksConfig) and isinstance(cfg.dfn, DFNConfig)
    assert cfg.fractal.grid == 64 and cfg.blocks.seed == 3 and cfg.dfn.seed == 1
    # same sections as the single-stage documents the commands used to read
    alone = load_config(_write(tmp_path, BLOCKS, "b.toml"), BlocksDocument).blocks
    assert cfg.blocks == alone
    assert cfg.dfn == load_config(SAMPLES / "dfn_seed001.toml", DFNDocument).dfn


def test_absent_stage_sections_are_none_and_appear_in_the_canonical_text():
    cfg = RockmassConfig()
    assert cfg.dfn is None and cfg.blocks is None
    assert '"blocks":null' in canonical_json(cfg) and '"dfn":null' in canonical_json(cfg)


def test_error_inside_a_stage_section_names_the_full_dotted_field(tmp_path):
    text = BLOCKS.replace("spacing_m = 0.5\norigin_xy_m = [0.0, 0.0]\n[[blocks.sets]]", "spacing_m = -1\n[[blocks.sets]]")
    problems = _problems(_write(tmp_path, text))
    assert list(problems) == ["blocks.sets[0].spacing_m"]
    assert problems["blocks.sets[0].spacing_m"].startswith("must be > 0, got -1")


def test_unknown_key_inside_a_lazy_section_lists_that_sections_keys(tmp_path):
    problems = _problems(_write(tmp_path, BLOCKS.replace("seed = 3", "sed = 3")))
    message = problems["blocks.sed"]
    assert message.startswith("unknown key (allowed: domain, sets,") and 'did you mean "seed"?' in message


def test_a_stage_section_given_as_a_value_not_a_table_is_refused(tmp_path):
    problems = _problems(_write(tmp_path, "blocks = 3\n"))
    assert list(problems) == ["blocks"]


def test_model_instances_are_accepted_for_stage_sections():
    blocks = BlocksConfig.model_validate({"domain": {"width_m": 1.0, "height_m": 1.0},
                                          "sets": [{"angle_deg": 0.0, "spacing_m": 0.25}]})
    assert RockmassConfig(blocks=blocks).blocks is blocks


def test_config_import_and_empty_document_do_not_import_numpy_or_the_stage_modules():
    code = ("import sys, rockmass.config as c; c.RockmassConfig(); "
            "print(sorted(m for m in ('numpy', 'rockmass.dfn_config', 'rockmass.blocks_config') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_blocks_command_reads_its_section_from_a_multi_stage_file(tmp_path, capsys):
    dfn_text = (SAMPLES / "dfn_seed001.toml").read_text()
    path = _write(tmp_path, BLOCKS + dfn_text)
    assert main(["blocks", str(path), "--out", str(tmp_path / "out")]) == 0
    # 2 x 1 m cut by 0.5 m orthogonal sets: (2 / 0.5) * (1 / 0.5) = 8 blocks
    assert capsys.readouterr().out.startswith("8 blocks")


def test_blocks_command_without_a_blocks_section_exits_2_naming_it(tmp_path, capsys):
    path = _write(tmp_path, "[fractal]\ngrid = 64\n")
    assert main(["blocks", str(path), "--out", str(tmp_path / "out")]) == 2
    assert "blocks: required section is missing" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
