"""Translations: one context, one ``.qm`` per language in ``i18n/``.

English is the source language. German lives in ``i18n/photodem_de.ts`` (committed) and is
compiled to ``photodem_de.qm`` by ``lrelease`` at build time (``tools/update_translations.py``,
``tools/build_zip.py``).

The locale is found robustly: QGIS's ``QgsApplication.locale()`` inside QGIS, the system locale
outside. We never slice ``QSettings().value("locale/userLocale")`` — it is ``None`` in a fresh
QGIS profile and crashes plugins that do (qgis/QGIS#52359).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any, Optional

from ..algorithms.errors import Message, fill
from .qt import QCoreApplication, QLocale, QTranslator

#: Translation context of every PhotoDEM string (plugin and algorithm specs alike).
CONTEXT = "photodem"
I18N_DIR = Path(__file__).resolve().parents[1] / "i18n"

_installed: Optional[QTranslator] = None  # keep a reference, or Qt drops the translator


def tr(text: str) -> str:
    """Translate ``text`` in the PhotoDEM context (returns it unchanged without a translation)."""
    if not text:
        return text
    return QCoreApplication.translate(CONTEXT, text)


def message_text(message: Message) -> str:
    """A core message (:class:`~photodem.algorithms.errors.Message`) in the operator's language.

    The template is translated and filled with the same values; values that are messages
    themselves are translated first. A translation that lost or misspelt a value falls back
    to the English sentence, which is better than no message at all.
    """
    values = {key: message_text(value) if isinstance(value, Message) else value
              for key, value in message.values.items()}
    try:
        return fill(tr(message.template), values)
    except (KeyError, IndexError, ValueError, TypeError, AttributeError):
        return str(message)


def error_text(error: Any, message: Optional[Message] = None) -> str:
    """The text of an operator error for the GUIs: its translated :class:`Message` when it has
    one (``message``, else ``error.message``), else ``str(error)`` as the core wrote it."""
    message = message if message is not None else getattr(error, "message", None)
    return message_text(message) if isinstance(message, Message) else str(error)


def language(locale: Optional[str] = None) -> str:
    """Two-letter language code to translate into, e.g. ``"de"``; ``"en"`` when unknown.

    Parameters
    ----------
    locale : str, optional
        A locale name such as ``"de_DE"``, ``"de-AT"`` or ``"de"``; default: QGIS's locale inside
        QGIS, else the system locale.
    """
    if not locale:
        qgis_core = sys.modules.get("qgis.core")
        if qgis_core is not None:
            try:
                locale = qgis_core.QgsApplication.locale()
            except Exception:  # an app that is not fully initialised
                locale = None
    if not locale:
        locale = QLocale.system().name()
    text = str(locale or "").strip().replace("-", "_").lower()
    code = text.split("_")[0].split(".")[0]
    return code if len(code) in (2, 3) and code.isalpha() else "en"


def qm_path(lang: str) -> Path:
    """The compiled translation for ``lang`` (it may not exist)."""
    return I18N_DIR / f"photodem_{lang}.qm"


def load_translator(lang: str) -> Optional[QTranslator]:
    """A QTranslator loaded with ``i18n/photodem_<lang>.qm``; ``None`` if there is none."""
    path = qm_path(lang)
    if lang == "en" or not path.is_file():
        return None
    translator = QTranslator()
    if not translator.load(str(path)):
        return None
    return translator


def install_translator(locale: Optional[str] = None) -> Optional[QTranslator]:
    """Install the translator for the current (or given) locale application-wide.

    Calling it again replaces the previous PhotoDEM translator. Returns the installed translator
    (``None`` for English or a language without a ``.qm``).
    """
    global _installed
    remove_translator()
    translator = load_translator(language(locale))
    if translator is not None and QCoreApplication.instance() is not None:
        QCoreApplication.installTranslator(translator)
        _installed = translator
    return _installed


def remove_translator() -> None:
    """Remove the translator installed by :func:`install_translator`, if any."""
    global _installed
    if _installed is not None:
        if QCoreApplication.instance() is not None:
            QCoreApplication.removeTranslator(_installed)
        _installed = None
