"""The methods: each config class, the module that implements it, and the one method list.

A method is one module (config, named state, hooks); :data:`FAMILY_OF_CONFIG` maps
each config class to it, in the order every table, figure and ``rnhql compare`` lists
the methods. Dispatch (:mod:`learning.compiled.hooks`) reads :data:`FAMILY_OF_STATE`: a
compiled call on a state goes to the module whose ``State`` it is.

Adding a method ``my-ql``:

1. write ``learning/methods/my_ql.py`` after :mod:`learning.methods.q_learning` (the template): a
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

import importlib
import inspect
from types import ModuleType

from learning.config import MethodConfig
from learning.methods import (
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
from learning.methods.dyna_q import DynaQ
from learning.methods.haql import HAQL
from learning.methods.pfh_rl import PFHRL
from learning.methods.q_lambda import QLambda
from learning.methods.q_learning import STQL, QOpt
from learning.methods.references import fsa_replan, lrta_star, mf_r_max, r_max
from learning.methods.references.abstraction_ql import AbstractionQL
from learning.methods.references.fsa_replan import FSAReplan
from learning.methods.references.lrta_star import LRTAStar
from learning.methods.references.mf_r_max import MFRMax
from learning.methods.references.r_max import RMax
from learning.methods.rn_ql import RNQL
from learning.methods.rnh_ql import RNHQL
from learning.methods.rnh_ql_plus import RNHQLPlus, RNHQLPlusExplore
from learning.methods.rnh_ql_plus_ablation import RNHQLPlusAblation
from learning.methods.sarsa_rs import SarsaRS
from learning.plain import policy as policy_state

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
    # the references a route learner is judged against (docs/methods.md): learning by
    # trials (LRTA*), planning on the optimistic map (the free-space replanner) and
    # model-based RL with optimism (R-max, the untried valued by the free-space distance)
    (LRTAStar, lrta_star, True),
    (FSAReplan, fsa_replan, True),
    (RMax, r_max, True),
    # rnh-ql+ with the ablation's switches (run for run rnh-ql+ at its defaults)
    (RNHQLPlusAblation, rnh_ql_plus_ablation, False),
    # rnh-ql+ with the held-out maps' options on, named: run on request
    (RNHQLPlusExplore, rnh_ql_plus, False),
    # shaping from a coarse abstraction of a map given in advance, run on request: the one
    # method told the map (coarsely) before its first step, so not in the default list of
    # methods that learn an unknown map; its row says what such a prior is worth
    (AbstractionQL, pfh_rl, False),  # PFH-RL's rules, its own static Φ
    # R-max over levels of fidelity (the grid, then a physics rung), run on request: the
    # learn-on-the-grid study's reference (docs/ladder.md)
    (MFRMax, mf_r_max, False),
)
HOOKS = ("State", "init_state", "act", "update", "begin", "exploit")
# each compiled hook's parameters, as learning.compiled.hooks calls it
HOOK_PARAMETERS = {"act": ("st", "s", "rng"),
                   "update": ("st", "s", "a", "r", "s2", "terminated", "rng"),
                   "begin": ("st", "s0"), "exploit": ("st", "s")}

FAMILY_OF_CONFIG: dict[type[MethodConfig], ModuleType] = {}
METHODS: dict[str, type[MethodConfig]] = {}  # by CLI name
FAMILY_OF_STATE: dict[type, ModuleType] = {}
_COMPARED: list[str] = []
# methods registered from outside the package: CLI name -> ("module:Config", compared), what
# a worker process re-registers (restore_external) when it did not inherit the registry
EXTERNAL: dict[str, tuple[str, bool]] = {}


def check_method_module(module: ModuleType) -> None:
    """Refuse a method module whose parts the compiled loops could not use, saying which
    part and how to mend it (at :func:`register`, not inside a worker later)."""
    name = module.__name__
    missing = [h for h in HOOKS if not hasattr(module, h)]
    if missing:
        raise ValueError(f"{name} has no {', '.join(missing)}: a method module "
                         "declares State, init_state and the hooks act, update, begin, exploit")
    if tuple(getattr(module.State, "_fields", ())[:2]) != ("par", "tally"):
        raise ValueError(f"{name}.State is not a named tuple whose first fields "
                         "are par and tally")
    for hook, params in HOOK_PARAMETERS.items():
        fn = getattr(module, hook)
        if not hasattr(fn, "py_func"):
            raise ValueError(f"{name}.{hook} is a plain Python function: the compiled loops "
                             f"inline it, so decorate it with @numba.njit(cache=True, "
                             f"inline='always'); or write a plain-Python learner (a class "
                             f"with act, update and greedy: docs/python-api.md), which needs "
                             f"no numba")
        got = tuple(inspect.signature(fn.py_func).parameters)
        if len(got) != len(params):
            raise ValueError(f"{name}.{hook} takes ({', '.join(got)}), but the loops call it "
                             f"as {hook}({', '.join(params)}): give it {len(params)} "
                             "parameters")
    if not callable(module.init_state):
        raise ValueError(f"{name}.init_state is not callable: define "
                         "init_state(cfg, geom, rng) -> State")
    if len(inspect.signature(module.init_state).parameters) != 3:
        raise ValueError(f"{name}.init_state must take (cfg, geom, rng)")


_FINGERPRINTS: dict[ModuleType, bytes] = {}


def state_fingerprint(config: type[MethodConfig], module: ModuleType) -> bytes:
    """How numba's dispatcher tells this method's states apart: the fingerprint of a state
    built on a 3 x 3 arena (a named tuple's is its class's bare name and its fields' types;
    an array's, its dtype, rank and layout, not its size)."""
    if module not in _FINGERPRINTS:
        import numpy as np
        from numba._dispatcher import compute_fingerprint

        from learning.geometry import Geometry

        xy = np.array([(x + 0.5, y + 0.5) for y in range(3) for x in range(3)])
        geom = Geometry(xy, 8, (0.0, 0.0, 3.0, 3.0), 9, 4, 1.0, np.arange(8, dtype=np.int32))
        st = module.init_state(config(), geom, np.random.default_rng(0))
        _FINGERPRINTS[module] = compute_fingerprint(st)
    return _FINGERPRINTS[module]


def check_state_is_its_own(config: type[MethodConfig], module: ModuleType) -> None:
    """Refuse a method whose states numba cannot tell from another method's: its dispatcher
    keys compiled loops on a state's class *name* and field types, so a second ``State``
    with the same fields would run the first method's compiled rules."""
    mine = state_fingerprint(config, module)
    for other_config, other in FAMILY_OF_CONFIG.items():
        if other is not module and state_fingerprint(other_config, other) == mine:
            raise ValueError(
                f"{module.__name__}.State has the class name and the field types of "
                f"{other.__name__}.State: numba's compiled loops tell states apart by those "
                f"alone, so {config.cli} would run {other_config.cli}'s compiled rules. Give "
                f"the class a name of its own (e.g. class {config.__name__}State"
                "(NamedTuple), then State = that class)")


def register(config: type[MethodConfig], module: ModuleType, compared: bool = True) -> None:
    """Add a method: its config class and the module with its ``State`` and hooks.

    ``compared``: in :func:`comparison_methods` (after the methods already there).
    Compiled code that already ran is not affected; a new ``State`` compiles anew. A method
    from outside the package is remembered (:data:`EXTERNAL`) so that a sweep's worker
    processes register it too, and its kernels are kept out of numba's on-disk cache.
    """
    check_method_module(module)
    if not (isinstance(config, type) and issubclass(config, MethodConfig)):
        raise ValueError(f"{config!r} is not a MethodConfig subclass: a method's config is a "
                         "frozen dataclass subclassing learning.config.MethodConfig")
    if _TABLE_DONE and module not in FAMILY_OF_CONFIG.values():
        check_state_is_its_own(config, module)
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
    if not module.__name__.startswith(f"{__package__}."):
        from learning.jitcache import FOREIGN_STATES, guard_cache

        guard_cache()
        FOREIGN_STATES.add(module.State)
        EXTERNAL[config.cli] = (f"{config.__module__}:{config.__qualname__}", compared)


def unregister(cli: str) -> None:
    """Remove the method registered as ``cli`` (a test's throwaway method)."""
    config = METHODS.pop(cli)
    module = FAMILY_OF_CONFIG.pop(config)
    if module not in FAMILY_OF_CONFIG.values():
        del FAMILY_OF_STATE[module.State]
    if cli in _COMPARED:
        _COMPARED.remove(cli)
    EXTERNAL.pop(cli, None)


def restore_external(external: dict[str, tuple[str, bool]]) -> None:
    """Register, in this process, the methods another process registered from outside the
    package (a worker started by spawn or forkserver has only the built-in ones)."""
    for cli, (where, compared) in external.items():
        if cli not in METHODS:
            config = import_attribute(where, "--methods")
            register(config, importlib.import_module(config.__module__), compared)


def import_attribute(where: str, flag: str = "method"):
    """The object named ``"package.module:Attribute"`` (``Attribute`` may be dotted)."""
    module_name, _, attr = where.partition(":")
    if not module_name or not attr:
        raise ValueError(f"{flag} {where!r} is not module:Attribute; write e.g. "
                         "mypkg.mymodule:MyLearner")
    if module_name.startswith(".") or "/" in module_name or module_name.endswith(".py"):
        raise ValueError(f"{flag} {where!r}: {module_name!r} is not a module name (a relative "
                         "name or a path); put the file's folder on PYTHONPATH and write "
                         "mymodule:MyLearner")
    try:
        obj: object = importlib.import_module(module_name)
    except ImportError as exc:
        raise ValueError(f"{flag} {where!r}: cannot import {module_name} ({exc}); put its "
                         "folder on PYTHONPATH or install its package") from None
    except SyntaxError as exc:  # the user's own module: one line, its file and line
        raise ValueError(f"{flag} {where!r}: {exc.filename}:{exc.lineno}: {exc.msg}; fix "
                         "the module") from None
    except SystemExit as exc:  # sys.exit() at import: the run would end doing nothing
        raise ValueError(f"{flag} {where!r}: importing {module_name} called sys.exit("
                         f"{exc.code!r}); a learner's module must not exit") from None
    except Exception as exc:  # an error in the user's module as it imports
        tb = exc.__traceback__
        while tb is not None and tb.tb_next is not None:
            tb = tb.tb_next
        at = "" if tb is None else f" at {tb.tb_frame.f_code.co_filename}:{tb.tb_lineno}"
        raise ValueError(f"{flag} {where!r}: importing {module_name} raised "
                         f"{type(exc).__name__}: {exc}{at}; fix the module") from None
    for part in attr.split("."):
        if not hasattr(obj, part):
            raise ValueError(f"{flag} {where!r}: {module_name} has no {attr!r}; name a class "
                             "defined in that module")
        obj = getattr(obj, part)
    return obj


def is_located(method: str) -> bool:
    """Whether ``method`` names a learner by where it lives (``module:Attribute``)."""
    return ":" in method


def config_class(method: str) -> type:
    """The config class of ``method``: a registered CLI name, or ``module:Attribute`` naming a
    compiled method's config (registered here on first use, left out of ``rnhql compare``'s
    default list) or a plain-Python learner class (:func:`learning.plain.learner.plain_config`)."""
    if method in METHODS:
        return METHODS[method]
    if not is_located(method):
        import difflib

        close = difflib.get_close_matches(method, list(METHODS), n=2, cutoff=0.6)
        hint = f"did you mean {' or '.join(close)}? " if close else ""
        raise ValueError(f"unknown method {method!r}; {hint}known: {', '.join(METHODS)}, or "
                         "module:Class for a learner of your own")
    from learning.plain.learner import known_class, plain_config

    obj = known_class(method) or import_attribute(method)
    if isinstance(obj, type) and issubclass(obj, MethodConfig):
        if METHODS.get(obj.cli) is not obj:
            register(obj, importlib.import_module(obj.__module__), compared=False)
        return obj
    return plain_config(obj, method)


def comparison_methods() -> tuple[str, ...]:
    """CLI names of the methods ``rnhql compare`` (and the studies built on it) runs by
    default, in display order."""
    return tuple(_COMPARED)


_TABLE_DONE = False  # the package's own methods are distinct by construction (tested)
for _config, _module, _compared in _TABLE:
    register(_config, _module, _compared)
_TABLE_DONE = True
FAMILY_OF_STATE[policy_state.State] = policy_state  # graded policies: no method, no name


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
    if cli not in METHODS and not is_located(cli):
        raise ValueError(f"unknown method {cli!r}; known: {', '.join(METHODS)}")
    return config_class(cli).from_fields(fields)


def shown_name(method: str) -> str:
    """How tables, figures and verdicts name a method: its key (``rnh-ql+``), or, for a
    learner of one's own (``module:Class``), the ``name`` it declares ("how tables name it");
    its key where the class cannot be imported here (a results.json read elsewhere)."""
    if not is_located(method):
        return method
    try:
        return str(config_class(method).name)
    except (ValueError, ImportError, AttributeError):
        return method
