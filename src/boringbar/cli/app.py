"""``boringbar app``: the design page, served locally (docs/app.md)."""

from __future__ import annotations

import boringbar as bb
from boringbar._validate import ParameterError, check_int
from boringbar.cli.options import Outcome
from boringbar.model.system_file import load_system


def add_app(sub) -> None:
    p = sub.add_parser("app", help="the design page: explore a damped bar live in the browser",
                       description="Serve the design page at http://127.0.0.1:PORT/: the bar, "
                                   "one run, its frequency response and stability lobes beside "
                                   "the solid and TMD bars, redrawn as you change the design; "
                                   "pin, export, search (docs/app.md). Ctrl-C stops it.")
    p.add_argument("--system", metavar="FILE.toml",
                   help="a system file (default: the published bar)")
    p.add_argument("--port", type=int, default=5006, metavar="N",
                   help="the port (default: 5006)")
    p.add_argument("--host", default="127.0.0.1", metavar="ADDRESS",
                   help="the address to bind (default 127.0.0.1, this machine only; another "
                        "exposes the page to the network, with a warning)")
    p.add_argument("--show", action="store_true", help="open the page in a browser")
    p.set_defaults(func=cmd_app, json=False, quiet=True)


def cmd_app(args) -> Outcome:
    check_int("--port", args.port, 1, 65535)
    spec = load_system(args.system) if args.system else None
    # the page's libraries (Panel, Bokeh: an extra, boringbar[app]) are loaded only to
    # serve it, so that `boringbar app --help` and a bad option answer at once
    try:
        serve = bb.serve
    except ImportError as exc:
        raise ParameterError(f"boringbar app needs the design page's libraries ({exc.name} "
                             "is missing): pip install 'boringbar[app]'") from None
    serve(spec, port=args.port, host=args.host, show=args.show)
    return Outcome({"served": True}, lambda say: None)
