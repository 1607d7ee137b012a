"""The reference controller: grid actions driven as motion primitives, every step through
Chipmunk.

The kinematics, a leg's plan and commands and the end-of-leg test live below this room, in
:mod:`sim.physics.motion` (the one definition of each, which the batched kernel calls too,
so their plans agree bit for bit).

Why discrete profiles: the wheel commands change once per control period ``T``, by at
most ``a_max * T``, never beyond ``v_max``. For a distance ``D`` the profile is the fewest
periods whose largest admissible trapezoid covers ``D``, scaled down uniformly to cover it
exactly (scaling keeps every limit). The robot tracks the control body exactly while the
joints' force limits are not reached (:mod:`sim.physics.reference.world`), so in free space a
primitive lands on the cell centre to rounding error with no feedback; the controller
re-plans from the measured pose when something disturbed the robot.

A primitive: turn in place to face the centre of the neighbouring cell (this *is* the
action's cardinal heading when the robot stands on its cell centre, and it keeps the
drive a straight line when it does not), stop, drive straight to that centre, stop. It
ends within ``tolerance_m`` / ``tolerance_rad`` of the centre / the cardinal heading, at
a contact, or at ``timeout_s`` (checked between legs).

Return to start after a contact (``exact``): the robot is *placed* back on the centre of
the cell it started from, at rest, keeping its heading: driving back would retrace the
segment it just drove, doubling the cost of every bump without telling the learner
anything; the grid's "the agent stays" is what the placement reproduces (a placement is
not a reset: the same actions still replay bit for bit). The knobs above ``exact``
(:mod:`sim.physics.fidelity`) are :meth:`PrimitiveController.run`'s rules.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from sim.grid.actions import ACTION_DELTAS, ACTION_HEADINGS
from sim.grid.discretiser import Discretiser
from sim.physics.drive_profiles import DriveLimits, profiles
from sim.physics.fidelity import Fidelity, delay_periods, lag_keep, slip_start_probability
from sim.physics.motion import (  # noqa: F401 (their home was here: re-exported)
    MIN_TURN_RAD,
    SETTLE_M_S,
    Leg,
    PrimitiveOutcome,
    at_target,
    cell_of,
    lag_wheel,
    leg_command,
    plan_commands,
    plan_leg,
    slip_step,
    twist_to_wheels,
    wheel_twist,
    wheels_to_twist,
    wheels_twist,
    wrap_angle,
)
from sim.physics.static import DEEPER_M

if TYPE_CHECKING:
    from sim.physics.reference.world import PhysicsConfig, PhysicsWorld
    from sim.scenario import Scenario

class PrimitiveController:
    """Drives grid actions as motion primitives in a
    :class:`sim.physics.reference.world.PhysicsWorld`:
    the **reference** every fidelity knob of the batched kernel is tested against (every
    step through ``cpSpaceStep``). One per scenario, config and fidelity; any world.

    At ``exact`` a leg's commands run in :meth:`PhysicsWorld.drive`'s tight loop, with the
    leg's swept-disc guard cast once (the time-of-impact clamp that keeps a step from
    carrying the disc deeper than ``contact_depth_m`` into anything). Above ``exact`` each
    step is guarded by its own cast and the knobs' rules apply (:meth:`run`).
    """

    def __init__(self, scenario: Scenario, config: PhysicsConfig,
                 fidelity: Fidelity | None = None) -> None:
        self.disc = Discretiser.from_scenario(scenario)
        self.limits = lim = DriveLimits.from_robot(scenario.robot)
        self.config = config
        self.fidelity = fid = fidelity or Fidelity()
        fid.validate()
        if fid.biased or fid.open_loop or fid.localisation:
            raise ValueError(
                f"the reference controller drives wheel noise and carried pose only, not "
                f"{fid.label}: the bias, open-loop and localisation knobs live in the batched "
                "kernel and are tested against their analytic models (tests/test_ladder_knobs.py)")
        period = config.control_period_s
        self._period = period
        self._dt = config.dt_s
        self._keep = lag_keep(fid, period)
        self._delay = delay_periods(fid, period)
        self._slip_p = slip_start_probability(fid, period)
        self._split_turn_rad = config.tolerance_rad if fid.latency else math.inf
        self.profiles = profiles(lim, period, scenario.cell_size_m)
        self._tol_m = config.tolerance_m
        self._tol_rad = config.tolerance_rad
        self._timeout_steps = math.ceil(config.timeout_s / config.dt_s - 1e-9)

    def plan_leg(self, pose: tuple[float, float, float], target: tuple[float, float],
                 heading: float) -> tuple[list[tuple[float, float, float]], float]:
        """Twists (vx [m/s], vy [m/s], omega [rad/s]) per control period, and the drive length
        (:func:`plan_leg`, :func:`leg_command`). Each motion ends with a zero twist."""
        leg, cmds = plan_commands(*pose, *target, heading, self._tol_m, self._period,
                                  *self.profiles)
        return [tuple(c) for c in cmds.tolist()], leg.dist

    def run(self, world: PhysicsWorld, action: int,
            rng: np.random.Generator | None = None) -> PrimitiveOutcome:
        """Drive grid ``action`` from the robot's current pose; ``world.trajectory`` becomes
        the start pose, then the pose after every physics step.

        The fidelity's rules (the reference of :func:`sim.physics.kernel.primitive.advance`):

        - wheel noise: each control period's twist is delivered by :func:`wheel_twist` with
          the next two normals of ``rng`` (left, right), along the chord of the arc it turns
          through (:func:`sim.physics.motion.held_twist_velocity`); every step is guarded by
          its own cast (:meth:`PhysicsWorld.before_step`);
        - carried pose: a contact stops the robot where it is, at rest, resting against the
          surface (``world.resting``); see :meth:`_held_step` for the steps that follow.
          Without it a bump places the robot back on its start cell's centre; above
          ``exact`` that centre may overlap a shape (noise lets a robot stop within
          tolerance of a centre that is not clear): then it rests there.
        """
        fid, disc = self.fidelity, self.disc
        if (fid.wheel_noise > 0.0 or fid.slips) and rng is None:
            raise ValueError("this fidelity has wheel noise: pass rng")
        x, y, th = pose = world.pose
        ix, iy = cell_of(x, y, disc.cell_size_m, disc.nx, disc.ny)
        dx, dy = ACTION_DELTAS[action]
        tx, ty = disc.cell_centre(ix + dx, iy + dy)
        heading = ACTION_HEADINGS[action]
        world.trajectory = traj = [pose]
        steps0, n_contacts0 = world.steps, len(world.contacts)
        world.solve_contacts = fid.is_exact  # above it the rule holds the robot, not the solver
        self._press = 0.0  # carried pose: the bumper's travel this primitive [m]
        bumped = reached = False
        while True:
            leg, cmds = plan_commands(*pose, tx, ty, heading, self._tol_m, self._period,
                                      *self.profiles, self._split_turn_rad)
            if not cmds.shape[0]:  # nothing left to do (only when already exactly on target)
                reached = True
                break
            commands = [tuple(c) for c in cmds.tolist()]
            if fid.is_exact:
                guard = (world.cast_free_distance(x, y, tx, ty, leg.dist)
                         if leg.ndrive > 0 else None)
                bumped = world.drive(commands, guard, traj)
            else:
                bumped = self._drive_noisy(world, commands, leg.nturn, rng)
            x, y, th = pose = world.pose
            if bumped:
                if fid.carried_pose:
                    world.place(x, y, th, resting=True)
                else:  # above exact a start centre may overlap a shape: it rests there
                    world.place(*disc.cell_centre(ix, iy), th)
                    world.resting = not fid.is_exact and world.overlap_m() > 0.0
                pose = world.pose
                break
            if at_target(x, y, th, tx, ty, heading, self._tol_m, self._tol_rad):
                reached = True
                break
            if world.steps - steps0 >= self._timeout_steps:
                break
        steps = world.steps - steps0
        cell = disc.state_of(pose[0], pose[1])
        return PrimitiveOutcome(
            state=cell, bumped=bumped, reached=reached, timeout=not (bumped or reached),
            steps=steps, contacts=len(world.contacts) - n_contacts0, cell=cell)

    def _drive_noisy(self, world: PhysicsWorld, commands: list[tuple[float, float, float]],
                     nturn: int, rng: np.random.Generator | None) -> bool:
        """One leg above ``exact``; True when it ended in a bump."""
        fid, sub = self.fidelity, self.config.substeps
        sigma, base = fid.wheel_noise, self.limits.wheel_base_m
        traj = world.trajectory
        for k, (vx, vy, w) in enumerate(commands):
            e = rng.standard_normal(2) if sigma > 0.0 else (0.0, 0.0)
            if fid.latency or fid.slips:
                z = rng.standard_normal(2) if fid.slips else (0.0, 0.0)
                world.set_twist(*self._deliver(world, vx, vy, w, e, z))
            else:
                world.set_twist(*wheel_twist(vx, vy, w, world.pose[2], world.velocity[2],
                                             self._dt, self._period, e[0], e[1], sigma,
                                             base))
            turning = 0 < nturn and k <= nturn  # the turn and the stop after it
            if self._steps(world, turning, sub, traj):
                return True
        if fid.latency:  # hold a stop until the wheels settle (SETTLE_M_S)
            held = 0
            while held < self._delay or max(abs(world.wheels.left),
                                             abs(world.wheels.right)) > SETTLE_M_S:
                e = rng.standard_normal(2) if sigma > 0.0 else (0.0, 0.0)
                z = rng.standard_normal(2) if fid.slips else (0.0, 0.0)
                world.set_twist(*self._deliver(world, 0.0, 0.0, 0.0, e, z))
                held += 1
                if self._steps(world, False, sub, traj):
                    return True
        return False

    def _steps(self, world: PhysicsWorld, turning: bool, sub: int, traj: list) -> bool:
        """A control period's ``sub`` physics steps, each guarded by its own cast; True when
        one ended in a bump."""
        for _ in range(sub):
            if (self._held_step(world, turning) if self.fidelity.carried_pose or world.resting
                    else world.advance(1, traj)):
                return True
        return False

    def _deliver(self, world: PhysicsWorld, vx: float, vy: float, w: float, e: Any,
                 z: Any) -> tuple[float, float, float]:
        """One period's twist through latency and slip (the kernel's rule, see
        :func:`sim.physics.kernel.primitive.advance`): the command joins those in flight, the
        one sent ``delay`` periods ago reaches the motors, each wheel lags toward it, slips
        or not, and :func:`wheels_twist` delivers it with the wheel noise ``e``."""
        fid, wheels, base = self.fidelity, world.wheels, self.limits.wheel_base_m
        vl, vr = twist_to_wheels(math.hypot(vx, vy), w, base)
        if fid.latency:
            wheels.sent.append((vl, vr))
            vl, vr = (wheels.sent[-1 - self._delay] if len(wheels.sent) > self._delay
                      else (0.0, 0.0))
            del wheels.sent[:-1 - self._delay]
            wheels.left = vl = lag_wheel(vl, wheels.left, self._keep)
            wheels.right = vr = lag_wheel(vr, wheels.right, self._keep)
        f_left = f_right = 1.0
        if fid.slips:
            f_left, wheels.slip_left = slip_step(wheels.slip_left, z[0], self._slip_p,
                                                 fid.slip_duration_s, self._period,
                                                 fid.slip_fraction)
            f_right, wheels.slip_right = slip_step(wheels.slip_right, z[1], self._slip_p,
                                                   fid.slip_duration_s, self._period,
                                                   fid.slip_fraction)
        return wheels_twist(vl, vr, world.pose[2], world.velocity[2], self._dt, self._period,
                            e[0], e[1], fid.wheel_noise, base, 1.0, 1.0,
                            1.0, f_left, f_right)

    def _held_step(self, world: PhysicsWorld, turning: bool) -> bool:
        """One guarded step with carried pose, or of a robot resting against a surface;
        True when a bump ended it.

        While the robot rests against a surface (``world.resting``), a step that leaves it
        deeper in (by more than 1e-12 m) is held (:meth:`PhysicsWorld.hold`): it keeps only
        its motion along the surface, and on a drive (not while ``turning``) the part taken
        away presses the bumper; at ``bumper_travel_m`` it is a bump, and the robot stays
        where it was before that step. A step that leaves it touching nothing, further than
        ``bumper_release_m`` from every shape, ends the resting (the switch's hysteresis).
        Otherwise a contact begins when Chipmunk's narrow phase finds the disc, at
        the pose the step leaves, touching a shape it did not touch at the step's start
        (Chipmunk's own ``begin`` would fire at the pose before the hold).
        """
        before = world.touching_shapes() if world.resting else []
        depth0 = world.deepest(before)
        x0, y0, th0 = world.pose
        world.before_step()
        world.step(None, book=False)
        if world.resting:
            depth1 = world.deepest(world.touching_shapes())
            if depth1 > depth0 + DEEPER_M:
                into = world.hold(x0, y0)
                if not turning:
                    self._press += into
                    if self._press >= self.fidelity.bumper_travel_m:  # the bumper reports
                        world.place(x0, y0, th0, resting=True)
                        world.trajectory.append(world.pose)
                        world.record_contacts(world.touching_shapes())
                        return True
            elif depth1 <= 0.0 and not (self.fidelity.bumper_release_m > 0.0 and world.within_m(
                    self.fidelity.bumper_release_m)):
                world.resting = False
        world.trajectory.append(world.pose)
        known = {info.shape for info in before}
        found = [info for info in world.touching_shapes() if info.shape not in known]
        world.record_contacts(found)
        return bool(found)
