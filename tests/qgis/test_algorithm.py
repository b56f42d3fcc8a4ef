"""The generic QgsProcessingAlgorithm: parameter mapping, identical results, errors, cancel."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from _qgis_helpers import normalise, to_qgis_params, tree_digest

pytestmark = pytest.mark.qgis

QGIS_TYPE = {
    "raster": "raster",
    "vector": "vector",
    "file": "file",
    "folder": "file",
    "project": "file",
    "output_folder": "folderDestination",
    "output_file": "fileDestination",
    "output_raster": "rasterDestination",
    "output_vector": "vectorDestination",
    "number": "number",
    "integer": "number",
    "enum": "enum",
    "bool": "boolean",
    "crs": "crs",
    "extent": "extent",
    "model": "string",
    "image": "string",
    "string": "string",
    "multiple_rasters": "multilayer",
}


def _qgis_alg(algorithm_id: str):
    from qgis.core import QgsApplication

    alg = QgsApplication.processingRegistry().algorithmById(f"photodem:{algorithm_id}")
    assert alg is not None, f"photodem:{algorithm_id} is not registered"
    return alg


def _check_definitions(spec) -> None:
    from qgis.core import (
        QgsProcessingParameterDefinition,
        QgsProcessingParameterFile,
        QgsProcessingParameterNumber,
    )

    alg = _qgis_alg(spec.id)
    definitions = alg.parameterDefinitions()
    assert [d.name() for d in definitions] == [p.name for p in spec.parameters]
    for p, d in zip(spec.parameters, definitions):
        where = f"{spec.id}.{p.name}"
        assert d.type() == QGIS_TYPE[p.kind], where
        optional = bool(d.flags() & QgsProcessingParameterDefinition.FlagOptional)
        assert optional == p.optional, where
        default = d.defaultValue()
        if p.kind == "enum":
            expected = None if p.default is None else [o.lower() for o in p.options].index(
                str(p.default).lower())
            assert default == expected, where
            assert len(d.options()) == len(p.options), where
        elif p.kind == "extent" and p.default is not None:
            xmin, ymin, xmax, ymax = p.default
            assert [float(v) for v in default.split(",")] == [xmin, xmax, ymin, ymax], where
        else:
            assert default == p.default or (default in (None, "") and p.default is None), where
        if p.kind in ("number", "integer"):
            expected_type = (QgsProcessingParameterNumber.Integer if p.kind == "integer"
                             else QgsProcessingParameterNumber.Double)
            assert d.dataType() == expected_type, where
            if p.minimum is not None:
                assert d.minimum() == p.minimum, where
            if p.maximum is not None:
                assert d.maximum() == p.maximum, where
        if p.kind in ("folder", "project"):
            assert d.behavior() == QgsProcessingParameterFile.Folder, where
        if p.kind == "file":
            assert d.behavior() == QgsProcessingParameterFile.File, where
            for ext in p.extensions:
                assert ext in d.fileFilter(), where
    outputs = {o.name(): o.type() for o in alg.outputDefinitions()}
    for o in spec.outputs:
        assert o.name in outputs, f"{spec.id}: output {o.name} missing"
    assert alg.displayName() and alg.group() and alg.groupId()
    assert alg.shortHelpString() is not None


def test_every_algorithm_matches_its_spec(fixture_alg):
    from photodem.algorithms.processing import registry

    for spec in registry.algorithms().values():
        _check_definitions(spec)


def _fixture_inputs(tmp_path: Path) -> dict:
    """Raw (CLI-style) values for every input kind of the fixture."""
    import numpy as np
    from affine import Affine

    from photodem.algorithms.raster.io import write_raster

    raster = tmp_path / "in" / "dem.tif"
    write_raster(raster, np.ones((4, 5), np.float32), transform=Affine(1, 0, 0, 0, -1, 4),
                 crs="EPSG:25832")
    vector = tmp_path / "in" / "points.geojson"
    vector.write_text(json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {}, "geometry": {"type": "Point",
                                                           "coordinates": [1, 2]}}]}))
    text = tmp_path / "in" / "list.txt"
    text.write_text("a\n")
    return {
        "raster": str(raster),
        "vector": str(vector),
        "file": str(text),
        "folder": str(tmp_path / "in"),
        "project": str(tmp_path / "in"),
        "model": "0182_0184",
        "image": "0182",
        "number": 2.25,
        "integer": 4,
        "choice": "large",
        "flag": True,
        "crs": "EPSG:25832",
        "extent": (500000.0, 5700000.0, 500100.0, 5700050.0),
        "label": "stereo",
        "rasters": [str(raster), str(raster)],
    }


def _outputs(folder: Path) -> dict:
    return {
        "output_folder": str(folder / "products"),
        "output_raster": str(folder / "dem.tif"),
        "output_vector": str(folder / "points.geojson"),
        "output_file": str(folder / "summary.json"),
    }


def test_processing_run_equals_registry_run(fixture_alg, tmp_path):
    """Same inputs through processing.run and registry.run → the same outputs and files."""
    import processing

    from photodem.algorithms.processing import registry

    raw = _fixture_inputs(tmp_path)
    out_py, out_qgis = tmp_path / "py", tmp_path / "qgis"
    expected = registry.run(fixture_alg.id, {**raw, **_outputs(out_py)})
    params = to_qgis_params(fixture_alg, {**raw, **_outputs(out_qgis)})
    assert params["choice"] == 3 and params["extent"] == "500000.0,500100.0,5700000.0,5700050.0"
    got = processing.run("photodem:fixture_all_kinds", params)
    mapping_py, mapping_qgis = {str(out_py): "<OUT>"}, {str(out_qgis): "<OUT>"}
    assert normalise(got, mapping_qgis) == normalise(expected, mapping_py)
    assert got["summary"]["choice"] == "large"
    assert got["summary"]["extent"] == [500000.0, 5700000.0, 500100.0, 5700050.0]
    assert tree_digest(out_qgis, mapping_qgis) == tree_digest(out_py, mapping_py)


def test_layer_objects_and_qgis_forms_are_converted(fixture_alg, tmp_path):
    """Layers given as objects, a CRS object, an extent with CRS suffix: same raw values."""
    import processing
    from qgis.core import QgsCoordinateReferenceSystem, QgsRasterLayer, QgsVectorLayer

    raw = _fixture_inputs(tmp_path)
    raster = QgsRasterLayer(raw["raster"], "dem")
    vector = QgsVectorLayer(raw["vector"], "points", "ogr")
    assert raster.isValid() and vector.isValid()
    got = processing.run("photodem:fixture_all_kinds", {
        "raster": raster, "vector": vector, "rasters": [raster, raw["raster"]],
        "crs": QgsCoordinateReferenceSystem("EPSG:25832"),
        "extent": "10,20,30,40 [EPSG:25832]", "choice": 0,
        "output_file": str(tmp_path / "o.json"),
    })
    summary = got["summary"]
    assert summary["raster"] == raw["raster"]
    assert summary["vector"] == raw["vector"]
    assert summary["rasters"] == [raw["raster"], raw["raster"]]
    assert summary["crs"] == "EPSG:25832"
    assert summary["extent"] == [10.0, 30.0, 20.0, 40.0]  # QGIS xmin,xmax,ymin,ymax → spec order
    assert summary["choice"] == "tiny"
    assert summary["number"] == 1.5 and summary["integer"] == 3  # spec defaults


def test_crs_without_authid_is_passed_as_wkt(fixture_alg, tmp_path):
    import processing
    from qgis.core import QgsCoordinateReferenceSystem

    crs = QgsCoordinateReferenceSystem.fromProj("+proj=tmerc +lon_0=9.5 +k=1 +x_0=0 +y_0=0 "
                                                "+ellps=GRS80 +units=m +no_defs")
    got = processing.run("photodem:fixture_all_kinds", {"crs": crs,
                                                         "output_file": str(tmp_path / "o.json")})
    assert got["summary"]["crs"].startswith(("PROJCRS", "PROJCS", "BOUNDCRS"))


def test_operator_error_becomes_processing_exception(fixture_alg, tmp_path):
    import processing
    from qgis.core import QgsProcessingException

    with pytest.raises(QgsProcessingException, match="Fixture failure: the parameter 'fail'"):
        processing.run("photodem:fixture_all_kinds",
                       {"fail": True, "output_file": str(tmp_path / "o.json")})
    assert not (tmp_path / "o.json").exists()
    # A spec-level check (range) surfaces the same way, with the spec's message.
    alg = _qgis_alg("fixture_all_kinds")
    from qgis.core import QgsProcessingContext, QgsProcessingFeedback

    with pytest.raises(QgsProcessingException, match="outside the allowed range"):
        alg.processAlgorithm({"number": 99.0, "output_file": str(tmp_path / "o.json")},
                             QgsProcessingContext(), QgsProcessingFeedback())


def test_feedback_progress_log_and_cancel(fixture_alg, tmp_path):
    """Progress and log lines reach QgsProcessingFeedback; a cancel leaves no output."""
    import processing
    from qgis.core import QgsProcessingException, QgsProcessingFeedback

    class Recorder(QgsProcessingFeedback):
        def __init__(self, cancel_at=None):
            super().__init__()
            self.infos, self.warnings, self.progress_values = [], [], []
            self.cancel_at = cancel_at
            self.progressChanged.connect(self._on_progress)

        def _on_progress(self, value):
            self.progress_values.append(value)
            if self.cancel_at is not None and value >= self.cancel_at:
                self.cancel()

        def pushInfo(self, text):  # noqa: N802 (QGIS API)
            self.infos.append(text)
            super().pushInfo(text)

        def pushWarning(self, text):  # noqa: N802
            self.warnings.append(text)
            super().pushWarning(text)

    ok = Recorder()
    processing.run("photodem:fixture_all_kinds",
                   {"integer": 4, "output_file": str(tmp_path / "ok.json")}, feedback=ok)
    assert ok.progress_values[-1] == 100.0
    assert ok.progress_values == sorted(ok.progress_values)
    assert "step 4 of 4" in ok.infos
    assert ok.warnings == ["fixture warning"]

    out = tmp_path / "cancelled"
    cancel = Recorder(cancel_at=40)
    with pytest.raises(QgsProcessingException, match="Cancelled"):
        processing.run("photodem:fixture_all_kinds", {
            "integer": 10, "delay": 0.01, "output_file": str(out / "o.json"),
            "output_folder": str(out / "folder"), "output_raster": str(out / "r.tif"),
        }, feedback=cancel)
    assert cancel.isCanceled()
    assert max(cancel.progress_values) < 100
    assert not [p for p in out.rglob("*") if p.is_file()]  # nothing left, not even .partial


def test_missing_required_parameter_is_rejected_by_qgis(fixture_alg):
    import processing
    from qgis.core import QgsProcessingException

    with pytest.raises(QgsProcessingException):
        processing.run("photodem:fixture_all_kinds", {})


def test_temporary_outputs(fixture_alg):
    """A required output may be temporary; an optional one given as "temporary output" (what
    the Processing dialog passes for an empty field) counts as not given: the core's default
    applies (here: not written; in PhotoDEM's algorithms: the project's products folder)."""
    import processing

    got = processing.run("photodem:fixture_all_kinds", {
        "output_file": "TEMPORARY_OUTPUT", "output_folder": "TEMPORARY_OUTPUT",
        "output_raster": "TEMPORARY_OUTPUT",
    })
    assert Path(got["output_file"]).is_file()
    assert not got.get("output_folder") and not got.get("output_raster")
    assert got["summary"]["output_folder"] is None


def test_empty_optional_output_of_the_dialog_goes_to_the_products(provider, tmp_path):
    """The dialog's empty optional output folder lands in ``products/epipolar/<model>/``, not in
    a temporary folder that is gone with the session."""
    import processing

    from photodem.algorithms.processing import registry

    root = tmp_path / "tiny"
    registry.run("synthetic_block", {"output": str(root), "size": "tiny"})
    got = processing.run("photodem:epipolar_pair", {
        "project": str(root), "model": "0101_0102", "output": "TEMPORARY_OUTPUT"})
    assert Path(got["folder"]) == root / "products" / "epipolar" / "0101_0102"
    assert Path(got["left"]).is_file()


def test_project_parameter_accepts_project_toml(fixture_alg, tmp_path):
    """'project' is a folder parameter in QGIS, yet the spec also takes the project.toml path."""
    import processing

    toml = tmp_path / "project.toml"
    toml.write_text("name = 'x'\n")
    got = processing.run("photodem:fixture_all_kinds",
                         {"project": str(toml), "output_file": str(tmp_path / "o.json")})
    assert got["summary"]["project"] == str(toml)
