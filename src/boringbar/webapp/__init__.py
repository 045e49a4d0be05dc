"""The design page (docs/app.md): :func:`app` for a notebook, :func:`serve` for
``boringbar app``.  Panel serves both from one code base."""

from boringbar.webapp.server import app, serve

__all__ = ["app", "serve"]
