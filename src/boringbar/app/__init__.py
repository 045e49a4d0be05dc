"""The design page (docs/app.md): :func:`design_page` for a notebook, :func:`serve` for
``boringbar app``.  Panel serves both from one code base."""

from boringbar.app.server import design_page, serve

__all__ = ["design_page", "serve"]
