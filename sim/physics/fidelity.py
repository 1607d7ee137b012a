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
  turn in place against it turns. The switch has hysteresis: the robot rests against the
  surface until it has moved more than ``bumper_release_m`` [m] away from every surface;
  within that band a move back toward it presses the bumper again (no new bump before
  ``bumper_travel_m``), where a switch without it would fire anew at each re-touch (wheel
  noise during a turn in place lifts the disc 0.1-6 mm off the surface).
- ``wheel_ratio_sigma``, ``wheelbase_sigma`` [-]: a systematic error per robot, drawn once
  per run from the robot's physics stream (UMBmark's two dominant odometry errors):
  ``E_d = 1 + wheel_ratio_sigma * e`` (right over left wheel diameter; the mean diameter
  is the nominal one, so the left wheel delivers ``2 / (E_d + 1)`` of its command, the right
  ``2 E_d / (E_d + 1)``) and ``E_b = 1 + wheelbase_sigma * e`` (true over nominal
  wheelbase: a turn commanded with the nominal one turns ``1 / E_b`` of it). Typical
  uncalibrated robots: of the order of 1 %.
- ``open_loop``: a primitive is planned once, from the pose the robot *believes* it has
  (its cell's centre and the heading it was last told to take, or the pose estimate with
  localisation), and its commands run without feedback from the true pose. A robot
  without encoders; offsets within the cell and heading errors carry from move to move.
- ``localisation``: the controller and the learner read a pose *estimate*, never the true
  pose. The estimate is dead-reckoned from wheel odometry: each control period the wheels'
  travel as encoders read it (through the robot's nominal geometry, so the per-run bias
  shows as UMBmark's systematic drift), split into rotate-translate-rotate and perturbed
  by the odometry motion model (Thrun et al., *Probabilistic Robotics* 5.4: variances
  ``odometry_rot_rot * rot^2 + odometry_rot_trans * trans^2`` for each rotation,
  ``odometry_trans_trans * trans^2 + odometry_trans_rot * (rot1^2 + rot2^2)`` for the
  translation). Every ``fix_every`` primitives an absolute fix re-anchors it: the true
  pose plus normal errors ``fix_sigma_m`` per axis and ``fix_sigma_rad``. The learner's
  state is the *believed* cell; contacts, the reward and reaching G are the true pose's.
  Needs carried pose (a bump does not teleport a robot to a centre it does not know).
- ``lag_tau_s`` [s], ``command_delay_s`` [s]: command latency. Each wheel's speed follows
  its command through a first-order lag of time constant ``lag_tau_s`` (a motor and its
  speed loop; MRPT's differential-drive simulator uses the same model, tau = 1.8 s on its
  reference robot), and the command reaches the wheels ``command_delay_s`` late (a bus, a
  driver's queue), rounded to whole control periods (at most :data:`MAX_DELAY_PERIODS`).
  The lag is exact for a command held over a period (``keep = exp(-period / tau)``), applied
  once per period: the delivered speed is constant within a period, as every other knob's.
  Wheel speeds and the commands in flight carry from primitive to primitive; a bump stops
  the motors (both are cleared).
- ``slip_rate_hz`` [1/s], ``slip_fraction`` [-], ``slip_duration_s`` [s]: slip events.
  Each wheel that is not slipping starts a slip in a control period with probability
  ``1 - exp(-slip_rate_hz * period)`` (a Poisson process sampled once per period, from one
  normal of the robot's stream per wheel); a slipping wheel delivers ``slip_fraction`` of
  its speed for ``slip_duration_s`` (rounded up to whole periods). A wet patch, dust, a
  wheel lifted by a cable. The odometry of ``localisation`` reads the delivered motion: a
  slip is not an odometry error here (encoders on a slipping wheel would over-count).

What each preset stands for is written beside it in :data:`PRESETS`. Every knob is
deterministic per seed: the noise comes from the generator the env (or the sweep) gives
each robot. ``parse_fidelity("noisy")`` or ``"exact,wheel_noise=0.02"`` (a
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
MAX_BUMPER_RELEASE_M = 0.05  # a switch that stays pressed further off is not a bumper [m]
MAX_BIAS_SIGMA = 0.1  # a 10 % wheel-radius or wheelbase error is a broken robot, not a bias
MAX_ODOMETRY_ALPHA = 1.0  # odometry variance per squared motion; beyond, odometry is noise
MAX_FIX_SIGMA_M = 1.0  # [m]
MAX_FIX_SIGMA_RAD = math.pi / 4  # [rad]
MAX_LAG_TAU_S = 5.0  # a wheel that takes longer to answer is not driving primitives [s]
MAX_DELAY_PERIODS = 8  # commands in flight a robot keeps (the kernel's ring per robot)
MAX_COMMAND_DELAY_S = 1.0  # [s]; also at most MAX_DELAY_PERIODS control periods
MAX_SLIP_RATE_HZ = 10.0  # [1/s]
MAX_SLIP_DURATION_S = 5.0  # [s]
RENAMED = {"rough": "slippery"}  # old preset names: what they were renamed to


@dataclass(frozen=True)
class Fidelity:
    """One rung of the ladder (see the module doc for each knob and what it stands for)."""

    name: str = "exact"
    wheel_noise: float = 0.0  # relative sigma of each wheel's commanded speed, per period [-]
    carried_pose: bool = False  # after a contact the robot stays where it stopped
    bumper_travel_m: float = 0.002  # carried pose: a drive pressing into the surface the
    #   robot rests on reports a new bump after this much travel [m] (a bumper switch)
    bumper_release_m: float = 0.003  # ... and it rests against surfaces until this far from
    #   all of them [m] (the switch's hysteresis; 0: released at once when contact ends)
    wheel_ratio_sigma: float = 0.0  # per-run bias: sigma of E_d - 1, E_d = right/left wheel
    #   diameter (UMBmark), drawn once per run from the robot's physics stream [-]
    wheelbase_sigma: float = 0.0  # per-run bias: sigma of E_b - 1, E_b = actual/nominal
    #   wheelbase, drawn once per run [-]
    open_loop: bool = False  # a primitive is planned once, from the pose the robot believes
    #   it has, and its commands run without feedback from the true pose
    localisation: bool = False  # the controller and the learner read a pose estimate (wheel
    #   odometry, fixes), not the true pose; contacts and rewards stay the true pose's
    odometry_rot_rot: float = 0.0  # alpha1: rotation variance per squared rotation [rad^2/rad^2]
    odometry_rot_trans: float = 0.0  # alpha2: rotation variance per squared distance [rad^2/m^2]
    odometry_trans_trans: float = 0.0  # alpha3: distance variance per squared distance [m^2/m^2]
    odometry_trans_rot: float = 0.0  # alpha4: distance variance per squared rotation [m^2/rad^2]
    fix_every: int = 0  # localisation: an absolute fix every this many primitives (0: never)
    fix_sigma_m: float = 0.0  # the fix's position error, per axis [m]
    fix_sigma_rad: float = 0.0  # the fix's heading error [rad]
    lag_tau_s: float = 0.0  # first-order lag of each wheel's speed on its command [s] (0: none)
    command_delay_s: float = 0.0  # commands reach the wheels this late [s], whole periods
    slip_rate_hz: float = 0.0  # slip events per wheel and second [1/s] (0: none)
    slip_fraction: float = 0.3  # a slipping wheel delivers this fraction of its speed [-]
    slip_duration_s: float = 0.3  # how long a slip lasts [s] (rounded up to whole periods)

    @property
    def label(self) -> str:
        """The name, and the knobs when they differ from the named preset's."""
        base = PRESETS.get(self.name)
        if base is not None and base == self:
            return self.name
        default = Fidelity()
        knobs = ", ".join(f"{f.name}={getattr(self, f.name)}" for f in dataclasses.fields(self)
                          if f.name != "name" and (f.name in _FIRST_KNOBS
                                                   or getattr(self, f.name)
                                                   != getattr(default, f.name)))
        return f"{self.name} ({knobs})"

    @property
    def is_exact(self) -> bool:
        return self == dataclasses.replace(PRESETS["exact"], name=self.name,
                                           bumper_travel_m=self.bumper_travel_m,
                                           bumper_release_m=self.bumper_release_m)

    @property
    def biased(self) -> bool:
        """A per-run wheel bias is drawn (E_d or E_b)."""
        return self.wheel_ratio_sigma > 0.0 or self.wheelbase_sigma > 0.0

    @property
    def hidden_state(self) -> bool:
        """Where the robot stands within its cell is not known to what plans its moves (open
        loop), or its cell itself is an estimate (localisation): the world is not Markov in
        the stochastic model's states, so V* (:mod:`sim.physics.models.stochastic`) is not
        defined at this rung. Latency and slip carry state between primitives too (wheel
        speeds, commands in flight, a slip under way)."""
        return (self.open_loop or self.localisation or self.latency or self.slips)

    @property
    def latency(self) -> bool:
        """The wheels answer late: a lag or a delay (state carried between primitives)."""
        return self.lag_tau_s > 0.0 or self.command_delay_s > 0.0

    @property
    def slips(self) -> bool:
        """Slip events are drawn."""
        return self.slip_rate_hz > 0.0

    def knobs(self) -> dict[str, object]:
        """Every knob by name (what records carry)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}

    def validate(self, source: str = "fidelity") -> None:
        _number(source, "wheel_noise", self.wheel_noise, 0.0, MAX_WHEEL_NOISE,
                "use e.g. 0.05 (5 % per wheel)")
        if not (isinstance(self.bumper_travel_m, int | float)
                and math.isfinite(self.bumper_travel_m)
                and 0.0 < self.bumper_travel_m <= MAX_BUMPER_TRAVEL_M):
            raise ScenarioError(source, "bumper_travel_m", f"must be in (0, "
                                f"{MAX_BUMPER_TRAVEL_M}] m, got {self.bumper_travel_m!r}",
                                "use e.g. 0.002 (2 mm)")
        _number(source, "bumper_release_m", self.bumper_release_m, 0.0, MAX_BUMPER_RELEASE_M,
                "use e.g. 0.003 (3 mm); 0: no hysteresis")
        for key in ("carried_pose", "open_loop", "localisation"):
            if not isinstance(getattr(self, key), bool):
                raise ScenarioError(source, key, f"must be true or false, got "
                                    f"{getattr(self, key)!r}", "use true or false")
        for key in ("wheel_ratio_sigma", "wheelbase_sigma"):
            _number(source, key, getattr(self, key), 0.0, MAX_BIAS_SIGMA,
                    "use e.g. 0.01 (1 %, an uncalibrated robot)")
        for key in ("odometry_rot_rot", "odometry_rot_trans", "odometry_trans_trans",
                    "odometry_trans_rot"):
            _number(source, key, getattr(self, key), 0.0, MAX_ODOMETRY_ALPHA,
                    "use e.g. 0.01 (a variance per squared motion)")
        if not (isinstance(self.fix_every, int) and not isinstance(self.fix_every, bool)
                and 0 <= self.fix_every <= 1_000_000):
            raise ScenarioError(source, "fix_every", f"must be a whole number of primitives "
                                f">= 0, got {self.fix_every!r}", "use e.g. 5 (0: no fixes)")
        _number(source, "fix_sigma_m", self.fix_sigma_m, 0.0, MAX_FIX_SIGMA_M,
                "use e.g. 0.05 (5 cm)")
        _number(source, "fix_sigma_rad", self.fix_sigma_rad, 0.0, MAX_FIX_SIGMA_RAD,
                "use e.g. 0.05 (about 3 degrees)")
        _number(source, "lag_tau_s", self.lag_tau_s, 0.0, MAX_LAG_TAU_S,
                "use e.g. 0.2 (a small robot's motors); 0: no lag")
        _number(source, "command_delay_s", self.command_delay_s, 0.0, MAX_COMMAND_DELAY_S,
                "use e.g. 0.1 (one control period); 0: none")
        _number(source, "slip_rate_hz", self.slip_rate_hz, 0.0, MAX_SLIP_RATE_HZ,
                "use e.g. 0.5 (a slip every 2 s per wheel); 0: none")
        _number(source, "slip_fraction", self.slip_fraction, 0.0, 1.0,
                "use e.g. 0.3 (a slipping wheel delivers 30 %)")
        _number(source, "slip_duration_s", self.slip_duration_s, 0.0, MAX_SLIP_DURATION_S,
                "use e.g. 0.3")
        if (self.slip_rate_hz > 0.0 or self.lag_tau_s > 0.0 or self.command_delay_s > 0.0) \
                and not self.carried_pose:
            key = "slip_rate_hz" if self.slip_rate_hz > 0.0 else (
                "lag_tau_s" if self.lag_tau_s > 0.0 else "command_delay_s")
            raise ScenarioError(source, key, "needs carried_pose=true",
                                "wheels that answer late or slip do not stop on a cell "
                                "centre after a bump: add carried_pose=true")
        if self.localisation and not self.carried_pose:
            raise ScenarioError(source, "localisation", "needs carried_pose=true",
                                "a robot that localises is never placed back on a centre it "
                                "does not know: add carried_pose=true")
        unused = [k for k in ("odometry_rot_rot", "odometry_rot_trans", "odometry_trans_trans",
                              "odometry_trans_rot", "fix_every", "fix_sigma_m", "fix_sigma_rad")
                  if getattr(self, k) and not self.localisation]
        if unused:
            raise ScenarioError(source, unused[0], "has no effect without localisation=true",
                                "add localisation=true, or drop the knob")
        default = Fidelity()
        unused = [k for k in ("slip_fraction", "slip_duration_s")
                  if getattr(self, k) != getattr(default, k) and not self.slips]
        if unused:
            raise ScenarioError(source, unused[0], "has no effect without slip_rate_hz > 0",
                                "add e.g. slip_rate_hz=0.5, or drop the knob")


_FIRST_KNOBS = ("wheel_noise", "carried_pose", "bumper_travel_m")  # always in labels


def delay_periods(fidelity: Fidelity, period_s: float, source: str = "fidelity") -> int:
    """``command_delay_s`` in whole control periods of ``period_s`` [s] (nearest), refused
    beyond :data:`MAX_DELAY_PERIODS` (the commands a robot keeps in flight)."""
    n = round(fidelity.command_delay_s / period_s)
    if n > MAX_DELAY_PERIODS:
        raise ScenarioError(source, "command_delay_s", f"is {n} control periods of "
                            f"{period_s} s; at most {MAX_DELAY_PERIODS} are kept in flight",
                            f"use at most {MAX_DELAY_PERIODS * period_s:g} s, or a longer "
                            "control period")
    return n


def lag_keep(fidelity: Fidelity, period_s: float) -> float:
    """The part of a wheel's speed error left after one control period: exp(-period / tau)
    (0 without a lag: the wheel answers within the period)."""
    return math.exp(-period_s / fidelity.lag_tau_s) if fidelity.lag_tau_s > 0.0 else 0.0


def slip_start_probability(fidelity: Fidelity, period_s: float) -> float:
    """Probability that a wheel not slipping starts a slip in one control period."""
    return -math.expm1(-fidelity.slip_rate_hz * period_s)


def _number(source: str, key: str, value: object, lo: float, hi: float, hint: str) -> None:
    if not (isinstance(value, int | float) and not isinstance(value, bool)
            and math.isfinite(value) and lo <= value <= hi):
        raise ScenarioError(source, key, f"must be in {lo}..{hi}, got {value!r}", hint)


_NOISY = dict(wheel_noise=0.05, carried_pose=True)
_UNCALIBRATED = dict(_NOISY, wheel_ratio_sigma=0.01, wheelbase_sigma=0.01)
PRESETS = {
    # the paper's world: closed-loop primitives to cell centres, a bump places back
    "exact": Fidelity(),
    # motor gain noise on a robot that knows its true pose (feedback until within 2 cm)
    "noisy": Fidelity(name="noisy", **_NOISY),
    # the same on a slippery or uneven floor: 15 % per wheel per control period
    "slippery": Fidelity(name="slippery", wheel_noise=0.15, carried_pose=True),
    # noisy, and every robot (every run) has its own wheel-diameter ratio and wheelbase
    # error, 1 % sigma each: a robot nobody calibrated (UMBmark)
    "uncalibrated": Fidelity(name="uncalibrated", **_UNCALIBRATED),
    # uncalibrated, and the primitives run open loop: planned from the cell centre and the
    # heading the robot was last told to take, no feedback (encoder-less PWM motors; the
    # cell itself is still known, e.g. an overhead camera between moves)
    "open-loop": Fidelity(name="open-loop", **_UNCALIBRATED, open_loop=True),
    # uncalibrated, and the robot knows only its dead-reckoned pose: wheel odometry (the
    # odometry model's alphas, applied per 0.1 s control period; on a noise-free 1 m drive
    # the estimate is off by 2.6 cm along and 2.1 degrees in heading, 1 sigma, measured
    # with the controller steering by it), re-anchored by a fix of 5 cm / 1.7 degrees every
    # 5 primitives (a beacon, a marker seen)
    "localised": Fidelity(name="localised", **_UNCALIBRATED, localisation=True,
                          odometry_rot_rot=0.002, odometry_rot_trans=0.0015,
                          odometry_trans_trans=0.001, odometry_trans_rot=0.0001,
                          fix_every=5, fix_sigma_m=0.05, fix_sigma_rad=0.03),
    # noisy, and the wheels answer late: a first-order lag of 0.2 s on each wheel's speed
    # (a small robot's motors and speed loop) and commands one control period late (0.1 s)
    "latency": Fidelity(name="latency", **_NOISY, lag_tau_s=0.2, command_delay_s=0.1),
    # noisy, and wheels slip now and then: a slip every 10 s per wheel, each 0.3 s long,
    # a slipping wheel delivering 30 % (a dusty or wet floor, a wheel over a cable)
    "slip": Fidelity(name="slip", **_NOISY, slip_rate_hz=0.1, slip_fraction=0.3,
                     slip_duration_s=0.3),
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
        if parts[0] in RENAMED:
            raise ScenarioError(source, "fidelity", f"the preset {parts[0]!r} was renamed "
                                f"{RENAMED[parts[0]]!r}: it models wheel noise on a robot "
                                "that knows its true pose, not open-loop motors",
                                f"use {RENAMED[parts[0]]!r}, or 'open-loop' for motors "
                                "without feedback")
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
        if key in changes:  # two values for one knob: which was meant?
            raise ScenarioError(source, key, "is given twice", f"give {key} once")
        if fields[key].type in (bool, "bool"):
            if value.strip().lower() not in ("true", "false", "1", "0"):
                raise ScenarioError(source, key, f"expected true or false, got {value!r}",
                                    f"write {key}=true or {key}=false")
            changes[key] = value.strip().lower() in ("true", "1")
        elif fields[key].type in (int, "int"):
            try:
                changes[key] = int(value)
            except ValueError:
                raise ScenarioError(source, key, f"expected a whole number, got {value!r}",
                                    f"write e.g. {key}=5") from None
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
