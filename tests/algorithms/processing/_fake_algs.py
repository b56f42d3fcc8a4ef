"""Test-only algorithms for the CLI, batch and toolbox tests.

Register them with ``PHOTODEM_EXTRA_ALGORITHMS=_fake_algs`` (this folder on ``sys.path``) or
:func:`install` (in-process, into the registry cache).
"""

from __future__ import annotations

import json
import os
import signal
import time
from pathlib import Path

from photodem.algorithms.errors import InputError
from photodem.algorithms.processing import registry
from photodem.algorithms.processing.spec import Algorithm, Output, Parameter
from photodem.algorithms.raster.io import atomic_output


class SleepWrite(Algorithm):
    """Sleeps in small steps (checking cancel), then writes a JSON file atomically."""

    id = "fake_sleep_write"
    name = "Fake: sleep and write"
    group = "Testing"
    group_id = "testing"
    help = "Waits `seconds`, reporting progress, and writes a small JSON file."
    iterates_over = "model"
    parameters = (
        Parameter("project", "project", "Project folder"),
        Parameter("model", "model", "Stereo model"),
        Parameter("seconds", "number", "Duration [s]", default=0.2, minimum=0, maximum=60,
                  unit="s"),
        Parameter("steps", "integer", "Progress steps", default=10, minimum=1, maximum=1000),
        Parameter("mode", "enum", "Mode", default="fast", options=("fast", "slow", "exact")),
        Parameter("shout", "bool", "Upper-case the note", default=False),
        Parameter("note", "string", "A note", optional=True),
        Parameter("output", "output_file", "Output JSON", extensions=(".json",)),
    )
    outputs = (
        Output("output", "file", "The JSON file"),
        Output("value", "number", "seconds × 2"),
    )

    def run(self, params, feedback):
        steps = params["steps"]
        for i in range(steps):
            time.sleep(params["seconds"] / steps)
            feedback.progress(100.0 * (i + 1) / steps)
        note = params["note"] or ""
        if params["shout"]:
            note = note.upper()
        feedback.info(f"model {params['model']} done")
        with atomic_output(params["output"]) as tmp:
            Path(tmp).write_text(json.dumps({"model": params["model"], "note": note,
                                             "mode": params["mode"]}))
            feedback.check()
        return {"output": params["output"], "value": 2 * params["seconds"]}


class FailOn(Algorithm):
    """Fails (operator error) for the models listed in ``fail``; else writes like SleepWrite."""

    id = "fake_fail_on"
    name = "Fake: fail on some models"
    group = "Testing"
    group_id = "testing"
    help = "Raises an InputError for the models named in `fail`."
    iterates_over = "model"
    parameters = (
        Parameter("project", "project", "Project folder"),
        Parameter("model", "model", "Stereo model"),
        Parameter("fail", "string", "Comma-separated models to fail on", default=""),
        Parameter("output", "output_file", "Output"),
    )
    outputs = (Output("output", "file", "The file"),)

    def run(self, params, feedback):
        if params["model"] in params["fail"].split(","):
            raise InputError(f"model {params['model']} is broken; fix it and run again")
        feedback.progress(50)
        with atomic_output(params["output"]) as tmp:
            Path(tmp).write_text(params["model"])
        return {"output": params["output"]}


class Crash(Algorithm):
    """A bug: raises ZeroDivisionError."""

    id = "fake_crash"
    name = "Fake: crash"
    group = "Testing"
    group_id = "testing"
    help = "Divides by zero."
    parameters = (Parameter("x", "number", "x", default=1.0),)
    outputs = ()

    def run(self, params, feedback):
        return {"y": params["x"] / 0}


class Chatty(Algorithm):
    """Prints to stdout (a misbehaving library) and returns numbers."""

    id = "fake_chatty"
    name = "Fake: chatty"
    group = "Testing"
    group_id = "testing"
    help = "Prints to stdout and logs."
    parameters = (
        Parameter("input", "file", "Input file", optional=True),
        Parameter("factor", "number", "Factor", default=2.0, unit="m"),
        Parameter("extent", "extent", "Extent", optional=True),
        Parameter("crs", "crs", "CRS", optional=True),
        Parameter("flag", "bool", "Flag", default=False),
    )
    outputs = (Output("result", "json", "Everything"),)

    def run(self, params, feedback):
        print("noise on stdout from a library")
        feedback.info("working")
        feedback.warning("just a warning")
        feedback.progress(50)
        return {"result": {"factor": params["factor"], "flag": params["flag"],
                           "extent": params["extent"], "crs": params["crs"],
                           "input": params["input"]}}


class FileSize(Algorithm):
    """Runs over image files: writes the file's size; fails on files named ``bad*``."""

    id = "fake_file_size"
    name = "Fake: file size"
    group = "Testing"
    group_id = "testing"
    help = "Writes the size of `image`; an InputError for files whose name starts with bad."
    iterates_over = "image"
    parameters = (
        Parameter("image", "file", "Image"),  # not a real raster: no pre-flight read
        Parameter("output", "output_file", "Output"),
    )
    outputs = (Output("output", "file", "The file"),)

    def run(self, params, feedback):
        image = Path(params["image"])
        if image.name.startswith("bad"):
            raise InputError(f"{image.name} is not an image")
        with atomic_output(params["output"]) as tmp:
            Path(tmp).write_text(str(image.stat().st_size))
        return {"output": params["output"]}


class DieOnModels(Algorithm):
    """Kills its own process (SIGKILL) for the models in ``die``, ``deaths`` times per model.

    The deaths so far are counted as files ``<marks>/<model>.<n>``. Run it on worker processes
    only (``workers`` ≥ 2): in-process it would kill the caller.
    """

    id = "fake_die"
    name = "Fake: die on some models"
    group = "Testing"
    group_id = "testing"
    help = "SIGKILLs its process for the models named in `die`."
    iterates_over = "model"
    parameters = (
        Parameter("project", "project", "Project folder"),
        Parameter("model", "model", "Stereo model"),
        Parameter("die", "string", "Comma-separated models to die on", default=""),
        Parameter("deaths", "integer", "Deaths per model", default=1, minimum=0, maximum=9),
        Parameter("marks", "string", "Folder counting the deaths"),
        Parameter("seconds", "number", "Duration [s]", default=0.2, minimum=0, maximum=60),
        Parameter("output", "output_file", "Output"),
    )
    outputs = (Output("output", "file", "The file"),)

    def run(self, params, feedback):
        model = params["model"]
        marks = Path(params["marks"])
        for i in range(10):
            time.sleep(params["seconds"] / 10)
            feedback.progress(10.0 * (i + 1))
            if i == 4 and model in params["die"].split(","):
                died = len(list(marks.glob(f"{model}.*")))
                if died < params["deaths"]:
                    marks.mkdir(parents=True, exist_ok=True)
                    (marks / f"{model}.{died}").write_text(str(os.getpid()))
                    os.kill(os.getpid(), signal.SIGKILL)
        with atomic_output(params["output"]) as tmp:
            Path(tmp).write_text(model)
        return {"output": params["output"]}


ALGORITHMS = [SleepWrite, FailOn, Crash, Chatty, FileSize, DieOnModels]


def install(monkeypatch) -> None:
    """Add the fake algorithms to the registry cache for the duration of a test."""
    monkeypatch.setattr(registry, "_CACHE", registry.algorithms())  # restored after the test
    for cls in ALGORITHMS:
        registry.add(cls())
