"""Build the installable QGIS plugin zip: dist/photodem-<version>.zip (``make zip``).

The zip holds one top folder ``photodem/`` with what the plugin needs at run time: the root
``__init__.py``, ``metadata.txt``, ``LICENSE``, ``README.md``, ``algorithms/``, ``plugin/``,
``resources/`` and the compiled translations ``i18n/*.qm`` (built here with lrelease; ``.qm``
files are not committed). Tests, benchmarks, tools, CI and development files stay out.

Files come from git (tracked plus untracked-but-not-ignored, so a build before the first commit
works too), filtered by the allow-list below. Entries get a fixed timestamp so two builds of the
same tree give the same zip.

Usage::

    python tools/build_zip.py [OUTPUT_DIR]     # default: dist
"""

from __future__ import annotations

import configparser
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path
from typing import List, Optional

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = "photodem"
#: Top-level files and folders that ship; everything else (tests/, bench/, tools/, .ci/, docs/,
#: pyproject.toml, Makefile, .gitignore, i18n/*.ts …) does not.
SHIP_FILES = ("__init__.py", "metadata.txt", "LICENSE", "README.md")
SHIP_DIRS = ("algorithms", "plugin", "resources")
SKIP_PARTS = ("__pycache__",)
SKIP_SUFFIXES = (".pyc", ".pyo", ".partial")
FIXED_TIME = (2020, 1, 1, 0, 0, 0)


def repository_files(root: Path = ROOT) -> List[str]:
    """Tracked and untracked-but-not-ignored files (posix paths relative to ``root``)."""
    proc = subprocess.run(
        ["git", "ls-files", "--cached", "--others", "--exclude-standard", "-z"],
        cwd=root, capture_output=True, text=True, check=True,
    )
    names = sorted({n for n in proc.stdout.split("\0") if n})
    return [n for n in names if (root / n).is_file()]  # drop files deleted but still tracked


def shipped(name: str) -> bool:
    """True if the repository file ``name`` belongs in the plugin zip."""
    parts = name.split("/")
    if any(p in SKIP_PARTS for p in parts) or name.endswith(SKIP_SUFFIXES):
        return False
    if len(parts) == 1:
        return name in SHIP_FILES
    return parts[0] in SHIP_DIRS


def plugin_version(root: Path = ROOT) -> str:
    meta = configparser.ConfigParser(interpolation=None)
    meta.read(root / "metadata.txt", encoding="utf-8")
    return meta["general"]["version"]


def _add(archive: zipfile.ZipFile, source: Path, arcname: str) -> None:
    info = zipfile.ZipInfo(arcname, date_time=FIXED_TIME)
    info.compress_type = zipfile.ZIP_DEFLATED
    info.external_attr = 0o644 << 16
    archive.writestr(info, source.read_bytes())


def build(output_dir: Path, root: Path = ROOT) -> Path:
    """Write ``<output_dir>/photodem-<version>.zip`` and return its path.

    Raises
    ------
    RuntimeError
        When lrelease is missing (Debian: qttools5-dev-tools) or no translation exists.
    """
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from update_translations import release

    ts_files = sorted((root / "i18n").glob("photodem_*.ts"))
    if not ts_files:
        raise RuntimeError("no i18n/photodem_*.ts found")
    output_dir = Path(output_dir)
    output_dir.mkdir(parents=True, exist_ok=True)
    target = output_dir / f"{PACKAGE}-{plugin_version(root)}.zip"
    tmp_target = target.with_name(target.name + ".partial")
    with tempfile.TemporaryDirectory(prefix="photodem-qm-") as qm_dir:
        qm_files = release(ts_files, Path(qm_dir))
        with zipfile.ZipFile(tmp_target, "w") as archive:
            for name in repository_files(root):
                if shipped(name):
                    _add(archive, root / name, f"{PACKAGE}/{name}")
            for qm in qm_files:
                _add(archive, qm, f"{PACKAGE}/i18n/{qm.name}")
    tmp_target.replace(target)
    return target


def main(argv: Optional[List[str]] = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    target = build(Path(args[0]) if args else ROOT / "dist")
    with zipfile.ZipFile(target) as archive:
        count = len(archive.namelist())
    print(f"{target} ({count} files, {target.stat().st_size / 1024:.0f} KiB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
