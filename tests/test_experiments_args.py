"""An experiment's arguments declared as a dataclass (scenarios.script_args)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import pytest

from scenarios.script_args import arg, parse, parser_of


@dataclass(frozen=True)
class Args:
    out: str = arg("results/x", "output folder")
    seeds: int = arg(10, "seeds per method (0 .. N-1)")
    rate: float = arg(0.5, "share of episodes [0, 1]")
    jobs: int | None = arg(None, "worker processes [default: all cores]")
    map_seed: int = arg(7, "generator seed of the maps")
    artifact: str | None = arg(None, "also write an artifact", metavar="NAME")
    resume: bool = arg(False, "skip finished runs")


DOC = """A study in one line.

More prose that --help leaves out.
"""


def test_defaults_and_flags_parse_to_the_dataclass():
    assert parse(Args, DOC, []) == Args()
    a = parse(Args, DOC, ["--out", "o", "--seeds", "3", "--rate", "0.25", "--jobs", "2",
                          "--map-seed", "8", "--artifact", "a", "--resume"])
    assert a == Args("o", 3, 0.25, 2, 8, "a", True)
    with pytest.raises(dataclasses.FrozenInstanceError):
        a.out = "p"  # type: ignore[misc]


def test_a_bad_value_is_a_usage_error(capsys):
    with pytest.raises(SystemExit) as exc:
        parse(Args, DOC, ["--seeds", "many"])
    assert exc.value.code == 2 and "--seeds" in capsys.readouterr().err


def test_help_is_the_first_paragraph_then_each_flag_with_its_default():
    text = parser_of(Args, DOC).format_help()
    assert "A study in one line." in text and "More prose" not in text
    assert "seeds per method (0 .. N-1) (default: 10)" in " ".join(text.split())
    assert "--artifact NAME" in text and "(default: None)" not in text
    assert "(default: False)" not in text


def test_a_switch_must_default_to_off():
    @dataclass(frozen=True)
    class Bad:
        fast: bool = arg(True, "go fast")

    with pytest.raises(TypeError, match="off by default"):
        parser_of(Bad, DOC)


def test_the_artifact_and_jobs_fields_are_spelled_once():
    """``--artifact`` is a field type: its name is checked when the flag is parsed (exit 2
    before any work), and ``--jobs`` defaults to every core in every study that uses it."""
    from dataclasses import dataclass

    import pytest

    from scenarios.script_args import artifact_arg, jobs_arg, parse

    @dataclass(frozen=True)
    class Args:
        jobs: int | None = jobs_arg()
        artifact: str | None = artifact_arg("demo")

    assert parse(Args, "A study.", []) == Args(None, None)
    assert parse(Args, "A study.", ["--artifact", "seed7", "--jobs", "2"]) == Args(2, "seed7")
    with pytest.raises(SystemExit) as stop:
        parse(Args, "A study.", ["--artifact", "../x"])
    assert stop.value.code == 2
