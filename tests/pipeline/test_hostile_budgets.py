"""Resource budgets checked before work starts (issue 18, item 1): configs within their documented
ranges that would need more memory than the limit exit 2 naming the field, the estimate and the
limit, before anything is drawn or built.

Oracles: the issue's measured cases (P32 = 1e4 with max_fractures = 1e9; a 10⁶ m square domain; a
1 mm crack size), each refused in well under a second where it used to run out of memory; the
same configs at a sane size run; the block estimate against blocks actually built.
"""

from __future__ import annotations

import time

import pytest

from rockmass.cli import main

from .test_cli_dfn import CONFIG as DFN_CONFIG


def _fails(args, capsys, *fragments: str) -> str:
    t0 = time.perf_counter()
    assert main(args) == 2
    assert time.perf_counter() - t0 < 5.0  # refused before the work, not after it
    err = capsys.readouterr().err
    for fragment in fragments:
        assert fragment in err, (fragment, err)
    return err


@pytest.fixture(autouse=True)
def sixteen_gib(monkeypatch):
    """The same limit on every machine."""
    monkeypatch.setenv("ROCKMASS_MAX_MEMORY", "16G")


def test_dfn_intensity_needing_a_hundred_gib_is_refused_naming_the_set(tmp_path, capsys):
    # 2.4e8 disks of radius 1 m (P32 = 1e4 m²/m³, the largest a config allows, in a 40 m cube
    # padded by 1 m): about 400 GiB
    config = tmp_path / "dense.toml"
    config.write_text(DFN_CONFIG.replace("realizations = 3", "realizations = 3\nmax_fractures = 1000000000")
                      .replace('{ measure = "P10", value = 0.2, trend_deg = 90, plunge_deg = 0 }',
                               '{ measure = "P32", value = 10000.0 }')
                      .replace("max_m = [12, 10, 8]", "max_m = [40, 40, 40]"))
    out = tmp_path / "out"
    _fails(["dfn", str(config), "--out", str(out)], capsys, f"{config}: dfn.sets[1].intensity",
           "fractures", "GiB of memory", "limit of 16 GiB (ROCKMASS_MAX_MEMORY)")
    assert not out.exists()


def test_the_dfn_limit_is_the_environment_variable(tmp_path, capsys, monkeypatch):
    config = tmp_path / "site.toml"
    config.write_text(DFN_CONFIG)
    monkeypatch.setenv("ROCKMASS_MAX_MEMORY", "1K")
    _fails(["dfn", str(config), "--out", str(tmp_path / "a")], capsys, "limit of 9.54e-07 GiB")
    monkeypatch.setenv("ROCKMASS_MAX_MEMORY", "1G")
    assert main(["dfn", str(config), "--out", str(tmp_path / "b")]) == 0
    monkeypatch.setenv("ROCKMASS_MAX_MEMORY", "plenty")
    _fails(["dfn", str(config), "--out", str(tmp_path / "c")], capsys, "ROCKMASS_MAX_MEMORY",
           "'plenty'")


BLOCKS = """[blocks]
[blocks.domain]
width_m = {side}
height_m = {side}
[blocks.two_sets]
alpha_deg = 30.0
theta_deg = 60.0
spacing_m = [3.0, 4.0]
"""


def test_a_huge_blocks_domain_is_refused_naming_the_spacings(tmp_path, capsys):
    config = tmp_path / "huge.toml"
    config.write_text(BLOCKS.format(side=1e6))
    _fails(["blocks", str(config), "--out", str(tmp_path / "out")], capsys,
           f"{config}: blocks.two_sets.spacing_m", "7.22e+10 blocks", "limit of 16 GiB")


def test_a_tiny_crack_size_is_refused_naming_it(tmp_path, capsys):
    config = tmp_path / "cracks.toml"
    config.write_text(BLOCKS.format(side=100.0) + "[blocks.cracks]\nsize_m = 0.001\n")
    _fails(["blocks", str(config), "--out", str(tmp_path / "out")], capsys,
           f"{config}: blocks.cracks.size_m", "1e+10 from cracks")


def test_block_estimate_is_close_to_the_blocks_built(tmp_path):
    from types import SimpleNamespace

    from rockmass.blocks_stage import compute
    from rockmass.budgets import block_count_terms

    config = tmp_path / "small.toml"
    config.write_text(BLOCKS.format(side=24.0).replace("[3.0, 4.0]", "[1.5, 2.0]"))
    _, model, _, _ = compute(SimpleNamespace(config=str(config)))
    built = model.n_blocks
    terms = block_count_terms([(0, 0), (24, 0), (24, 24), (0, 24)], [(30, 1.5), (90, 2.0)], None)
    estimate = 1 + sum(terms.values())
    assert built <= estimate <= 1.5 * built, (built, terms)
