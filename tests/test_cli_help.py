"""Every ``python -m cnclab`` command's --help is plain text a shop-floor user can read: no Sphinx or
reST markup, every option that has a default shows it, an ``Example:`` line, the files written.

The parser of each command is captured where it parses (``ArgumentParser.parse_args`` patched to
record the parser and stop), so the check reads the real options, not the help text's layout.
"""
from __future__ import annotations

import argparse
import importlib
import re

import pytest

from cnclab import clihelp
from cnclab.__main__ import COMMANDS

_MARKUP = re.compile(r":(?:func|class|data|meth|mod|attr|py:\w+):`|``")


class _Captured(Exception):
    pass


def _parser_of(command: str, monkeypatch) -> argparse.ArgumentParser:
    seen = []

    def capture(self, args=None, namespace=None):
        seen.append(self)
        raise _Captured

    monkeypatch.setattr(argparse.ArgumentParser, "parse_args", capture)
    monkeypatch.setattr(argparse.ArgumentParser, "parse_known_args", capture)
    mod = importlib.import_module(COMMANDS[command][0])
    with pytest.raises(_Captured):
        mod.main(["--help"])
    return seen[0]


def _parsers(ap):
    """``ap`` and the parsers of its subcommands."""
    yield ap
    for act in ap._actions:
        if isinstance(act, argparse._SubParsersAction):
            for sub in act.choices.values():
                yield from _parsers(sub)


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_help_is_plain_with_defaults_and_example(command, monkeypatch):
    ap = _parser_of(command, monkeypatch)
    for p in _parsers(ap):
        text = p.format_help()
        assert not _MARKUP.search(text), f"{command}: markup in --help:\n{text}"
        assert re.search(r"^Example:\n  python -m cnclab ", text, re.M), f"{command}: no Example line:\n{text}"
        for act in p._actions:
            if act.default in (None, False, argparse.SUPPRESS) or act.required or act.help == argparse.SUPPRESS:
                continue
            if not act.option_strings and act.nargs not in ("?", "*"):
                continue
            line = p._get_formatter()._expand_help(act) if act.help else ""
            assert "default" in line.lower(), f"{command} {act.option_strings}: no default shown: {line!r}"
    assert "Writes:" in ap.format_help(), f"{command}: the files written are not listed"


def test_every_command_uses_the_common_formatter(monkeypatch):
    for command in COMMANDS:
        ap = _parser_of(command, monkeypatch)
        assert issubclass(ap.formatter_class, clihelp.HelpFormatter), command


def test_formatter_appends_defaults_only_where_missing():
    ap = clihelp.parser("python -m cnclab x", "X.", examples=["python -m cnclab x"])
    ap.add_argument("--a", type=float, default=0.5, help="a length (mm)")
    ap.add_argument("--b", type=float, default=2.0, help="a feed (mm/min; default: 2)")
    ap.add_argument("--c", default=None, help="optional")
    text = ap.format_help()
    assert "a length (mm) (default: 0.5)" in text
    assert "(mm/min; default: 2)" in text and "default: 2.0" not in text
    assert "optional\n" in text
