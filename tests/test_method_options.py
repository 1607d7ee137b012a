"""An option a method inherits but its rules ignore is refused, by one rule for every method:
a run never records a setting that did nothing."""

from __future__ import annotations

import dataclasses
import re

import pytest

from learning.methods.registry import METHODS


@pytest.mark.parametrize("cli", sorted(METHODS))
def test_every_ignored_field_is_refused_away_from_its_default(cli):
    cls = METHODS[cli]
    for name in cls.IGNORED:
        default = next(f.default for f in dataclasses.fields(cls) if f.name == name)
        with pytest.raises(ValueError, match=re.escape(f"{cli}'s rules do not read {name}")):
            cls(**{name: type(default)(1) if default == 0 else type(default)(0)})
        assert name not in cls.settable()
        reader = cls.reader_of(name)
        if reader != "a method that has it":  # (a field every learner reads: eps, alpha, gamma)
            assert reader in METHODS and name not in METHODS[reader].IGNORED


def test_the_ablation_ignores_the_held_out_options():
    assert set(METHODS["rnh-ql+ablation"].IGNORED) == {"model_acting", "model_test",
                                                       "explore_steps"}


def test_set_on_an_ignored_field_exits_2_naming_the_method_that_reads_it(capsys):
    from scenarios.cli import main

    assert main(["train", "paper-40", "--method", "rnh-ql+ablation", "--set", "model_test=1",
                 "--episodes", "3"]) == 2
    err = capsys.readouterr().err
    assert "rnh-ql+ablation's rules do not read model_test" in err
    assert "use --method rnh-ql+" in err


def test_a_sweeps_set_skips_the_methods_that_ignore_it():
    from scenarios.api import settings_per_method

    per = settings_per_method(["rnh-ql+", "rnh-ql+ablation"], (("model_test", 1.0),))
    assert per == {"rnh-ql+": (("model_test", 1.0),), "rnh-ql+ablation": ()}
