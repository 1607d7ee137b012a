"""A plain learner written as a numba ``@jitclass`` runs in a compiled loop: the same runs as
the compiled method it ports, its failures said as any learner's, nothing left in numba's
on-disk cache."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from learning.plain.learner import LearnerError
from scenarios import api
from tests.plain_learners import differing

JIT = "tests.plain_learners.st_ql_jit:STQLJit"


def test_a_jitclass_port_of_st_ql_equals_compiled_st_ql_in_grid_and_physics():
    cmp = api.compare("paper-40", ["st-ql", JIT], worlds=("grid", "physics"), seeds=2,
                      episodes=20, jobs=1)
    for world in ("grid", "physics"):
        for ours, theirs in zip(cmp.of("st-ql", world), cmp.of(JIT, world), strict=True):
            assert differing(dict(ours.record), dict(theirs.record)) == []
            assert np.array_equal(ours.policy, theirs.policy)


def test_a_jitclass_run_leaves_nothing_in_numbas_cache():
    api.train("paper-40", method=JIT, episodes=5)
    here = Path(__file__).resolve().parent.parent
    places = [here / "learning" / "plain" / "__pycache__", here / "tests" / "plain_learners"
              / "__pycache__"]
    if os.environ.get("NUMBA_CACHE_DIR"):
        places.append(Path(os.environ["NUMBA_CACHE_DIR"]))
    left = [p for d in places if d.is_dir() for p in d.rglob("*.nb[ic]")
            if "compiled" in p.name.split(".")[0] or "st_ql_jit" in p.name]
    assert left == []


def test_a_jitclass_answering_no_action_fails_the_run_naming_it():
    import numba
    from numba import types
    from numba.experimental import jitclass

    @jitclass([("n", types.int64)])
    class Four:
        def __init__(self, n_states, n_actions, rng):
            self.n = n_actions

        def act(self, s):
            return 4

        def update(self, s, a, r, s2, terminal):
            pass

        def greedy(self, s):
            return 0

    assert numba is not None
    with pytest.raises(LearnerError, match=r"Four\.act\(\d+\) returned 4, not an action"):
        api.train("paper-40", method=Four, episodes=3)
