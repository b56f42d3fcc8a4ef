"""Interrupts of single runs (issue 16, points 4 and 8): Ctrl-C at random moments and SIGKILL.

Three algorithms run long enough on the tiny project to be hit at many moments: ``match_model``
(an output folder), ``filter_lowpass`` (an output folder) and ``mosaic`` (one raster). Each is
first run once undisturbed to learn its duration and its complete product. Then, at six moments
drawn with ``random.Random(16)``, a run gets SIGINT. Afterwards the disk must hold either the
complete product with exit 0 (and no "no output was written"), or nothing at all with exit 130
and a message that says so; never a staging leftover. A rerun into the same output succeeds
and leaves nothing beside the output.

Two targeted moments complete the random ones: SIGINT as soon as a staged output appears, and
SIGINT right after the final rename (the commit point: the run must then report success).
SIGKILL of a run (while staged, or half-way) leaves staging leftovers of a dead process; the
rerun removes them and says so.
"""

from __future__ import annotations

import os
import random
import signal
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Tuple

import pytest
from _safety import PHOTODEM, changed_inputs, leftovers, snapshot

pytestmark = pytest.mark.slow

N_MOMENTS = 6


@dataclass(frozen=True)
class Subject:
    """An algorithm run: its arguments (``{p}`` project, ``{out}`` output) and output kind."""

    name: str
    args: Tuple[str, ...]
    output: str  # "folder" or "raster"

    def argv(self, project: Path, out: Path) -> List[str]:
        return [str(PHOTODEM), "run", *(a.format(p=project, out=out) for a in self.args)]

    def out_path(self, folder: Path) -> Path:
        return folder / ("out.tif" if self.output == "raster" else "out")


SUBJECTS = [
    Subject("match_model", ("match_model", "--project", "{p}", "--model", "0101_0102",
                            "--output", "{out}"), "folder"),
    Subject("filter_lowpass", ("filter_lowpass", "--input", "{p}/truth/dsm.tif", "--output",
                               "{out}"), "folder"),
    Subject("mosaic", ("mosaic", "--project", "{p}", "--dem", "{p}/truth/dtm.tif", "--output",
                       "{out}"), "raster"),
]


def _moments() -> List[Tuple[Subject, int, float]]:
    """Six moments per subject as shares of its undisturbed duration (seeded)."""
    rng = random.Random(16)
    return [(s, k, rng.uniform(0.05, 1.1)) for s in SUBJECTS for k in range(N_MOMENTS)]


MOMENTS = _moments()


def _run(argv: List[str], cwd: Path, timeout: float = 300.0) -> Tuple[int, str]:
    proc = subprocess.run(argv, cwd=cwd, capture_output=True, timeout=timeout)
    return proc.returncode, os.fsdecode(proc.stderr)


def _product_names(folder: Path) -> List[str]:
    """The product's entries in ``folder``: the output and its sidecars (``out_seamlines.gpkg``
    …), i.e. visible names starting with ``out``."""
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("out"))


def _beside(folder: Path) -> List[str]:
    """Entries of ``folder`` that are not part of the product (staging leftovers and such)."""
    return sorted(p.name for p in folder.iterdir() if not p.name.startswith("out"))


def _content(folder: Path, out: Path) -> Dict[str, object]:
    """What a product holds: its file names (and a folder's file names, or a raster's shape)."""
    content: Dict[str, object] = {"names": _product_names(folder)}
    if not out.exists():
        return content
    if out.is_dir():
        content["files"] = sorted(p.name for p in out.iterdir())
    else:
        import rasterio

        with rasterio.open(out) as src:
            content["shape"] = (src.count, src.height, src.width)
    return content


@pytest.fixture(scope="module")
def references(tmp_path_factory, tiny_project) -> Dict[str, Tuple[float, Dict[str, object]]]:
    """Each subject run once undisturbed: (duration in s, content of its complete product)."""
    result = {}
    for s in SUBJECTS:
        folder = tmp_path_factory.mktemp(f"ref_{s.name}")
        out = s.out_path(folder)
        start = time.perf_counter()
        code, err = _run(s.argv(tiny_project, out) + ["--quiet"], folder)
        assert code == 0, err
        result[s.name] = (time.perf_counter() - start, _content(folder, out))
    return result


def _check_after_interrupt(code: int, err: str, folder: Path, out: Path,
                           complete: Dict[str, object], when: str) -> None:
    """The disk holds the complete product and the run says it finished (exit 0), or nothing
    and the run says it was cancelled (exit 130); never a leftover."""
    assert "Traceback" not in err, err
    names = _product_names(folder)
    if names:
        assert _content(folder, out) == complete, \
            f"{when}: a partial product {names} (exit {code}):\n{err}"
        assert code == 0, f"{when}: the product is complete but the exit is {code}:\n{err}"
        assert "no output was written" not in err, f"{when}: says cancelled:\n{err}"
    else:
        assert code == 130, f"{when}: nothing written, exit {code} (expected 130):\n{err}"
        assert "cancel" in err.lower(), f"{when}: exit 130 without 'cancelled':\n{err}"
    assert _beside(folder) == [], f"{when}: left beside the output: {_beside(folder)}"


def _rerun(subject: Subject, project: Path, folder: Path, out: Path,
           complete: Dict[str, object], quiet: bool = True) -> str:
    """Run again into the same output: it succeeds and leaves only the product. (When a
    complete product is there already, a clean one-line refusal is accepted too.)"""
    existed = out.exists()
    code, err = _run(subject.argv(project, out) + (["--quiet"] if quiet else []), folder)
    if existed and code == 2:
        assert err.strip().splitlines()[-1].startswith("photodem: error:"), err
    else:
        assert code == 0, f"rerun failed (exit {code}):\n{err}"
    assert _content(folder, out) == complete
    assert _beside(folder) == [], f"rerun left: {_beside(folder)}"
    return err


def _start(subject: Subject, project: Path, folder: Path, out: Path) -> subprocess.Popen:
    return subprocess.Popen(subject.argv(project, out) + ["--quiet"], cwd=folder,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def _wait_for_staging(proc: subprocess.Popen, folder: Path, limit: float) -> bool:
    """Poll until a staging entry appears beside the output (True) or the run ends (False)."""
    end = time.monotonic() + limit
    while proc.poll() is None and time.monotonic() < end:
        if _beside(folder):
            return True
        time.sleep(0.005)
    return False


@pytest.mark.parametrize("subject,k,share", MOMENTS,
                         ids=[f"{s.name}-{k}-{share:.2f}" for s, k, share in MOMENTS])
def test_sigint_at_random_moment(subject: Subject, k: int, share: float, references,
                                 tiny_project: Path, tmp_path: Path) -> None:
    duration, complete = references[subject.name]
    out = subject.out_path(tmp_path)
    inputs = snapshot([tiny_project])
    proc = _start(subject, tiny_project, tmp_path, out)
    time.sleep(share * duration)
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=max(120.0, 5 * duration))
    _check_after_interrupt(proc.returncode, os.fsdecode(err), tmp_path, out, complete,
                           f"SIGINT at {share:.2f} × {duration:.1f} s")
    assert not changed_inputs(inputs, snapshot([tiny_project]))
    _rerun(subject, tiny_project, tmp_path, out, complete)


@pytest.mark.parametrize("subject", SUBJECTS, ids=[s.name for s in SUBJECTS])
def test_sigint_while_staged(subject: Subject, references, tiny_project: Path,
                             tmp_path: Path) -> None:
    """SIGINT the moment a staged output appears: the window before the final rename."""
    duration, complete = references[subject.name]
    out = subject.out_path(tmp_path)
    proc = _start(subject, tiny_project, tmp_path, out)
    staged = _wait_for_staging(proc, tmp_path, limit=10 * duration)
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=max(120.0, 5 * duration))
    _check_after_interrupt(proc.returncode, os.fsdecode(err), tmp_path, out, complete,
                           f"SIGINT while staged (staging seen: {staged})")
    _rerun(subject, tiny_project, tmp_path, out, complete)


@pytest.mark.parametrize("subject", SUBJECTS, ids=[s.name for s in SUBJECTS])
def test_sigint_right_after_commit(subject: Subject, references, tiny_project: Path,
                                   tmp_path: Path) -> None:
    """SIGINT the moment the final output appears (the commit point, issue point 4): the run
    must report success (exit 0), never "cancelled; no output was written"."""
    duration, complete = references[subject.name]
    out = subject.out_path(tmp_path)
    proc = _start(subject, tiny_project, tmp_path, out)
    end = time.monotonic() + 10 * duration
    while proc.poll() is None and not out.exists() and time.monotonic() < end:
        time.sleep(0.001)
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=max(120.0, 5 * duration))
    _check_after_interrupt(proc.returncode, os.fsdecode(err), tmp_path, out, complete,
                           "SIGINT right after the final rename")
    _rerun(subject, tiny_project, tmp_path, out, complete)


@pytest.mark.parametrize("subject", SUBJECTS, ids=[s.name for s in SUBJECTS])
@pytest.mark.parametrize("moment", ["staged", "midrun"])
def test_sigkill_then_rerun_cleans_up(subject: Subject, moment: str, references,
                                      tiny_project: Path, tmp_path: Path) -> None:
    """SIGKILL while the output is staged (or half-way); the rerun succeeds, removes the dead
    run's staging leftovers and says so in its log."""
    duration, complete = references[subject.name]
    out = subject.out_path(tmp_path)
    proc = _start(subject, tiny_project, tmp_path, out)
    if moment == "staged":
        _wait_for_staging(proc, tmp_path, limit=10 * duration)
    else:
        time.sleep(0.5 * duration)
    proc.kill()
    proc.communicate(timeout=60)
    stale = _beside(tmp_path)  # what the dead run left (none when killed before staging)
    err = _rerun(subject, tiny_project, tmp_path, out, complete, quiet=False)
    assert not leftovers(str(p) for p in tmp_path.rglob("*"))
    if stale:
        said = [line for line in err.splitlines()
                if any(w in line.lower() for w in ("stale", "leftover", "removed"))]
        assert said, f"the rerun removed {stale} without saying so:\n{err}"
