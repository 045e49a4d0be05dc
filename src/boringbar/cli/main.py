"""The ``boringbar`` command: ``simulate``, ``sweep``, ``lobes``, ``bifurcation``,
``basins`` and ``sensitivity``; ``run`` (study files) and ``paper`` (the whole
published study) are in :mod:`boringbar.cli.study`.

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
import importlib
import re
import sys
import textwrap

from boringbar.cli.options import PROG, Outcome
from boringbar.model.system import READINGS
from boringbar.version import __version__

#: the subcommands, in the order --help lists them: name -> (module, its add_ function).
#: A command line imports only its own command's module (the design search's Optuna, the
#: FRF fit's SciPy signal tools and the figures' matplotlib load only where used); --help
#: and a mistyped command build them all.
COMMANDS = {
    "modes": ("boringbar.cli.modes", "add_modes"),
    "fit-frf": ("boringbar.cli.frf", "add_fit_frf"),
    "simulate": ("boringbar.cli.simulate", "add_simulate"),
    "sweep": ("boringbar.cli.sweeps", "add_sweep"),
    "lobes": ("boringbar.cli.sweeps", "add_lobes"),
    "bifurcation": ("boringbar.cli.nonlinear", "add_bifurcation"),
    "basins": ("boringbar.cli.nonlinear", "add_basins"),
    "sensitivity": ("boringbar.cli.nonlinear", "add_sensitivity"),
    "continue": ("boringbar.cli.continuation", "add_continue"),
    "run": ("boringbar.cli.study", "add_run"),
    "paper": ("boringbar.cli.study", "add_paper"),
    "audit": ("boringbar.cli.audit", "add_audit"),
    "design": ("boringbar.cli.design", "add_design"),
}


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line error (exit code 2) instead of usage + error."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        # a value starting with '-' and a digit is a value, not an option, so
        # ranges work unquoted: --displacement-mm -1.5:1.5:30 (argparse's own
        # pattern only knows plain negative numbers before Python 3.13)
        self._negative_number_matcher = re.compile(r"^-\.?\d")

    def error(self, message):
        self.exit(2, f"{PROG}: error: {message} (see '{self.prog} --help')\n")


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The command line's parser: with every subcommand, or only ``command``'s."""
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
    for name, (module, add) in COMMANDS.items():
        if command in (None, name):
            getattr(importlib.import_module(module), add)(sub)
    return parser


def main(argv=None) -> int:
    """Run the command line; returns the exit code (0 ok, 2 bad input, 1 I/O error)."""
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(argv[0] if argv and argv[0] in COMMANDS else None)
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, usage errors
        return exc.code if isinstance(exc.code, int) else 0
    try:
        outcome = args.func(args)
        if isinstance(outcome, Outcome):
            outcome.report(args)
            return 0
        return outcome
    except ValueError as exc:  # ParameterError is a ValueError
        print(f"{PROG}: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"{PROG}: error: {_one_line(exc)}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


if __name__ == "__main__":
    sys.exit(main())
