"""Every command the README shows parses as written: its subcommand and every flag exist.

The README's commands are what a new user types first; a flag renamed in the code
and not in the README (``--resume DIR`` once) fails them on their first try. Each
``rnhql ...`` and ``python -m scenarios....`` command, in fenced blocks and in inline
code, is parsed by the real argument parser (the command's own ``main`` is stopped
right after parsing, so nothing runs). Placeholders in capitals (``DIR``, ``N``,
``FIELD=VALUE``) are filled with a value of the right kind first, and optional parts
in brackets (``[--web]``) are taken.
"""

from __future__ import annotations

import argparse
import importlib
import re
import runpy
import shlex
import sys
import warnings

import pytest

from tests.conftest import REPO

PREFIXES = ("rnhql ", "python -m scenarios.", "python3 -m scenarios.")
# what a capitalised placeholder stands for, so that typed flags parse
PLACEHOLDERS = {"N": "3", "K": "3", "DIR": "out", "FILE": "x", "MAP": "x.map",
                "FIELD=VALUE": "alpha=0.2", "X,Y": "1,1", "SCENARIO": "paper-40",
                "ADDRESS": "auto", "PATH": "x"}


def segments(text: str) -> list[str]:
    """The commands of one shell snippet: continuation lines joined, split at && ; |."""
    text = re.sub(r"\\\n\s*", " ", text)
    out = []
    for line in text.splitlines():
        line = line.split(" #", 1)[0].strip()
        for part in re.split(r"&&|;|\|", line):
            part = part.strip()
            part = re.sub(r"^(\S+=\S+\s+)+", "", part)  # VAR=value prefixes
            part = re.sub(r"^(\S*/)?(\.venv/bin/)", "", part)
            if part.startswith(PREFIXES):
                out.append(part)
    return out


def readme_commands() -> list[str]:
    text = (REPO / "README.md").read_text(encoding="utf-8")
    found: list[str] = []
    for block in re.findall(r"```[a-z]*\n(.*?)```", text, flags=re.S):
        found += segments(block)
    prose = re.sub(r"```.*?```", "", text, flags=re.S)
    for span in re.findall(r"`([^`\n]+)`", prose):
        if len(span.split()) > 2:  # `rnhql compare` alone names a command, it is not one
            found += segments(span)
    return list(dict.fromkeys(found))


def argv_of(command: str) -> list[str]:
    """The command's words, optional parts (``[--web]``) taken, placeholders filled."""
    words = [w.strip("[]") for w in shlex.split(command) if w not in ("...", "[...]")]
    return [PLACEHOLDERS.get(w, w) for w in words if w]


class Parsed(Exception):
    """Raised right after a successful parse: the command itself never runs."""


COMMANDS = readme_commands()


def test_the_readme_shows_commands():
    assert len(COMMANDS) >= 20
    assert any(c.startswith("rnhql compare") for c in COMMANDS)


@pytest.mark.parametrize("command", COMMANDS)
def test_readme_command_parses(command, monkeypatch, capsys):
    argv = argv_of(command)
    original = argparse.ArgumentParser.parse_args

    def parse_then_stop(self, args=None, namespace=None):
        ns = original(self, args, namespace)
        raise Parsed(ns)

    monkeypatch.setattr(argparse.ArgumentParser, "parse_args", parse_then_stop)
    try:
        if argv[0] == "rnhql":
            from scenarios.cli.app import main

            main(argv[1:])
        else:
            module = importlib.import_module(argv[2])
            if hasattr(module, "main"):
                module.main(argv[3:])
            else:  # a module that parses in its __main__ block
                monkeypatch.setattr(sys, "argv", [argv[2], *argv[3:]])
                with warnings.catch_warnings():  # it may be imported already: that is fine
                    warnings.simplefilter("ignore", RuntimeWarning)
                    runpy.run_module(argv[2], run_name="__main__")
    except Parsed:
        return
    except SystemExit as exc:
        pytest.fail(f"README command does not parse (exit {exc.code}): {command}\n"
                    f"{capsys.readouterr().err}")
    pytest.fail(f"README command ran without parsing arguments: {command}")
