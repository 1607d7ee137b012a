"""A batched plain learner (one call per step for every run of a batch): the same runs as
the compiled method it ports, in the grid's lock-step batches and in physics, its failures
said as any learner's; recorded, resumed and graded in physics as a Python learner is."""

from __future__ import annotations

import numpy as np
import pytest

from learning.plain.learner import LearnerError
from scenarios import api
from scenarios.runs.physics_batch import plan_tasks
from scenarios.sweep.run import make_specs
from tests.plain_learners import differing
from tests.plain_learners.features import check_recorded, check_resumes_and_graded

BATCHED = "tests.plain_learners.st_ql_batched:STQLBatched"


def test_a_batched_port_of_st_ql_equals_compiled_st_ql_in_grid_and_physics():
    cmp = api.compare("paper-40", ["st-ql", BATCHED], worlds=("grid", "physics"), seeds=3,
                      episodes=20, jobs=1)
    for world in ("grid", "physics"):
        for ours, theirs in zip(cmp.of("st-ql", world), cmp.of(BATCHED, world), strict=True):
            assert differing(dict(ours.record), dict(theirs.record)) == []
            assert np.array_equal(ours.policy, theirs.policy)
    assert cmp.of(BATCHED, "grid")[0].method_name == "ST-QL (numpy, batched)"


def test_a_batched_learners_grid_runs_are_one_task_and_others_stay_alone():
    specs = make_specs("paper-40", ["st-ql", BATCHED], [0, 1, 2], 10, ["grid"])
    tasks = plan_tasks(specs, jobs=1)
    batched = [t for t in tasks if specs[t[0]].method == BATCHED]
    assert batched == [[3, 4, 5]]  # the three seeds step together
    assert sorted(t for t in tasks if specs[t[0]].method == "st-ql") == [[0], [1], [2]]


def test_a_single_batched_run_trains_as_a_batch_of_one():
    run = api.train("paper-40", method=BATCHED, episodes=20)
    ref = api.train("paper-40", method="st-ql", episodes=20)
    assert np.array_equal(run.policy, ref.policy)


class _Floats:
    batched = True

    def __init__(self, n_states, n_actions, rngs):
        self.n = len(rngs)

    def act_batch(self, runs, states):
        return np.full(runs.size, 1.0)

    def update_batch(self, runs, states, actions, rewards, next_states, terminal):
        pass

    def greedy(self, run, state):
        return 0


def test_a_batched_learner_answering_floats_fails_the_run_naming_it():
    with pytest.raises(LearnerError, match=r"_Floats\.act_batch returned .* not 1 integer"):
        api.train("paper-40", method=_Floats, episodes=3)


def test_a_class_declaring_batched_without_its_calls_is_refused():
    class Half:
        batched = True

        def __init__(self, n_states, n_actions, rngs):
            pass

        def act(self, s):
            return 0

    with pytest.raises(ValueError, match="has no act_batch, update_batch, greedy"):
        api.train("paper-40", method=Half, episodes=3)


def test_a_warm_start_of_a_batched_learner_is_refused_before_any_work():
    from sim.errors import InputError

    with pytest.raises(InputError, match=r"pretrain.*batched learner.*from scratch"):
        api.train("paper-40", method=BATCHED, world="physics", fidelity="noisy",
                  pretrain=("grid", 5), episodes=2)
    with pytest.raises(InputError, match=r"pretrain.*batched learner"):
        api.compare("paper-40", ["st-ql", BATCHED], worlds=("physics",), seeds=1, episodes=2,
                    pretrain=("grid", 5))


BLOCKS = "tests.plain_learners.st_ql_blocks:STQLBlocks"


def test_a_block_draws_runs_are_its_own_whatever_else_is_in_the_batch():
    """The port written for numpy's speed draws its numbers in blocks, so its runs are not
    st-ql's draw for draw; each run's are its own: a seed trained in a batch of two, in
    both worlds, equals it trained alone."""
    both = api.compare("paper-40", [BLOCKS], worlds=("grid", "physics"), seeds=2,
                       episodes=10, jobs=1)
    for world in ("grid", "physics"):
        alone = api.compare("paper-40", [BLOCKS], worlds=(world,), seeds=1, seed_base=1,
                            episodes=10, jobs=1).of(BLOCKS, world)[0]
        batched = both.of(BLOCKS, world)[1]
        assert differing(dict(alone.record), dict(batched.record)) == []
        assert np.array_equal(alone.policy, batched.policy)
    runs = both.of(BLOCKS, "grid")
    assert not np.array_equal(runs[0].policy, runs[1].policy)  # seeds differ


def test_the_block_draws_port_learns_as_st_ql_does():
    """Its draws differ from st-ql's, its algorithm does not: on a small rooms map, over
    1000 episodes of 4 seeds, its success rate is st-ql's within 0.05 (medians)."""
    cmp = api.compare("rooms-102", ["st-ql", BLOCKS], seeds=4, episodes=1000, jobs=1,
                      rewards="goal-only")
    rate = {m: np.median([r.record["success_rate"] for r in cmp.of(m, "grid")])
            for m in ("st-ql", BLOCKS)}
    assert rate["st-ql"] > 0.9  # the yardstick learned
    assert abs(rate[BLOCKS] - rate["st-ql"]) < 0.05, rate



@pytest.mark.parametrize("world", ["grid", "physics"])
def test_its_run_is_recorded_like_a_python_learners(tmp_path, world):
    check_recorded(BATCHED, world, tmp_path)


def test_its_sweep_resumes_and_its_physics_runs_are_graded_by_their_drives(tmp_path, capsys):
    check_resumes_and_graded(BATCHED, tmp_path, capsys)
