"""Every way of writing ST-QL as one's own learner (per run in Python, a numba
``@jitclass``, batched in numpy) gives the compiled ``st-ql``'s physics runs figure for
figure above ``exact`` too: at ``noisy`` the wheels' noise is drawn from each run's noise
stream, the graded tests drive the robots at the rung, and a plain learner's runs step in
other loops than the compiled method's (the lock-step loop, the fused step with the
class's hooks), so equal records say those loops draw and grade alike."""

from __future__ import annotations

import numpy as np

from scenarios import api
from tests.plain_learners import differing

PORTS = ("tests.plain_learners.st_ql:STQLPort", "tests.plain_learners.st_ql_jit:STQLJit",
         "tests.plain_learners.st_ql_batched:STQLBatched")


def test_every_port_of_st_ql_equals_compiled_st_ql_at_noisy():
    cmp = api.compare("paper-40", ["st-ql", *PORTS], worlds=("physics",), fidelity="noisy",
                      seeds=2, episodes=10, jobs=1)
    for port in PORTS:
        for ours, theirs in zip(cmp.of("st-ql", "physics"), cmp.of(port, "physics"),
                                strict=True):
            assert differing(dict(ours.record), dict(theirs.record)) == [], port
            assert np.array_equal(ours.policy, theirs.policy), port
