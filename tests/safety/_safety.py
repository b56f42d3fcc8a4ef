"""Helpers of the safety tests (issue 16): a tiny project, a folder of bad files, and the
checks every case makes (exit code and one-line message, input hashes, nothing left behind)."""

from __future__ import annotations

import hashlib
import json
import os
import resource
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, Iterable, List, Optional, Sequence, Tuple

import numpy as np

#: The console script of this environment (the same interpreter as the tests).
PHOTODEM = Path(sys.prefix) / "bin" / "photodem"
#: Names of staging and scratch files that must never survive a run.
LEFTOVER_MARKS = (".partial", ".scratch", ".tmp")
ERROR_PREFIX = "photodem: error:"
WARNING_PREFIX = "photodem: warning:"


# -- data made once per session ------------------------------------------------------------------
def make_bad_files(folder: Path, project: Path) -> None:
    """Write the corpus' input files into ``folder``.

    Rasters: ``dsm.tif`` (valid copy), ``truncated.tif`` (valid GeoTIFF cut to half its size),
    ``garbage.tif``, ``empty.tif``, ``text.tif``, ``nan.tif`` (NaN only), ``wrong_crs.tif``
    (the DSM's grid labelled EPSG:32633), ``no_crs.tif``, ``one_pixel.tif``,
    ``image_truncated.tif`` (a project image cut in half), ``dsm_\\xff.tif`` (non-UTF-8 name).
    Vectors: ``garbage.gpkg``, ``empty.gpkg``, ``lines_2d.gpkg``, ``bowtie.gpkg``,
    ``unknown_action.gpkg``, ``points_only.gpkg``. Text: point files and orientation files.
    """
    dsm = project / "truth" / "dsm.tif"
    shutil.copy(dsm, folder / "dsm.tif")
    data = dsm.read_bytes()
    (folder / "truncated.tif").write_bytes(data[: len(data) // 2])
    image = (project / "images" / "0101.tif").read_bytes()
    (folder / "image_truncated.tif").write_bytes(image[: len(image) // 2])
    rng = np.random.default_rng(16)
    (folder / "garbage.tif").write_bytes(rng.integers(0, 256, 5000, dtype=np.uint8).tobytes())
    (folder / "empty.tif").write_bytes(b"")
    (folder / "text.tif").write_text("this is not a raster\n", encoding="utf-8")
    shutil.copy(dsm, folder / os.fsdecode(b"dsm_\xff.tif"))
    _variant_rasters(folder, dsm)
    _vectors(folder, project)
    _texts(folder)
    _orientation(folder, project)


def _orientation(folder: Path, project: Path) -> None:
    """A valid exterior CSV and interior YAML of the project's images (for project_create)."""
    import tomllib

    data = tomllib.loads((project / "project.toml").read_text(encoding="utf-8"))
    rows = ["filename,x,y,z,omega,phi,kappa"]
    for im in data["images"]:
        rows.append(",".join([im["name"] + ".tif", *map(str, im["position"]),
                              *map(str, im["opk"])]))
    (folder / "exterior.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    cam = data["cameras"]["synthetic_tiny"]
    w, h, px = cam["width"], cam["height"], cam["pixel_size_mm"][0]
    (folder / "interior.yaml").write_text(
        f"synthetic_tiny:\n  type: pinhole\n  im_size: [{w}, {h}]\n"
        f"  focal_len: {cam['focal_length_mm']}\n  sensor_size: [{w * px}, {h * px}]\n",
        encoding="utf-8")


def _variant_rasters(folder: Path, dsm: Path) -> None:
    import rasterio

    with rasterio.open(dsm) as src:
        profile, band = src.profile, src.read(1)
    nan = np.full_like(band, np.nan, dtype="float32")
    _write(folder / "nan.tif", profile, nan)
    _write(folder / "wrong_crs.tif", {**profile, "crs": "EPSG:32633"}, band)
    _write(folder / "no_crs.tif", {k: v for k, v in profile.items() if k != "crs"}, band)
    one = {**profile, "width": 1, "height": 1, "tiled": False}
    one.pop("blockxsize", None)
    one.pop("blockysize", None)
    _write(folder / "one_pixel.tif", one, band[:1, :1])


def _write(path: Path, profile: dict, band: np.ndarray) -> None:
    import rasterio

    with rasterio.open(path, "w", **profile) as dst:
        dst.write(band.astype(profile.get("dtype", "float32")), 1)


def _vectors(folder: Path, project: Path) -> None:
    import fiona
    from shapely.geometry import LineString, Polygon, mapping

    (folder / "garbage.gpkg").write_bytes(b"\x00\x01GPKG?" * 300)
    (folder / "empty.gpkg").write_bytes(b"")
    x0, y0 = 402280.0, 5674660.0  # inside the tiny block
    crs = "EPSG:25832"

    def layer(name: str, layer_name: str, geometry: str, props: dict, rows: list) -> None:
        schema = {"geometry": geometry, "properties": props}
        with fiona.open(folder / name, "w", driver="GPKG", layer=layer_name, schema=schema,
                        crs=crs) as dst:
            for geom, values in rows:
                dst.write({"geometry": mapping(geom), "properties": values})

    line2d = LineString([(x0, y0), (x0 + 40, y0 + 30)])
    layer("lines_2d.gpkg", "breaklines", "LineString", {"kind": "str"},
          [(line2d, {"kind": "hard"})])
    bowtie = Polygon([(x0, y0), (x0 + 20, y0 + 20), (x0 + 20, y0), (x0, y0 + 20), (x0, y0)])
    layer("bowtie.gpkg", "exclusion_areas", "Polygon", {"action": "str", "note": "str"},
          [(bowtie, {"action": "remove", "note": "bow tie"})])
    square = Polygon([(x0, y0), (x0 + 20, y0), (x0 + 20, y0 + 20), (x0, y0 + 20)])
    layer("unknown_action.gpkg", "exclusion_areas", "Polygon", {"action": "str", "note": "str"},
          [(square, {"action": "vaporise", "note": "not an action"})])
    layer("polygons_no_class.gpkg", "polygons", "Polygon", {"name": "str"},
          [(square, {"name": "a"})])


def _texts(folder: Path) -> None:
    x0, y0 = 402290.0, 5674680.0
    (folder / "identical.xyz").write_text(f"{x0} {y0} 55.0\n" * 5000, encoding="utf-8")
    (folder / "empty.xyz").write_text("", encoding="utf-8")
    (folder / "words.xyz").write_text("north east up\nfoo bar baz\n", encoding="utf-8")
    (folder / "two_columns.xyz").write_text(f"{x0} {y0}\n{x0 + 1} {y0 + 1}\n", encoding="utf-8")
    (folder / "nan.xyz").write_text(f"nan nan nan\n{x0} nan 5\n", encoding="utf-8")
    (folder / "binary.xyz").write_bytes(bytes(range(256)) * 20)
    (folder / "labels_short.txt").write_text("0\n1\n", encoding="utf-8")
    (folder / "labels_words.txt").write_text("ground\nobject\n", encoding="utf-8")
    (folder / "exterior_garbage.csv").write_bytes(b"\xff\xfe\x00garbage,,,\n\x00\x00")
    (folder / "exterior_words.csv").write_text(
        "name,x,y,z,omega,phi,kappa\n0101,east,north,up,a,b,c\n", encoding="utf-8")
    (folder / "exterior_short.csv").write_text("name,x,y\n0101,1,2\n", encoding="utf-8")
    (folder / "exterior_nan.csv").write_text(
        "name,x,y,z,omega,phi,kappa\n0101,nan,5674670,127,0,0,0\n", encoding="utf-8")
    (folder / "interior_garbage.yaml").write_text("camera: [unclosed\n  : : :\n",
                                                  encoding="utf-8")
    (folder / "not_toml.toml").write_text("[batch\nproject = \n", encoding="utf-8")


# -- one case's workspace ------------------------------------------------------------------------
@dataclass
class Workspace:
    """The folders of one case: ``p`` a private copy of the project, ``w`` a work folder (the
    current directory during the run), ``bad`` the shared bad files."""

    p: Path
    w: Path
    bad: Path

    @property
    def roots(self) -> List[Path]:
        return [self.p, self.w, self.bad]

    def fmt(self, text: str) -> str:
        """``text`` with ``{p}``, ``{w}``, ``{bad}``, ``{truth}``, ``{img}`` filled in."""
        return text.format(p=self.p, w=self.w, bad=self.bad, truth=self.p / "truth",
                           img=self.p / "images")


# -- the checks ----------------------------------------------------------------------------------
Snapshot = Dict[str, Optional[str]]  # path -> sha256 of a file, None for a folder


def snapshot(roots: Iterable[Path]) -> Snapshot:
    """Every file (sha256) and folder below ``roots``, hidden ones included."""
    state: Snapshot = {}
    for root in roots:
        for dirpath, _dirs, filenames in os.walk(root):
            state[os.fsdecode(dirpath)] = None
            for name in filenames:
                path = os.path.join(dirpath, name)
                if os.path.islink(path):
                    state[path] = "link:" + os.readlink(path)
                    continue
                digest = hashlib.sha256()
                with open(path, "rb") as f:
                    for block in iter(lambda: f.read(1 << 20), b""):
                        digest.update(block)
                state[path] = digest.hexdigest()
    return state


def changed_inputs(before: Snapshot, after: Snapshot, allowed: Sequence[Path] = ()) -> List[str]:
    """Paths of ``before`` that are gone or changed, outside the ``allowed`` outputs."""
    return [path for path, digest in before.items()
            if not _under(path, allowed) and after.get(path, "<gone>") != digest]


def new_paths(before: Snapshot, after: Snapshot) -> List[str]:
    """Paths that did not exist before the run."""
    return sorted(path for path in after if path not in before)


def leftovers(paths: Iterable[str]) -> List[str]:
    """Paths whose name marks a staging, scratch or temporary file."""
    return [p for p in paths if any(m in os.path.basename(p) for m in LEFTOVER_MARKS)]


def _under(path: str, folders: Sequence[Path]) -> bool:
    return any(path == str(f) or path.startswith(str(f) + os.sep) for f in folders)


def stderr_lines(err: str) -> List[str]:
    """The non-empty lines of stderr."""
    return [line for line in err.splitlines() if line.strip()]


def assert_operator_error(code: int, err: str, allow_warnings: bool = False) -> None:
    """Exit 2 and exactly one stderr line ``photodem: error: …`` (so no traceback); with
    ``allow_warnings``, ``photodem: warning: …`` lines may come before it."""
    lines = stderr_lines(err)
    if allow_warnings:
        lines = [line for line in lines if not line.startswith(WARNING_PREFIX)]
    assert "Traceback" not in err, f"traceback instead of an operator error:\n{err[-2000:]}"
    assert code == 2, f"exit {code}, expected 2; stderr:\n{err[-2000:]}"
    assert len(lines) == 1 and lines[0].startswith(ERROR_PREFIX), \
        f"expected one line '{ERROR_PREFIX} …', got {len(lines)} lines:\n{err[-2000:]}"


def assert_success(code: int, err: str, warning: bool) -> None:
    """Exit 0, no traceback, only warning lines; at least one when ``warning``."""
    lines = stderr_lines(err)
    assert "Traceback" not in err, f"traceback:\n{err[-2000:]}"
    assert code == 0, f"exit {code}, expected 0; stderr:\n{err[-2000:]}"
    others = [line for line in lines if not line.startswith(WARNING_PREFIX)]
    assert not others, f"unexpected stderr lines under --quiet: {others}"
    if warning:
        assert lines, ("expected a warning line: the input is usable only with a repair, "
                       "a reprojection or a caveat the operator must read")


# -- running photodem ----------------------------------------------------------------------------
def run_in_process(argv: Sequence[str], capfd) -> Tuple[int, str, str]:
    """``photodem ARGV`` through :func:`cli.main` in this process; returns (code, out, err)."""
    from photodem.algorithms import cli

    capfd.readouterr()
    code = cli.main(list(argv))
    out, err = capfd.readouterr()
    return code, out, err


def _limit_memory(limit_bytes: int) -> None:
    resource.setrlimit(resource.RLIMIT_AS, (limit_bytes, limit_bytes))


def run_isolated(argv: Sequence[str], cwd: Path, timeout: float = 90.0,
                 memory_gb: float = 3.0) -> Tuple[int, str, str]:
    """``photodem ARGV`` as a subprocess with a memory limit and a timeout (cases that may try
    huge allocations or long work on today's code must not endanger the test session)."""
    limit = int(memory_gb * 2**30)
    try:
        proc = subprocess.run([str(PHOTODEM), *argv], cwd=cwd, capture_output=True,
                              timeout=timeout, preexec_fn=lambda: _limit_memory(limit))
    except subprocess.TimeoutExpired as exc:
        err = os.fsdecode(exc.stderr or b"")
        return -1, "", f"timed out after {timeout:.0f} s (no early parameter check)\n{err}"
    return proc.returncode, os.fsdecode(proc.stdout), os.fsdecode(proc.stderr)


def read_marker(folder: Path) -> dict:
    """The product marker of a folder PhotoDEM wrote."""
    return json.loads((folder / ".photodem-product.json").read_text(encoding="utf-8"))
