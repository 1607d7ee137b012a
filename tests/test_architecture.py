"""The layout is the architecture: imports run only downward and never in a cycle.

Parses every module with ``ast`` (no imports executed) and checks, over *all*
imports, lazy ones inside functions included:

- ``sim`` never imports ``learning`` or ``scenarios``; ``learning`` never
  imports ``sim`` or ``scenarios``; neither imports rerun or matplotlib;
- inside ``scenarios`` the subpackages are ranked ``cli`` > ``bench`` >
  ``studies`` > ``sweep`` > ``runs`` > ``recording`` > ``figures``: a module imports its
  own subpackage or lower ones only;
- inside ``learning`` and ``sim.physics`` the rooms are ranked the same way
  (:data:`ROOMS`): the package's own modules at the bottom, then each room in turn;
- the module import graph has no cycle.
"""

from __future__ import annotations

import ast
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
PACKAGES = ("sim", "learning", "scenarios")
SCENARIO_RANK = {"artifacts": 0, "figures": 1, "recording": 2, "runs": 3, "sweep": 4,
                 "studies": 5, "bench": 6, "cli": 7}
FORBIDDEN = {
    "sim": ("learning", "scenarios", "rerun", "matplotlib"),
    "learning": ("sim", "scenarios", "rerun", "matplotlib", "pymunk"),
}


# rooms of a package, bottom first: a module imports its own room or lower ones only (a
# package's face, its ``__init__``, may hand on any of its rooms' names)
ROOMS = {
    "learning": ("", "parts", "plain", "methods", "compiled", "drivers"),
    "sim.physics": ("", "reference", "kernel", "envs", "models", "crosscheck"),
}


def module_name(path: Path) -> str:
    parts = list(path.relative_to(REPO).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def imports_of(path: Path, known: set[str]) -> set[str]:
    """Modules (of this repository, or top-level names of others) that ``path`` imports."""
    tree = ast.parse(path.read_text(), filename=str(path))
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module)
            # `from pkg import mod` imports a module when mod is one of ours
            found.update(f"{node.module}.{a.name}" for a in node.names
                         if f"{node.module}.{a.name}" in known)
    return found


def graph() -> dict[str, set[str]]:
    files = [p for pkg in PACKAGES for p in (REPO / pkg).rglob("*.py")]
    known = {module_name(p) for p in files}
    return {module_name(p): imports_of(p, known) for p in files}


def subpackage(mod: str) -> str | None:
    parts = mod.split(".")
    return parts[1] if parts[0] == "scenarios" and len(parts) > 2 else None


def test_layers_never_import_upward():
    bad = []
    for mod, deps in graph().items():
        top = mod.split(".")[0]
        for dep in deps:
            if any(dep == f or dep.startswith(f + ".") for f in FORBIDDEN.get(top, ())):
                bad.append(f"{mod} imports {dep}")
            sub, dep_sub = subpackage(mod), subpackage(dep)
            if sub in SCENARIO_RANK and dep_sub in SCENARIO_RANK and \
                    SCENARIO_RANK[dep_sub] > SCENARIO_RANK[sub]:
                bad.append(f"{mod} ({sub}) imports {dep} ({dep_sub}), a higher layer")
    assert bad == [], "\n".join(sorted(bad))


def room_of(mod: str, package: str) -> str | None:
    """The room of ``package`` that ``mod`` stands in ("" for the package's own modules),
    None outside the package or for the package's face."""
    if not mod.startswith(package + "."):
        return None
    rest = mod[len(package) + 1:].split(".")
    if len(rest) == 1 and not (REPO / Path(*mod.split("."))).is_dir():
        return ""
    return rest[0]


def test_rooms_import_only_their_own_room_or_lower_ones():
    bad = []
    for package, order in ROOMS.items():
        rank = {room: i for i, room in enumerate(order)}
        for mod, deps in graph().items():
            room = room_of(mod, package)
            if room is None or mod.endswith(".__init__"):
                continue
            for dep in deps:
                dep_room = room_of(dep, package)
                if dep_room is not None and rank[dep_room] > rank[room]:
                    bad.append(f"{mod} ({room or 'the package'}) imports {dep} ({dep_room})")
    assert bad == [], "\n".join(sorted(bad))


def test_every_room_is_ranked():
    for package, order in ROOMS.items():
        folder = REPO / Path(*package.split("."))
        rooms = {p.name for p in folder.iterdir() if (p / "__init__.py").is_file()}
        assert rooms == set(order) - {""}, package


def test_no_folder_holds_more_than_twelve_modules():
    """A room a reader takes in at a glance: a folder that grows past twelve modules is
    split into rooms of its own."""
    crowded = {str(d.relative_to(REPO)): n for pkg in PACKAGES
               for d in [REPO / pkg, *(REPO / pkg).rglob("*")] if d.is_dir()
               if (n := len(list(d.glob("*.py")))) > 12}
    assert crowded == {}


def test_every_scenarios_subpackage_is_ranked():
    subs = {p.name for p in (REPO / "scenarios").iterdir()
            if p.is_dir() and (p / "__init__.py").is_file()}
    assert subs == set(SCENARIO_RANK)


def find_cycle(g: dict[str, set[str]]) -> list[str] | None:
    """One import cycle among our own modules (as a path), or None."""
    state: dict[str, int] = {}  # 1 on the stack, 2 done
    stack: list[str] = []

    def visit(m: str) -> list[str] | None:
        state[m] = 1
        stack.append(m)
        for d in sorted(g.get(m, ())):
            if d not in g or d == m:
                continue
            if state.get(d) == 1:
                return [*stack[stack.index(d):], d]
            if d not in state and (c := visit(d)):
                return c
        stack.pop()
        state[m] = 2
        return None

    for m in sorted(g):
        if m not in state and (c := visit(m)):
            return c
    return None


def test_no_import_cycles():
    g = graph()
    # a package importing its own submodules (re-exports in __init__) is not a cycle
    for mod, deps in g.items():
        g[mod] = {d for d in deps if not (d.startswith(mod + ".") and
                                          (REPO / Path(*mod.split("."))).is_dir())}
    assert find_cycle(g) is None, " -> ".join(find_cycle(g) or [])


def test_the_checker_sees_a_cycle():
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None


def method_modules() -> set[str]:
    """The method modules of ``learning`` (``q_learning``, ``rnh_ql_plus``, ...): the
    registry's (a new method is added there, not here)."""
    from learning.methods.registry import FAMILY_OF_CONFIG

    return {m.__name__.split(".")[2] for m in FAMILY_OF_CONFIG.values()
            if m.__name__.startswith("learning.methods.")}


# a method that is another one with more switches builds on it (never the other way round)
BUILDS_ON = {"rnh_ql_plus_ablation": "rnh_ql_plus"}


def test_each_method_module_imports_no_other_method():
    """A method is one module (or package): it may use the shared pieces of ``learning``
    (tabular rules, traces, tally, move model, free space, features of its own), never
    another method's module, except the one method it is a variant of (``BUILDS_ON``)."""
    bad = []
    methods = method_modules()
    assert {"q_learning", "rnh_ql_plus", "rnh_ql_plus_ablation"} <= methods
    for mod, deps in graph().items():
        parts = mod.split(".")
        if parts[:2] != ["learning", "methods"] or len(parts) < 3 or parts[2] not in methods:
            continue
        for dep in deps:
            dparts = dep.split(".")
            if dparts[:2] == ["learning", "methods"] and len(dparts) > 2 \
                    and dparts[2] in methods \
                    and dparts[2] not in (parts[2], BUILDS_ON.get(parts[2])):
                bad.append(f"{mod} imports {dep}")
    assert bad == [], "\n".join(sorted(bad))


def test_every_registered_method_declares_config_state_and_hooks():
    from learning.methods.registry import FAMILY_OF_CONFIG, HOOKS

    for module in set(FAMILY_OF_CONFIG.values()):
        for attr in HOOKS:
            assert hasattr(module, attr), f"{module.__name__} has no {attr}"
        assert tuple(module.State._fields[:2]) == ("par", "tally"), module.__name__


def test_the_physics_copy_of_the_generator_handle_equals_learnings():
    """``sim`` and ``learning`` import nothing of each other, so each has the generator
    handle (a Generator passed to compiled code as integers); the two stay one definition."""
    import inspect

    import learning.compiled.generator_handle as learning_copy
    import sim.physics.generator_handle as physics_copy

    for name in ("handle", "handles", "generator_from", "HANDLE_SIZE"):
        a, b = getattr(physics_copy, name), getattr(learning_copy, name)
        if isinstance(a, int):
            assert a == b, name
        else:
            code = getattr(a, "_defn", a)  # the intrinsic's Python function
            assert inspect.getsource(code) == inspect.getsource(getattr(b, "_defn", b)), name
