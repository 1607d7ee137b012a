"""A study's code as its tables' provenance: a hash of what it computes (imports and
docstrings left out) and of the study code it computes with (:func:`study_helpers`)."""

from __future__ import annotations

import ast
import hashlib
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]


def study_code_digest(source: str) -> str:
    """A hash of a study's *code*: its syntax tree without import statements and
    docstrings. Imports say where a name comes from, and docstrings what the code is for,
    not what the study measures: moving a module, hoisting an import or rewording a
    docstring leaves its tables fresh, as comments and layout do. A change of a row's
    settings, a formula or a printed string changes the hash."""
    tree = ast.parse(source)
    for node in ast.walk(tree):
        for field in ("body", "orelse", "finalbody", "handlers"):
            block = getattr(node, field, None)
            if not isinstance(block, list):
                continue
            block = [n for n in block if not isinstance(n, ast.Import | ast.ImportFrom)]
            if field == "body" and isinstance(node, _DOCUMENTED) and block and \
                    isinstance(block[0], ast.Expr) and isinstance(block[0].value, ast.Constant) \
                    and isinstance(block[0].value.value, str):
                block = block[1:]
            setattr(node, field, block)
    return hashlib.sha256(ast.dump(tree).encode()).hexdigest()


_DOCUMENTED = (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)


def study_digest(path: str | Path) -> dict[str, Any]:
    """The study script a table came from, and a hash of its code
    (:func:`study_code_digest`): a change of the study's own code (a row's settings, what
    it measures) is not in the behaviour digests. ``with``: the same hash of every module
    the study computes its numbers with beyond ``sim`` and ``learning`` (whose behaviour the
    golden records hold): its own package's modules and the studies' helpers, found by
    following its imports (:func:`study_helpers`)."""
    path = Path(path).resolve()
    return {"path": _rel(path), "code_sha256": study_code_digest(path.read_text()),
            "with": {_rel(h): study_code_digest(h.read_text()) for h in study_helpers(path)}}


def _rel(path: Path) -> str:
    return path.relative_to(ROOT).as_posix() if path.is_relative_to(ROOT) else str(path)


# code that computes a table's numbers outside the golden records' reach (sim and learning,
# the runs and sweeps): the studies and their helpers, the crosscheck's IR-SIM side, and the
# example learners a study imports (a user's learner, which no golden record covers)
STUDY_CODE = ("scenarios/studies", "sim/physics/crosscheck", "examples")


def study_helpers(path: Path) -> list[Path]:
    """The modules a study's numbers also come from: following its imports (at any depth),
    every module of the repository's study code, :data:`STUDY_CODE` (the predictivity
    statistics of the ladder, the ranking of the held-out study, the IR-SIM world of the
    crosscheck), not the study itself."""
    seen: set[Path] = set()
    todo = [path]
    while todo:
        tree = ast.parse(todo.pop().read_text())
        for node in ast.walk(tree):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module] if isinstance(node, ast.ImportFrom) and node.module
                     and node.level == 0 else [])
            for name in names:
                for cand in (ROOT / Path(*name.split("."))).with_suffix(".py"), \
                        ROOT / Path(*name.split(".")) / "__init__.py":
                    inside = any(cand.is_relative_to(ROOT / d) for d in STUDY_CODE)
                    if cand.is_file() and inside and cand not in seen and cand != path:
                        seen.add(cand)
                        todo.append(cand)
    return sorted(seen)


def study_changed(study: dict[str, Any]) -> bool:
    """Whether the study script an artifact recorded, or a module it computed with
    (``with``), is gone or its code changed (an artifact written before the code hash holds
    the hash of the file's bytes)."""
    path = ROOT / study["path"]
    if not path.is_file():
        return True
    for helper, digest in study.get("with", {}).items():
        h = ROOT / helper
        if not h.is_file() or study_code_digest(h.read_text()) != digest:
            return True
    if "code_sha256" in study:
        return study_code_digest(path.read_text()) != study["code_sha256"]
    return hashlib.sha256(path.read_bytes()).hexdigest() != study.get("sha256")
