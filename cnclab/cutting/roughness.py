"""Roughness of sampled surface profiles (ISO 21920-2 amplitude parameters) and ideal cusp profiles.

Definitions used (ISO 21920-2:2021 profile amplitude parameters, evaluated on the profile after
removing its least-squares mean line; no λs/λc filtering is applied — for an ideal periodic cusp
profile whose period is far below the cut-off λc = 0.8 mm the Gaussian filter passes it unchanged
apart from edge effects):

- ``Ra`` arithmetic mean of |z| (mean height deviation)
- ``Rq`` root mean square of z
- ``Rz`` maximum height: mean over ``n_sections`` equal sections of (highest peak − deepest valley)
  in each section (the section-averaged form, default 5 sections, as reported by instruments such
  as the Mitutoyo SJ-301 used in Mgherony ch. 3)
- ``Rt`` total height over the whole evaluation length

Heights in the unit of the input (cnclab uses µm for roughness, mm for geometry).

>>> import numpy as np
>>> x = np.linspace(0, 1, 100001); z = np.cos(2 * np.pi * 20 * x)
>>> p = profile_parameters(z)
>>> round(p["Ra"], 4), round(p["Rq"], 4), round(p["Rz"], 3)   # 2/π, 1/√2, 2
(0.6366, 0.7071, 2.0)
"""
from __future__ import annotations

import numpy as np


def ideal_cusp_profile(spacing: float, corner_radius: float, length: float, n: int = 20001):
    """Sampled ideal profile (x, z) in mm left by arcs of radius ``corner_radius`` spaced ``spacing``.

    ``z`` is measured upward from the arc bottoms (0 at each tool-centre position, the cusp height
    at the midpoints). The profile starts at an arc bottom.
    """
    if spacing <= 0 or corner_radius <= 0 or length <= 0:
        raise ValueError("spacing, corner_radius and length must be > 0 mm")
    if spacing > 2 * corner_radius:
        raise ValueError("spacing must be <= 2*corner_radius")
    x = np.linspace(0.0, length, int(n))
    u = x - spacing * np.round(x / spacing)  # offset from the nearest arc bottom
    z = corner_radius - np.sqrt(corner_radius**2 - u**2)
    return x, z


def profile_parameters(z, n_sections: int = 5) -> dict:
    """Ra, Rq, Rz (section mean of peak-to-valley), Rt of a uniformly sampled profile ``z``.

    The least-squares mean line (straight) is removed first.
    """
    z = np.asarray(z, dtype=float)
    if z.ndim != 1 or z.size < 2 * n_sections:
        raise ValueError(f"profile needs at least {2 * n_sections} samples")
    if not np.all(np.isfinite(z)):
        raise ValueError("profile contains non-finite heights")
    t = np.arange(z.size, dtype=float)
    a, b = np.polyfit(t, z, 1)
    d = z - (a * t + b)
    sections = np.array_split(d, n_sections)
    return {
        "Ra": float(np.mean(np.abs(d))),
        "Rq": float(np.sqrt(np.mean(d**2))),
        "Rz": float(np.mean([s.max() - s.min() for s in sections])),
        "Rt": float(d.max() - d.min()),
    }


#: Ra/CH and Rq/CH of an ideal parabolic cusp profile (small-CH limit): 4/(9√3) and 2/(3√5).
RA_OVER_CH_PARABOLIC = 4.0 / (9.0 * np.sqrt(3.0))
RQ_OVER_CH_PARABOLIC = 2.0 / (3.0 * np.sqrt(5.0))
