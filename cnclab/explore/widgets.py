"""ipywidgets explorers: a thin layer wiring controls to the pure scene functions of
:mod:`cnclab.explore.scenes` and the drawings of :mod:`cnclab.explore.draw`.

Every control is a standard ipywidgets control (sliders and drop-downs are keyboard operable: Tab to
focus, arrow keys to change) whose label states the unit. Values the package refuses are shown with
the package's own ``ValueError`` message (nothing is drawn for them). Each explorer renders its figure
to a PNG ``Image`` widget, so it also works headless and leaves a static snapshot in exported HTML.

>>> ex = thesis1_explorer()
>>> ex.controls["stepover"].value = 2.0
>>> "θ =" in ex.readout.value
True
"""
from __future__ import annotations

import base64
import functools
import html
import io

import ipywidgets as W
import numpy as np

from ..works.mgherony2024.ch7_9 import DIRECTIONS
from . import draw, scenes

__all__ = ["Explorer", "slider", "choice", "thesis1_explorer", "ce_growth_explorer", "trochoid_explorer",
           "kim_yang_explorer", "hoang_explorer", "working_diameter_explorer", "cusp_explorer",
           "spindle_explorer"]

_STYLE = {"description_width": "16em"}
_LAYOUT = {"width": "34em"}


def slider(label, unit, value, lo, hi, step, integer=False):
    """A keyboard-operable slider labelled ``"label [unit]"``; updates when released / on each key."""
    cls = W.IntSlider if integer else W.FloatSlider
    return cls(value=value, min=lo, max=hi, step=step, description=f"{label} [{unit}]", style=_STYLE,
               layout=_LAYOUT, continuous_update=False, readout=True)


def choice(label, options, value=None):
    """A drop-down (keyboard: arrow keys) labelled ``label``."""
    return W.Dropdown(options=options, value=value if value is not None else options[0], description=label,
                      style=_STYLE, layout=_LAYOUT)


def figure_png(fig) -> bytes:
    """PNG bytes of a matplotlib figure (96 dpi)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=96)
    return buf.getvalue()


class Explorer(W.VBox):
    """Controls + figure + readout. ``compute(**values)`` returns a scene (may raise ValueError),
    ``render(scene)`` a matplotlib Figure, ``describe(scene)`` an HTML readout line.

    Attributes: ``controls`` (name -> widget), ``image`` (PNG), ``readout`` (HTML), ``message`` (HTML,
    the package's refusal), ``scene`` (last scene or None), ``error`` (last message or None).
    """

    def __init__(self, title, controls, compute, render, describe):
        self.controls = dict(controls)
        self._compute, self._render, self._describe = compute, render, describe
        self.image = W.Image(format="png", layout={"max_width": "100%"})
        self.readout = W.HTML()
        self.message = W.HTML()
        self.scene, self.error = None, None
        header = W.HTML(f"<b>{html.escape(title)}</b>")
        super().__init__([header, *self.controls.values(), self.message, self.readout, self.image])
        self.add_class("cnclab-explorer")
        for w in self.controls.values():
            w.observe(self._changed, names="value")
        self.update()

    def values(self) -> dict:
        return {k: w.value for k, w in self.controls.items()}

    def _changed(self, _change):
        self.update()

    def update(self):
        """Recompute the scene and redraw; on ValueError show the package's message instead."""
        try:
            sc = self._compute(**self.values())
        except ValueError as exc:
            self.scene, self.error = None, str(exc)
            self.message.value = (f"<span style='color:#b00' role='alert'>refused: {html.escape(str(exc))}"
                                  "</span>")
            return
        self.scene, self.error = sc, None
        self.message.value = ""
        fig = self._render(sc)
        self.image.value = figure_png(fig)
        self.readout.value = self._describe(sc)

    def _repr_mimebundle_(self, **kwargs):
        """Widget view in JupyterLab; a static PNG snapshot + readout for HTML exports."""
        bundle = super()._repr_mimebundle_(**kwargs) or {}
        png = base64.b64encode(self.image.value).decode() if self.image.value else ""
        snap = (f"<div class='cnclab-explorer-snapshot'><p><i>Static snapshot of an interactive explorer "
                f"(open the notebook in JupyterLab to move the controls).</i></p>{self.readout.value}"
                f"<br><img alt='explorer snapshot' src='data:image/png;base64,{png}'></div>")
        bundle = dict(bundle)
        bundle["text/html"] = snap
        return bundle


def _fmt(sc, *items):
    return " &nbsp; ".join(f"{lab} = <b>{sc[k]:.{d}f}</b> {u}" for lab, k, d, u in items)


# ------------------------------------------------------------------------------ the explorers
def thesis1_explorer():
    """Thesis I: engagement angle vs stepover and arc radius, drawn to scale."""
    def compute(stepover, rho, tool_radius, kind):
        return scenes.thesis1_scene(stepover, rho, tool_radius, kind), scenes.thesis1_curves(rho, tool_radius)

    def describe(sc):
        s = sc[0]
        s1 = "—" if s["s_thesis1_mm"] is None else f"{s['s_thesis1_mm']:.4f} mm"
        return (_fmt(s, ("θ", "theta_deg", 3, "°"), ("drawn arc", "drawn_theta_deg", 3, "°"))
                + f" &nbsp; Thesis I s(θ, ρ) = <b>{s1}</b>")

    return Explorer("Thesis I — engagement angle vs stepover and contour radius",
                    {"stepover": slider("stepover s", "mm", 1.5, 0.0, 12.0, 0.1),
                     "rho": slider("contour radius ρ", "mm", 8.0, 0.5, 50.0, 0.5),
                     "tool_radius": slider("tool radius r", "mm", 3.0, 1.0, 8.0, 0.5),
                     "kind": choice("contour", ["concave", "convex", "straight"])},
                    compute, lambda sc: draw.thesis1(*sc), describe)


_ce_growth = functools.lru_cache(maxsize=64)(scenes.ce_growth_scene)
_trochoid = functools.lru_cache(maxsize=32)(scenes.trochoid_scene)
_kim_yang = functools.lru_cache(maxsize=32)(scenes.kim_yang_scene)


def ce_growth_explorer(resolution_mm=0.15):
    """Thesis III: the constant-engagement path growing along a contour, with simulated engagement."""
    def compute(contour, theta, tool_radius, progress):
        return _ce_growth(contour, theta, tool_radius, progress, resolution_mm)

    def describe(sc):
        e = sc["engagement_deg"]
        m = sc["s_mm"] > 2 * sc["tool_radius_mm"]
        med = float(np.nanmedian(e[m])) if m.any() else float("nan")
        return f"path {sc['s_mm'][-1]:.1f} mm, median simulated engagement after entry <b>{med:.2f}°</b>"

    return Explorer("Thesis III — constant-engagement path on a contour",
                    {"contour": choice("contour", list(scenes.CE_CONTOURS)),
                     "theta": slider("engagement θ", "deg", 60.0, 10.0, 150.0, 5.0),
                     "tool_radius": slider("tool radius r", "mm", 3.0, 1.0, 5.0, 0.5),
                     "progress": slider("grown share of contour", "–", 0.5, 0.05, 1.0, 0.05)},
                    compute, draw.ce_growth, describe)


def trochoid_explorer(resolution_mm=0.1):
    """Thesis IV: circle, cycloid and constant-engagement trochoids with simulated engagement."""
    def compute(pattern, step, width, tool_radius, theta):
        return _trochoid(pattern, step, width, tool_radius, theta, 5, resolution_mm)

    def describe(sc):
        m = sc["metrics"]
        return (f"step <b>{sc['step_mm']:.3f} mm</b>, max steady engagement <b>{m['engagement_max_deg']:.1f}°</b>, "
                f"path per mm of slot <b>{m['length_per_mm_slot']:.2f}</b>, MRR <b>{m['mrr_avg_mm3_min']:.0f} mm³/min</b>")

    return Explorer("Thesis IV — trochoid patterns in a slot",
                    {"pattern": choice("pattern", list(scenes.TROCHOID_PATTERNS)),
                     "step": slider("trochoidal step", "mm", 1.0, 0.1, 3.0, 0.1),
                     "width": slider("slot width W", "mm", 12.0, 6.5, 20.0, 0.5),
                     "tool_radius": slider("tool radius r", "mm", 3.0, 1.0, 5.0, 0.5),
                     "theta": slider("engagement θ (CE pattern)", "deg", 60.0, 20.0, 120.0, 5.0)},
                    compute, draw.trochoid, describe)


def kim_yang_explorer():
    """Kim & Yang: MRR along the contour-parallel path and the inserted segments vs θ."""
    def compute(theta, tolerance, pixel):
        return _kim_yang(theta, 5.0, pixel, tolerance, 500.0, 0.5, 0.5)

    def describe(sc):
        return (f"s = <b>{sc['stepover_mm']:.2f} mm</b>, excessive segments <b>{sc['n_excessive']}</b>, "
                f"insertions <b>{sc['n_insertions']}</b>, nominal MRR <b>{sc['nominal_mrr_mm3_min']:.0f} mm³/min</b>")

    return Explorer("Kim & Yang — constant-MRR contour-parallel path (test pocket scaled 0.5)",
                    {"theta": slider("reference engagement θ", "deg", 60.0, 20.0, 120.0, 10.0),
                     "tolerance": slider("MRR tolerance", "–", 0.25, 0.0, 0.5, 0.05),
                     "pixel": slider("pixel size p", "mm", 0.5, 0.3, 1.0, 0.1)},
                    compute, draw.kim_yang, describe)


def hoang_explorer():
    """Hoang: constant-volume forward step vs scallop height and tool radius."""
    def describe(sc):
        return _fmt(sc, ("S_z", "Sz", 4, "mm"), ("θ", "theta_deg", 3, "°"), ("F_r", "Fr_consistent", 4, "mm"),
                    ("F_r as printed", "Fr_printed_convention", 4, "mm"))

    return Explorer("Hoang — constant-volume zig-zag step",
                    {"scallop_height_mm": slider("scallop height S_c", "mm", 0.05, 0.005, 3.0, 0.005),
                     "tool_radius_mm": slider("tool radius R_T", "mm", 2.5, 0.5, 10.0, 0.5),
                     "volume_mm3": slider("block volume V", "mm³", 0.1, 0.01, 2.0, 0.01)},
                    scenes.hoang_scene, draw.hoang, describe)


def working_diameter_explorer():
    """Mgherony ch. 4-5: ball-end working diameter on an inclined surface, in 3D."""
    return Explorer("Mgherony — ball-end working diameter on an inclined surface",
                    {"D": slider("tool diameter D", "mm", 10.0, 1.0, 20.0, 0.5),
                     "a_p": slider("depth of cut a_p", "mm", 0.3, 0.05, 12.0, 0.05),
                     "A_N1": slider("normal azimuth A_N1", "deg", 30.0, -180.0, 180.0, 5.0),
                     "A_N2": slider("normal tilt A_N2", "deg", 20.0, -120.0, 120.0, 5.0),
                     "A_f": slider("feed direction A_f", "deg", 0.0, -180.0, 180.0, 5.0),
                     "a_e": slider("width of cut a_e", "mm", 0.25, 0.0, 3.0, 0.05),
                     "milling": choice("milling", ["up", "down"])},
                    scenes.working_diameter_scene, draw.working_diameter,
                    lambda sc: _fmt(sc, ("D point 1", "d1_mm", 4, "mm"), ("D point 2", "d2_mm", 4, "mm")))


def cusp_explorer():
    """Mgherony ch. 3: cusp height and ideal roughness vs feed and corner radius."""
    return Explorer("Mgherony — cusp height and ideal roughness",
                    {"feed_mm": slider("feed f", "mm/rev", 0.1, 0.01, 1.0, 0.01),
                     "corner_radius_mm": slider("corner radius RE", "mm", 0.4, 0.05, 2.0, 0.05)},
                    scenes.cusp_scene, draw.cusp,
                    lambda sc: _fmt(sc, ("CH", "CH_mm", 6, "mm"), ("CH (eq 3-2)", "CH_approx_mm", 6, "mm"),
                                    ("Ra", "Ra_mm", 6, "mm"), ("Rz", "Rz_mm", 6, "mm")))


def spindle_explorer():
    """Mgherony ch. 8: controlled spindle speed along the zig-zag for each feed direction."""
    def describe(sc):
        s = sc["summary"]
        return (f"A_f = {sc['feed_angle_deg']:g}°: n from <b>{s['n_min']:.0f}</b> to <b>{s['n_max']:.0f} rpm</b>, D_eff {s['d_eff_min']:.2f}–"
                f"{s['d_eff_max']:.2f} mm, v_c within ±5 %: <b>{100 * s['vc_within_5pct_share']:.1f} %</b> of the path")

    return Explorer("Mgherony ch. 8 — spindle speed along the path vs feed direction",
                    {"feed_angle_deg": W.SelectionSlider(options=[float(a) for a in DIRECTIONS], value=0.0,
                                                         description="feed direction A_f [deg]", style=_STYLE,
                                                         layout=_LAYOUT, continuous_update=False)},
                    scenes.spindle_scene, draw.spindle, describe)
