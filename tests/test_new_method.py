"""Adding a method touches its module and the registry, nothing else: a throwaway method,
defined and registered here at test time, runs end to end through ``rnhql compare`` and
shows in its results and summary.

This module is the throwaway method's module: a config, a ``State`` of its own,
``init_state`` and the four hooks (Q-learning's rules, borrowed from
:mod:`learning.methods.q_learning`, the template a new method starts from). The steps of
:mod:`learning.methods.registry`'s docstring, but for the row in the registry's table, which
:func:`~learning.methods.registry.register` adds here.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numpy as np
import pytest

from learning.config import BaseParams, MethodConfig
from learning.geometry import Geometry
from learning.methods import q_learning
from learning.parts.tally import Tally, new_tally


@dataclass(frozen=True)
class Throwaway(MethodConfig):
    """Q-learning under another name, with an optimistic start of its own."""

    name: ClassVar[str] = "THROWAWAY-QL"
    cli: ClassVar[str] = "throwaway-ql"
    q0: float = 1.0  # initial Q for every (s, a) [reward units]


class ThrowawayState(NamedTuple):  # its own class and name: dispatch goes by them
    par: BaseParams
    tally: Tally
    q: np.ndarray  # float64[nS, nA]


State = ThrowawayState


def init_state(cfg: Throwaway, geom: Geometry, rng: np.random.Generator) -> State:
    return State(cfg.params(), new_tally(), np.full((geom.n_states, geom.n_actions), cfg.q0))


act, update = q_learning.act, q_learning.update
begin, exploit = q_learning.begin, q_learning.exploit


@pytest.fixture
def throwaway():
    """The method registered for one test, and gone again after it. Its kernels stay out of
    numba's on-disk cache by themselves (a method from outside the package:
    :func:`learning.jitcache.guard_cache`)."""
    import sys

    from learning.methods.registry import register, unregister

    register(Throwaway, sys.modules[__name__])
    try:
        yield Throwaway.cli
    finally:
        unregister(Throwaway.cli)


def test_a_registered_method_runs_through_compare(throwaway, tmp_path, capsys):
    from learning.methods.registry import METHODS, comparison_methods
    from scenarios.cli import main

    assert comparison_methods()[-1] == throwaway  # compare's default list has it
    out = tmp_path / "cmp"
    assert main(["compare", "paper-40", "--methods", f"{throwaway},st-ql", "--seeds", "2",
                 "--episodes", "20", "--jobs", "1", "--set", "q0=2", "--out", str(out)]) == 0
    data = json.loads((out / "results.json").read_text())
    runs = [r for r in data["runs"] if r["method"] == throwaway]
    assert [r["seed"] for r in runs] == [0, 1]
    for r in runs:
        assert r["method_name"] == "THROWAWAY-QL" and r["config"]["q0"] == 2.0
        assert len(r["steps_per_episode"]) == 20
        assert r["final_route_length"] == -1 or r["final_route_length"] >= 60
    assert data["summary"][throwaway]["grid"]["seeds"] == 2
    assert list(data["summary"]) == [throwaway, "st-ql"]
    md = (out / "summary.md").read_text()
    assert f"| {throwaway} | grid | 2 |" in md
    assert (out / "steps_per_episode.png").stat().st_size > 5000
    assert throwaway in capsys.readouterr().out
    assert type(METHODS[throwaway]()) is Throwaway


def test_unregister_leaves_the_registry_as_it_was(throwaway):
    from learning.methods.registry import METHODS, comparison_methods, unregister

    before = comparison_methods()
    unregister(throwaway)
    try:
        assert throwaway not in METHODS and throwaway not in comparison_methods()
        assert comparison_methods() == before[:-1]
    finally:
        import sys

        from learning.methods.registry import register

        register(Throwaway, sys.modules[__name__])  # for the fixture to remove


def test_register_refuses_a_taken_name_and_a_module_without_hooks(throwaway):
    import sys
    import types

    from learning.methods.registry import register

    with pytest.raises(ValueError, match="registered already"):
        register(Throwaway, sys.modules[__name__])
    with pytest.raises(ValueError, match="has no State, init_state"):
        register(type("Other", (Throwaway,), {"cli": "other"}), types.ModuleType("bare"))
