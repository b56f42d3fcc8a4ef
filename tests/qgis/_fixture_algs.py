"""A test-only algorithm with one parameter of every kind (tier-B tests of the generic mapping).

``fixture_all_kinds`` echoes the values it received (as ``run`` sees them after
``prepare_parameters``) into its ``summary`` output and into the files it writes, so a test can
check that the QGIS face hands the core exactly what the CLI would. It is registered by
monkeypatching the registry cache (in-process tests) or by a ``sitecustomize`` hook
(``qgis_process`` tests); it never ships.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any, Dict

import numpy as np
from affine import Affine

from photodem.algorithms.errors import InputError
from photodem.algorithms.feedback import Feedback
from photodem.algorithms.processing.spec import Algorithm, Output, Parameter
from photodem.algorithms.raster.io import atomic_output, staged_folder, write_raster

FIXTURE_ID = "fixture_all_kinds"


class FixtureAllKinds(Algorithm):
    id = FIXTURE_ID
    name = "Fixture with every parameter kind"
    group = "Tests"
    group_id = "tests"
    help = "Echoes its parameters into a JSON file; for tests only."
    parameters = (
        Parameter("raster", "raster", "Input raster", optional=True),
        Parameter("vector", "vector", "Input vector", optional=True),
        Parameter("file", "file", "Input file", optional=True, extensions=(".txt", ".csv")),
        Parameter("folder", "folder", "Input folder", optional=True),
        Parameter("project", "project", "Project folder", optional=True),
        Parameter("model", "model", "Stereo model", optional=True),
        Parameter("image", "image", "Image name", optional=True),
        Parameter("number", "number", "Scale [m]", default=1.5, minimum=0.0, maximum=10.0,
                  unit="m", help="A floating-point number."),
        Parameter("integer", "integer", "Count", default=3, minimum=1, maximum=50),
        Parameter("choice", "enum", "Size", default="small",
                  options=("tiny", "small", "medium", "large")),
        Parameter("flag", "bool", "Flag", default=False),
        Parameter("crs", "crs", "CRS", optional=True),
        Parameter("extent", "extent", "Extent", optional=True),
        Parameter("label", "string", "Label", default="hello"),
        Parameter("rasters", "multiple_rasters", "Rasters", optional=True),
        Parameter("delay", "number", "Delay per step [s]", default=0.0, minimum=0.0),
        Parameter("fail", "bool", "Fail with an operator error", default=False),
        Parameter("output_folder", "output_folder", "Output folder", optional=True),
        Parameter("output_raster", "output_raster", "Output raster", optional=True),
        Parameter("output_vector", "output_vector", "Output vector", optional=True),
        Parameter("output_file", "output_file", "Output JSON", extensions=(".json",)),
    )
    outputs = (
        Output("output_file", "file", "Output JSON"),
        Output("output_folder", "folder", "Output folder"),
        Output("output_raster", "raster", "Output raster"),
        Output("output_vector", "vector", "Output vector"),
        Output("steps", "number", "Steps done"),
        Output("label", "string", "Label"),
        Output("summary", "json", "Parameters as received"),
    )

    def run(self, params: Dict[str, Any], feedback: Feedback) -> Dict[str, Any]:
        if params["fail"]:
            raise InputError("Fixture failure: the parameter 'fail' was set; unset it.")
        summary = {k: (list(v) if isinstance(v, tuple) else v) for k, v in params.items()}
        steps = params["integer"]
        out_file = Path(params["output_file"])
        with atomic_output(out_file) as tmp:
            # The work happens inside the atomic block: a cancel leaves no file behind.
            for i in range(steps):
                time.sleep(params["delay"])
                feedback.progress(100.0 * i / steps)
                feedback.info(f"step {i + 1} of {steps}")
            feedback.warning("fixture warning")
            tmp.write_text(json.dumps(summary, sort_keys=True, indent=1), encoding="utf-8")
        result: Dict[str, Any] = {"output_file": str(out_file), "steps": steps,
                                  "label": params["label"], "summary": summary}
        if params["output_folder"]:
            with staged_folder(params["output_folder"]) as tmp_dir:
                (tmp_dir / "readme.txt").write_text(params["label"], encoding="utf-8")
            result["output_folder"] = params["output_folder"]
        if params["output_raster"]:
            data = np.arange(12, dtype=np.float32).reshape(3, 4) * params["number"]
            write_raster(params["output_raster"], data, transform=Affine(1, 0, 5e5, 0, -1, 5.7e6),
                         crs="EPSG:25832")
            result["output_raster"] = params["output_raster"]
        if params["output_vector"]:
            with atomic_output(params["output_vector"]) as tmp:
                tmp.write_text(json.dumps({"type": "FeatureCollection", "features": []}),
                               encoding="utf-8")
            result["output_vector"] = params["output_vector"]
        return result


ALGORITHMS = [FixtureAllKinds]
