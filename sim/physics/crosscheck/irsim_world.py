"""The same primitives in IR-SIM, an independent simulator: our controller, their physics.

Why: the batched kernel is checked against the reference world (Chipmunk), but both use
this project's geometry and contact rules. IR-SIM (Han et al., ``pip install ir-sim``) has
its own: an Euler step of the unicycle model with velocity noise, collision as a Shapely
intersection of the robot's disc with each obstacle, and a robot that stops where a
collision is found. Driving the same controller (:func:`plan_commands`: the same legs,
the same per-period commands, the same re-planning from the measured pose) there and
comparing outcomes says whether what the grid and this project's physics agree on is the
physics, or the implementation.

The mapping, one knob at a time:

- a control period is ``SUBSTEPS`` IR-SIM steps of ``period / SUBSTEPS`` with the period's
  command held (a contact is found within a centimetre);
- wheel noise: IR-SIM draws normal noise on (v, omega) every step with standard
  deviations ``sqrt(a0 v^2 + a1 w^2)`` and ``sqrt(a2 v^2 + a3 w^2)``. Per-wheel noise of
  relative sigma s over a period gives a forward speed variance ``s^2 v^2 / 2 +
  s^2 b^2 w^2 / 8`` and a yaw-rate variance ``2 s^2 v^2 / b^2 + s^2 w^2 / 2`` (b the
  wheelbase); IR-SIM's per-step draws average over ``SUBSTEPS`` steps, so each alpha is
  ``SUBSTEPS`` times that (:func:`calibrated_alpha`). The means and variances of a period's
  motion match; the two wheels' correlation within a period does not exist there;
- a bump: IR-SIM reports a collision after the step that made it; the robot goes back to
  the pose before that step, then creeps on by halves of that step's command (each that
  collides undone), ``CREEP`` times: it stops within 1/32 of a sub-step (a fraction of a
  millimetre) short of the surface, never inside it. At
  ``exact`` it is then placed on its start cell's centre, as here; with carried pose it
  stays. IR-SIM's robot has no bumper travel and no hysteresis: any new contact is a bump;
- the rungs IR-SIM has no model of (bias, open loop, localisation, latency, slip) are
  refused (:data:`SUPPORTED`).
"""

from __future__ import annotations

import math
import sys
import tempfile
from pathlib import Path

import numpy as np

from sim.errors import InputError
from sim.grid.actions import ACTION_DELTAS, ACTION_HEADINGS
from sim.grid.discretiser import Discretiser
from sim.physics.drive_profiles import DriveLimits, profiles
from sim.physics.fidelity import Fidelity
from sim.physics.kernel.sweep import static_geometry
from sim.physics.motion import at_target, cell_of, plan_commands
from sim.physics.static import PhysicsConfig
from sim.scenario import Scenario

CREEP = 5  # halvings of the colliding step a bumped robot creeps on by
SUBSTEPS = 5  # IR-SIM steps per control period (a contact is found within 1 cm at 0.5 m/s)
SUPPORTED = "exact, or wheel_noise and carried_pose only (e.g. noisy, slippery)"


class CrosscheckError(InputError):
    """IR-SIM is missing, or the rung has knobs it cannot model."""


def check_rung(fid: Fidelity) -> None:
    """Refuse a rung IR-SIM has no model of, naming the knob."""
    extra = [k for k, on in (("wheel_ratio_sigma/wheelbase_sigma", fid.biased),
                             ("open_loop", fid.open_loop), ("localisation", fid.localisation),
                             ("lag_tau_s/command_delay_s", fid.latency),
                             ("slip_rate_hz", fid.slips)) if on]
    if extra:
        raise CrosscheckError("command line", "--fidelity", f"{fid.label} has "
                              f"{', '.join(extra)}, which IR-SIM has no model of",
                              f"use {SUPPORTED}")


def calibrated_alpha(wheel_noise: float, wheel_base_m: float,
                     substeps: int = SUBSTEPS) -> list[float]:
    """IR-SIM's (a0, a1, a2, a3) for per-wheel noise of relative sigma ``wheel_noise`` per
    control period (see the module doc)."""
    s2, b = wheel_noise ** 2, wheel_base_m
    return [substeps * s2 / 2, substeps * s2 * b * b / 8, substeps * 2 * s2 / (b * b),
            substeps * s2 / 2]


def _world_yaml(sc: Scenario, fid: Fidelity, period_s: float) -> str:
    """IR-SIM's world file for the scenario: the arena's boundary, its circles and its
    blocked-cell boxes, one diff-drive disc robot."""
    g = static_geometry(sc)
    w, h = sc.width_m, sc.height_m
    lim = DriveLimits.from_robot(sc.robot)
    noise = fid.wheel_noise > 0.0
    alpha = calibrated_alpha(fid.wheel_noise, lim.wheel_base_m) if noise else [0, 0, 0, 0]
    v_max = 2.0 * lim.v_max_m_s
    w_max = 4.0 * lim.v_max_m_s / lim.wheel_base_m
    lines = ["world:", f"  height: {h!r}", f"  width: {w!r}",
             f"  step_time: {period_s / SUBSTEPS!r}", f"  sample_time: {period_s!r}",
             "  offset: [0, 0]", "  collision_mode: 'stop'",
             "robot:",
             f"  - kinematics: {{name: 'diff', noise: {str(noise).lower()}, "
             f"alpha: [{', '.join(repr(float(a)) for a in alpha)}]}}",
             f"    shape: {{name: 'circle', radius: {sc.robot.radius_m!r}}}",
             "    state: [0.0, 0.0, 0.0]",
             f"    vel_min: [{-v_max!r}, {-w_max!r}]", f"    vel_max: [{v_max!r}, {w_max!r}]",
             "obstacle:",
             f"  - shape: {{name: 'linestring', vertices: [[0, 0], [{w!r}, 0], [{w!r}, {h!r}],"
             f" [0, {h!r}], [0, 0]]}}",
             "    state: [0, 0, 0]"]
    for x, y, r in g.circles.tolist():
        lines += [f"  - shape: {{name: 'circle', radius: {r!r}}}", f"    state: [{x!r}, {y!r}, 0]"]
    for x0, y0, x1, y1 in g.boxes.tolist():
        lines += [f"  - shape: {{name: 'polygon', vertices: [[{x0!r}, {y0!r}], [{x1!r}, {y0!r}], "
                  f"[{x1!r}, {y1!r}], [{x0!r}, {y1!r}]]}}", "    state: [0, 0, 0]"]
    return "\n".join(lines) + "\n"


def _irsim():
    """IR-SIM, imported quietly: at import it tries GUI backends for matplotlib, printing a
    line for each that fails, and switches the process's backend. The lines are dropped; a
    backend the caller had already chosen is put back (nothing here draws, or imports
    matplotlib itself: ``sim`` does not draw)."""
    import contextlib
    import io

    mpl = sys.modules.get("matplotlib")
    backend = mpl.get_backend() if mpl is not None else None
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            import irsim  # optional (rnhql[crosscheck])
        from loguru import logger  # IR-SIM's logger: a line per collision otherwise
    except ImportError:
        raise CrosscheckError("rnhql crosscheck", "IR-SIM", "is not installed (an optional "
                              "extra)", "pip install 'rnhql[crosscheck]' (or pip install "
                              "ir-sim)") from None
    finally:
        if mpl is not None:
            with contextlib.suppress(Exception):
                mpl.use(backend)
    logger.disable("irsim")
    return irsim


class IrSimRobot:
    """One robot in an IR-SIM world of the scenario, driven by this project's controller."""

    def __init__(self, sc: Scenario, fid: Fidelity, config: PhysicsConfig | None = None,
                 seed: int = 0) -> None:
        check_rung(fid)
        irsim = _irsim()
        self.scenario, self.fidelity = sc, fid
        self.config = cfg = config or PhysicsConfig()
        self.disc = Discretiser.from_scenario(sc)
        self.period = cfg.control_period_s
        self.profiles = profiles(DriveLimits.from_robot(sc.robot), self.period, sc.cell_size_m)
        self.timeout_periods = math.ceil(cfg.timeout_s / self.period - 1e-9)
        with tempfile.TemporaryDirectory(prefix="rnhql-irsim-") as d:
            path = Path(d) / "world.yaml"
            path.write_text(_world_yaml(sc, fid, self.period))
            self.env = irsim.make(str(path), display=False, disable_all_plot=True, seed=seed)
        self.robot = self.env.robot
        self.steps = 0

    def reseed(self, seed: int) -> None:
        self.env.set_random_seed(seed)

    @property
    def pose(self) -> tuple[float, float, float]:
        x, y, th = (float(v) for v in np.asarray(self.robot.state).ravel()[:3])
        return x, y, th

    def place(self, x: float, y: float, th: float) -> None:
        self.robot.set_state([x, y, th])
        self.robot.stop_flag = self.robot.collision_flag = False

    def _period(self, v: float, w: float) -> bool:
        """One control period's command held for ``SUBSTEPS`` steps; True at a collision
        (the robot put back on the pose before the step that made it)."""
        for _ in range(SUBSTEPS):
            before = self.pose
            self.env.step(np.array([[v], [w]]))
            self.steps += 1
            if self.robot.collision_flag:
                self.place(*before)
                frac = 0.5
                for _ in range(CREEP):  # on toward the surface, never into it
                    before = self.pose
                    self.env.step(np.array([[v * frac], [w * frac]]))
                    if self.robot.collision_flag:
                        self.place(*before)
                    frac *= 0.5
                return True
        return False

    def drive(self, action: int) -> tuple[bool, bool, int]:
        """Grid ``action`` from the robot's pose: (bumped, reached, the cell it ends in), by
        the rules of :meth:`sim.physics.reference.controller.PrimitiveController.run`."""
        cfg, disc = self.config, self.disc
        x, y, th = self.pose
        ix, iy = cell_of(x, y, disc.cell_size_m, disc.nx, disc.ny)
        dx, dy = ACTION_DELTAS[action]
        tx, ty = disc.cell_centre(ix + dx, iy + dy)
        heading = ACTION_HEADINGS[action]
        periods = 0
        bumped = reached = False
        while True:
            _, cmds = plan_commands(x, y, th, tx, ty, heading, cfg.tolerance_m, self.period,
                                    *self.profiles)
            if not cmds.shape[0]:
                reached = True
                break
            for vx, vy, w in cmds.tolist():
                periods += 1
                if self._period(math.hypot(vx, vy), w):
                    bumped = True
                    break
            x, y, th = self.pose
            if bumped:
                if not self.fidelity.carried_pose:
                    self.place(*disc.cell_centre(ix, iy), th)
                break
            if at_target(x, y, th, tx, ty, heading, cfg.tolerance_m, cfg.tolerance_rad):
                reached = True
                break
            if periods >= self.timeout_periods:
                break
        x, y, _ = self.pose
        return bumped, reached, disc.state_of(x, y)
