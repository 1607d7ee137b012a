"""How far the physics world departs from the grid: a ladder of named presets, each knob in SI.

At ``exact`` (the default, the paper's world) a primitive is driven closed-loop to the
next cell centre and a bump puts the robot back on its start centre, so the physics world
is the grid's MDP up to the cells the grid's clearance blocks. The rungs above it add what
a real robot does:

- ``wheel_noise`` [-]: each wheel's commanded speed is multiplied by ``1 + wheel_noise * e``
  per control period, ``e`` a standard normal from the robot's own random stream (motor
  gain errors, uneven floors, a wheel slipping a little: 2-10 % on small indoor robots).
  A noisy drive no longer runs straight; the controller's feedback (re-planning from the
  measured pose until within 2 cm / 2 degrees) still lands it near the target centre.
- ``carried_pose``: after a contact the robot stays where the contact stopped it, at rest,
  instead of being placed back (a bumper that stops the motors). The next primitive
  starts from there: its cell is whatever cell that pose lies in. A bump is what a
  bumper reports: a contact with a surface it was not touching, or a drive that presses
  into the surface it rests on by ``bumper_travel_m`` [m] (a switch with mm of travel);
  the surface holds the disc meanwhile (it slides along it, it does not sink in), and a
  turn in place against it turns.

Every knob is deterministic per seed: the noise comes from the generator the env (or the
sweep) gives each robot. ``parse_fidelity("noisy")`` or ``"exact,wheel_noise=0.02"`` (a
preset, then fields); bad names or values raise :class:`sim.errors.ScenarioError` naming
the field.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from sim.errors import ScenarioError

MAX_WHEEL_NOISE = 0.5  # beyond this a "primitive" is no longer a move to a neighbour
MAX_BUMPER_TRAVEL_M = 0.005  # PhysicsConfig.contact_depth_m: no step goes deeper [m]


@dataclass(frozen=True)
class Fidelity:
    """One rung of the ladder (see the module doc for each knob and what it stands for)."""

    name: str = "exact"
    wheel_noise: float = 0.0  # relative sigma of each wheel's commanded speed, per period [-]
    carried_pose: bool = False  # after a contact the robot stays where it stopped
    bumper_travel_m: float = 0.002  # carried pose: a drive pressing into the surface the
    #   robot rests on reports a new bump after this much travel [m] (a bumper switch)

    @property
    def label(self) -> str:
        """The name, and the knobs when they differ from the named preset's."""
        base = PRESETS.get(self.name)
        if base is not None and base == self:
            return self.name
        knobs = ", ".join(f"{f.name}={getattr(self, f.name)}" for f in dataclasses.fields(self)
                          if f.name != "name")
        return f"{self.name} ({knobs})"

    @property
    def is_exact(self) -> bool:
        return self.wheel_noise == 0.0 and not self.carried_pose

    def validate(self, source: str = "fidelity") -> None:
        if not (isinstance(self.wheel_noise, int | float) and math.isfinite(self.wheel_noise)
                and 0.0 <= self.wheel_noise <= MAX_WHEEL_NOISE):
            raise ScenarioError(source, "wheel_noise", f"must be in 0..{MAX_WHEEL_NOISE}, got "
                                f"{self.wheel_noise!r}", "use e.g. 0.05 (5 % per wheel)")
        if not (isinstance(self.bumper_travel_m, int | float)
                and math.isfinite(self.bumper_travel_m)
                and 0.0 < self.bumper_travel_m <= MAX_BUMPER_TRAVEL_M):
            raise ScenarioError(source, "bumper_travel_m", f"must be in (0, "
                                f"{MAX_BUMPER_TRAVEL_M}] m, got {self.bumper_travel_m!r}",
                                "use e.g. 0.002 (2 mm)")
        if not isinstance(self.carried_pose, bool):
            raise ScenarioError(source, "carried_pose", f"must be true or false, got "
                                f"{self.carried_pose!r}", "use true or false")


PRESETS = {
    "exact": Fidelity(),
    "noisy": Fidelity(name="noisy", wheel_noise=0.05, carried_pose=True),
    # a cheap robot on a poor floor: open-loop PWM motors without encoders, a slippery or
    # uneven surface (15 % per wheel per control period), bumper stops as at noisy
    "rough": Fidelity(name="rough", wheel_noise=0.15, carried_pose=True),
}


def parse_fidelity(text: str | None, source: str = "--fidelity") -> Fidelity:
    """``None``/``"exact"``, a preset name, or ``"PRESET,key=value,..."`` / ``"key=value,..."``
    (fields over ``exact``)."""
    if text is None:
        return PRESETS["exact"]
    parts = [p.strip() for p in str(text).split(",") if p.strip()]
    if not parts:
        raise ScenarioError(source, "fidelity", "is empty", f"use one of {', '.join(PRESETS)}")
    base = PRESETS["exact"]
    if "=" not in parts[0]:
        if parts[0] not in PRESETS:
            raise ScenarioError(source, "fidelity", f"unknown preset {parts[0]!r}",
                                f"use one of {', '.join(PRESETS)}, or key=value pairs")
        base = PRESETS[parts[0]]
        parts = parts[1:]
    fields = {f.name: f for f in dataclasses.fields(Fidelity) if f.name != "name"}
    changes: dict[str, object] = {}
    for part in parts:
        key, sep, value = part.partition("=")
        key = key.strip()
        if not sep or key not in fields:
            raise ScenarioError(source, key or part, "is not a fidelity knob",
                                f"use {', '.join(fields)} as key=value")
        if fields[key].type in (bool, "bool"):
            if value.strip().lower() not in ("true", "false", "1", "0"):
                raise ScenarioError(source, key, f"expected true or false, got {value!r}",
                                    f"write {key}=true or {key}=false")
            changes[key] = value.strip().lower() in ("true", "1")
        else:
            try:
                changes[key] = float(value)
            except ValueError:
                raise ScenarioError(source, key, f"expected a number, got {value!r}",
                                    f"write e.g. {key}=0.05") from None
    fid = dataclasses.replace(base, **changes)
    if changes:
        fid = dataclasses.replace(fid, name=f"{base.name}+" if base.name != "exact" else "custom")
    fid.validate(source)
    return fid


def fidelity_from_table(table: dict, source: str) -> Fidelity:
    """A scenario's ``[physics]`` table: ``fidelity = "noisy"`` and/or knobs."""
    table = dict(table)
    preset = table.pop("fidelity", None)
    head = [str(preset)] if preset is not None else []
    text = ",".join(head + [f"{k}={str(v).lower() if isinstance(v, bool) else v}"
                            for k, v in table.items()])
    return parse_fidelity(text or None, f"{source}: [physics]")
