"""Trochoidal slot-milling patterns: circular trochoid, cycloid and the constant-engagement pattern.

Jacsó (2021) §3.4, Thesis IV. A straight slot of width ``width`` (mm) runs along +X with its
centre line on y = 0; the tool (radius ``tool_radius`` r, mm — a *radius*) advances by the
trochoidal step ``step`` (mm) per period. The tool centre must stay in |y| <= W/2 - r (the
final-contour limit). All patterns are climb milling with a clockwise (M3) spindle: the uncut
material lies on the right of the feed direction, so circles run counter-clockwise.

Patterns (each returned as a :class:`~cnclab.toolpath.path.ToolPath` at z = 0: centre points, kind
``link`` on linking moves, tags ``"period k"`` / ``"period k:roll-in"`` (:func:`period_index`,
:func:`pattern_kinds`), ``info["step"]``):

* **circular trochoid** — full circles of radius R = W/2 - r whose centres advance by ``step``; the
  transfer from one circle to the next is a straight move of length ``step`` at the rear point of
  the circle (circle-and-line trochoid; Otkur & Lazoglu, "Trochoidal milling", *Int. J. Mach. Tools
  Manuf.* 47 (2007) 1324-1332, Fig. 1; Rauch, Duc & Hascoët, *Int. J. Mach. Tools Manuf.* 49 (2009)
  375-383, "circular" pattern).
* **cycloid** — the prolate trochoid x = s phi / (2 pi) + R cos phi, y = R sin phi (the classical
  trochoid x = a phi - b sin phi, y = a - b cos phi of Weisstein, MathWorld "Trochoid", with
  a = s / 2pi, b = R, rotated a quarter turn), one period per 2 pi.
* **constant engagement** (Thesis IV) — per period the current front of the material is read from
  a dixel stock, the Thesis III algorithm (:func:`cnclab.toolpath.constant_engagement.thesis3_path`)
  generates the cut holding ``theta_deg`` along it from one wall to the other, the cut is clipped
  to the final-contour limit (roll-in/roll-out), the stock is cut, and a linking arc through the
  cleared region leads back to the next period. The period shape converges (booklet Fig. 3.5);
  :func:`ce_trochoid_iteration` returns every period and its change, :func:`ce_trochoid` repeats the
  converged period with the largest step whose simulated maximum engagement stays at the limit
  (:func:`ce_admissible_step`, the same bisection as for the circle and the cycloid).
  **Roll-in corner.** The Thesis III cut leaves the wall at a steep angle (about 75 deg to the wall
  at theta = 30 deg): a tool arriving along the wall then meets the previous period's corner and
  its engagement jumps to about that turn angle however small the step (simulated: 4 -> 46 deg
  within one 0.1 mm sample; 43 deg at a 0.05 mm step, 59 deg at the iteration's step at
  theta = 30 deg). :func:`fillet_entry` replaces the corner by a G1 arc of radius rho tangent to the
  wall and to the cut (and :func:`fillet_exit` the corner at the far wall): the next period,
  shifted by s, then cuts a rounded corner like a circular trochoid of radius rho at step s, and
  its engagement rises without a jump.

Evaluation (:func:`evaluate_pattern`) cuts the pattern through a dixel slot stock and reports the
steady-state engagement trace, path length per period and per mm of slot, cutting vs linking
length and the average MRR; :func:`admissible_step` finds the largest step whose simulated maximum
engagement stays at ``theta_max_deg``.

Modules: :mod:`~cnclab.toolpath.trochoidal.patterns` (circle, cycloid, evaluation, admissible step),
:mod:`~cnclab.toolpath.trochoidal.ce` (the constant-engagement pattern); everything is re-exported
here. The study sweeps over the patterns (``compare_patterns``, ``pattern_sweep``) are recipes of
the Jacsó work: :mod:`cnclab.works.jacso2021.studies`.

Units: mm, mm/min, mm^3/min; angles in degrees at the API.

>>> p = circular_trochoid(step=1.0, width=12.0, tool_radius=3.0, n_periods=2, ds=0.1)
>>> round(length_per_period(p), 2)          # 2 pi R + step = 2 pi 3 + 1
19.85
>>> c = cycloid(step=1.0, width=12.0, tool_radius=3.0, n_periods=1, ds=0.05)
>>> bool(abs(c.xyz[:, 1]).max() <= 3.0 + 1e-9)
True
"""
from __future__ import annotations

from .ce import *  # noqa: F401,F403
from .ce import __all__ as _ce_all
from .patterns import *  # noqa: F401,F403
from .patterns import __all__ as _patterns_all

__all__ = list(_patterns_all) + list(_ce_all)
