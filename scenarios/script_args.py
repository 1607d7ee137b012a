"""One way to declare an experiment script's arguments: a frozen dataclass, like CleanRL's Args.

Each field is a flag, ``--`` and its name with ``-`` for ``_``: the field's type is the
flag's (``int``, ``float``, ``str``, or one of them ``| None``; a ``bool`` field is a
switch, off by default), its default the flag's, and :func:`arg` gives the help line
(units in brackets) and any other ``add_argument`` keyword (``metavar``, ``choices``)::

    @dataclass(frozen=True)
    class Args:
        out: str = arg("results/scaling", "output folder")
        seeds: int = arg(10, "seeds per method (0 .. N-1)")
        resume: bool = arg(False, "skip runs already finished in --out")

    def main(argv: list[str] | None = None) -> int:
        args = parse(Args, __doc__, argv)

A required positional argument is :func:`positional`. Two fields every study spells the
same way: :func:`artifact_arg` (``--artifact NAME``:
also write ``docs/results/<kind>.NAME.json``; the name and the source checkout are checked
when the flag is parsed, before any work) and :func:`jobs_arg` (``--jobs``: worker
processes, all cores by default).

The script's ``--help`` is its docstring's first paragraph, then each flag with its help
and default. :func:`script_parser` is that parser alone, for a script that still adds
its flags by hand.
"""

from __future__ import annotations

import argparse
import dataclasses
import shlex
import types
import typing
from collections.abc import Sequence
from typing import Any, TypeVar

from scenarios.artifacts import ARTIFACT_NAME, checkout_problem

T = TypeVar("T")


def arg(default: Any, help: str, **kwargs: Any) -> Any:
    """A field of an ``Args`` dataclass: its flag's default, help line and other
    ``add_argument`` keywords."""
    return dataclasses.field(default=default, metadata={"help": help, **kwargs})


def positional(help: str, **kwargs: Any) -> Any:
    """A required positional field of an ``Args`` dataclass (a folder, a scenario), named
    by the field; place it before the flags with defaults."""
    return dataclasses.field(metadata={"help": help, "positional": True, **kwargs})


def artifact_name(text: str) -> str:
    """``--artifact``'s type: a short lower-case word (it becomes a file name and a Cog
    call), accepted only in a source checkout (where ``docs/results`` lives)."""
    if not ARTIFACT_NAME.fullmatch(text):
        raise argparse.ArgumentTypeError(f"{text!r}: use lower-case letters, digits and '-' "
                                         "(at most 64), e.g. --artifact seed7")
    problem = checkout_problem()
    if problem is not None:
        raise argparse.ArgumentTypeError(f"{text!r}: {problem}; run it from a clone of the "
                                         "repository")
    return text


def artifact_arg(kind: str) -> Any:
    """The ``--artifact NAME`` field of a study that writes artifacts of ``kind``."""
    return arg(None, f"also write docs/results/{kind}.NAME.json (the docs' table)",
               metavar="NAME", type=artifact_name)


def jobs_arg() -> Any:
    """The ``--jobs`` field: worker processes (None: every core)."""
    return arg(None, "worker processes (default: every core)")


class _Help(argparse.ArgumentDefaultsHelpFormatter):
    """A flag's help line ends with its default, unless that is None, a switch's False, or
    the help names the default itself."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        if action.default in (None, False) or "default" in (action.help or ""):
            return action.help
        return super()._get_help_string(action)


def script_parser(doc: str | None) -> argparse.ArgumentParser:
    """An experiment script's parser: described by the first paragraph of ``doc`` (the
    module docstring), every flag's help line ending with its default."""
    return argparse.ArgumentParser(description=" ".join((doc or "").split("\n\n")[0].split()),
                                   formatter_class=_Help)


def _scalar(hint: Any) -> type:
    """``int`` of ``int``, of ``int | None`` and of ``list[int]`` (a flag given again and
    again, ``action="append"``): what argparse converts the flag's text with."""
    if isinstance(hint, types.UnionType) or typing.get_origin(hint) is typing.Union:
        (hint,) = (h for h in typing.get_args(hint) if h is not type(None))
    if typing.get_origin(hint) is list:
        (hint,) = typing.get_args(hint)
    return hint


def parser_of(cls: type, doc: str | None) -> argparse.ArgumentParser:
    """:func:`script_parser` with a flag per field of the dataclass ``cls``."""
    p = script_parser(doc)
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        flag = "--" + f.name.replace("_", "-")
        kind = _scalar(hints[f.name])
        if f.metadata.get("positional"):
            extra = {k: v for k, v in f.metadata.items() if k != "positional"}
            p.add_argument(f.name, **{"type": kind, **extra})
        elif kind is bool:
            if f.default is not False:
                raise TypeError(f"{cls.__name__}.{f.name}: a switch is off by default")
            p.add_argument(flag, action="store_true", **f.metadata)
        else:
            p.add_argument(flag, **{"type": kind, "default": f.default, **f.metadata})
    return p


def command_line(prog: str, parser: argparse.ArgumentParser, values: Any) -> str:
    """The command that gives ``values`` (a parsed namespace or an ``Args`` instance),
    derived from ``parser``'s declared arguments: the positionals, then every flag that has
    a value (its default too: a default may change, the record may not), in declaration
    order. An artifact's provenance is written this way, never by hand, so it names what
    ran."""
    got = (values if isinstance(values, dict) else dataclasses.asdict(values)
           if dataclasses.is_dataclass(values) else vars(values))
    words = prog.split()
    for act in parser._actions:
        if isinstance(act, argparse._HelpAction | argparse._VersionAction) or \
                act.dest.startswith("_") or act.dest in ("func", "command"):
            continue
        v = got.get(act.dest, act.default)
        if not act.option_strings:
            words += [] if v is None else [str(v)]
        elif v is None or v is False:
            continue
        elif isinstance(act, argparse._StoreTrueAction):
            words.append(act.option_strings[-1])
        else:
            for one in (v if isinstance(act, argparse._AppendAction) else [v]):
                words += [act.option_strings[-1], str(one)]
    return " ".join(shlex.quote(w) for w in words)


def study_command(module: str, cls: type, args: Any) -> str:
    """``python -m MODULE`` and the flags that give ``args`` (an ``Args`` instance of
    ``cls``), derived from the declared fields (:func:`command_line`); ``--resume`` says how
    a run went, not what it computed, and is left out."""
    return command_line(f"python -m {module}", parser_of(cls, None),
                        {**dataclasses.asdict(args), "resume": False})


def parse(cls: type[T], doc: str | None, argv: Sequence[str] | None = None) -> T:
    """The ``cls`` (an ``Args`` dataclass) of the command line ``argv`` (None: sys.argv);
    a usage error exits 2 with argparse's message."""
    return cls(**vars(parser_of(cls, doc).parse_args(argv)))
