"""Staging: names owned by a process, stale leftovers removed, commit points (issue 16)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import rasterio

from photodem.algorithms import output_policy
from photodem.algorithms.errors import InputError
from photodem.algorithms.feedback import Feedback
from photodem.algorithms.processing import registry
from photodem.algorithms.processing.spec import Algorithm, Output, Parameter
from photodem.algorithms.raster import io as rio
from photodem.algorithms.raster.io import (
    PRODUCT_MARKER,
    atomic_output,
    staged_folder,
    write_raster,
)


@pytest.fixture(scope="module")
def dead_pid() -> int:
    """The id of a process that has ended."""
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    assert not output_policy.pid_alive(proc.pid)
    return proc.pid


def _leftovers(folder: Path, pid: int) -> list:
    """One of each kind of staging leftover of process ``pid`` in ``folder``."""
    made = [folder / f".dsm.{pid}.0123abcd.partial.tif",
            folder / f".dsm.{pid}.0123abcd.partial.scratch.tif",
            folder / f".dsm.{pid}.0123abcd.partial.tif.aux.xml",
            folder / f".model.{pid}.89abcdef.partial",
            folder / f".model.{pid}.fedcba98.old"]
    for path in made:
        if path.suffix in (".tif", ".xml"):
            path.write_bytes(b"half")
        else:
            path.mkdir()
            (path / "dsm.tif").write_bytes(b"half")
    return made


# -- names -----------------------------------------------------------------------------------------
def test_staging_names_carry_the_process_id(tmp_path):
    seen = []
    with atomic_output(tmp_path / "a.tif") as tmp:
        seen.append(tmp.name)
        tmp.write_bytes(b"x")
    with staged_folder(tmp_path / "f", product="t") as tmp:
        seen.append(tmp.name)
    for name in seen:
        assert f".{os.getpid()}." in name and ".partial" in name
    assert (tmp_path / "a.tif").read_bytes() == b"x"
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_a_failure_leaves_nothing(tmp_path):
    with pytest.raises(RuntimeError), atomic_output(tmp_path / "a.tif") as tmp:
        tmp.write_bytes(b"x")
        raise RuntimeError("boom")
    with pytest.raises(RuntimeError), staged_folder(tmp_path / "f", product="t") as tmp:
        (tmp / "x").write_text("x")
        raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []


# -- leftovers -------------------------------------------------------------------------------------
def test_stale_leftovers_of_a_dead_process_are_removed(tmp_path, dead_pid):
    made = _leftovers(tmp_path, dead_pid)
    mine = _leftovers(tmp_path, os.getpid())
    operator = tmp_path / ".notes.partial"  # not a staging name: never touched
    operator.write_text("mine")
    said = []
    removed = output_policy.remove_stale([tmp_path], said.append)
    assert sorted(removed) == sorted(made)
    assert all(not p.exists() for p in made)
    assert all(p.exists() for p in mine) and operator.exists()
    assert len(said) == len(made)
    assert all(f"process {dead_pid}, no longer running" in s for s in said)


def test_a_run_removes_leftovers_where_it_writes_and_says_so(tmp_path, dead_pid, monkeypatch):
    class Write(Algorithm):
        id = "test_stage_write"
        parameters = (Parameter("output", "output_folder", "Folder"),)
        outputs = (Output("folder", "folder", "Folder"),)

        def run(self, params, feedback):
            with staged_folder(params["output"], replace=True) as tmp:
                (tmp / "a.txt").write_text("a")
            return {"folder": params["output"]}

    monkeypatch.setattr(registry, "_CACHE", registry.algorithms())
    registry.add(Write())
    out = tmp_path / "out"
    registry.run("test_stage_write", {"output": str(out)})
    beside = _leftovers(tmp_path, dead_pid)
    inside = _leftovers(out, dead_pid)
    live = [p.rename(p.with_name(p.name.replace(".dsm.", ".live.")))
            for p in _leftovers(tmp_path, os.getppid())]
    feedback = Feedback()
    registry.run("test_stage_write", {"output": str(out)}, feedback)
    assert not any(p.exists() for p in beside)
    assert all(p.exists() for p in live)
    # the folder itself was replaced, so its leftovers went with it
    assert not any(p.exists() for p in inside)
    assert any("Removed the leftover" in line for line in feedback.lines)
    assert json.loads((out / PRODUCT_MARKER).read_text())["product"] == "test_stage_write"


# -- staged_folder: the second line of defence ---------------------------------------------------
def test_staged_folder_replaces_only_the_same_product(tmp_path):
    out = tmp_path / "f"
    with staged_folder(out, replace=True, product="alpha") as tmp:
        (tmp / "v").write_text("1")
    with staged_folder(out, replace=True, product="alpha") as tmp:
        (tmp / "v").write_text("2")
    assert (out / "v").read_text() == "2"
    with pytest.raises(InputError, match="product of 'alpha'"), \
            staged_folder(out, replace=True, product="beta"):
        pass
    assert (out / "v").read_text() == "2"
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_staged_folder_never_replaces_or_marks_a_project(tmp_path):
    out = tmp_path / "p"
    with staged_folder(out, product="synthetic_block") as tmp:
        (tmp / "project.toml").write_text('name = "x"\n')
    assert not (out / PRODUCT_MARKER).exists()
    (out / PRODUCT_MARKER).write_text(json.dumps({"product": "dem_compare"}))  # old marker
    with pytest.raises(InputError, match="project"), \
            staged_folder(out, replace=True, product="dem_compare"):
        pass
    assert (out / "project.toml").is_file()


#: The swap with a SIGINT between its two renames, in a fresh interpreter with Python's default
#: SIGINT handler — whatever earlier tests left in this process, and although a shell starts
#: background jobs with SIGINT ignored (then Python keeps it ignored and nothing is raised).
_SWAP_INTERRUPTED = """
import os, signal, sys
from pathlib import Path
from photodem.algorithms.raster import io as rio
signal.signal(signal.SIGINT, signal.default_int_handler)
out = Path(sys.argv[1])
with rio.staged_folder(out, replace=True, product="alpha") as tmp:
    (tmp / "v").write_text("old")
real_replace, calls = os.replace, []

def replace_with_interrupt(src, dst):
    calls.append(dst)
    if len(calls) == 1:  # between "old moved aside" and "new moved in"
        signal.raise_signal(signal.SIGINT)
    real_replace(src, dst)

rio.os.replace = replace_with_interrupt
try:
    with rio.staged_folder(out, replace=True, product="alpha") as tmp:
        (tmp / "v").write_text("new")
except KeyboardInterrupt:
    print("interrupted after", len(calls), "renames")
"""


def test_an_interrupt_during_the_swap_leaves_the_new_folder(tmp_path):
    out = tmp_path / "f"
    proc = subprocess.run([sys.executable, "-c", _SWAP_INTERRUPTED, str(out)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert "interrupted after 2 renames" in proc.stdout  # the interrupt waited for both
    assert (out / "v").read_text() == "new"


# -- commit points and product tags ----------------------------------------------------------------
def test_commits_are_recorded_for_the_run_outputs_only(tmp_path):
    target = output_policy.Target(tmp_path / "a.tif", "file", "output")
    committed = []
    with output_policy.run_scope("test", committed.append, [target]) as scope:
        write_raster(tmp_path / "scratch.tif", np.zeros((2, 2), np.float32))  # not an output
        assert not output_policy.committed()
        write_raster(tmp_path / "a.tif", np.zeros((2, 2), np.float32), overviews=True)
        assert output_policy.committed()
    assert scope.committed == [tmp_path / "a.tif"] and committed == [tmp_path / "a.tif"]
    assert output_policy.file_product(tmp_path / "a.tif") == "test"
    assert output_policy.file_product(tmp_path / "scratch.tif") is None


def test_a_committed_run_is_no_longer_cancelled(tmp_path):
    feedback = Feedback()
    target = output_policy.Target(tmp_path / "a.txt", "file", "output")
    with output_policy.run_scope("test", feedback.mark_committed, [target]):
        with atomic_output(tmp_path / "a.txt") as tmp:
            tmp.write_text("a")
        feedback.cancel()
        feedback.check()  # no Cancelled: the product set is finished
        feedback.step(0, 50).progress(100)
    assert output_policy.file_product(tmp_path / "a.txt") == "test"
    assert feedback.committed == [tmp_path / "a.txt"]  # what the CLI names after a stop


def test_product_tag_reader_on_bad_files(tmp_path):
    (tmp_path / "bad.tif").write_bytes(b"II*\x00\xff\xff\xff\xff")
    (tmp_path / "empty.tif").write_bytes(b"")
    (tmp_path / "text.tif").write_text("not a tiff")
    for name in ("bad.tif", "empty.tif", "text.tif", "missing.tif"):
        assert output_policy.file_product(tmp_path / name) is None
    write_raster(tmp_path / "big.tif", np.zeros((3, 3), np.float32), BIGTIFF="YES")
    rio.tag_product(tmp_path / "big.tif", "bigtest")
    assert output_policy.file_product(tmp_path / "big.tif") == "bigtest"


def test_product_tag_is_written_as_the_geotiff_is_created(tmp_path, monkeypatch):
    # no reopening in r+ mode: open_image tags the staged file when it creates it
    def no_reopen(path, product):
        raise AssertionError(f"{path} reopened to tag it")

    monkeypatch.setattr(rio, "tag_product", no_reopen)
    targets = [output_policy.Target(tmp_path / name, "file", "output")
               for name in ("a.tif", "c.tif")]
    with output_policy.run_scope("test", None, targets):
        write_raster(tmp_path / "a.tif", np.zeros((2, 2), np.float32))
        write_raster(tmp_path / "c.tif", np.zeros((300, 300), np.float32), overviews=True)
    assert output_policy.file_product(tmp_path / "a.tif") == "test"
    assert output_policy.file_product(tmp_path / "c.tif") == "test"
    assert not rio._TAG_ON_CREATE  # nothing pending is left behind


def test_other_writers_are_tagged_after_writing(tmp_path):
    target = output_policy.Target(tmp_path / "b.tif", "file", "output")
    profile = rio.gtiff_profile(2, 2, crs="EPSG:25832")
    with output_policy.run_scope("test", None, [target]), \
            rio.atomic_output(tmp_path / "b.tif") as tmp, \
            rasterio.open(tmp, "w", **profile) as dst:
        dst.write(np.zeros((1, 2, 2), np.float32))
    assert output_policy.file_product(tmp_path / "b.tif") == "test"
    assert not rio._TAG_ON_CREATE
