"""Translations: robust locale detection and the German .qm in use when QGIS's locale is de."""

from __future__ import annotations

import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

pytestmark = pytest.mark.qgis

ROOT = Path(__file__).resolve().parents[2]
TS = ROOT / "i18n" / "photodem_de.ts"


@pytest.fixture(scope="module")
def german_qm(tmp_path_factory) -> Path:
    """photodem_de.qm compiled from the committed .ts with lrelease (a build-time step)."""
    sys.path.insert(0, str(ROOT / "tools"))
    from update_translations import find_lrelease, release

    if find_lrelease() is None:
        pytest.skip("lrelease not installed (Debian package qttools5-dev-tools)")
    out = tmp_path_factory.mktemp("qm")
    release([TS], out)
    return out


def _translations() -> dict:
    return {m.findtext("source"): m.findtext("translation")
            for m in ET.parse(TS).getroot().iter("message")}


@pytest.mark.parametrize(("locale", "expected"), [
    ("de_DE", "de"), ("de-AT", "de"), ("DE", "de"), ("de_DE.UTF-8", "de"), ("en_US", "en"),
    ("C", "en"), ("", None), (None, None),
])
def test_language_is_robust(qgis_app, locale, expected):
    from photodem.plugin.i18n import language

    got = language(locale)
    assert got == (expected or language(None))  # empty/None → QGIS's own locale
    assert isinstance(got, str) and got


def test_fresh_profile_has_no_user_locale_and_nothing_crashes(qgis_app):
    """The Plugin-Builder idiom QSettings().value('locale/userLocale')[0:2] would crash here."""
    from qgis.core import QgsSettings

    from photodem.plugin.i18n import install_translator, language

    assert QgsSettings().value("locale/userLocale") is None
    assert language() == "en"  # QgsApplication.locale() is "C" without LANG
    assert install_translator() is None  # English: no translator needed


def test_every_string_has_a_german_translation():
    sys.path.insert(0, str(ROOT / "tools"))
    from update_translations import collect

    translations = _translations()
    missing = [s for s in collect() if not translations.get(s)]
    assert not missing, f"untranslated (run tools/update_translations.py): {missing}"


def test_german_translator_used_when_qgis_locale_is_de(qgis_app, provider, german_qm,
                                                       monkeypatch):
    from qgis.core import QgsApplication, QgsSettings

    from photodem.algorithms.processing import registry
    from photodem.plugin import i18n

    monkeypatch.setattr(i18n, "I18N_DIR", german_qm)
    settings = QgsSettings()
    settings.setValue("locale/overrideFlag", True)
    settings.setValue("locale/userLocale", "de_DE")
    try:
        assert QgsApplication.locale() == "de_DE"
        translator = i18n.install_translator()  # what the plugin does in its constructor
        assert translator is not None
        provider.refreshAlgorithms()  # the plugin installs it before creating the provider
        assert provider.longName().startswith("PhotoDEM Luftbildphotogrammetrie")
        translations = _translations()
        for spec in registry.algorithms().values():
            alg = QgsApplication.processingRegistry().algorithmById(f"photodem:{spec.id}")
            assert alg.displayName() == translations[spec.name], spec.id
            assert alg.group() == translations[spec.group], spec.id
            for p, d in zip(spec.parameters, alg.parameterDefinitions()):
                assert d.description() == translations[p.description], f"{spec.id}.{p.name}"
    finally:
        i18n.remove_translator()
        settings.setValue("locale/overrideFlag", False)
        settings.remove("locale/userLocale")
        provider.refreshAlgorithms()
    assert provider.longName().startswith("PhotoDEM aerial photogrammetry")
