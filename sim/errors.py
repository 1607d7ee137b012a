"""Typed input errors: every message names the file, the field, what is wrong and the fix.

Why a module of its own: the CLI catches exactly these (and nothing else) to print
one line and exit 2, so a user never sees a traceback for bad input, while a
genuine bug still shows its traceback.
"""

from __future__ import annotations


class InputError(ValueError):
    """Bad user input. ``str(err)`` is the one-line message the CLI prints."""

    def __init__(self, source: str, field: str, problem: str, fix: str) -> None:
        self.source = source
        self.field = field
        self.problem = problem
        self.fix = fix
        super().__init__(f"{source}: {field}: {problem}. Fix: {fix}")

    def __reduce__(self):
        """Rebuilt from its four parts: a sweep's worker pickles the error to its parent,
        and an exception pickles by its ``args`` (here the one message) by default, which
        this constructor cannot take; the parent then saw a dead pool, not the error."""
        return type(self), (self.source, self.field, self.problem, self.fix)


class ScenarioError(InputError):
    """A scenario (TOML or built-in) that cannot describe a valid route problem."""


class MapError(ScenarioError):
    """A Moving AI ``.map`` / ``.scen`` file that cannot be read."""
