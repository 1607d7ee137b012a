"""The methods: each config class, the module that implements it, and the one method list.

A method is one module (config, named state, hooks); :data:`FAMILY_OF_CONFIG` maps
each config class to it, in the order every table, figure and ``rnhql compare`` lists
the methods. Dispatch (:mod:`learning.hooks`) reads :data:`FAMILY_OF_STATE`: a
compiled call on a state goes to the module whose ``State`` it is.

Adding a method ``my-ql``:

1. write ``learning/my_ql.py`` after :mod:`learning.q_learning` (the template): a
   frozen config subclassing :class:`~learning.config.MethodConfig` with ``name``
   (display) and ``cli`` (``"my-ql"``), a ``State`` named tuple whose first fields are
   ``par`` and ``tally``, ``init_state(cfg, geom, rng)``, and the hooks ``act``,
   ``update``, ``begin``, ``exploit`` (``njit(cache=True, inline="always")``);
2. add its row to ``_TABLE`` below (``compared=False`` keeps it out of ``rnhql
   compare``'s default list, as the RNH-QL+ ablation's method is);
3. a compared method joins the golden sweep: regenerate its digests with
   ``python -m tests.golden_sweep --write`` and say so in the commit.

Nothing else names the methods: ``rnhql compare``, the studies, checkpoints, figures
(a method without a colour in :mod:`scenarios.palette` gets a stable one) and
recordings read this module. :func:`register` does step 2 at run time (a test's
throwaway method: ``tests/test_new_method.py``).
"""

from __future__ import annotations

from types import ModuleType

from learning import (
    dyna_q,
    haql,
    pfh_rl,
    q_lambda,
    q_learning,
    rn_ql,
    rnh_ql,
    rnh_ql_plus,
    rnh_ql_plus_ablation,
    sarsa_rs,
)
from learning.config import MethodConfig
from learning.dyna_q import DynaQ
from learning.haql import HAQL
from learning.pfh_rl import PFHRL
from learning.q_lambda import QLambda
from learning.q_learning import STQL, QOpt
from learning.rn_ql import RNQL
from learning.rnh_ql import RNHQL
from learning.rnh_ql_plus import RNHQLPlus, RNHQLPlusExplore
from learning.rnh_ql_plus_ablation import RNHQLPlusAblation
from learning.sarsa_rs import SarsaRS

# every method: config, module, in rnhql compare's default list; in display order
_TABLE: tuple[tuple[type[MethodConfig], ModuleType, bool], ...] = (
    (RNHQL, rnh_ql, True),
    (RNHQLPlus, rnh_ql_plus, True),
    (STQL, q_learning, True),
    (RNQL, rn_ql, True),
    (PFHRL, pfh_rl, True),
    (SarsaRS, sarsa_rs, True),
    (HAQL, haql, True),
    (QOpt, q_learning, True),
    (QLambda, q_lambda, True),
    (DynaQ, dyna_q, True),
    # rnh-ql+ with the ablation's switches (run for run rnh-ql+ at its defaults)
    (RNHQLPlusAblation, rnh_ql_plus_ablation, False),
    # rnh-ql+ with the held-out maps' options on (issue 37), named: run on request
    (RNHQLPlusExplore, rnh_ql_plus, False),
)
HOOKS = ("State", "init_state", "act", "update", "begin", "exploit")

FAMILY_OF_CONFIG: dict[type[MethodConfig], ModuleType] = {}
METHODS: dict[str, type[MethodConfig]] = {}  # by CLI name
FAMILY_OF_STATE: dict[type, ModuleType] = {}
_COMPARED: list[str] = []


def register(config: type[MethodConfig], module: ModuleType, compared: bool = True) -> None:
    """Add a method: its config class and the module with its ``State`` and hooks.

    ``compared``: in :func:`comparison_methods` (after the methods already there).
    Compiled code that already ran is not affected; a new ``State`` compiles anew. The
    module must be importable in every process that reads numba's on-disk cache (a
    module of a package, not a script): the cached kernels name its ``State`` class.
    """
    missing = [h for h in HOOKS if not hasattr(module, h)]
    if missing:
        raise ValueError(f"{module.__name__} has no {', '.join(missing)}: a method module "
                         "declares State, init_state and the hooks act, update, begin, exploit")
    if tuple(getattr(module.State, "_fields", ())[:2]) != ("par", "tally"):
        raise ValueError(f"{module.__name__}.State is not a named tuple whose first fields "
                         "are par and tally")
    if config.cli in METHODS:
        raise ValueError(f"a method named {config.cli!r} is registered already "
                         f"({METHODS[config.cli].__name__})")
    known = FAMILY_OF_STATE.get(module.State)
    if known is not None and known is not module:
        raise ValueError(f"{module.__name__}.State is {known.__name__}'s already")
    FAMILY_OF_CONFIG[config] = module
    METHODS[config.cli] = config
    FAMILY_OF_STATE[module.State] = module
    if compared:
        _COMPARED.append(config.cli)


def unregister(cli: str) -> None:
    """Remove the method registered as ``cli`` (a test's throwaway method)."""
    config = METHODS.pop(cli)
    module = FAMILY_OF_CONFIG.pop(config)
    if module not in FAMILY_OF_CONFIG.values():
        del FAMILY_OF_STATE[module.State]
    if cli in _COMPARED:
        _COMPARED.remove(cli)


def comparison_methods() -> tuple[str, ...]:
    """CLI names of the methods ``rnhql compare`` (and the studies built on it) runs by
    default, in display order."""
    return tuple(_COMPARED)


for _config, _module, _compared in _TABLE:
    register(_config, _module, _compared)


def family_of(cfg: MethodConfig) -> ModuleType:
    """The module that implements ``cfg``'s method."""
    try:
        return FAMILY_OF_CONFIG[type(cfg)]
    except KeyError:
        raise ValueError(f"{type(cfg).__name__} is not a registered method; known: "
                         f"{', '.join(METHODS)}") from None


def family_of_state(st) -> ModuleType:
    return FAMILY_OF_STATE[type(st)]


def n_states_of(st) -> int:
    """States the learner ``st`` was built for."""
    fam = family_of_state(st)
    return fam.n_states(st) if hasattr(fam, "n_states") else int(st.q.shape[0])


def config_from_fields(cli: str, fields: dict[str, object]) -> MethodConfig:
    """Rebuild a config from its CLI name and field values (e.g. from a checkpoint)."""
    if cli not in METHODS:
        raise ValueError(f"unknown method {cli!r}; known: {', '.join(METHODS)}")
    return METHODS[cli].from_fields(fields)
