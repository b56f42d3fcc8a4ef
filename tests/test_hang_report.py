"""The hang alarm of ``tests/conftest.py`` and ``tools/hang_report.py``: a hung test ends the
run and is named last, with its own frames."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.slow
@pytest.mark.skipif(not hasattr(signal, "alarm"), reason="no SIGALRM on this system")
def test_a_hung_test_ends_the_run_and_is_named(tmp_path: Path) -> None:
    shutil.copy(ROOT / "tests" / "conftest.py", tmp_path / "conftest.py")
    (tmp_path / "test_sleeps.py").write_text(
        "import time\n\ndef test_quick():\n    pass\n\n"
        "def test_sleeps_long():\n    time.sleep(60)\n")
    trace = tmp_path / "trace"
    env = dict(os.environ, PHOTODEM_HUNG_TEST_S="4", PHOTODEM_TEST_TRACE=str(trace))
    run = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                          "test_sleeps.py"], cwd=tmp_path, env=env, capture_output=True,
                         timeout=60)
    assert run.returncode == -signal.SIGALRM
    report = subprocess.run([sys.executable, str(ROOT / "tools" / "hang_report.py"),
                             str(trace)], capture_output=True, text=True, timeout=30)
    lines = report.stderr.strip().splitlines()
    assert lines[-1] == "=== hung test: test_sleeps.py::test_sleeps_long ==="
    assert any("test_sleeps.py\", line 7 in test_sleeps_long" in line for line in lines)
    assert not any("_pytest" in line for line in lines)  # the runner's frames left out


def test_no_report_without_a_hang(tmp_path: Path) -> None:
    (tmp_path / "stacks").write_text("")
    (tmp_path / "current").write_text("test_x.py::test_y\n")
    report = subprocess.run([sys.executable, str(ROOT / "tools" / "hang_report.py"),
                             str(tmp_path)], capture_output=True, text=True, timeout=30)
    assert report.returncode == 0 and report.stdout == report.stderr == ""
