"""plugin/qt.py and plugin/i18n.py outside QGIS (tier A: PyQt5 wheel) and inside (tier B)."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def test_qt_shim_picks_one_binding():
    from photodem.plugin import qt

    assert qt.BINDING in ("PyQt5", "qgis.PyQt")
    assert qt.QCoreApplication is qt.QtCore.QCoreApplication
    assert qt.QAction is qt.QtWidgets.QAction


@pytest.mark.parametrize(("locale", "expected"), [
    ("de_DE", "de"), ("de-AT", "de"), ("DE", "de"), ("de_DE.UTF-8", "de"), ("en_US", "en"),
    ("C", "en"), ("POSIX", "en"), ("123", "en"),
])
def test_language(locale, expected):
    from photodem.plugin.i18n import language

    assert language(locale) == expected


def test_tr_without_translator_returns_source():
    from photodem.plugin.i18n import tr

    assert tr("Epipolar pair") == "Epipolar pair"
    assert tr("") == ""


def test_german_qm_translates(tmp_path, monkeypatch):
    """Compile the committed .ts with lrelease and load it, as the plugin does for locale de."""
    lrelease = shutil.which("lrelease") or shutil.which("/usr/lib/qt5/bin/lrelease")
    if lrelease is None:
        pytest.skip("lrelease not installed (Debian package qttools5-dev-tools)")
    from photodem.plugin import i18n
    from photodem.plugin.qt import QCoreApplication

    qm = tmp_path / "photodem_de.qm"
    subprocess.run([lrelease, "-silent", str(ROOT / "i18n" / "photodem_de.ts"), "-qm", str(qm)],
                   check=True)
    monkeypatch.setattr(i18n, "I18N_DIR", tmp_path)
    app = QCoreApplication.instance() or QCoreApplication([])
    assert app is not None
    try:
        assert i18n.install_translator("de_DE") is not None
        assert i18n.tr("PhotoDEM algorithms") == "PhotoDEM-Algorithmen"
        assert i18n.install_translator("en_GB") is None  # English: the source text
        assert i18n.tr("PhotoDEM algorithms") == "PhotoDEM algorithms"
    finally:
        i18n.remove_translator()
