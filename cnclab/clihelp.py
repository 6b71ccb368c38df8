"""One help style for every ``python -m cnclab`` command: plain text, defaults, an example, the outputs.

:func:`parser` builds the ``argparse.ArgumentParser`` of a command with :class:`HelpFormatter`: the
description is plain text (Sphinx roles such as ``:func:`x``` and double back-quotes are removed by
:func:`plain`), every option that has a default shows it (``(default: 0.05)``) unless its help text
already says ``default``, and the epilog lists one or more ``Example:`` lines and the files the
command writes (``Writes:``). Options whose default is ``None`` say in their help what happens
without them.

>>> ap = parser("python -m cnclab demo", "Demo of :func:`cnclab.plan` with ``--x``.",
...             examples=["python -m cnclab demo --x 2"], writes=["nothing"])
>>> _ = ap.add_argument("--x", type=float, default=1.5, help="a length (mm)")
>>> text = ap.format_help()
>>> "a length (mm) (default: 1.5)" in text, "Example:" in text, ":func:" in text
(True, True, False)
>>> plain("see :func:`~cnclab.toolpath.planners.plan` and ``--strategy``")
'see planners.plan and --strategy'
"""
from __future__ import annotations

import argparse
import math
import re

__all__ = ["HelpFormatter", "number", "parser", "plain"]

_ROLE_RE = re.compile(r":(?:py:)?[a-z]+:`~?([^`]+)`")
_LITERAL_RE = re.compile(r"``([^`]*)``")
#: a decimal number as a machine operator types it (the APT reader's grammar): no '1_0', hex, 'nan'
#: spelled non-finite values: parsed, then refused by the range check as "must be finite"
_NONFINITE_WORDS = ("nan", "inf", "-inf", "+inf")
_NUMBER_RE = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?", re.ASCII)


def plain(text: str) -> str:
    """``text`` without reStructuredText markup: ``:role:`~a.b.c``` -> ``b.c`` (``~``: last two parts)
    or ``a.b.c``, ````x```` -> ``x``, ``*x*`` kept (readable as is)."""
    def role(m):
        target = m.group(1)
        if m.group(0).split("`", 1)[1].startswith("~"):
            target = ".".join(target.split(".")[-2:])
        return target
    return _LITERAL_RE.sub(r"\1", _ROLE_RE.sub(role, text))


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """Description and epilog kept as written (line breaks matter in examples); every option with a
    default other than ``None``/``False`` gets ``(default: X)`` appended unless its help says it."""

    def _get_help_string(self, action):
        text = action.help or ""
        if "default" in text.lower() or action.required or action.default in (None, False, argparse.SUPPRESS):
            return text
        if not action.option_strings and action.nargs not in ("?", "*"):
            return text
        return f"{text} (default: %(default)s)"


def parser(prog: str, description: str, examples=(), writes=(), **kwargs) -> argparse.ArgumentParser:
    """An ``ArgumentParser`` for ``prog`` in the common style.

    Parameters
    ----------
    prog : the command as typed, e.g. ``"python -m cnclab plan"``.
    description : what the command does (plain text; markup is removed by :func:`plain`).
    examples : command lines shown under ``Example:`` (at least one).
    writes : the files written, one item each, shown under ``Writes:``.
    kwargs : more ``ArgumentParser`` keywords.
    """
    epilog = []
    if examples:
        epilog.append("Example:\n" + "\n".join(f"  {e}" for e in examples))
    if writes:
        epilog.append("Writes:\n" + "\n".join(f"  {w}" for w in writes))
    return argparse.ArgumentParser(prog=prog, description=plain(description).strip(),
                                   epilog="\n\n".join(epilog) or None, formatter_class=HelpFormatter, **kwargs)


def number(name: str, lo=None, lo_open: bool = True, hi=None, kind=float):
    """An argparse ``type``: a finite decimal number in the range ``(lo, hi]`` (``[lo, hi]`` with
    ``lo_open=False``; None: unbounded); the error message names the option ``name``.

    >>> conv = number("--stepover", 0)
    >>> conv("0.25")
    0.25
    >>> conv("-1")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: --stepover must be finite and in (0, inf), got '-1'
    >>> number("--teeth", 1, lo_open=False, kind=int)("2.7")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: --teeth must be an integer, got '2.7'
    """
    def conv(text):
        try:
            if not _NUMBER_RE.fullmatch(text.strip()) and text.strip().lower() not in _NONFINITE_WORDS:
                raise ValueError(text)      # strict grammar: no '1_0', no hex, no full-width digits
            v = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be {'an integer' if kind is int else 'a number'}, "
                                             f"got {text!r}") from None
        if not (math.isfinite(v) and (lo is None or (v > lo if lo_open else v >= lo)) and (hi is None or v <= hi)):
            rng = ("(" if lo_open else "[") + (f"{lo:g}" if lo is not None else "-inf") + ", " + \
                  (f"{hi:g}]" if hi is not None else "inf)")
            raise argparse.ArgumentTypeError(f"{name} must be finite and in {rng}, got {text!r}")
        return v
    conv.__name__ = name
    return conv
