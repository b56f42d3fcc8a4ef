"""The console script's entry: a Ctrl-C while the command is still loading."""

from __future__ import annotations

import signal
import sys

from photodem.algorithms import cli_entry


class _InterruptedImport:
    """A meta-path finder that acts as if Ctrl-C came while the command line was loading."""

    def find_spec(self, name, path=None, target=None):
        if name == "photodem.algorithms.cli":
            raise KeyboardInterrupt
        return None


def test_ctrl_c_while_loading_is_a_quiet_cancel(monkeypatch, capsys) -> None:
    monkeypatch.delitem(sys.modules, "photodem.algorithms.cli", raising=False)
    monkeypatch.setattr(sys, "meta_path", [_InterruptedImport(), *sys.meta_path])
    assert cli_entry.main() == 130
    err = capsys.readouterr().err
    assert "cancelled" in err and "Traceback" not in err


def test_the_command_runs_through_the_entry(monkeypatch, capsys) -> None:
    from photodem.algorithms import cli

    # the console-script path changes process-wide SIGINT handling: restore it afterwards
    monkeypatch.setattr(cli, "_IGNORE_LATE_SIGINT", cli._IGNORE_LATE_SIGINT)
    before = signal.getsignal(signal.SIGINT)
    monkeypatch.setattr(sys, "argv", ["photodem", "list", "--json"])
    try:
        assert cli_entry.main() == 0
    finally:
        signal.signal(signal.SIGINT, before)
    assert '"project_create"' in capsys.readouterr().out


def test_ctrl_c_while_the_parser_is_built_is_a_quiet_cancel(monkeypatch, capsys) -> None:
    from photodem.algorithms import cli

    def interrupted() -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "build_parser", interrupted)
    monkeypatch.setattr(cli, "_IGNORE_LATE_SIGINT", cli._IGNORE_LATE_SIGINT)
    monkeypatch.setattr(sys, "argv", ["photodem", "list"])
    assert cli_entry.main() == 130
    err = capsys.readouterr().err
    assert "cancelled" in err and "Traceback" not in err
