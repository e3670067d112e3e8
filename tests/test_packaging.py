"""The installed package: layout, light CLI start-up, doctests, and choices that cannot drift."""

import doctest
import importlib
import pkgutil
import subprocess
import sys

import pytest

import rockmass


def test_six_stage_packages_are_installed_under_rockmass():
    for stage in ("imaging", "fractal", "dfn", "blockgen", "solver"):
        module = importlib.import_module(f"rockmass.{stage}")
        assert module.__name__ == f"rockmass.{stage}"


def test_cli_import_loads_no_heavy_module():
    code = ("import sys, rockmass.cli; rockmass.cli.build_parser(); "
            "print(sorted(m for m in ('numba', 'numpy', 'matplotlib', 'cv2', 'skimage', 'scipy', "
            "'shapely') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_fractal_import_does_not_compile_numba():
    code = "import sys, rockmass.fractal; print('numba' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_cli_choices_match_the_library():
    from rockmass import boxcount_cmd
    from rockmass.config import FractalConfig
    from rockmass.fractal import LINE_RULES, METHODS
    from rockmass.fractal.image import SKELETONIZE_CHOICES

    assert boxcount_cmd.METHOD_CHOICES == METHODS
    assert boxcount_cmd.LINE_RULE_CHOICES == LINE_RULES
    assert boxcount_cmd.SKELETONIZE_CHOICES == SKELETONIZE_CHOICES
    for name, choices in (("method", METHODS), ("line_rule", LINE_RULES),
                          ("skeletonize", SKELETONIZE_CHOICES)):
        assert set(FractalConfig.model_fields[name].annotation.__args__) == set(choices)


_PACKAGES = ("rockmass", "rockmass.imaging", "rockmass.fractal", "rockmass.dfn", "rockmass.blockgen",
             "rockmass.solver")


def _modules():
    """Every module of the six packages. Each is walked on its own: in an editable install the stage
    packages are not folders below ``rockmass.__path__``, so walking that alone would miss them."""
    for package in _PACKAGES:
        yield package
        for info in pkgutil.iter_modules(importlib.import_module(package).__path__, prefix=package + "."):
            if not info.name.endswith("__main__"):
                yield info.name


@pytest.mark.parametrize("name", sorted(_modules()))
def test_docstring_examples_run(name):
    module = importlib.import_module(name)
    failures, _ = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert failures == 0
