"""What the ``rnhql`` command does, from Python: :func:`train`, :func:`compare`, :func:`route`,
each with ``record=`` for a Rerun recording.

Why a wrapper and not a second implementation: each function builds the command line the
CLI would parse and runs the same subcommand (:mod:`scenarios.cli`), so a call does exactly
what the command does, with the same checks, streams and outputs. The differences are
the ones Python wants: results come back as values (the run record, ``results.json``, the
route report), the printed report is kept quiet unless ``verbose=True``, and bad input
raises :class:`sim.errors.InputError` (the CLI prints it as one line and exits 2).

>>> from scenarios import api
>>> run = api.train("rooms-102", "q-opt", episodes=300, seed=0)      # doctest: +SKIP
>>> run["final_route_length"], run["optimal_route_length"]          # doctest: +SKIP

For Gymnasium and Stable-Baselines3 use the env ids directly (``docs/python-api.md``).
"""

from __future__ import annotations

import contextlib
import io
import json
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from sim.errors import InputError


def _flags(**options: Any) -> list[str]:
    """``--name value`` for every option that is set (``True``: a bare flag)."""
    argv: list[str] = []
    for name, value in options.items():
        if value is None or value is False:
            continue
        flag = "--" + name.replace("_", "-")
        if value is True:
            argv.append(flag)
        elif isinstance(value, list | tuple) and name == "set":
            for item in value:
                argv += [flag, str(item)]
        elif isinstance(value, list | tuple):
            argv += [flag, ",".join(str(v) for v in value)]
        else:
            argv += [flag, str(value)]
    return argv


def _run(argv: Sequence[str], verbose: bool) -> str:
    """Parse ``argv`` as the CLI does and run its subcommand; returns what it printed."""
    from scenarios.cli.app import build_parser

    out = io.StringIO()
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err):
            args = build_parser().parse_args(list(argv))
    except SystemExit:  # argparse's usage error: "rnhql CMD: error: PROBLEM. Fix: ..."
        problem = err.getvalue().strip().partition("error: ")[2].partition(". Fix:")[0]
        raise InputError("scenarios.api", argv[0], problem or "bad arguments",
                         f"see help(scenarios.api.{argv[0]})") from None
    if verbose:
        args.func(args)
        return ""
    with contextlib.redirect_stdout(out):
        args.func(args)
    return out.getvalue()


def _settings(overrides: dict[str, float] | None) -> list[str] | None:
    return None if not overrides else [f"{k}={v}" for k, v in overrides.items()]


def train(scenario: str = "paper-50", method: str = "rnh-ql", *, seed: int = 0,
          episodes: int = 3000, world: str = "grid", fidelity: str | None = None,
          rewards: str | None = None, settings: dict[str, float] | None = None,
          save: str | Path | None = None, record: str | Path | None = None,
          verbose: bool = False) -> dict[str, Any]:
    """``rnhql train``: one method on one scenario, one seed. Returns the run's record (what
    ``--json`` writes: route lengths against the optimum, episodes to a stable optimum, the
    configuration and the streams it ran on).

    ``world``: ``"grid"`` or ``"physics"`` (``fidelity``: ``"exact"``, ``"noisy"``, ...);
    ``rewards``: ``None`` (goal-only, as the CLI), ``"scenario"``, ``"paper"``, ...;
    ``settings``: method fields, e.g. ``{"eps": 0.2}``; ``save``: an ``AGENT.npz`` for
    :func:`route`; ``record``: a ``.rrd`` path.

    >>> api.train("rooms-102", "dyna-q", episodes=200)["final_route_length"]  # doctest: +SKIP
    """
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "run.json"
        _run(["train", scenario, *_flags(method=method, seed=seed, episodes=episodes,
                                          world=world, fidelity=fidelity, rewards=rewards,
                                          set=_settings(settings), save=save, record=record,
                                          json=path)], verbose)
        return json.loads(path.read_text())


def compare(scenario: str, out: str | Path, methods: Sequence[str] | None = None, *,
            seeds: int = 10, seed_base: int = 0, episodes: int = 3000,
            worlds: Sequence[str] = ("grid",), fidelity: str | None = None,
            rewards: str | None = None, settings: dict[str, float] | None = None,
            jobs: int | None = None, resume: bool = False, record: str | Path | None = None,
            verbose: bool = False) -> dict[str, Any]:
    """``rnhql compare``: methods x seeds (x worlds) into ``out`` (``results.json``,
    ``summary.md``, figures). Returns ``results.json`` as a dict.

    ``methods``: ``None`` for the comparison's default set; ``jobs``: worker processes
    (default: every core); the rest as :func:`train`.

    >>> res = api.compare("rooms-102", "out/cmp", ["q-opt", "dyna-q"], seeds=3,
    ...                   episodes=300)                                # doctest: +SKIP
    """
    _run(["compare", scenario, *_flags(out=out, methods=list(methods) if methods else None,
                                       seeds=seeds, seed_base=seed_base, episodes=episodes,
                                       world=list(worlds), fidelity=fidelity, rewards=rewards,
                                       set=_settings(settings), jobs=jobs, resume=resume,
                                       record=record)], verbose)
    return json.loads((Path(out) / "results.json").read_text())


def route(agent: str | Path, scenario: str = "paper-50", *, world: str = "grid",
          fidelity: str | None = None, rewards: str | None = None,
          png: str | Path | None = None, record: str | Path | None = None,
          verbose: bool = False) -> str:
    """``rnhql route``: a saved agent's greedy route from S against the BFS optimum (in
    physics: driven at ``fidelity``). Returns the report the command prints; ``png``
    draws it, ``record`` writes a ``.rrd``.

    >>> api.train("rooms-102", "q-opt", episodes=300, save="a.npz")   # doctest: +SKIP
    >>> print(api.route("a.npz", "rooms-102"))                          # doctest: +SKIP
    """
    return _run(["route", scenario, *_flags(agent=agent, world=world, fidelity=fidelity,
                                            rewards=rewards, png=png, record=record)],
                verbose)
