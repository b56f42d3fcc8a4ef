"""Helpers of the tier-B tests: raw (CLI-style) values → QGIS values, result normalisation."""

from __future__ import annotations

import hashlib
import shutil
from pathlib import Path
from typing import Any, Dict, Optional


def to_qgis_value(parameter, value: Any) -> Any:
    """A raw (CLI-style) value as QGIS takes it in ``processing.run``."""
    if value is None:
        return None
    if parameter.kind == "enum":
        return [o.lower() for o in parameter.options].index(str(value).lower())
    if parameter.kind == "extent":
        xmin, ymin, xmax, ymax = value
        return f"{xmin},{xmax},{ymin},{ymax}"
    return value


def to_qgis_params(spec, raw: Dict[str, Any]) -> Dict[str, Any]:
    return {name: to_qgis_value(spec.parameter(name), v) for name, v in raw.items()}


def to_cli_args(spec, raw: Dict[str, Any]) -> list:
    """Raw values as ``qgis_process run ALG -- name=value`` arguments."""
    args = []
    for name, value in raw.items():
        q = to_qgis_value(spec.parameter(name), value)
        if isinstance(q, bool):
            q = "true" if q else "false"
        for item in q if isinstance(q, list) else [q]:
            args.append(f"{name}={item}")
    return args


def normalise(value: Any, mapping: Dict[str, str], digits: Optional[int] = None) -> Any:
    """Replace run-specific paths (the output folders) in a result by placeholders.

    ``digits`` rounds floats to that many significant digits: results computed in *another
    process* (qgis_process) may differ in the last bit (BLAS/LAPACK code paths), while results of
    the same process must be identical (``digits=None``).
    """
    if isinstance(value, dict):
        return {k: normalise(v, mapping, digits) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [normalise(v, mapping, digits) for v in value]
    if isinstance(value, str):
        for old, new in sorted(mapping.items(), key=lambda kv: -len(kv[0])):
            value = value.replace(old, new)
        return value
    if isinstance(value, float) and digits is not None:
        return float(f"{value:.{digits}g}")
    return value


#: Significant digits compared between processes (in-process results must be bit-identical).
DIGITS = 12

#: JSON keys whose values differ between two identical runs (wall-clock times).
VOLATILE_KEYS = {"written", "started", "finished", "created", "timestamp", "elapsed_s", "seconds"}


def _drop_volatile(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _drop_volatile(v) for k, v in value.items() if k not in VOLATILE_KEYS}
    if isinstance(value, list):
        return [_drop_volatile(v) for v in value]
    return value


def _canonical(text: str, suffix: str, digits: Optional[int]) -> str:
    import json

    try:
        if suffix == ".json":
            data = json.loads(text)
        else:
            try:
                import tomllib
            except ImportError:  # Python < 3.11
                import tomli as tomllib
            data = tomllib.loads(text)
    except ValueError:
        return text
    return json.dumps(normalise(_drop_volatile(data), {}, digits), sort_keys=True, default=str)


TEXT_SUFFIXES = {".toml", ".json", ".csv", ".txt", ".yaml", ".yml", ".prj", ".xml", ".geojson"}


def tree_digest(folder: Path, mapping: Dict[str, str],
                digits: Optional[int] = None) -> Dict[str, str]:
    """Content digest of every file below ``folder``, comparable between two output folders.

    Text files are hashed after replacing run-specific paths (JSON without wall-clock keys);
    GeoTIFFs by pixels, CRS and transform (the bytes may legitimately differ); other files
    (GeoPackages carry timestamps) by existence. ``digits``: see :func:`normalise`.
    """
    digest: Dict[str, str] = {}
    for path in sorted(p for p in Path(folder).rglob("*") if p.is_file()):
        rel = path.relative_to(folder).as_posix()
        suffix = path.suffix.lower()
        if suffix in TEXT_SUFFIXES:
            text = normalise(path.read_text(encoding="utf-8", errors="replace"), mapping)
            if suffix in (".json", ".toml"):  # parsed: wall-clock keys dropped, floats rounded
                text = _canonical(text, suffix, digits)
            digest[rel] = hashlib.sha256(text.encode()).hexdigest()
        elif suffix in (".tif", ".tiff"):
            from photodem.algorithms.raster.io import open_image

            with open_image(path) as src:  # images and epipolar images have no georeference
                data = src.read()
                h = hashlib.sha256(data.tobytes())
                h.update(str((src.crs, tuple(src.transform), src.dtypes, src.nodata)).encode())
            digest[rel] = h.hexdigest()
        else:
            digest[rel] = "exists"
    return digest


# -- qgis_process -------------------------------------------------------------------------------
QGIS_PROCESS = "/usr/bin/qgis_process.bin"  # not /usr/bin/qgis_process: see DESIGN.md §4
FIXTURE_FILE = Path(__file__).with_name("_fixture_algs.py")

_SITECUSTOMIZE = '''"""Test-only: register the fixture algorithm inside qgis_process."""
import importlib.util
import os
import sys

sys.path.insert(0, os.environ["PHOTODEM_TEST_PLUGIN_DIR"])
from photodem.algorithms.processing import registry  # noqa: E402

_spec = importlib.util.spec_from_file_location("_fixture_algs", os.environ["PHOTODEM_TEST_FIXTURE"])
_module = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_module)
for _cls in _module.ALGORITHMS:
    registry.add(_cls())
'''


def qgis_process_env(base: Path, root: Path, with_fixture: bool = False) -> Dict[str, str]:
    """Environment for qgis_process.bin: temp profile, plugin folder with a symlink to the repo.

    ``with_fixture`` adds a ``sitecustomize`` on PYTHONPATH that registers the test-only
    algorithm in the registry before QGIS loads the plugin (qgis_process runs in its own process,
    so the in-process monkeypatch cannot reach it).
    """
    import os

    plugins = base / "plugins"
    plugins.mkdir(parents=True, exist_ok=True)
    link = plugins / "photodem"
    if not link.exists():
        link.symlink_to(root, target_is_directory=True)
    env = dict(os.environ)
    env.update(
        QT_QPA_PLATFORM="offscreen",
        QGIS_CUSTOM_CONFIG_PATH=str(base / "profile"),
        QGIS_PLUGINPATH=str(plugins),
        QGIS_PREFIX_PATH=env.get("QGIS_PREFIX_PATH", "/usr"),
    )
    # qgis_process embeds Debian's /usr/bin/python3: the test venv must not leak into it.
    for key in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV"):
        env.pop(key, None)
    if with_fixture:
        site = base / "site"
        site.mkdir(exist_ok=True)
        (site / "sitecustomize.py").write_text(_SITECUSTOMIZE, encoding="utf-8")
        env.update(PYTHONPATH=str(site), PHOTODEM_TEST_PLUGIN_DIR=str(plugins),
                   PHOTODEM_TEST_FIXTURE=str(FIXTURE_FILE))
    return env


def run_qgis_process(env: Dict[str, str], *args: str, timeout: float = 600):
    """Run qgis_process.bin with ``args``; returns the CompletedProcess (text)."""
    import subprocess

    return subprocess.run([QGIS_PROCESS, *args], env=env, capture_output=True, text=True,
                          timeout=timeout, check=False)


def qgis_process_results(env: Dict[str, str], algorithm_id: str, cli_args: list) -> Dict:
    """``qgis_process.bin run photodem:<id> --json -- name=value …`` → its ``results`` dict."""
    import json

    proc = run_qgis_process(env, "run", f"photodem:{algorithm_id}", "--json", "--", *cli_args)
    assert proc.returncode == 0, f"qgis_process failed ({proc.returncode}):\n{proc.stderr[-3000:]}"
    return json.loads(proc.stdout)["results"]


def copy_block(block: Path, folder: Path, name: str = "block") -> Path:
    """A copy of ``block`` as ``folder/name`` (each writer works on its own project)."""
    target = Path(folder) / name
    shutil.copytree(block, target)
    return target
