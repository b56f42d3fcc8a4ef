"""Truthful cancellation: the final rename is a commit point, messages match the disk (issue 16).

In-process tests raise SIGINT from inside a fake algorithm at exact moments (before any
commit, during the rename, after it; once or twice); a subprocess test sends SIGINT at seeded
random moments to a real run.
"""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from photodem.algorithms import cli
from photodem.algorithms.processing import registry
from photodem.algorithms.processing.spec import Algorithm, Output, Parameter
from photodem.algorithms.raster import io as rio
from photodem.algorithms.raster.io import PRODUCT_MARKER, atomic_output, staged_folder

PHOTODEM = Path(sys.prefix) / "bin" / "photodem"


class Interrupted(Algorithm):
    """Writes two files, with SIGINT raised at the moments named by ``when``."""

    id = "test_interrupted"
    name = "Test: interrupted run"
    parameters = (
        Parameter("output", "output_folder", "Folder"),
        Parameter("when", "string", "Comma list: before, before2, after, after2", default=""),
    )
    outputs = (Output("folder", "folder", "Folder"),)

    def run(self, params, feedback):
        when = params["when"].split(",")
        for name in ("before", "before2"):
            if name in when:
                signal.raise_signal(signal.SIGINT)
        for i in range(5):
            feedback.progress(10.0 * i)  # checks for cancellation
        with staged_folder(params["output"], replace=True) as tmp:
            (tmp / "a.txt").write_text("a")
        for name in ("after", "after2"):
            if name in when:
                signal.raise_signal(signal.SIGINT)
        for i in range(5):
            feedback.progress(60.0 + 5.0 * i)
        return {"folder": params["output"]}


class TwoFiles(Algorithm):
    """Writes a file through atomic_output; SIGINT arrives during its rename."""

    id = "test_rename_interrupt"
    name = "Test: interrupt during the rename"
    parameters = (Parameter("output", "output_file", "File"),)
    outputs = (Output("file", "file", "File"),)

    def run(self, params, feedback):
        with atomic_output(params["output"]) as tmp:
            tmp.write_text("complete")
        return {"file": params["output"]}


@pytest.fixture(autouse=True)
def algs(monkeypatch):
    monkeypatch.setattr(registry, "_CACHE", registry.algorithms())
    registry.add(Interrupted())
    registry.add(TwoFiles())


def _main(capsys, *argv):
    code = cli.main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def _hidden(folder: Path) -> list:
    return [p.name for p in folder.iterdir() if p.name.startswith(".")]


def test_cancel_before_any_commit_leaves_nothing(tmp_path, capsys):
    out = tmp_path / "out"
    code, _, err = _main(capsys, "run", "test_interrupted", "--output", str(out),
                         "--when", "before")
    assert code == 130
    assert "cancelled; no output was written" in err
    assert not out.exists() and _hidden(tmp_path) == []


def test_second_ctrl_c_before_any_commit_leaves_nothing(tmp_path, capsys):
    out = tmp_path / "out"
    code, _, err = _main(capsys, "run", "test_interrupted", "--output", str(out),
                         "--when", "before,before2")
    assert code == 130
    assert "cancelled (interrupted); no output was written" in err
    assert not out.exists() and _hidden(tmp_path) == []


@pytest.mark.parametrize("when", ["after", "after,after2"])
def test_an_interrupt_after_the_commit_reports_success(tmp_path, capsys, when):
    out = tmp_path / "out"
    code, stdout, err = _main(capsys, "run", "test_interrupted", "--output", str(out),
                              "--when", when)
    assert code == 0, err
    assert "finished writing before the interrupt" in err
    assert "no output was written" not in err
    assert (out / "a.txt").read_text() == "a" and (out / PRODUCT_MARKER).is_file()
    assert f"folder: {out}" in stdout
    assert _hidden(tmp_path) == []


def test_an_interrupt_during_the_rename_is_held_back(tmp_path, capsys, monkeypatch):
    real_replace = os.replace

    def replace_with_interrupt(src, dst):
        signal.raise_signal(signal.SIGINT)  # arrives "just as" the output is renamed
        real_replace(src, dst)

    monkeypatch.setattr(rio.os, "replace", replace_with_interrupt)
    out = tmp_path / "r.txt"
    code, _, err = _main(capsys, "run", "test_rename_interrupt", "--output", str(out))
    assert code == 0, err
    assert "finished writing before the interrupt" in err
    assert out.read_text() == "complete"


def test_a_rerun_after_a_late_interrupt_replaces_the_product(tmp_path, capsys):
    out = tmp_path / "out"
    assert _main(capsys, "run", "test_interrupted", "--output", str(out), "--when",
                 "after")[0] == 0
    code, _, err = _main(capsys, "run", "test_interrupted", "--output", str(out))
    assert code == 0 and "before the interrupt" not in err


# -- a real run, interrupted at seeded random moments ---------------------------------------------
@pytest.fixture(scope="module")
def project(tmp_path_factory):
    out = tmp_path_factory.mktemp("cancel") / "p"
    registry.run("synthetic_block", {"output": str(out), "size": "tiny"})
    return out


@pytest.mark.skipif(not PHOTODEM.exists(), reason="console script not installed")
@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.slow
def test_sigint_at_a_random_moment_matches_the_disk(project, tmp_path, seed):
    delay = random.Random(seed).uniform(0.8, 3.0)  # start-up ≈ 1 s, the run ≈ 1–2 s
    out = tmp_path / "cmp"
    proc = subprocess.Popen(
        [str(PHOTODEM), "run", "dem_compare", "--dem", str(project / "truth/dsm.tif"),
         "--reference", str(project / "truth/dtm.tif"), "--output", str(out), "--quiet"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(delay)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    if proc.returncode == 0:
        assert (out / PRODUCT_MARKER).is_file() and (out / "stats.json").is_file()
    else:
        assert proc.returncode == 130, err
        assert "no output was written" in err or "interrupted" in err
        assert not out.exists()
    assert "Traceback" not in err
    assert _hidden(tmp_path) == []
    # a rerun succeeds (and replaces a complete earlier result)
    rerun = subprocess.run(
        [str(PHOTODEM), "run", "dem_compare", "--dem", str(project / "truth/dsm.tif"),
         "--reference", str(project / "truth/dtm.tif"), "--output", str(out), "--quiet"],
        capture_output=True, text=True, timeout=120)
    assert rerun.returncode == 0, rerun.stderr
    assert (out / "stats.json").is_file() and _hidden(tmp_path) == []


@pytest.mark.skipif(not PHOTODEM.exists(), reason="console script not installed")
@pytest.mark.parametrize("seed", [4, 5])
@pytest.mark.slow
def test_a_killed_run_leaves_nothing_a_rerun_does_not_clean(project, tmp_path, seed):
    delay = random.Random(seed).uniform(1.0, 2.5)
    out = tmp_path / "cmp"
    argv = [str(PHOTODEM), "run", "dem_compare", "--dem", str(project / "truth/dsm.tif"),
            "--reference", str(project / "truth/dtm.tif"), "--output", str(out)]
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(delay)
    proc.kill()
    proc.wait(timeout=60)
    left = _hidden(tmp_path)
    if out.exists():  # killed after the rename: the product is complete
        assert (out / PRODUCT_MARKER).is_file()
    rerun = subprocess.run(argv, capture_output=True, text=True, timeout=120)
    assert rerun.returncode == 0, rerun.stderr
    assert _hidden(tmp_path) == []
    if left:
        assert f"process {proc.pid}, no longer running" in rerun.stderr
