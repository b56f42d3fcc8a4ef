"""Collect every user-facing string into i18n/photodem_<lang>.ts and compile it with lrelease.

Sources of strings (all in the translation context ``photodem``):

* the algorithm registry: display names, groups, help, parameter descriptions and help, enum
  options, output descriptions (translated at run time by the QGIS provider and the GUIs);
* literal ``tr("…")`` / ``QCoreApplication.translate("photodem", "…")`` calls in ``plugin/``;
* the templates of translatable operator errors in ``algorithms/``: the literal first argument
  of ``<Name>Error.of("…", …)`` and ``msg("…", …)`` (see ``algorithms/errors.py``).

Existing translations are kept; new strings get ``type="unfinished"``; strings that disappeared
are kept as ``type="vanished"`` (so a renamed-back string finds its translation again).
pylupdate5 is not used: it cannot see strings that live in the specs rather than in ``tr()``.

Usage::

    python tools/update_translations.py            # update i18n/photodem_de.ts
    python tools/update_translations.py --release  # … and compile i18n/photodem_de.qm
    python tools/update_translations.py --release-only  # compile only (build time)
    python tools/update_translations.py --check    # exit 1 if a string lacks a translation
"""

from __future__ import annotations

import argparse
import ast
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Dict, Iterable, List, Optional, Tuple

ROOT = Path(__file__).resolve().parents[1]
I18N = ROOT / "i18n"
CONTEXT = "photodem"
LANGUAGES = ("de",)
LANGUAGE_TAGS = {"de": "de_DE"}


def registry_strings() -> List[Tuple[str, str]]:
    """(text, where) for every user-facing string of the algorithm registry."""
    if str(ROOT.parent) not in sys.path:
        sys.path.insert(0, str(ROOT.parent))
    try:
        from photodem.algorithms.processing import registry
    except ImportError:  # the repository folder is not called photodem: use a temp symlink
        import tempfile

        link_dir = Path(tempfile.mkdtemp(prefix="photodem-i18n-"))
        (link_dir / "photodem").symlink_to(ROOT, target_is_directory=True)
        sys.path.insert(0, str(link_dir))
        from photodem.algorithms.processing import registry

    found: List[Tuple[str, str]] = []
    for alg in registry.algorithms().values():
        found.append((alg.name, f"{alg.id}: name"))
        found.append((alg.group, f"{alg.id}: group"))
        found.append((alg.help, f"{alg.id}: help"))
        for p in alg.parameters:
            found.append((p.description, f"{alg.id}.{p.name}: description"))
            found.append((p.help, f"{alg.id}.{p.name}: help"))
            found.extend((o, f"{alg.id}.{p.name}: option") for o in p.options)
        for o in alg.outputs:
            found.append((o.description, f"{alg.id} output {o.name}"))
    return [(text, where) for text, where in found if text]


def source_strings(folder: Path) -> List[Tuple[str, str]]:
    """Literal ``tr("…")`` and ``translate("photodem", "…")`` arguments in Python sources."""
    found: List[Tuple[str, str]] = []
    for path in sorted(folder.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for node in ast.walk(tree):
            if not isinstance(node, ast.Call):
                continue
            func = node.func
            name = func.id if isinstance(func, ast.Name) else getattr(func, "attr", "")
            args = node.args
            if name == "tr" and args:
                text = args[0]
            elif (name == "translate" and len(args) >= 2 and isinstance(args[0], ast.Constant)
                  and args[0].value == CONTEXT):
                text = args[1]
            else:
                continue
            if isinstance(text, ast.Constant) and isinstance(text.value, str) and text.value:
                where = f"{path.relative_to(ROOT).as_posix()}:{node.lineno}"
                found.append((text.value, where))
    return found


def _is_error_template(node: ast.Call) -> bool:
    """``XxxError.of(…)`` or ``msg(…)``: the markers of a translatable error message."""
    func = node.func
    if isinstance(func, ast.Name):
        return func.id == "msg"
    return (isinstance(func, ast.Attribute) and func.attr == "of"
            and isinstance(func.value, ast.Name) and func.value.id.endswith("Error"))


def error_templates(folder: Path) -> List[Tuple[str, str]]:
    """(template, where) of every translatable error message and phrase in ``folder``."""
    found: List[Tuple[str, str]] = []
    for path in sorted(folder.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for node in ast.walk(tree):
            if not (isinstance(node, ast.Call) and node.args and _is_error_template(node)):
                continue
            text = node.args[0]
            if isinstance(text, ast.Constant) and isinstance(text.value, str) and text.value:
                found.append((text.value, f"{path.relative_to(ROOT).as_posix()}:{node.lineno}"))
    return found


def collect() -> Dict[str, List[str]]:
    """Source text → places it comes from, in first-seen order."""
    strings: Dict[str, List[str]] = {}
    for text, where in [*registry_strings(), *source_strings(ROOT / "plugin"),
                        *error_templates(ROOT / "algorithms")]:
        strings.setdefault(text, []).append(where)
    return strings


def read_ts(path: Path) -> Dict[str, Tuple[str, str]]:
    """Source → (translation, type) of an existing .ts (type '' means finished)."""
    if not path.is_file():
        return {}
    known: Dict[str, Tuple[str, str]] = {}
    for message in ET.parse(path).getroot().iter("message"):
        source = message.findtext("source") or ""
        tr_el = message.find("translation")
        text = "" if tr_el is None else (tr_el.text or "")
        known[source] = (text, "" if tr_el is None else tr_el.get("type", ""))
    return known


def write_ts(path: Path, lang: str, strings: Dict[str, List[str]]) -> Dict[str, int]:
    """Write the .ts for ``lang``; returns counts of finished/unfinished/vanished messages."""
    known = read_ts(path)
    root = ET.Element("TS", version="2.1", language=LANGUAGE_TAGS.get(lang, lang),
                      sourcelanguage="en")
    context = ET.SubElement(root, "context")
    ET.SubElement(context, "name").text = CONTEXT
    counts = {"finished": 0, "unfinished": 0, "vanished": 0}

    def add(source: str, translation: str, kind: str, comment: Optional[str]) -> None:
        message = ET.SubElement(context, "message")
        ET.SubElement(message, "source").text = source
        if comment:
            ET.SubElement(message, "extracomment").text = comment
        tr_el = ET.SubElement(message, "translation")
        if translation:
            tr_el.text = translation
        if kind:
            tr_el.set("type", kind)

    for source, places in strings.items():
        translation, _ = known.get(source, ("", ""))
        kind = "" if translation else "unfinished"
        counts["unfinished" if kind else "finished"] += 1
        add(source, translation, kind, "; ".join(sorted(set(places)))[:300])
    for source, (translation, _) in known.items():
        if source not in strings and translation:
            counts["vanished"] += 1
            add(source, translation, "vanished", None)
    ET.indent(root, space="    ")
    body = ET.tostring(root, encoding="unicode")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text('<?xml version="1.0" encoding="utf-8"?>\n<!DOCTYPE TS>\n' + body + "\n",
                    encoding="utf-8")
    return counts


def find_lrelease() -> Optional[str]:
    """lrelease from Debian's qttools5-dev-tools (or the Qt 5 bin folder)."""
    for candidate in ("lrelease", "lrelease-qt5", "/usr/lib/qt5/bin/lrelease",
                      "/usr/lib/x86_64-linux-gnu/qt5/bin/lrelease"):
        found = shutil.which(candidate)
        if found:
            return found
    return None


def release(ts_files: Iterable[Path], out_dir: Optional[Path] = None) -> List[Path]:
    """Compile .ts → .qm with lrelease; returns the .qm paths.

    Raises
    ------
    RuntimeError
        When lrelease is missing (install qttools5-dev-tools) or fails.
    """
    lrelease = find_lrelease()
    if lrelease is None:
        raise RuntimeError("lrelease not found: install the Debian package qttools5-dev-tools")
    made = []
    for ts in ts_files:
        qm = (out_dir or ts.parent) / (ts.stem + ".qm")
        qm.parent.mkdir(parents=True, exist_ok=True)
        proc = subprocess.run([lrelease, "-silent", str(ts), "-qm", str(qm)],
                              capture_output=True, text=True, check=False)
        if proc.returncode != 0 or not qm.is_file():
            raise RuntimeError(f"lrelease failed for {ts}: {proc.stderr or proc.stdout}")
        made.append(qm)
    return made


def ts_path(lang: str) -> Path:
    return I18N / f"photodem_{lang}.ts"


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--release", action="store_true", help="also compile .qm files")
    parser.add_argument("--release-only", action="store_true", help="only compile .qm files")
    parser.add_argument("--check", action="store_true",
                        help="exit 1 when a string has no translation")
    args = parser.parse_args(argv)
    status = 0
    if not args.release_only:
        strings = collect()
        for lang in LANGUAGES:
            counts = write_ts(ts_path(lang), lang, strings)
            print(f"{ts_path(lang).relative_to(ROOT)}: {counts['finished']} translated, "
                  f"{counts['unfinished']} unfinished, {counts['vanished']} vanished")
            if args.check and counts["unfinished"]:
                status = 1
    if args.release or args.release_only:
        for qm in release(ts_path(lang) for lang in LANGUAGES):
            print(f"compiled {qm.relative_to(ROOT)}")
    return status


if __name__ == "__main__":
    sys.exit(main())
