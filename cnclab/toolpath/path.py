"""The tool-path model shared by every planner.

:class:`Move` is one motion block of a program (G0/G1/G2/G3, absolute end point, arc centre offsets,
feed, spindle). Units: mm, mm/min, rpm.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

__all__ = ["MOTIONS", "Move"]

MOTIONS = ("G0", "G1", "G2", "G3")


@dataclasses.dataclass(frozen=True)
class Move:
    """One motion block: absolute end point [mm], arc centre offsets [mm], feed [mm/min], spindle [rpm].

    ``motion`` is ``"G0"``, ``"G1"``, ``"G2"`` (CW) or ``"G3"`` (CCW). ``i, j`` are the arc-centre
    offsets from the *start* point (arcs only). ``feed`` is required for G1/G2/G3.
    """

    motion: str
    x: float
    y: float
    z: float
    i: float | None = None
    j: float | None = None
    feed: float | None = None
    spindle: float | None = None

    def __post_init__(self):
        if self.motion not in MOTIONS:
            raise ValueError(f"motion must be one of {MOTIONS}, got {self.motion!r}")
        for name in ("x", "y", "z"):
            v = getattr(self, name)
            if v is None or not math.isfinite(float(v)):
                raise ValueError(f"{name} must be a finite coordinate in mm, got {v!r}")
            object.__setattr__(self, name, float(v))
        if self.motion in ("G2", "G3"):
            if self.i is None or self.j is None:
                raise ValueError(f"{self.motion} needs both arc centre offsets i and j (mm)")
            object.__setattr__(self, "i", float(self.i))
            object.__setattr__(self, "j", float(self.j))
        elif self.i is not None or self.j is not None:
            raise ValueError(f"i/j only belong to arcs (G2/G3), got motion {self.motion}")
        if self.motion != "G0" and (self.feed is None or not (float(self.feed) > 0)):
            raise ValueError(f"{self.motion} needs a feed > 0 in mm/min, got {self.feed!r}")
        if self.feed is not None:
            object.__setattr__(self, "feed", float(self.feed))
        if self.spindle is not None:
            if not float(self.spindle) >= 0:
                raise ValueError(f"spindle must be >= 0 rpm, got {self.spindle!r}")
            object.__setattr__(self, "spindle", float(self.spindle))

    @property
    def xyz(self) -> np.ndarray:
        return np.array([self.x, self.y, self.z])
