"""German for screenshots before the lead merges the parts' new strings: the committed .ts plus
every ``/work/prompts/de_*.tsv`` compiled into a temporary .qm (the shared .ts is not edited)."""

from __future__ import annotations

import glob
import shutil
import subprocess
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest


def install_preview_german() -> None:
    """Install the merged German translation (skips the test without lrelease)."""
    from photodem.plugin import i18n
    from photodem.plugin.qt import QCoreApplication, QTranslator

    ts = Path(i18n.I18N_DIR) / "photodem_de.ts"
    if not ts.is_file() or shutil.which("lrelease") is None:
        pytest.skip("no German sources or lrelease to preview the translation")
    pairs = {}
    for name in sorted(glob.glob("/work/prompts/de_*.tsv")):
        for line in Path(name).read_text(encoding="utf-8").splitlines():
            if "\t" in line:
                english, german = line.split("\t", 1)
                pairs[english] = german
    tree = ET.parse(ts)
    context = tree.getroot().find("context")
    for message in tree.iter("message"):
        english = message.findtext("source")
        if english in pairs:
            message.find("translation").text = pairs.pop(english)
            message.find("translation").attrib.pop("type", None)
    for english, german in pairs.items():
        message = ET.SubElement(context, "message")
        ET.SubElement(message, "source").text = english
        ET.SubElement(message, "translation").text = german
    folder = Path(tempfile.mkdtemp(prefix="photodem-de-"))
    tree.write(folder / "de.ts", encoding="utf-8", xml_declaration=True)
    subprocess.run(["lrelease", "-silent", str(folder / "de.ts"), "-qm", str(folder / "de.qm")],
                   check=True)
    i18n.remove_translator()
    translator = QTranslator()
    assert translator.load(str(folder / "de.qm"))
    QCoreApplication.installTranslator(translator)
    i18n._installed = translator
