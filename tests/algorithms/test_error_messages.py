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


# -- part 2: the errors of the toolbox's main algorithms ------------------------------------------
def _failure(call, *args, **kwargs):
    """The operator error ``call(*args, **kwargs)`` raises."""
    from photodem.algorithms.errors import PhotodemError

    with pytest.raises(PhotodemError) as info:
        call(*args, **kwargs)
    return info.value


def test_an_unreadable_raster_names_its_role_as_a_phrase(tmp_path):
    from photodem.algorithms.input_errors import check_raster, check_raster_parameters

    bad = tmp_path / "bad.tif"
    bad.write_bytes(b"not a tiff at all")
    exc = _failure(check_raster, bad, "image")
    assert str(exc).startswith(f"'{bad}' is not a readable image (")
    assert exc.message.template == "'{path}' is not a readable {what} ({detail})."
    assert exc.message.values["what"] == Message("image")
    param = Parameter("dem", "raster", "DEM")
    wrapped = _failure(check_raster_parameters, [param], {"dem": str(bad)})
    assert str(wrapped).startswith(f"Parameter 'dem': '{bad}' is not a readable raster (")
    assert wrapped.message.values["error"].values["what"] == Message("raster")
    odd = _failure(check_raster, bad, "scan")  # a role without a phrase stays as it is
    assert odd.message.values["what"] == "scan"


def test_model_setup_messages_are_unchanged_and_translatable(chain_project):
    from photodem.algorithms.matching.model_setup import prepare_model

    root = chain_project("ab")
    exc = _failure(Project.load(root).model, "x_y")
    assert str(exc) == "Stereo model 'x_y' is not in project 't'. Models: a_b."
    assert exc.message.values == {"name": "x_y", "project": "t", "models": "a_b"}
    exc = _failure(prepare_model, root, "a_b", min_height=100.0, max_height=50.0)
    assert str(exc) == "max_height (50.0) must be larger than min_height (100.0)."
    exc = _failure(prepare_model, root, "a_b", min_height=0.0, max_height=1200.0)
    assert str(exc) == ("max_height (1200.0 m) reaches the cameras (1000.0 m); give a lower "
                        "max_height.")
    assert exc.message.values["z_cam"] == 1000.0


def test_images_that_do_not_overlap(tmp_path):
    from photodem.algorithms.errors import GeometryError
    from photodem.algorithms.geometry.camera import Camera
    from photodem.algorithms.geometry.orientation import ExteriorOrientation
    from photodem.algorithms.matching.model_setup import prepare_model
    from photodem.algorithms.project.model import ImageRecord, StereoModel

    images = [ImageRecord(n, f"{n}.tif", "c", ExteriorOrientation.from_opk(
        [x, 0.0, 1000.0], 0.0, 0.0, 0.0)) for n, x in (("a", 0.0), ("b", 5000.0))]
    project = Project(root=tmp_path / "p", name="t", crs="EPSG:25832",
                      cameras={"c": Camera("c", 100, 80, 1.0, (0.01, 0.01))}, images=images,
                      models=[StereoModel("a_b", "a", "b")], terrain_height=0.0)
    exc = _failure(prepare_model, project, "a_b")
    assert isinstance(exc, GeometryError)
    assert str(exc) == ("The images a and b of model 'a_b' do not overlap; check the model or "
                        "the orientations.")
    assert exc.message.values == {"left": "a", "right": "b", "model": "a_b"}


def test_edit_and_breakline_messages_are_unchanged_and_translatable():
    from shapely.geometry import LineString, Polygon

    from photodem.algorithms.project.breaklines import check_breaklines
    from photodem.algorithms.project.edits import check_feature, check_fields, check_layer

    exc = _failure(check_layer, "roads")
    assert str(exc).startswith("'roads' is not an edit layer; use one of ")
    exc = _failure(check_breaklines, [LineString([(0, 0, 1), (2, 2, 1)]),
                                      LineString([(0, 2, 1), (2, 0, 1)])])
    assert str(exc) == ("Breaklines 1 and 2 cross at (1.00, 1.00); breaklines must not cross "
                        "or touch — fix them in edits.gpkg.")
    exc = _failure(check_fields, "exclusion_areas", {"action": "burn"})
    assert str(exc).startswith("Layer 'exclusion_areas': action 'burn' is not one of ")
    assert exc.message.values["where"] == msg("Layer '{layer}'", layer="exclusion_areas")
    exc = _failure(check_feature, "/p/edits.gpkg", "exclusion_areas", 7,
                   Polygon([(0, 0), (1, 0), (1, 1), (0, 1)]), {"action": "burn"})
    assert str(exc).startswith("'edits.gpkg' layer exclusion_areas, feature 7: action 'burn'")


def test_batch_file_messages_are_unchanged_and_translatable(tmp_path):
    from photodem.algorithms.processing.batch import load_batch, plan_batch

    exc = _failure(load_batch, tmp_path / "none.toml")
    assert str(exc) == f"Batch file '{tmp_path / 'none.toml'}' does not exist."
    exc = _failure(plan_batch, {"steps": {"algorithm": "dem_compare"}}, tmp_path)
    assert str(exc) == ("Batch file: write each step as [[steps]] (two brackets), not "
                        "[steps].")
    exc = _failure(plan_batch, {"batch": {"workers": 0}, "steps": []}, tmp_path)
    assert str(exc) == "Batch file: workers = 0 in [batch] must be a whole number ≥ 1."
    exc = _failure(plan_batch, {"steps": [{"algorithm": "dem_compare", "colour": 1}]},
                   tmp_path)
    assert str(exc).startswith("Batch file: unknown key(s) colour in step 1; allowed are ")
    assert exc.message.values["where"] == msg("step {number}", number=1)
    exc = _failure(plan_batch, {"steps": [{"algorithm": "dem_compare",
                                           "params": {"output": "{model}/x"}}]}, tmp_path)
    assert str(exc) == ("Batch file: step 'dem_compare' uses {model}, but it does not run per "
                        "model.")


def test_georeferencing_messages_keep_their_counts(tmp_path):
    from photodem.algorithms.errors import GeometryError
    from photodem.algorithms.georef import pipeline
    from photodem.algorithms.georef.reference_layer import reference_objects_from_vector

    exc = _failure(pipeline.GeorefOptions(transform="spline").check)
    assert str(exc) == "Unknown transform 'spline'; use affine, projective or poly2."
    exc = _failure(reference_objects_from_vector, tmp_path / "none.gpkg")
    assert str(exc) == f"Reference layer '{tmp_path / 'none.gpkg'}' not found."
    with pytest.raises(GeometryError) as info:
        pipeline._fail({"image_objects": 12, "hypotheses": 0}, "no object pairs")
    assert str(info.value).startswith("Georeferencing failed: no object pairs (image objects "
                                      "12, hypotheses 0). Check that image and reference")
    assert info.value.counts == {"image_objects": 12, "hypotheses": 0}  # the report's data
    assert info.value.message.values["why"] == "no object pairs"


def test_filter_input_messages_are_unchanged_and_translatable(tmp_path):
    from photodem.algorithms.filtering.surface_input import read_filter_input

    exc = _failure(read_filter_input, tmp_path / "none.tif")
    template = "The filter input '{path}' does not exist or is not a file."
    assert exc.message.template == template
    assert str(exc) == template.format(path=tmp_path / "none.tif")


def test_georeferencing_review_messages_are_unchanged_and_translatable(tmp_path):
    from photodem.algorithms.georef.review import load_review, read_check_points

    exc = _failure(load_review, tmp_path)
    assert str(exc) == (f"'{tmp_path}' holds no georeferencing result (report.json and a "
                        ".points file); choose the output folder of 'Georeference image "
                        "against polygons'.")
    points = tmp_path / "check.csv"
    points.write_text("col,row,x,y\n1,2,three,4\n", encoding="utf-8")
    exc = _failure(read_check_points, points)
    assert str(exc) == "'check.csv' line 2: x 'three' is not a number."
    assert exc.message.values == {"name": "check.csv", "number": 2, "column": "x",
                                  "token": "three"}


def test_an_unreadable_vector_file_names_its_role(tmp_path):
    from photodem.algorithms.project.vector_io import read_features

    bad = tmp_path / "seams.gpkg"
    bad.write_bytes(b"no geopackage")
    exc = _failure(read_features, bad, None, "seamline file")
    assert str(exc).startswith("Cannot read the seamline file 'seams.gpkg': ")
    assert exc.message.values["what"] == Message("seamline file")
