"""What the audit reads and returns: a ``boringbar paper`` output folder
(:class:`Evidence`) and one claim's judgement under one preset (:class:`Verdict`)."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path

from boringbar._validate import ParameterError

VERDICTS = ("reproduced", "partly", "not reproduced", "not available")
#: Relative tolerance of a published number (a value "within 15 %").
TOLERANCE = 0.15


@dataclass
class Verdict:
    """One claim under one preset: ``verdict`` (one of VERDICTS), ``measured``
    (name -> value, units in the names), ``reason`` (worded from the data) and
    ``figure`` (the output file the verdict is judged on, or None)."""

    verdict: str
    measured: dict = field(default_factory=dict)
    reason: str = ""
    figure: str | None = None


class Evidence:
    """A ``boringbar paper`` output folder: its manifest, step summaries, datasets."""

    def __init__(self, out):
        self.out = Path(out)
        path = self.out / "manifest.json"
        if not self.out.is_dir():
            raise ParameterError(f"DIR = {str(out)!r} is not a directory")
        try:
            self.manifest = json.loads(path.read_text())
        except (OSError, ValueError):
            raise ParameterError(f"DIR = {str(out)!r} holds no boringbar paper output "
                                 f"(no readable {path.name})") from None
        if "steps" not in self.manifest or "presets" not in self.manifest:
            raise ParameterError(f"{path}: not a boringbar paper manifest (no steps)")
        #: the presets, then the further columns (a preset with a reading changed)
        self.variants = {v["name"]: v for v in self.manifest.get("variants", [])}
        self.presets = list(self.manifest["presets"]) + list(self.variants)
        self.quick = bool(self.manifest.get("quick"))
        self.records = {(r["preset"], r["key"]): r for r in self.manifest["steps"]}

    def summary(self, preset: str, key: str) -> dict | None:
        rec = self.records.get((preset, key))
        return None if rec is None else rec.get("summary")

    def figure(self, preset: str, key: str, which: str | None = None) -> str | None:
        """The step's figure, relative to the output folder."""
        s = self.summary(preset, key)
        if s is None:
            return None
        png = s.get("files", {}).get("png")
        if isinstance(png, list):
            png = next((p for p in png if which is None or which in p), png[0] if png else None)
        if png is None:
            return None
        return os.path.relpath(Path(png), self.out).replace(os.sep, "/")
