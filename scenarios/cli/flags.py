"""The one table between the command's flags and the library's arguments.

The library (:mod:`scenarios.api`) checks every argument; a subcommand passes its flags
through as arguments and, when the library refuses one, says so in flag words: the
library's :class:`~sim.errors.InputError` names ``scenarios.api.train: episodes``, the
command prints ``command line: --episodes`` with the same problem and fix. So a check,
limit or default lives once, in the library, and the two doors cannot drift apart.
"""

from __future__ import annotations

import contextlib
import re
from collections.abc import Iterator

from sim.errors import InputError

# library argument -> the flag that sets it (the same for every subcommand that has it)
FLAG_OF = {
    "scenario": "scenario", "method": "--method", "methods": "--methods",
    "world": "--world", "worlds": "--world", "fidelity": "--fidelity",
    "episodes": "--episodes", "seed": "--seed", "seeds": "--seeds", "seed_base": "--seed-base",
    "rewards": "--rewards", "settings": "--set", "s_starts": "--s-starts",
    "start": "--start", "goal": "--goal", "jobs": "--jobs", "backend": "--backend",
    "address": "--address", "out": "--out", "resume": "--resume", "save": "--save",
    "record": "--record", "record_every": "--record-every",
    "record_values_every": "--record-values-every", "record_seeds": "--record-seeds",
    "init": "--init", "pretrain": "--pretrain", "drives": "--drives",
}


def flag_words(err: InputError) -> InputError:
    """``err`` as the command says it: a library argument named by its flag, ``arg=value``
    in the fix written ``--flag value``; errors from elsewhere (a file, a field) unchanged."""
    if not err.source.startswith("scenarios.api."):
        return err
    name = err.field.split("[", 1)[0]
    flag = FLAG_OF.get(name)
    if flag is None:
        return err
    field = flag + err.field[len(name):]

    def say(text: str) -> str:
        for arg, fl in FLAG_OF.items():
            # arg=('grid', 300) -> --pretrain grid:300; arg='x' -> --flag x; arg=3 -> --flag 3
            text = re.sub(rf"\b{arg}=\(([^)]*)\)", lambda m, fl=fl: f"{fl} " + ":".join(
                v.strip(" '\"") for v in m[1].split(",")), text)
            text = re.sub(rf"\b{arg}='([^']*)'", rf"{fl} \1", text)
            text = re.sub(rf"\b{arg}=([^\s,;)']+)", rf"{fl} \1", text)
        return text

    out = type(err)("command line", field, say(err.problem), say(err.fix))
    return out


@contextlib.contextmanager
def in_flag_words() -> Iterator[None]:
    """Library errors raised in the block reach the user in flag words (exit 2)."""
    try:
        yield
    except InputError as err:
        raise flag_words(err) from None
