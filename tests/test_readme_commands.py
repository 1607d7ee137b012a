"""Every command the README and the docs/ pages show parses as written: its subcommand and
every flag exist.

The README's commands are what a new user types first; a flag renamed in the code
and not in the README (``--resume DIR`` once) fails them on their first try. Each
``rnhql ...`` and ``python -m scenarios....`` command, in fenced blocks and in inline
code, in README.md and in every ``docs/*.md`` page, is parsed by the real argument
parser (the command's own ``main`` is stopped right after parsing, so nothing runs; a
module that takes no arguments is only imported). Placeholders in capitals (``DIR``, ``N``,
``FIELD=VALUE``) are filled with a value of the right kind first, and optional parts
in brackets (``[--web]``) are taken.
"""

from __future__ import annotations

import argparse
import importlib
import inspect
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


def split_outside_quotes(line: str) -> list[str]:
    """``line`` split at && ; | that stand outside quotes (a method's overrides are quoted
    because they hold ';'); an output redirection (``> FILE``) ends a command."""
    parts, start, quote, i = [], 0, "", 0
    while i < len(line):
        c = line[i]
        if quote:
            quote = "" if c == quote else quote
        elif c in "'\"":
            quote = c
        elif c == ">":
            return [*parts, line[start:i]]
        elif line.startswith("&&", i) or c in ";|":
            parts.append(line[start:i])
            i += 2 if c == "&" else 1
            start = i
            continue
        i += 1
    return [*parts, line[start:]]


def segments(text: str) -> list[str]:
    """The commands of one shell snippet: continuation lines joined, split at && ; |."""
    text = re.sub(r"\\\n\s*", " ", text)
    out = []
    for line in text.splitlines():
        line = line.split(" #", 1)[0].strip()
        for part in split_outside_quotes(line):
            part = part.strip()
            part = re.sub(r"^(\S+=\S+\s+)+", "", part)  # VAR=value prefixes
            part = re.sub(r"^(\S*/)?(\.venv/bin/)", "", part)
            if part.startswith(PREFIXES):
                out.append(part)
    return out


PAGES = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]


def page_commands(text: str) -> list[str]:
    """The commands of one Markdown page: fenced blocks and inline code spans."""
    found: list[str] = []
    for block in re.findall(r"```[a-z]*\n(.*?)```", text, flags=re.S):
        found += segments(block)
    prose = re.sub(r"```.*?```", "", text, flags=re.S)
    for span in re.findall(r"`([^`\n]+)`", prose):
        if len(span.split()) > 2:  # `rnhql compare` alone names a command, it is not one
            found += segments(span)
    return list(dict.fromkeys(found))


def readme_commands() -> list[str]:
    return page_commands((REPO / "README.md").read_text(encoding="utf-8"))


def docs_commands() -> list[tuple[str, str]]:
    """(page, command) for every page, each command once (at its first page)."""
    seen: dict[str, str] = {}
    for page in PAGES:
        for command in page_commands(page.read_text(encoding="utf-8")):
            seen.setdefault(command, page.relative_to(REPO).as_posix())
    return [(page, command) for command, page in seen.items()]


def argv_of(command: str) -> list[str]:
    """The command's words, optional parts (``[--web]``) taken, placeholders filled."""
    words = [w.strip("[]") for w in shlex.split(command) if w not in ("...", "[...]")]
    return [PLACEHOLDERS.get(w, w) for w in words if w]


class Parsed(Exception):
    """Raised right after a successful parse: the command itself never runs."""


COMMANDS = docs_commands()


def test_the_readme_and_the_docs_show_commands():
    readme = readme_commands()
    assert any(c.startswith("rnhql compare") for c in readme)
    assert len(COMMANDS) >= 20
    assert {page for page, _ in COMMANDS} > {"README.md"}, "no command found in docs/*.md"


@pytest.mark.parametrize(("page", "command"), COMMANDS, ids=[f"{p}: {c}" for p, c in COMMANDS])
def test_readme_command_parses(page, command, monkeypatch, capsys):
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
            source = inspect.getsource(module)
            if "argparse" not in source and "scenarios.script_args" not in source:
                # takes no arguments (a benchmark run as is): it exists; running it would run it
                assert len(argv) == 3, f"{page}: {argv[2]} takes no arguments: {command}"
                return
            if hasattr(module, "main") and inspect.signature(module.main).parameters:
                module.main(argv[3:])
            elif hasattr(module, "main"):  # main() reads sys.argv
                monkeypatch.setattr(sys, "argv", [argv[2], *argv[3:]])
                module.main()
            else:  # a module that parses in its __main__ block
                monkeypatch.setattr(sys, "argv", [argv[2], *argv[3:]])
                with warnings.catch_warnings():  # it may be imported already: that is fine
                    warnings.simplefilter("ignore", RuntimeWarning)
                    runpy.run_module(argv[2], run_name="__main__")
    except Parsed:
        return
    except SystemExit as exc:
        pytest.fail(f"{page}: command does not parse (exit {exc.code}): {command}\n"
                    f"{capsys.readouterr().err}")
    pytest.fail(f"{page}: command ran without parsing arguments: {command}")
