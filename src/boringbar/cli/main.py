"""The ``boringbar`` command: ``simulate``, ``sweep``, ``lobes``, ``chatter-map``,
``bifurcation``, ``basins`` and ``sensitivity``; ``run`` (study files) and ``paper`` (the
whole published study) are in :mod:`boringbar.cli.study`.

Units are in the option names (docs/model.md, section 7): ``--gap-mm``,
``--force-n``, ``--duration-s``...; everything is converted to SI here and
handed to the library.  Every bad value ends the command with one line,
``boringbar: error: <message>``, and exit code 2; results go to files in
``--out`` (written atomically) and a summary to stdout (``--json``: exactly
one JSON object).  A new subcommand is a ``_add_<name>`` function that
builds its subparser and a ``_cmd_<name>(args) -> int`` handler.
"""

from __future__ import annotations

import argparse
import contextlib
import difflib
import importlib
import os
import re
import signal
import sys
import textwrap
import threading
from pathlib import Path

from boringbar._validate import ParameterError
from boringbar.cli.options import PROG, Outcome, default_out
from boringbar.model.system import READINGS
from boringbar.simulate.run import IntegrationError
from boringbar.version import __version__

#: the subcommands, in the order --help lists them: name -> (module, its add_ function,
#: its one line in --help). A command line imports only its own command's module (the
#: design search's Optuna, the FRF fit's SciPy signal tools and the figures' matplotlib
#: load only where used); --help and a mistyped command import none of them
#: (tests/test_cli.py checks that the lines are the commands' own).
COMMANDS = {
    "modes": ("boringbar.cli.modes", "add_modes",
              "the modal model of a bar, and its mode shapes"),
    "fit-frf": ("boringbar.cli.frf", "add_fit_frf",
                "fit modes to a measured tip FRF (tap test)"),
    "simulate": ("boringbar.cli.simulate", "add_simulate",
                 "one time-domain run under harmonic forcing or a cut"),
    "sweep": ("boringbar.cli.sweeps", "add_sweep",
              "tip RMS and impact pattern against Omega/omega_n"),
    "lobes": ("boringbar.cli.sweeps", "add_lobes",
              "stability lobes by time-domain simulation of cuts"),
    "chatter-map": ("boringbar.cli.chatter_map", "add_chatter_map",
                    "the settled vibration of every cut of a speed x depth grid"),
    "bifurcation": ("boringbar.cli.nonlinear", "add_bifurcation",
                    "Poincare samples of the tip against F0 (or Omega/omega_n, gap, e)"),
    "basins": ("boringbar.cli.nonlinear", "add_basins",
               "basins of attraction over initial tip displacement x velocity"),
    "sensitivity": ("boringbar.cli.nonlinear", "add_sensitivity",
                    "tip RMS (and chatter of cuts) for several values of one parameter"),
    "continue": ("boringbar.cli.continuation", "add_continue",
                 "continue a periodic orbit in one parameter, with Floquet stability and "
                 "bifurcations"),
    "run": ("boringbar.cli.study", "add_run",
            "run a study file (TOML): many runs of one analysis, resumable"),
    "paper": ("boringbar.cli.study", "add_paper",
              "rerun the whole published study under both presets, with an HTML report"),
    "audit": ("boringbar.cli.audit", "add_audit",
              "judge every published claim against a paper output"),
    "design": ("boringbar.cli.design", "add_design",
               "search for the best damper, robust to uncertainty"),
    "app": ("boringbar.cli.app", "add_app",
            "the design page: explore a damped bar live in the browser"),
}


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line error (exit code 2) instead of usage + error."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        # a value starting with '-' and a digit is a value, not an option, so
        # ranges work unquoted: --displacement-mm -1.5:1.5:30 (argparse's own
        # pattern only knows plain negative numbers before Python 3.13)
        self._negative_number_matcher = re.compile(r"^-\.?\d")

    #: the subcommand this parser was built for (build_parser), whose help an unknown
    #: option points to, and the options it takes, for a suggestion
    command: str | None = None
    command_options: tuple[str, ...] = ()

    def error(self, message):
        where = f"{PROG} {self.command}" if self.command and self.prog == PROG else self.prog
        unknown = re.match(r"unrecognized arguments: (--[\w-]+)", message)
        close = (difflib.get_close_matches(unknown.group(1), self.command_options, n=1,
                                           cutoff=0.8) if unknown else [])
        hint = f"; did you mean {close[0]}?" if close else ""
        self.exit(2, f"{PROG}: error: {message}{hint} (see '{where} --help')\n")


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The command line's parser: only ``command``'s subcommand in full, or (None) every
    subcommand's name and line, for --help and the list of choices."""
    readings = "\n".join(textwrap.fill(f"{k}: {v}", 79, initial_indent="  ",
                                       subsequent_indent="    ")
                         for k, v in READINGS.items())
    parser = _Parser(
        prog=PROG, formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Vibration of impact-damped boring bars (ball damper, TMD, solid bar).",
        epilog="Presets: 'physical' (default) is the model as physics demands; 'paper'\n"
               "switches on the published readings:\n" + readings)
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, (module, add, summary) in COMMANDS.items():
        if command == name:
            getattr(importlib.import_module(module), add)(sub)
            parser.command = name
            parser.command_options = tuple(
                o for a in sub.choices[name]._actions for o in a.option_strings)
        elif command is None:
            sub.add_parser(name, help=summary)  # for the list; a command builds its own
    return parser


#: How long a SIGTERM's interruption may take to end the command (its workers stopped,
#: its finished work kept) before the default SIGTERM ends the process.
TERM_GRACE_S = 5.0


class Terminated(KeyboardInterrupt):
    """SIGTERM (a job scheduler's or a container's stop), taken as Ctrl-C is: the work
    finished so far is kept, the worker processes end, and the command exits."""


@contextlib.contextmanager
def _sigterm_as_interrupt():
    """SIGTERM raises :class:`Terminated` while the command runs (the main thread only:
    Python delivers signals there)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum, frame):
        # An exception raised in a signal handler is lost where it lands in a weakref
        # callback or a __del__ (Python prints "Exception ignored" and goes on: a page's
        # server kept serving).  So the first SIGTERM also restores the default action
        # and sends itself a second one after TERM_GRACE_S, which ends the process if
        # the interruption did not.
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        timer = threading.Timer(TERM_GRACE_S, os.kill, (os.getpid(), signal.SIGTERM))
        timer.daemon = True  # a command that ends in time ends with it
        timer.start()
        raise Terminated

    previous = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def main(argv=None) -> int:
    """Run the command line; returns the exit code (0 ok, 2 bad input, 1 I/O error, 130
    interrupted, 143 terminated)."""
    with _sigterm_as_interrupt():
        return _run(argv)


def _run(argv) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(argv[0] if argv and argv[0] in COMMANDS else None)
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, usage errors
        return exc.code if isinstance(exc.code, int) else 0
    # every --out is a folder but run's, its result file (default: the study's own)
    folder_out = args.command != "run"
    if folder_out and getattr(args, "out", "") is None:
        args.out = default_out(args)
    try:
        if folder_out:
            _check_out(getattr(args, "out", None))
        outcome = args.func(args)
        if isinstance(outcome, Outcome):
            outcome.report(args)
            return 0
        return outcome
    except ValueError as exc:  # ParameterError is a ValueError
        print(f"{PROG}: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except (OSError, IntegrationError) as exc:  # a file, or a run that could not finish
        print(f"{PROG}: error: {_one_line(exc)}", file=sys.stderr)
        return 1
    except KeyboardInterrupt as exc:
        stop = isinstance(exc, Terminated)
        print(f"{PROG}: {'terminated' if stop else 'interrupted'}", file=sys.stderr)
        return 143 if stop else 130


def _check_out(out) -> None:
    """--out names a folder, or one that can be made: refused before any run, not as an
    I/O error once the work is done."""
    if out is None:
        return
    path = Path(out)
    if path.exists() and not path.is_dir():
        raise ParameterError(f"--out = {str(out)!r} is a file; give a folder (made if missing)")
    parent = next(p for p in (path, *path.parents) if p.exists())
    if not parent.is_dir() or not os.access(parent, os.W_OK | os.X_OK):
        raise ParameterError(f"--out = {str(out)!r} cannot be made: {str(parent)!r} is not a "
                             "folder this user may write in")


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


if __name__ == "__main__":
    sys.exit(main())
