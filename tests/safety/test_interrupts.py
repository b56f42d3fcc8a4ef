"""Interrupts of single runs (issue 16, points 4 and 8): Ctrl-C at random moments and SIGKILL.

Three algorithms run long enough on the tiny project to be hit at many moments: ``match_model``
(an output folder), ``filter_lowpass`` (an output folder) and ``mosaic`` (one raster). Each is
first run once undisturbed to learn its duration and its complete product. Then, at six moments
drawn with ``random.Random(16)``, a run gets SIGINT. Afterwards the disk must hold either the
complete product with exit 0 (and no "no output was written"), or nothing at all with exit 130
and a message that says so; never a staging leftover. A rerun into the same output succeeds
and leaves nothing beside the output.

SIGKILL of a run leaves staging leftovers of a dead process; the rerun removes them and says so.
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


def _content(path: Path) -> Dict[str, int]:
    """What a product holds: file names (sizes left out: they vary) or a raster's shape."""
    if path.is_dir():
        return {p.name: 1 for p in path.iterdir()}
    import rasterio

    with rasterio.open(path) as src:
        return {"width": src.width, "height": src.height, "count": src.count}


@pytest.fixture(scope="module")
def references(tmp_path_factory, tiny_project) -> Dict[str, Tuple[float, Dict[str, int]]]:
    """Each subject run once undisturbed: (duration in s, content of its complete product)."""
    result = {}
    for s in SUBJECTS:
        folder = tmp_path_factory.mktemp(f"ref_{s.name}")
        out = s.out_path(folder)
        start = time.perf_counter()
        code, err = _run(s.argv(tiny_project, out) + ["--quiet"], folder)
        assert code == 0, err
        result[s.name] = (time.perf_counter() - start, _content(out))
    return result


def _beside(folder: Path, out: Path) -> List[str]:
    """Entries of ``folder`` other than the output."""
    return sorted(p.name for p in folder.iterdir() if p != out)


@pytest.mark.parametrize("subject,k,share", MOMENTS,
                         ids=[f"{s.name}-{k}-{share:.2f}" for s, k, share in MOMENTS])
def test_sigint_at_random_moment(subject: Subject, k: int, share: float, references,
                                 tiny_project: Path, tmp_path: Path) -> None:
    duration, complete = references[subject.name]
    out = subject.out_path(tmp_path)
    inputs = snapshot([tiny_project])
    proc = subprocess.Popen(subject.argv(tiny_project, out) + ["--quiet"], cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    time.sleep(share * duration)
    sent = proc.poll() is None
    if sent:
        proc.send_signal(signal.SIGINT)
    _, err_bytes = proc.communicate(timeout=max(120.0, 5 * duration))
    code, err = proc.returncode, os.fsdecode(err_bytes)
    assert "Traceback" not in err, err
    assert code in (0, 130), f"exit {code} after SIGINT at {share:.2f}×{duration:.1f} s:\n{err}"
    if code == 0:
        assert out.exists(), f"exit 0 but no output:\n{err}"
        assert _content(out) == complete, f"exit 0 with an incomplete product:\n{err}"
        assert "no output was written" not in err, f"says cancelled, output complete:\n{err}"
    else:
        assert not out.exists(), f"exit 130 ('{err.strip()}') but {out} exists"
        assert "cancel" in err.lower() or "interrupt" in err.lower(), err
    assert _beside(tmp_path, out) == [], f"left beside the output: {_beside(tmp_path, out)}"
    assert not changed_inputs(inputs, snapshot([tiny_project]))
    # a rerun into the same output succeeds (replacing its own product) and leaves nothing else
    code, err = _run(subject.argv(tiny_project, out) + ["--quiet"], tmp_path)
    assert code == 0, f"rerun failed (exit {code}):\n{err}"
    assert _content(out) == complete
    assert _beside(tmp_path, out) == [], f"rerun left: {_beside(tmp_path, out)}"


@pytest.mark.parametrize("subject", SUBJECTS[:2], ids=[s.name for s in SUBJECTS[:2]])
@pytest.mark.parametrize("share", [0.4, 0.8])
def test_sigkill_then_rerun_cleans_up(subject: Subject, share: float, references,
                                      tiny_project: Path, tmp_path: Path) -> None:
    """SIGKILL mid-run; the rerun succeeds, removes the dead run's staging leftovers and says
    so (it names what it removed)."""
    duration, complete = references[subject.name]
    out = subject.out_path(tmp_path)
    proc = subprocess.Popen(subject.argv(tiny_project, out) + ["--quiet"], cwd=tmp_path,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(share * duration)
    proc.kill()
    proc.wait(timeout=60)
    stale = _beside(tmp_path, out)  # what the dead run left (none when killed before staging)
    code, err = _run(subject.argv(tiny_project, out), tmp_path)  # not quiet: the log line
    assert code == 0, f"rerun after SIGKILL failed (exit {code}):\n{err}"
    assert _content(out) == complete
    assert _beside(tmp_path, out) == [], f"stale leftovers not removed: {_beside(tmp_path, out)}"
    assert not leftovers(str(p) for p in tmp_path.rglob("*"))
    if stale:
        said = [line for line in err.splitlines()
                if any(w in line.lower() for w in ("stale", "leftover", "removed"))]
        assert said, f"the rerun removed {stale} without saying so:\n{err}"
