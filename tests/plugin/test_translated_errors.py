"""Operator errors in the operator's language: the worker hands template and values to the GUI,
which translates them (pytest-qt; German with the committed .ts)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
pytest.importorskip("pytestqt")

FAKES = Path(__file__).resolve().parents[1] / "algorithms" / "processing"
if str(FAKES) not in sys.path:
    sys.path.insert(0, str(FAKES))

import _fake_algs  # noqa: E402

from photodem.algorithms.errors import InputError, Message, msg  # noqa: E402
from photodem.algorithms.project.model import check_identifier  # noqa: E402
from photodem.plugin import i18n  # noqa: E402
from photodem.plugin.app.main_window import ToolboxWindow  # noqa: E402
from photodem.plugin.widgets.worker import AlgorithmWorker, start_in_thread  # noqa: E402

MISSING = "Parameter '{name}': '{path}' does not exist."


class _Refusing(AlgorithmWorker):
    """A run that fails at once with a translatable operator error."""

    def call(self) -> dict:
        raise InputError.of("{label} holds {what}.", label=msg(
            "Parameter '{name}': the output '{path}'", name="output", path="/o"),
            what=msg("files PhotoDEM did not write"))


def test_failed_signal_carries_template_and_values(qtbot):
    # Collected directly (not with waitSignal): Qt deletes the worker once its run is done.
    got: list = []
    ended: list = []
    worker = _Refusing("none", {})
    worker.failed.connect(lambda *args: got.append(args))
    start_in_thread(worker, on_finished=lambda: ended.append(1))
    qtbot.waitUntil(lambda: bool(ended), timeout=10000)
    [(text, operator_error, message)] = got
    assert text == ("Parameter 'output': the output '/o' holds files PhotoDEM did not write.")
    assert operator_error is True
    assert isinstance(message, Message) and message.template == "{label} holds {what}."
    assert message.values["label"].values == {"name": "output", "path": "/o"}
    assert i18n.error_text(text, message) == text  # no translator: the English sentence


def test_german_text_of_nested_messages(qapp, german):
    german()
    exc = InputError.of("{label} holds {what}; only an earlier '{algorithm}' result is "
                        "replaced. Choose an empty or new folder.",
                        label=msg("Parameter '{name}': the output '{path}'", name="output",
                                  path="/o"),
                        what=msg("a product of '{other}'", other="mosaic"), algorithm="dsm")
    assert i18n.error_text(exc) == (
        "Parameter 'output': Die Ausgabe '/o' enthält ein Produkt von 'mosaic'; ersetzt wird "
        "nur ein früheres Ergebnis von 'dsm'. Wählen Sie einen leeren oder neuen Ordner.")
    assert i18n.error_text(InputError("plain")) == "plain"
    required = InputError.of("Parameter '{name}' ({description}) is required.", name="extent",
                             description=Message("Extent"))  # a spec string, as the form
    assert i18n.error_text(required) == "Parameter 'extent' (Ausdehnung) muss angegeben werden."
    with pytest.raises(InputError) as info:  # a name that is no valid path part
        check_identifier("../x", "stereo model", "'p.toml' [[models]] #1")
    assert i18n.error_text(info.value) == (
        "'p.toml' [[models]] #1: Der Stereomodellname '../x' kann nicht verwendet werden: er "
        "enthält einen Pfadtrenner ('/' oder '\\'). Namen werden zu Ordnernamen; verwenden "
        "Sie Buchstaben, Ziffern, '-' und '_'.")


def test_batch_dialog_shows_a_failed_task_in_german(qapp, german):
    from photodem.plugin.widgets.batch_dialog import record_error

    german()
    error = InputError.of(MISSING, name="dem", path="/x.tif")
    record = {"status": "failed", "error": str(error), "error_message": error.message.to_dict()}
    assert record_error(record) == "Parameter 'dem': '/x.tif' existiert nicht."
    assert record_error({"status": "failed", "error": "old record"}) == "old record"


def test_a_broken_translation_falls_back_to_english(monkeypatch):
    monkeypatch.setattr(i18n, "tr", lambda text: "Parameter '{nam}' fehlt.")
    exc = InputError.of(MISSING, name="dem", path="/x.tif")
    assert i18n.error_text(exc) == "Parameter 'dem': '/x.tif' does not exist."


def test_german_run_panel_shows_a_translated_error(qtbot, monkeypatch, tmp_path, german,
                                                   shots_dir):
    _fake_algs.install(monkeypatch)
    german()
    window = ToolboxWindow(message_boxes=False)
    qtbot.addWidget(window)
    window.resize(900, 520)
    window.show()
    qtbot.waitExposed(window)
    window.select_algorithm("fake_chatty")
    missing = tmp_path / "fehlt.tif"
    window.form.set_values({"input": str(missing)})
    with qtbot.waitSignal(window.run_panel.run_finished, timeout=10000) as blocker:
        window.run_current()
    expected = f"Parameter 'input': '{missing}' existiert nicht."
    assert blocker.args == ["failed", expected]  # the message box shows the same text
    log = window.run_panel.log_view.toPlainText()
    assert f"Fehler: {expected}" in log and "does not exist" not in log
    assert window.grab().save(str(shots_dir / "run_panel_error_de.png"))
    window.run_panel.wait(10000)
