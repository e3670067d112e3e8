"""Provenance manifest: every input hashed, every version recorded, written atomically as JSON."""

from __future__ import annotations

import datetime as dt
import hashlib
import json
import os
import subprocess
import sys
from importlib.metadata import version

import pytest

from rockmass import manifest as manifest_module
from rockmass.config import FractalConfig, RockmassConfig, config_hash
from rockmass.errors import InputError
from rockmass.manifest import build_manifest, write_manifest


def test_input_hash_equals_hashlib_of_file_bytes(tmp_path):
    data = os.urandom((5 << 19) + 17)  # 2.5 MiB + 17 bytes: several read chunks and a partial one
    big = tmp_path / "traces.csv"
    big.write_bytes(data)
    empty = tmp_path / "empty.csv"
    empty.write_bytes(b"")
    record = build_manifest(command="test", inputs=[big, str(empty)])["inputs"]
    assert record == [
        {"path": str(big), "sha256": hashlib.sha256(data).hexdigest(), "bytes": len(data)},
        {"path": str(empty), "sha256": hashlib.sha256(b"").hexdigest(), "bytes": 0},
    ]


def test_versions_of_installed_dependencies_are_recorded(monkeypatch):
    monkeypatch.setattr(
        manifest_module, "TRACKED_DISTRIBUTIONS", (*manifest_module.TRACKED_DISTRIBUTIONS, "no-such-dist-for-rockmass")
    )
    deps = build_manifest(command="test")["dependencies"]
    assert deps["numpy"] == version("numpy")
    assert deps["pydantic"] == version("pydantic")
    assert deps["no-such-dist-for-rockmass"] is None
    assert {"scipy", "numba", "opencv-python-headless", "scikit-image", "shapely", "matplotlib", "trimesh",
            "meshio", "tqdm"} <= set(deps)


def test_written_manifest_is_valid_json_with_every_section(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_NUM_THREADS", "3")
    source = tmp_path / "in.geojson"
    source.write_text("{}")
    cfg = RockmassConfig(fractal=FractalConfig(grid=512))
    path = write_manifest(
        tmp_path / "out",
        command=["rockmass", "boxcount", source],
        config=cfg,
        inputs=[source],
        seeds={"root": 12345, "spawn_key": (0,)},
        timings_s={"count": 0.25},
        extra={"skipped": ["dfn"]},
    )
    assert path == tmp_path / "out" / "manifest.json"
    assert sorted(p.name for p in path.parent.iterdir()) == ["manifest.json"]
    m = json.loads(path.read_text())
    assert list(m) == [
        "manifest_version", "rockmass_version", "created_utc", "command", "config", "config_hash",
        "inputs", "seeds", "timings_s", "dependencies", "platform", "extra",
    ]
    assert m["command"] == ["rockmass", "boxcount", str(source)]
    assert m["config"]["fractal"]["grid"] == 512 and m["config"]["fractal"]["n_offsets"] == 8
    assert m["config_hash"] == config_hash(cfg)
    assert m["seeds"] == {"root": 12345, "spawn_key": [0]}
    assert m["timings_s"] == {"count": 0.25}
    assert m["extra"] == {"skipped": ["dfn"]}
    assert m["platform"]["NUMBA_NUM_THREADS"] == "3"
    assert m["platform"]["cpu_count"] == os.cpu_count()
    assert m["platform"]["python"] == ".".join(map(str, sys.version_info[:3]))
    created = dt.datetime.fromisoformat(m["created_utc"])
    assert created.utcoffset() == dt.timedelta(0)
    assert abs((dt.datetime.now(dt.timezone.utc) - created).total_seconds()) < 60


def test_numba_threads_absent_when_not_set(monkeypatch):
    monkeypatch.delenv("NUMBA_NUM_THREADS", raising=False)
    assert "NUMBA_NUM_THREADS" not in build_manifest(command="x")["platform"]


def test_missing_input_raises_input_error_naming_it(tmp_path):
    missing = tmp_path / "no_such_scanline.csv"
    with pytest.raises(InputError, match="no_such_scanline.csv: input file not found"):
        build_manifest(command="x", inputs=[missing])


def test_single_path_as_inputs_is_refused(tmp_path):
    with pytest.raises(TypeError, match="list of paths"):
        build_manifest(command="x", inputs=str(tmp_path))


def test_nan_timing_is_refused_naming_it():
    with pytest.raises(ValueError, match=r"timings_s\.solve is NaN"):
        build_manifest(command="x", timings_s={"solve": float("nan")})


def test_modules_do_not_import_heavy_libraries():
    code = (
        "import sys, rockmass.atomic, rockmass.config, rockmass.manifest\n"
        "rockmass.manifest.build_manifest(command='x', config=rockmass.config.RockmassConfig())\n"
        "heavy = {'numpy', 'numba', 'matplotlib', 'cv2', 'skimage', 'scipy', 'shapely'}\n"
        "print(sorted(heavy & set(sys.modules)))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
