"""The ``photodem`` command: list, help, run, batch and the standalone GUI.

Usage::

    photodem list [--json]
    photodem help ID [--json]
    photodem run ID --name-with-dashes VALUE … [--json] [--quiet]
    photodem batch FILE.toml [--workers N] [--scheduler tcp://HOST:8786] [--resume | --no-resume]
                   [--dry-run] [--json]
    photodem batch --template PROJECT
    photodem gui
    photodem --version

Conventions of ``run``:

- A flag per parameter: the spec's snake_case name with dashes (``--angle-unit``).
- Values are passed as strings to :func:`.processing.registry.run`, which converts and checks
  them exactly as for Python and QGIS (so the results are identical).
- ``bool``: ``--flag`` alone means true; ``--flag true|false`` (also yes/no/1/0/on/off).
- ``enum``: the option string (case-insensitive), e.g. ``--angle-unit gon``.
- ``extent``: ``xmin,ymin,xmax,ymax``; ``multiple_rasters``: several values or a comma list.
- ``--json`` prints the outputs as one JSON object on stdout and nothing else goes to stdout
  (progress and log lines go to stderr; anything an algorithm or library prints is redirected
  to stderr too). Without ``--json`` the outputs are printed as ``name: value`` lines.

Exit codes: 0 success; 1 unexpected error (a bug: the traceback is printed) or failed batch
tasks; 2 an operator error (:class:`~.errors.PhotodemError`, a bad flag or value), printed as
one line ``photodem: error: …``; 130 cancelled with Ctrl-C (the first Ctrl-C cancels the run,
which then removes its staged outputs; a second one aborts at once).
"""

from __future__ import annotations

# Imports inside functions here are lazy on purpose: they keep ``photodem list`` fast (package
# metadata, the demo chain) or load Qt only when the GUI starts.
import argparse
import contextlib
import json
import os
import signal
import sys
import threading
import traceback
from pathlib import Path
from typing import Any, Dict, Iterator, List, Optional, Sequence

from .cli_feedback import CliFeedback
from .errors import Cancelled, PhotodemError
from .feedback import Feedback
from .processing import batch as batch_mod
from .processing import registry
from .processing.spec import Algorithm, Parameter

PROG = "photodem"
EXIT_OK, EXIT_FAILED, EXIT_USAGE, EXIT_CANCELLED = 0, 1, 2, 130
#: Said when Ctrl-C came after the run had committed its outputs (the run then finishes).
LATE_INTERRUPT = "the run had finished writing before the interrupt; its outputs are complete."
#: Set by :func:`main` for the console script: Ctrl-C after the work is ignored.
_IGNORE_LATE_SIGINT = False
#: Option names of ``run`` itself; no algorithm parameter may use them.
RESERVED = ("json", "quiet", "help")


class UsageError(PhotodemError):
    """A wrong command line (unknown flag, missing value)."""


class _Parser(argparse.ArgumentParser):
    """argparse that raises instead of printing the usage and exiting."""

    def error(self, message: str) -> None:  # type: ignore[override]
        hint = f" (see '{self.prog} --help')"
        raise UsageError(message + hint)


# -- version -------------------------------------------------------------------------------------
def version() -> str:
    """The installed package version, else the one in ``metadata.txt``."""
    try:
        from importlib.metadata import PackageNotFoundError
        from importlib.metadata import version as _version

        try:
            return _version("photodem")
        except PackageNotFoundError:
            pass
    except ImportError:  # pragma: no cover
        pass
    meta = Path(__file__).resolve().parents[1] / "metadata.txt"
    try:
        for line in meta.read_text(encoding="utf-8").splitlines():
            if line.strip().startswith("version="):
                return line.split("=", 1)[1].strip()
    except OSError:
        pass
    return "unknown"


# -- the top-level parser ------------------------------------------------------------------------
def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog=PROG,
        description="PhotoDEM: aerial photogrammetry — DSMs, DTMs, orthophotos, georeferencing.",
        epilog="Run 'photodem help ID' for the parameters of an algorithm.",
    )
    parser.add_argument("--version", action="version", version=f"{PROG} {version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    p = sub.add_parser("list", help="list the algorithms")
    p.add_argument("--json", action="store_true", help="print a JSON list")

    p = sub.add_parser("help", help="describe an algorithm and its parameters")
    p.add_argument("algorithm", nargs="?", metavar="ID")
    p.add_argument("--json", action="store_true", help="print the spec as JSON")

    p = sub.add_parser("run", help="run an algorithm", add_help=False,
                       usage="photodem run ID --parameter VALUE … [--json] [--quiet]")
    p.add_argument("algorithm", metavar="ID")
    p.add_argument("rest", nargs=argparse.REMAINDER)

    p = sub.add_parser("batch", help="run algorithms over the stereo models of a project")
    p.add_argument("file", nargs="?", metavar="FILE.toml")
    p.add_argument("--workers", type=int, default=None, help="worker processes (default: file)")
    p.add_argument("--scheduler", metavar="tcp://HOST:8786", default=None,
                   help="run the tasks on this Dask scheduler's cluster (default: file, else "
                        "this machine); the project must be on storage every worker sees")
    p.add_argument("--resume", action=argparse.BooleanOptionalAction, default=True,
                   help="skip tasks completed by an earlier run with the same parameters")
    p.add_argument("--dry-run", action="store_true", help="show the tasks, run nothing")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.add_argument("--quiet", action="store_true", help="no progress or log lines")
    p.add_argument("--template", metavar="PROJECT", help="print an example batch file")

    gui = sub.add_parser("gui", help="start the standalone toolbox")
    gui.add_argument("project", nargs="?", default=None,
                     help="a project folder or project.toml to open on the map")

    p = sub.add_parser("demo", help="run the whole chain on a synthetic block")
    p.add_argument("output", nargs="?", default="demo-output", metavar="FOLDER",
                   help="demo folder (default: demo-output)")
    p.add_argument("--size", default="small", choices=("tiny", "small", "medium", "large"),
                   help="synthetic block size (default: small)")
    p.add_argument("--seed", type=int, default=1, help="random seed (default: 1)")
    p.add_argument("--workers", type=int, default=2, help="batch worker processes (default: 2)")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.add_argument("--quiet", action="store_true", help="no progress or log lines")
    return parser


def algorithm_parser(alg: Algorithm) -> argparse.ArgumentParser:
    """The parser of ``photodem run ID``: one flag per parameter of the spec."""
    parser = _Parser(prog=f"{PROG} run {alg.id}", description=alg.name, add_help=True)
    for p in alg.parameters:
        if p.name in RESERVED:
            raise RuntimeError(f"{alg.id}: parameter name {p.name!r} is reserved by the CLI")
        kwargs: Dict[str, Any] = {"dest": p.name, "default": None, "help": _flag_help(p),
                                  "metavar": _metavar(p)}
        if p.is_bool:
            kwargs.update(nargs="?", const="true")
        elif p.is_list:
            kwargs.update(nargs="+")
        parser.add_argument(p.flag, **kwargs)
    parser.add_argument("--json", action="store_true", help="print the outputs as JSON")
    parser.add_argument("--quiet", action="store_true", help="no progress or log lines")
    return parser


def _metavar(p: Parameter) -> str:
    if p.is_choice:
        return "{" + ",".join(p.options) + "}"
    if p.is_bool:
        return "true|false"
    return p.kind.upper()


def _flag_help(p: Parameter) -> str:
    text = p.description
    if p.default is not None:
        text += f" (default {p.default})"
    elif p.optional:
        text += " (optional)"
    else:
        text += " (required)"
    return text.replace("%", "%%")


# -- commands ------------------------------------------------------------------------------------
def cmd_list(args: argparse.Namespace) -> int:
    algs = registry.algorithms()
    if args.json:
        print(json.dumps([{"id": a.id, "name": a.name, "group": a.group} for a in algs.values()],
                         indent=2))
        return EXIT_OK
    if not algs:
        print("No algorithms registered.")
        return EXIT_OK
    width = max(len(a) for a in algs)
    for group in registry.groups():
        print(f"{group or 'Other'}:")
        for a in algs.values():
            if a.group == group:
                print(f"  {a.id:<{width}}  {a.name}")
    return EXIT_OK


def describe(alg: Algorithm) -> str:
    """The text of ``photodem help ID``."""
    lines = [f"{alg.name} ({alg.id})", f"Group: {alg.group}", ""]
    if alg.help:
        lines += [alg.help.strip(), ""]
    lines.append(f"Usage: photodem run {alg.id} " + " ".join(
        f"{p.flag} {_metavar(p)}" if p.required else f"[{p.flag} {_metavar(p)}]"
        for p in alg.parameters) + " [--json] [--quiet]")
    lines += ["", "Parameters:"]
    for p in alg.parameters:
        status = "required" if p.required else "optional"
        details = [p.kind]
        if p.unit:
            details.append(f"unit {p.unit}")
        if p.default is not None:
            details.append(f"default {p.default}")
        if p.minimum is not None or p.maximum is not None:
            low = "-∞" if p.minimum is None else f"{p.minimum:g}"
            high = "∞" if p.maximum is None else f"{p.maximum:g}"
            details.append(f"range {low}…{high}")
        if p.options:
            details.append("one of " + "|".join(p.options))
        if p.extensions:
            details.append("files " + " ".join(p.extensions))
        if p.is_bool:
            details.append("true|false")
        details.append(status)
        lines.append(f"  {p.flag}  {p.description}")
        lines.append(f"      {', '.join(details)}")
        if p.help:
            lines.append(f"      {p.help}")
    if alg.outputs:
        lines += ["", "Outputs (keys of --json):"]
        for o in alg.outputs:
            lines.append(f"  {o.name}  ({o.kind})  {o.description}")
    return "\n".join(lines)


def cmd_help(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    if not args.algorithm:
        parser.print_help()
        return EXIT_OK
    alg = registry.get(args.algorithm)
    if args.json:
        print(json.dumps(alg.to_dict(), indent=2, default=str))
    else:
        print(describe(alg))
    return EXIT_OK


def parse_run_arguments(alg: Algorithm, argv: Sequence[str]) -> argparse.Namespace:
    """Parse the flags of ``photodem run ID …``; unknown flags are an operator error."""
    parser = algorithm_parser(alg)
    namespace, unknown = parser.parse_known_args(list(argv))
    if unknown:
        known = ", ".join(p.flag for p in alg.parameters)
        raise UsageError(f"{alg.id}: unknown parameter {' '.join(unknown)}; known are {known} "
                         f"(see 'photodem help {alg.id}').")
    return namespace


def raw_parameters(alg: Algorithm, namespace: argparse.Namespace) -> Dict[str, Any]:
    """The raw values given on the command line (parameters not given are left out)."""
    values = {}
    for p in alg.parameters:
        value = getattr(namespace, p.name)
        if value is not None:
            values[p.name] = value
    return values


def cmd_run(args: argparse.Namespace) -> int:
    alg = registry.get(args.algorithm)
    if any(a in ("-h", "--help") for a in args.rest):
        print(describe(alg))
        return EXIT_OK
    namespace = parse_run_arguments(alg, args.rest)
    params = raw_parameters(alg, namespace)
    feedback = CliFeedback(quiet=namespace.quiet)
    with _cancel_on_sigint(feedback):
        try:
            with _stdout_to_stderr():
                result = registry.run(alg.id, params, feedback)
        finally:
            feedback.close()
    if feedback.is_canceled():  # the interrupt came after the outputs were committed
        feedback.warning(LATE_INTERRUPT)
    _print_result(result, namespace.json)
    return EXIT_OK


def _print_result(result: Dict[str, Any], as_json: bool) -> None:
    if as_json:
        sys.stdout.write(json.dumps(result, indent=2, ensure_ascii=False) + "\n")
        sys.stdout.flush()
        return
    for key, value in result.items():
        if isinstance(value, (dict, list)):
            value = json.dumps(value, ensure_ascii=False)
        print(f"{key}: {value}")


def cmd_demo(args: argparse.Namespace) -> int:
    from .demo import run_demo

    if args.workers < 1:
        raise UsageError(f"--workers {args.workers}: give a whole number ≥ 1")
    feedback = CliFeedback(quiet=args.quiet)
    with _cancel_on_sigint(feedback):
        try:
            with _stdout_to_stderr():
                summary = run_demo(args.output, size=args.size, seed=args.seed,
                                   workers=args.workers, feedback=feedback)
        finally:
            feedback.close()
    if args.json:
        _print_result(summary, True)
    else:
        print(Path(summary["summary"]).read_text(encoding="utf-8"))
        print(f"{PROG}: demo done; summary in {summary['summary']}")
    return EXIT_OK


def cmd_batch(args: argparse.Namespace) -> int:
    if args.template:
        print(batch_mod.batch_template(args.template), end="")
        return EXIT_OK
    if not args.file:
        raise UsageError("batch needs a FILE.toml (or --template PROJECT)")
    plan = batch_mod.load_batch(args.file)
    if args.workers is not None:
        if args.workers < 1:
            raise UsageError(f"--workers {args.workers}: give a whole number ≥ 1")
        plan.workers = args.workers
    if args.scheduler is not None:  # the CLI wins over [batch] scheduler
        plan.scheduler = batch_mod.check_scheduler(args.scheduler)
    if args.dry_run:
        if args.json:
            print(json.dumps(plan.to_dict(), indent=2, default=str))
        else:
            state = batch_mod.read_state(plan.state_home) if args.resume else {}
            print(f"project: {plan.project}\nrun folder: {plan.run_dir}\n"
                  f"workers: {plan.workers}\nscheduler: {plan.scheduler or 'this machine'}")
            for t in plan.tasks:
                would = "skip" if batch_mod.resumable(t, state) is not None else "run"
                print(f"  [{would}] {t.key}: {t.algorithm} {json.dumps(t.params)}")
        return EXIT_OK
    feedback = CliFeedback(quiet=args.quiet)
    with _cancel_on_sigint(feedback):
        try:
            with _stdout_to_stderr():
                summary = batch_mod.run_batch(plan, feedback, resume=args.resume)
        finally:
            feedback.close()
    if args.json:
        _print_result(summary, True)
    counts = summary["counts"]
    line = (f"{PROG}: batch {summary['status']}: "
            + ", ".join(f"{v} {k}" for k, v in counts.items() if v)
            + f"; summary in {summary['summary']}")
    print(line, file=sys.stderr)
    if summary["status"] == "cancelled":
        return EXIT_CANCELLED
    return EXIT_FAILED if summary["status"] == "failed" else EXIT_OK


def cmd_gui(project: Optional[str] = None) -> int:
    try:
        from ..plugin.app import main as app  # here, not above: Qt only when the GUI starts
    except ImportError as exc:
        raise PhotodemError(
            f"The standalone toolbox needs PyQt5 ({exc}); install it with "
            "'pip install photodem[gui]'."
        ) from exc
    return int(app.main([PROG], project=project))


# -- helpers -------------------------------------------------------------------------------------
class _Stopped(Exception):
    """A run ended by a cancellation (``interrupted``: by a second Ctrl-C), with the outputs
    it had committed before (from its feedback), for the message."""

    def __init__(self, interrupted: bool, committed: Sequence[Path]) -> None:
        super().__init__()
        self.interrupted = interrupted
        self.committed = list(committed)


@contextlib.contextmanager
def _cancel_on_sigint(feedback: Feedback) -> Iterator[None]:
    """First Ctrl-C cancels ``feedback`` (the run cleans up); a second one interrupts.

    Once the run has committed an output it is no longer interrupted: it finishes its product
    set, so that what is on disk is complete and matches the message. A cancelled or
    interrupted run ends as :class:`_Stopped` with the outputs ``feedback`` saw committed.
    """
    try:
        with _sigint_handler(feedback):
            yield
    except Cancelled:
        raise _Stopped(False, feedback.committed) from None
    except KeyboardInterrupt:
        raise _Stopped(True, feedback.committed) from None


@contextlib.contextmanager
def _sigint_handler(feedback: Feedback) -> Iterator[None]:
    """Install the Ctrl-C handler of :func:`_cancel_on_sigint` (main thread only)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, frame: Any) -> None:
        if feedback.is_committed():
            feedback.cancel()
            print(f"\n{PROG}: the outputs are being written; finishing the run.",
                  file=sys.stderr)
            return
        if feedback.is_canceled():
            raise KeyboardInterrupt
        feedback.cancel()
        print(f"\n{PROG}: cancelling… (Ctrl-C again to abort at once)", file=sys.stderr)

    previous = signal.signal(signal.SIGINT, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN if _IGNORE_LATE_SIGINT else previous)


@contextlib.contextmanager
def _stdout_to_stderr() -> Iterator[None]:
    """Keep stdout clean for the result: Python prints and C-level writes go to stderr."""
    fd_saved: Optional[int] = None
    try:
        sys.stdout.flush()
        if sys.stdout.fileno() == 1:
            fd_saved = os.dup(1)
            os.dup2(sys.stderr.fileno(), 1)
    except (AttributeError, OSError, ValueError):  # captured streams in tests
        fd_saved = None
    try:
        with contextlib.redirect_stdout(sys.stderr):
            yield
    finally:
        if fd_saved is not None:
            sys.stdout.flush()
            os.dup2(fd_saved, 1)
            os.close(fd_saved)


def _written_before_stop(committed: Sequence[Path] = ()) -> str:
    """What a stopped run left on disk, from the commits its feedback saw (so the message
    matches it)."""
    if not committed:
        return "no output was written."
    return "already complete before the stop: " + ", ".join(str(p) for p in committed) + "."


def _error(message: str) -> None:
    text = " ".join(str(message).split())  # one line
    print(f"{PROG}: error: {text}", file=sys.stderr)


def main(argv: Optional[List[str]] = None) -> int:
    """Entry point of the ``photodem`` console script; returns the exit code."""
    global _IGNORE_LATE_SIGINT
    # the console script: the process ends when main returns, so a Ctrl-C after the work
    # (while the result is printed) is ignored instead of killing it with a complete output
    _IGNORE_LATE_SIGINT = argv is None
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    try:
        registry.add_modules(registry.extra_modules())  # also when the cache is filled already
        try:
            args = parser.parse_args(argv)
        except SystemExit as exc:  # --help and --version
            return int(exc.code or 0)
        if args.command == "list":
            return cmd_list(args)
        if args.command == "help":
            return cmd_help(args, parser)
        if args.command == "run":
            return cmd_run(args)
        if args.command == "batch":
            return cmd_batch(args)
        if args.command == "gui":
            return cmd_gui(args.project)
        if args.command == "demo":
            return cmd_demo(args)
        parser.print_help(sys.stderr)
        return EXIT_USAGE
    except _Stopped as stop:
        interrupted = "\n" if stop.interrupted else ""
        how = " (interrupted)" if stop.interrupted else ""
        print(f"{interrupted}{PROG}: cancelled{how}; {_written_before_stop(stop.committed)}",
              file=sys.stderr)
        return EXIT_CANCELLED
    except Cancelled:
        print(f"{PROG}: cancelled; {_written_before_stop()}", file=sys.stderr)
        return EXIT_CANCELLED
    except KeyboardInterrupt:
        print(f"\n{PROG}: cancelled (interrupted); {_written_before_stop()}", file=sys.stderr)
        return EXIT_CANCELLED
    except PhotodemError as exc:
        _error(str(exc))
        return EXIT_USAGE
    except BrokenPipeError:  # `photodem list | head`
        return EXIT_OK
    except Exception:
        traceback.print_exc()
        return EXIT_FAILED


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
