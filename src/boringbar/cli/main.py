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
import re
import sys
import textwrap

from boringbar import __version__
from boringbar.cli.audit import add_audit
from boringbar.cli.continuation import add_continue
from boringbar.cli.design import add_design
from boringbar.cli.frf import add_fit_frf
from boringbar.cli.modes import add_modes
from boringbar.cli.nonlinear import add_basins, add_bifurcation, add_sensitivity
from boringbar.cli.options import PROG, Outcome
from boringbar.cli.simulate import add_simulate
from boringbar.cli.study import add_paper, add_run
from boringbar.cli.sweeps import add_lobes, add_sweep
from boringbar.model.system import READINGS


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


def build_parser() -> argparse.ArgumentParser:
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
    add_modes(sub)
    add_fit_frf(sub)
    add_simulate(sub)
    add_sweep(sub)
    add_lobes(sub)
    add_bifurcation(sub)
    add_basins(sub)
    add_sensitivity(sub)
    add_continue(sub)

    add_run(sub)
    add_paper(sub)
    add_audit(sub)
    add_design(sub)
    return parser


def main(argv=None) -> int:
    """Run the command line; returns the exit code (0 ok, 2 bad input, 1 I/O error)."""
    parser = build_parser()
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
