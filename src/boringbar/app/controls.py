"""The design page's controls: one widget per thing a designer varies, each change
checked into a new :class:`Design` (a bad value shows the command line's message
and leaves the design as it was), and a system file to upload."""

from __future__ import annotations

import panel as pn

from boringbar._validate import ParameterError
from boringbar.app.design_state import FIELDS, FORCINGS, TUNINGS, Design
from boringbar.model.materials import MATERIALS
from boringbar.model.system import PRESETS
from boringbar.model.system_file import FRICTION_FORMS, loads_system
from boringbar.simulate import INTEGRATOR_CHOICES

#: run settings -> (label, widget kind, choices)
SETTINGS = {
    "preset": ("preset", "select", PRESETS),
    "integrator": ("integrator", "select", INTEGRATOR_CHOICES),
    "forcing": ("forcing", "select", FORCINGS),
    "force_n": ("force amplitude (N)", "number", None),
    "ratio": ("frequency ratio Ω/ωn", "number", None),
    "rpm": ("spindle speed (rpm)", "number", None),
    "depth_mm": ("depth of cut (mm)", "number", None),
}
CHOICES = {"ball.material": tuple(MATERIALS), "tmd.tuning": TUNINGS}


class Controls:
    """The widgets of ``design``; ``on_change(design)`` is told of each checked change."""

    def __init__(self, design: Design, on_change):
        self.design, self.on_change, self.quiet = design, on_change, False
        self.message = pn.pane.Alert("", alert_type="danger", visible=False,
                                     css_classes=["control-error"], sizing_mode="stretch_width")
        self.widgets = {key: self._widget(key, label, kind, choices)
                        for key, (label, kind, choices) in SETTINGS.items()}
        for key, (label, unit) in FIELDS.items():
            if key != "ball.friction":
                self.widgets[key] = self._widget(
                    key, f"{label} ({unit})" if unit else label,
                    "select" if key in CHOICES else "number", CHOICES.get(key))
        self.widgets["friction_form"] = self._widget("friction_form", "friction law", "select",
                                                     tuple(FRICTION_FORMS))
        self.widgets["friction_value"] = self._widget("friction_value", "friction value",
                                                      "number", None)
        self.upload = pn.widgets.FileInput(accept=".toml", label="system file")
        self.upload.param.watch(self._upload, "value")
        self.title = pn.pane.Markdown("")
        self.show(design)
        self.panel = self._panel()

    def _widget(self, key, label, kind, choices):
        css = [f"ctl-{key.replace('.', '-')}"]  # how a browser test finds it
        if kind == "select":
            w = pn.widgets.Select(label=label, options=list(choices), css_classes=css)
        else:
            w = pn.widgets.FloatInput(label=label, value=0.0, css_classes=css)
        w.param.watch(lambda event, key=key: self._changed(key, event.new), "value")
        return w

    def _panel(self):
        w = self.widgets

        def group(title, keys):
            return pn.Card(*(w[k] for k in keys), title=title, collapsed=False,
                           sizing_mode="stretch_width")

        return pn.Column(
            self.title, self.upload, self.message,
            group("Run", ("preset", "integrator", "forcing", "force_n", "ratio", "rpm",
                          "depth_mm")),
            group("Ball damper", ("ball.gap_mm", "ball.material", "ball.diameter_mm",
                                  "ball.restitution", "friction_form", "friction_value",
                                  "cavity.position_mm")),
            group("Tuned mass damper", ("tmd.mass_kg", "tmd.tuning", "tmd.stiffness_n_m",
                                        "tmd.damping_n_s_m")),
            sizing_mode="stretch_width")

    def _changed(self, key: str, value) -> None:
        if self.quiet:
            return
        try:
            design = self.changed_design(key, value)
        except ParameterError as e:
            self.message.object, self.message.visible = str(e), True
            return
        self.message.visible = False
        self.design = design
        self.on_change(design)

    def changed_design(self, key: str, value) -> Design:
        """The design with control ``key`` at ``value`` (a ParameterError if not)."""
        if key in SETTINGS:
            return self.design.with_settings(**{key: value})
        if key in ("friction_form", "friction_value"):
            form = value if key == "friction_form" else self.widgets["friction_form"].value
            amount = value if key == "friction_value" else self.widgets["friction_value"].value
            return self.design.with_value("ball.friction", (form, amount))
        return self.design.with_value(key, value)

    def show(self, design: Design) -> None:
        """Set every widget to ``design`` without treating it as a change; the parts
        the system does not have are disabled."""
        self.quiet, self.design = True, design
        try:
            for key, w in self.widgets.items():
                value = _value(design, key)
                w.disabled = value is None
                if value is not None:
                    w.value = value
        finally:
            self.quiet = False
        self.title.object = f"### {design.name}\n{design.data.get('description', '')}"

    def _upload(self, event) -> None:
        if not event.new:
            return
        name = self.upload.filename or "upload.toml"
        try:
            text = event.new.decode("utf-8", errors="replace")
            design = Design.of(loads_system(text, name), self.design.settings)
        except ParameterError as e:
            self.message.object, self.message.visible = str(e), True
            return
        self.message.visible = False
        self.show(design)
        self.on_change(design)


def _value(design: Design, key: str):
    if key in SETTINGS:
        return getattr(design.settings, key)
    if key.startswith("friction_"):
        friction = design.value("ball.friction")
        if friction is None:
            return None
        form = next(k for k in FRICTION_FORMS if k in friction)
        if key == "friction_form":
            return form
        return 0.0 if form == "none" else float(friction[form])
    value = design.value(key)
    return float(value) if isinstance(value, int | float) else value
