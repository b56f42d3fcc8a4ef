"""Translatable operator errors: English text unchanged, template and values carried along."""

from __future__ import annotations

import pickle
import sys
from pathlib import Path

import pytest

from photodem.algorithms import output_policy
from photodem.algorithms.errors import GeometryError, InputError, Message, msg
from photodem.algorithms.processing.spec import Parameter
from photodem.algorithms.project.model import Project

ROOT = Path(__file__).resolve().parents[2]


def test_of_gives_the_english_sentence_and_keeps_template_and_values():
    exc = InputError.of("Parameter '{name}' = {number:g}{unit} is outside {low:g}…{high:g}.",
                        name="spacing", number=2.50, unit=" m", low=0.1, high=2)
    assert str(exc) == "Parameter 'spacing' = 2.5 m is outside 0.1…2."
    assert isinstance(exc, InputError) and exc.counts == {}
    assert exc.message.template.startswith("Parameter '{name}' = {number:g}")
    assert exc.message.values["number"] == 2.5
    assert isinstance(GeometryError.of("x"), GeometryError)


def test_plain_errors_have_no_message():
    assert InputError("as it is").message is None


def test_nested_phrases_and_errors_become_messages():
    inner = InputError.of("'{key}' is missing", key="crs")
    exc = InputError.of("{where}: {error} ({what})", where="p.toml", error=inner,
                        what=msg("files PhotoDEM did not write"))
    assert str(exc) == "p.toml: 'crs' is missing (files PhotoDEM did not write)"
    assert exc.message.values["error"] == inner.message  # no exception (nor its frames) kept
    assert isinstance(exc.message.values["what"], Message)
    other = InputError.of("{where}: {error}", where="w", error=ValueError("bad"))
    assert other.message.values["error"] == "bad"


def test_a_template_without_values_is_shown_as_it_is():
    assert str(Message("Pixel size {px}")) == "Pixel size {px}"


def test_the_message_survives_pickling():
    """Batch tasks in other processes hand their errors back pickled."""
    exc = pickle.loads(pickle.dumps(InputError.of("'{path}' does not exist.", path="/x")))
    assert str(exc) == "'/x' does not exist." and exc.message.values == {"path": "/x"}


def test_parameter_messages_are_unchanged_and_translatable():
    p = Parameter("spacing", "number", "Grid spacing [m]", minimum=0.1, maximum=10, unit="m")
    with pytest.raises(InputError) as info:
        p.convert(20)
    assert str(info.value) == ("Parameter 'spacing' = 20 m is outside the allowed range "
                               "0.1…10 m.")
    assert info.value.message.values["name"] == "spacing"
    req = Parameter("dem", "raster", "DEM {raster}")
    with pytest.raises(InputError) as info:
        req.convert(None)
    assert str(info.value) == "Parameter 'dem' (DEM {raster}) is required."
    assert info.value.message.values["description"] == Message("DEM {raster}")
    with pytest.raises(InputError) as info:
        Parameter("n", "integer", "N").convert("x")
    assert str(info.value) == "Parameter 'n': 'x' is not a valid whole number."


def test_output_policy_message_is_unchanged_and_nested(tmp_path):
    src = tmp_path / "in.tif"
    src.write_bytes(b"x")
    target = output_policy.Target(src, "file", "output")
    with pytest.raises(InputError) as info:
        output_policy.check_targets("alg", [target], inputs=[src])
    assert str(info.value) == (f"Parameter 'output': the output '{src}' is or contains the "
                               f"input '{src.resolve()}'; PhotoDEM never overwrites its "
                               "inputs. Choose another output.")
    assert info.value.message.values["label"].template == "Parameter '{name}': the output '{path}'"


def test_project_load_messages_are_translatable(tmp_path):
    with pytest.raises(InputError) as info:
        Project.load(tmp_path)
    assert str(info.value) == (f"'{tmp_path}' is not a PhotoDEM project: project.toml not "
                               "found. Create one with project_create or synthetic_block.")
    (tmp_path / "project.toml").write_text("[project]\nname = 3\n", encoding="utf-8")
    with pytest.raises(InputError) as info:
        Project.load(tmp_path)
    assert "'name' must be text in quotes, not 3; fix it in the project file." in str(info.value)
    assert info.value.message.values["problem"].template == "must be text in quotes, not {value}"


def test_every_error_template_is_extracted_and_translated():
    """The translation check: each template of algorithms/ has a German text with the same
    named values (a lost value would make the GUI fall back to English)."""
    import string
    import xml.etree.ElementTree as ET

    sys.path.insert(0, str(ROOT / "tools"))
    from update_translations import error_templates

    found = {text for text, _ in error_templates(ROOT / "algorithms")}
    assert "Parameter '{name}': '{path}' does not exist." in found
    assert "files PhotoDEM did not write" in found and len(found) >= 50
    german = {m.findtext("source"): m.findtext("translation") or ""
              for m in ET.parse(ROOT / "i18n" / "photodem_de.ts").getroot().iter("message")}

    def fields(text: str) -> list:
        return sorted((f, spec) for _, f, spec, _ in string.Formatter().parse(text)
                      if f is not None)

    for template in found:
        assert german.get(template), f"untranslated: {template}"
        assert fields(german[template]) == fields(template), template


def test_batch_records_carry_the_message_as_json(tmp_path):
    """A failed batch task keeps its message in the record (summary.json) for the GUIs."""
    import json

    from photodem.algorithms.processing.batch import execute_task

    missing = tmp_path / "none.tif"
    result = execute_task("dem_compare", {"dem": str(missing), "reference": str(missing),
                                          "output": str(tmp_path / "out")},
                          tmp_path / "task.log", lambda: False)
    assert result["status"] == "failed"
    data = json.loads(json.dumps(result["error_message"]))
    assert data["template"] == "Parameter '{name}': '{path}' does not exist."
    assert str(Message.from_dict(data)) == result["error"]
    nested = InputError.of("{label} holds {what}.", label=msg("'{path}'", path=tmp_path),
                           what=msg("files PhotoDEM did not write"))
    back = Message.from_dict(json.loads(json.dumps(nested.message.to_dict())))
    assert str(back) == str(nested) and isinstance(back.values["what"], Message)
