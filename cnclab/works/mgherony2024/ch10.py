"""Mgherony (2024) chapter 10 (summary of new scientific results): the thesis points as printed.

Transcribed in ``data/mgherony2024/ch10_theses.json`` (number, subject, related publications).

>>> thesis_point_count()
5
"""
from __future__ import annotations

import functools
import json

from ...paths import data_path


@functools.cache
def theses() -> dict:
    """The transcribed chapter 10 (intro sentence, announced count, the thesis points as printed)."""
    return json.loads(data_path("mgherony2024", "ch10_theses.json").read_text(encoding="utf-8"))


def thesis_point_count() -> int:
    """Number of thesis points chapter 10 actually states (numbered 1, 2, … without gaps)."""
    nums = [t["number"] for t in theses()["theses"]]
    if nums != list(range(1, len(nums) + 1)):
        raise ValueError(f"ch10_theses.json: thesis numbers {nums} are not 1..n")
    return len(nums)
