"""Serve the design page (``boringbar app``) or show it in a notebook (``bb.design_page``).

Each browser session gets a page of its own (:class:`~boringbar.app.page.Page`: its
design, its pinned design, its threads), so two sessions never share state.  The
server binds 127.0.0.1 unless told otherwise: the page runs simulations on request,
and is not meant to be reachable from other machines without a decision to expose it.
"""

from __future__ import annotations

import sys
from pathlib import Path

import panel as pn

from boringbar.app.design_state import Design
from boringbar.app.page import Page
from boringbar.model.system_file import SystemSpec, load_system, published_system

LOCAL = "127.0.0.1"
TITLE = "boringbar design page"


def _spec(system) -> SystemSpec:
    """The system the page opens with: None (the published bar), a system file's
    path, a SystemSpec, or a System (its file's description)."""
    if system is None:
        return published_system()
    if isinstance(system, SystemSpec):
        return system
    if isinstance(system, str | Path):
        return load_system(system)
    spec = getattr(system, "spec", None)
    if isinstance(spec, SystemSpec):
        return spec
    raise TypeError(f"system = {system!r}: expected None, a system file's path, a "
                    "SystemSpec or a System")


def page(system=None) -> Page:
    """A new page (one session's) for ``system``."""
    p = Page(Design.of(_spec(system)))
    pn.state.on_session_destroyed(lambda _ctx: p.close())
    return p


def design_page(system=None):
    """The design page in a notebook: ``bb.design_page(system)`` as a cell's last line shows it
    (``system`` as for :func:`serve`)."""
    pn.extension()
    return page(system).layout


def serve(system=None, *, port: int = 5006, host: str = LOCAL, show: bool = False,
          say=print) -> None:
    """Serve the page at http://``host``:``port``/ until interrupted (``system``: None
    for the published bar, a system file's path, a SystemSpec or a System; checked
    before the server starts).  A ``host`` other than 127.0.0.1 exposes the page to the
    network, with a warning; ``show`` opens it in a browser; ``say`` prints the address
    (``boringbar app`` passes print)."""
    spec = _spec(system)
    if host != LOCAL:
        print(f"boringbar app: warning: serving on {host}: anyone who can reach this "
              "machine can run simulations on it", file=sys.stderr)
    origins = ["*"] if host != LOCAL else [f"{LOCAL}:{port}", f"localhost:{port}"]
    say(f"boringbar app: {spec.name} at http://{'localhost' if host == LOCAL else host}:"
        f"{port}/ (Ctrl-C stops it)", flush=True)
    pn.serve({"/": lambda: page(spec).layout}, port=port, address=host, show=show,
             title=TITLE, websocket_origin=origins, print=False)
