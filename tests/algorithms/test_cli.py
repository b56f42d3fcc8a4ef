"""The photodem CLI: in-process main(argv) and the installed console script."""

from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from photodem.algorithms import cli
from photodem.algorithms.cli_feedback import CliFeedback

FAKES = Path(__file__).resolve().parent / "processing"
if str(FAKES) not in sys.path:
    sys.path.insert(0, str(FAKES))

import _fake_algs  # noqa: E402

PHOTODEM = Path(sys.prefix) / "bin" / "photodem"


@pytest.fixture
def fakes(monkeypatch):
    _fake_algs.install(monkeypatch)
    monkeypatch.setenv("PHOTODEM_EXTRA_ALGORITHMS", "_fake_algs")


@pytest.fixture
def project(chain_project):
    return chain_project("abc")


def _main(capsys, *argv):
    code = cli.main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_list_and_help(fakes, capsys):
    code, out, _ = _main(capsys, "list", "--json")
    assert code == 0
    entries = {e["id"]: e for e in json.loads(out)}
    assert entries["fake_sleep_write"] == {"id": "fake_sleep_write",
                                           "name": "Fake: sleep and write", "group": "Testing"}
    code, out, _ = _main(capsys, "list")
    assert code == 0 and "Testing:" in out and "fake_chatty" in out
    code, out, _ = _main(capsys, "help", "fake_sleep_write")
    assert code == 0
    for text in ("Fake: sleep and write", "--seconds", "unit s", "default 0.2", "range 0…60",
                 "one of fast|slow|exact", "--output", "required", "Outputs", "value"):
        assert text in out
    code, out, _ = _main(capsys, "help", "fake_sleep_write", "--json")
    assert json.loads(out)["parameters"][0]["name"] == "project"
    code, out, _ = _main(capsys, "run", "fake_chatty", "--help")
    assert code == 0 and "--factor" in out


def test_run_json_keeps_stdout_clean(fakes, project, tmp_path, capsys):
    out_file = tmp_path / "o.json"
    code, out, err = _main(capsys, "run", "fake_sleep_write", "--project", str(project),
                           "--model", "a_b", "--output", str(out_file), "--shout",
                           "--note", "hi", "--mode", "EXACT", "--json")
    assert code == 0, err
    assert json.loads(out) == {"output": str(out_file), "value": 0.4}
    assert json.loads(out_file.read_text()) == {"model": "a_b", "note": "HI", "mode": "exact"}
    assert "100%" in err
    # a library printing to stdout is redirected to stderr
    code, out, err = _main(capsys, "run", "fake_chatty", "--flag", "false", "--factor", "3",
                           "--extent", "0,0,10,5", "--json")
    assert code == 0
    assert json.loads(out) == {"result": {"factor": 3.0, "flag": False,
                                          "extent": [0.0, 0.0, 10.0, 5.0], "crs": None,
                                          "input": None}}
    assert "noise on stdout" in err and "warning: just a warning" in err
    code, out, err = _main(capsys, "run", "fake_chatty", "--flag", "--quiet")
    assert code == 0 and out.startswith("result: {") and '"flag": true' in out
    assert "working" not in err and "just a warning" in err


_BASE = ["--project", "/tmp", "--model", "a", "--output", "/tmp/photodem-never-written.json"]


@pytest.mark.parametrize(("argv", "message"), [
    (["run", "fake_chatty", "--input", "/no/such/file"], "does not exist"),
    (["run", "fake_chatty", "--bogus", "1"], "unknown parameter --bogus"),
    (["run", "fake_chatty", "--factor", "abc"], "not a valid number"),
    (["run", "fake_chatty", "--flag", "maybe"], "yes/no"),
    (["run", "fake_sleep_write", *_BASE, "--mode", "slowest"], "not one of fast, slow, exact"),
    (["run", "fake_sleep_write", *_BASE, "--seconds", "99"], "outside the allowed range"),
    (["run", "no_such_alg"], "No algorithm 'no_such_alg'"),
    (["help", "no_such_alg"], "No algorithm"),
    (["frobnicate"], "invalid choice"),
    (["batch", "/no/such.toml"], "does not exist"),
])
def test_operator_errors_exit_2_with_one_line(fakes, capsys, argv, message):
    code, out, err = _main(capsys, *argv)
    assert code == 2
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("photodem: error: ") and message in lines[0]


def test_missing_required_parameter(fakes, project, capsys):
    code, _, err = _main(capsys, "run", "fake_sleep_write", "--project", str(project),
                         "--model", "a_b")
    assert code == 2 and "'output'" in err and "required" in err


def test_bug_gives_traceback_and_exit_1(fakes, capsys):
    code, out, err = _main(capsys, "run", "fake_crash", "--json")
    assert code == 1 and out == ""
    assert "Traceback" in err and "ZeroDivisionError" in err


def test_version(capsys):
    code, out, _ = _main(capsys, "--version")
    assert code == 0 and out.startswith("photodem ")


def test_batch_cli(fakes, project, capsys):
    file = project.parent / "b.toml"
    file.write_text(
        '[batch]\nproject = "proj"\nworkers = 1\noutput = "{project}/runs/r"\n'
        '[[steps]]\nalgorithm = "fake_fail_on"\n[steps.params]\nfail = "b_c"\n'
        'output = "{project}/products/{step}/{model}.txt"\n')
    code, out, _ = _main(capsys, "batch", str(file), "--dry-run")
    assert code == 0 and "[run] fake_fail_on/a_b" in out
    code, out, _ = _main(capsys, "batch", str(file), "--dry-run", "--json")
    assert len(json.loads(out)["tasks"]) == 2
    code, out, err = _main(capsys, "batch", str(file), "--json", "--quiet")
    assert code == 1
    summary = json.loads(out)
    assert summary["counts"]["failed"] == 1 and summary["counts"]["done"] == 1
    assert "photodem: batch failed: 1 done, 1 failed" in err
    code, out, err = _main(capsys, "batch", str(file), "--quiet")
    assert code == 1 and "1 skipped, 1 failed" in err
    code, out, _ = _main(capsys, "batch", "--template", str(project))
    assert code == 0 and "[[steps]]" in out


def test_cli_feedback_modes():
    stream = io.StringIO()
    fb = CliFeedback(stream=stream, tty=False)
    for pct in range(0, 101, 5):
        fb.progress(pct)
    fb.info("hello")
    lines = stream.getvalue().splitlines()
    assert lines[:3] == ["photodem: 0%", "photodem: 10%", "photodem: 20%"]
    assert lines[-1] == "photodem: hello" and len(lines) == 12
    stream = io.StringIO()
    clock = iter(range(1000))
    fb = CliFeedback(stream=stream, tty=True, clock=lambda: next(clock))
    fb.progress(42)
    fb.info("step one")
    fb.progress(100)
    fb.close()
    text = stream.getvalue()
    assert "\r[ 42%] " in text and "step one\n" in text and "\r[100%] step one" in text
    assert "\n" not in text.replace("step one\n", "")  # progress redraws one line
    stream = io.StringIO()
    fb = CliFeedback(stream=stream, quiet=True, tty=False)
    fb.progress(50)
    fb.info("x")
    fb.warning("careful")
    assert stream.getvalue() == "photodem: warning: careful\n"


# -- the installed console script -----------------------------------------------------------------
def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(FAKES), env.get("PYTHONPATH", "")])
    env["PHOTODEM_EXTRA_ALGORITHMS"] = "_fake_algs"
    return env


needs_script = pytest.mark.skipif(not PHOTODEM.exists(), reason=f"{PHOTODEM} not installed")


@needs_script
def test_console_script_run_json(project, tmp_path):
    out_file = tmp_path / "o.json"
    proc = subprocess.run(
        [str(PHOTODEM), "run", "fake_sleep_write", "--project", str(project), "--model", "b_c",
         "--output", str(out_file), "--json"],
        capture_output=True, text=True, env=_env(), timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout) == {"output": str(out_file), "value": 0.4}
    proc = subprocess.run([str(PHOTODEM), "run", "fake_chatty", "--json"],
                          capture_output=True, text=True, env=_env(), timeout=60)
    assert json.loads(proc.stdout)["result"]["factor"] == 2.0  # the print went to stderr
    proc = subprocess.run([str(PHOTODEM), "run", "fake_chatty", "--input", "/nope"],
                          capture_output=True, text=True, env=_env(), timeout=60)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.strip().splitlines() == [
        "photodem: error: Parameter 'input': '/nope' does not exist."]


@needs_script
def test_console_script_ctrl_c_cancels_without_output(project, tmp_path):
    out_file = tmp_path / "o.json"
    proc = subprocess.Popen(
        [str(PHOTODEM), "run", "fake_sleep_write", "--project", str(project), "--model", "a_b",
         "--output", str(out_file), "--seconds", "20", "--steps", "200", "--json"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=_env())
    deadline = time.monotonic() + 30
    buffer = ""
    while "%" not in buffer and time.monotonic() < deadline:  # wait until it runs
        buffer += proc.stderr.read(1)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=30)
    assert proc.returncode == 130, err
    assert out == ""
    assert "cancelled" in err
    assert list(tmp_path.glob("*.json")) == [] and list(tmp_path.glob(".*")) == []
