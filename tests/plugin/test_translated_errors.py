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


def _typical_errors(tmp_path, chain_project) -> list:
    """One operator error of each area converted in part 2 (input rasters, model setup,
    edits, batch files, georeferencing, filter inputs)."""
    from shapely.geometry import LineString

    from photodem.algorithms.errors import PhotodemError
    from photodem.algorithms.filtering.surface_input import read_filter_input
    from photodem.algorithms.georef.pipeline import GeorefOptions, _fail
    from photodem.algorithms.georef.reference_layer import reference_objects_from_vector
    from photodem.algorithms.input_errors import check_raster
    from photodem.algorithms.matching.model_setup import prepare_model
    from photodem.algorithms.processing.batch import plan_batch
    from photodem.algorithms.project.breaklines import check_breaklines
    from photodem.algorithms.project.edits import check_layer
    from photodem.algorithms.project.model import Project

    bad = tmp_path / "bad.tif"
    bad.write_bytes(b"not a tiff")
    root = chain_project("ab")
    calls = [
        lambda: check_raster(bad, "image"),
        lambda: Project.load(root).model("x_y"),
        lambda: prepare_model(root, "a_b", min_height=100.0, max_height=50.0),
        lambda: check_layer("roads"),
        lambda: check_breaklines([LineString([(0, 0, 1), (2, 2, 1)]),
                                  LineString([(0, 2, 1), (2, 0, 1)])]),
        lambda: plan_batch({"steps": {"algorithm": "dem_compare"}}, tmp_path),
        lambda: plan_batch({"steps": [{"algorithm": "dem_compare", "colour": 1}]}, tmp_path),
        lambda: GeorefOptions(transform="spline").check(),
        lambda: reference_objects_from_vector(tmp_path / "none.gpkg"),
        lambda: _fail({"hypotheses": 0}, "no object pairs"),
        lambda: read_filter_input(tmp_path / "none.tif"),
    ]
    errors = []
    for call in calls:
        with pytest.raises(PhotodemError) as info:
            call()
        errors.append(info.value)
    return errors


def test_errors_of_the_main_algorithms_in_german(qapp, german, tmp_path, chain_project):
    errors = _typical_errors(tmp_path, chain_project)
    german()
    texts = [i18n.error_text(e) for e in errors]
    assert all(text != str(e) for text, e in zip(texts, errors)), texts
    assert texts[0].startswith(f"'{tmp_path / 'bad.tif'}' kann nicht als Bild gelesen werden (")
    assert texts[1] == "Das Stereomodell 'x_y' ist nicht im Projekt 't'. Modelle: a_b."
    assert texts[4] == ("Die Bruchkanten 1 und 2 kreuzen sich bei (1.00, 1.00); Bruchkanten "
                        "dürfen sich weder kreuzen noch berühren — korrigieren Sie sie in "
                        "edits.gpkg.")
    assert texts[6].startswith("Batch-Datei: unbekannte(r) Schlüssel colour in Schritt 1; ")


def test_georeferencing_review_reports_in_german(qapp, german, tmp_path):
    from photodem.plugin.widgets.georef_review import open_review

    german()
    got: list = []
    assert open_review(None, str(tmp_path), message_boxes=False, on_error=got.append) is None
    assert got == [f"'{tmp_path}' enthält kein Ergebnis einer Georeferenzierung (report.json "
                   "und eine .points-Datei); wählen Sie den Ausgabeordner von 'Bild an "
                   "Polygonen georeferenzieren'."]
