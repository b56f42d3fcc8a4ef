"""Shared fixtures: real data in ../shared/data (skipped when absent)."""

from __future__ import annotations

import faulthandler
import os
import signal
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = Path(os.environ.get("PHOTODEM_SHARED_DATA", ROOT.parent / "shared" / "data"))


#: Seconds after which a test counts as hung and ends the run (``SIGALRM``'s default action,
#: which needs no Python, so it works even when a deadlock holds the GIL). Every thread's stack
#: has been dumped 30 s before (a fifth of the time for short limits) (``faulthandler``, from
#: its own C thread): a hang costs minutes and says where it is, instead of running into CI's
#: time limit silently.
HUNG_TEST_S = int(os.environ.get("PHOTODEM_HUNG_TEST_S", "660"))
#: Folder for the hang record (``make test`` sets it): ``current`` holds the running test's id,
#: ``stacks`` the dump. A run killed by the alarm leaves both for ``tools/hang_report.py``,
#: which prints them last — CI shows only the end of the output, where pytest's own dump of
#: all threads would leave the main thread's bottom frames and no test name. Unset: the dump
#: goes to stderr.
TRACE_DIR = os.environ.get("PHOTODEM_TEST_TRACE", "")
_TRACE: dict = {}


def pytest_configure(config) -> None:
    if TRACE_DIR:
        folder = Path(TRACE_DIR)
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "current").unlink(missing_ok=True)
        _TRACE["current"] = folder / "current"
        # kept open for the whole run: faulthandler writes to it from its own thread
        _TRACE["stacks"] = open(folder / "stacks", "w")  # noqa: SIM115
    else:  # a copy of stderr as it is now: fd 2 is redirected while a test's output is captured
        _TRACE["stacks"] = os.fdopen(os.dup(sys.stderr.fileno()), "w")


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    """Arm the stack dump and the hang alarm for one test (setup, call and teardown)."""
    armed = hasattr(signal, "alarm") and HUNG_TEST_S > 0
    if armed:
        if "current" in _TRACE:
            _TRACE["current"].write_text(item.nodeid + "\n")
        faulthandler.dump_traceback_later(HUNG_TEST_S - min(30.0, 0.2 * HUNG_TEST_S),
                                          file=_TRACE["stacks"])
        signal.alarm(HUNG_TEST_S)
    try:
        yield
    finally:
        if armed:
            signal.alarm(0)
            faulthandler.cancel_dump_traceback_later()


def shared_data(name: str) -> Path:
    """Folder of a real data set below ../shared/data, or skip the test with the reason."""
    path = SHARED_DATA / name
    if not path.is_dir():
        pytest.skip(f"real data '{name}' not found at {path} (../shared/data is absent)")
    return path


@pytest.fixture
def ngi_block() -> Path:
    """The NGI aerial block (4 frames, EO/IO, reference DEM)."""
    return shared_data("ngi_aerial_block")


@pytest.fixture
def chain_project(tmp_path):
    """A factory of small projects without image files: ``chain_project("abc")`` makes
    ``<tmp>/proj`` with images a, b, c on one camera and the stereo models a_b, b_c."""
    def make(names: str) -> Path:
        from photodem.algorithms.geometry.camera import Camera
        from photodem.algorithms.geometry.orientation import ExteriorOrientation
        from photodem.algorithms.project.model import ImageRecord, Project, StereoModel

        root = tmp_path / "proj"
        eo = ExteriorOrientation.from_opk([0.0, 0.0, 1000.0], 0.0, 0.0, 0.0)
        images = [ImageRecord(n, f"{n}.tif", "c", eo) for n in names]  # no files
        Project(root=root, name="t", crs="EPSG:25832",
                cameras={"c": Camera("c", 100, 80, 1.0, (0.01, 0.01))}, images=images,
                models=[StereoModel(f"{a}_{b}", a, b) for a, b in zip(names, names[1:])]).save()
        return root
    return make


@pytest.fixture
def shots_dir(tmp_path) -> Path:
    """Where screenshot tests save their PNGs: ``$PHOTODEM_SHOTS`` (to look at them) or a
    temporary folder."""
    folder = Path(os.environ.get("PHOTODEM_SHOTS") or tmp_path / "shots")
    folder.mkdir(parents=True, exist_ok=True)
    return folder


@pytest.fixture
def german(tmp_path, monkeypatch):
    """A function that installs the German translation compiled from the committed
    ``i18n/photodem_de.ts`` (skips without ``lrelease``); English again after the test."""
    import shutil
    import subprocess

    from photodem.plugin import i18n

    def install() -> None:
        lrelease = shutil.which("lrelease") or shutil.which("/usr/lib/qt5/bin/lrelease")
        if lrelease is None:
            pytest.skip("lrelease not installed (Debian package qttools5-dev-tools)")
        qm = tmp_path / "photodem_de.qm"
        subprocess.run([lrelease, "-silent", str(ROOT / "i18n" / "photodem_de.ts"), "-qm",
                        str(qm)], check=True)
        monkeypatch.setattr(i18n, "I18N_DIR", tmp_path)
        assert i18n.install_translator("de_DE") is not None

    yield install
    i18n.remove_translator()


@pytest.fixture(scope="session")
def tiny_block(tmp_path_factory) -> Path:
    """The tiny synthetic block (``synthetic_block --size tiny``, ≈ 4 s), made once per run.
    Read it only: a test that writes into a project copies it first."""
    from photodem.algorithms.processing import registry

    root = tmp_path_factory.mktemp("tiny-block") / "block"
    registry.run("synthetic_block", {"output": str(root), "size": "tiny"})
    return root


@pytest.fixture(scope="session")
def drone_block(tmp_path_factory) -> Path:
    """The synthetic drone block (``synthetic_block --size drone``, ≈ 15 s), made once per
    run. Read it only: a test that writes into a project copies it first."""
    from photodem.algorithms.processing import registry

    root = tmp_path_factory.mktemp("drone-block") / "block"
    registry.run("synthetic_block", {"output": str(root), "size": "drone"})
    return root
