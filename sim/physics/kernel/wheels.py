"""A control period's command as the wheels deliver it above ``exact``, per robot record:
latency's commands in flight and lag, slip events, then noise and bias
(:func:`sim.physics.motion.wheels_twist`). The reference world's rule is
:meth:`sim.physics.reference.controller.PrimitiveController._deliver`; the two are tested
field by field (``tests/test_physics_batch.py``)."""

from __future__ import annotations

import math

from numba import njit

from sim.physics.kernel.state import SENT_RING
from sim.physics.motion import lag_wheel, slip_step, twist_to_wheels, wheels_twist


@njit(cache=True)
def deliver(rb, p, vx, vy, w, e_left, e_right, z_left, z_right):
    """One period's twist through latency and slip (as
    :meth:`sim.physics.reference.controller.PrimitiveController._deliver`): the wheel
    command joins those in flight (``rb.sent``), the one sent ``p.delay`` periods ago reaches
    the motors (nothing before that: they stand), each wheel lags toward it, slips or not
    (:func:`slip_step`), and :func:`wheels_twist` adds the noise and the per-run bias."""
    vl, vr = twist_to_wheels(math.hypot(vx, vy), w, p.wheel_base_m)
    if p.latency:
        slot = rb.nsent % SENT_RING
        rb.sent[slot, 0], rb.sent[slot, 1] = vl, vr
        rb.nsent += 1
        if rb.nsent > p.delay:
            back = (rb.nsent - 1 - p.delay) % SENT_RING
            vl, vr = rb.sent[back, 0], rb.sent[back, 1]
        else:
            vl = vr = 0.0
        rb.wl = vl = lag_wheel(vl, rb.wl, p.lag_keep)
        rb.wr = vr = lag_wheel(vr, rb.wr, p.lag_keep)
    f_left = f_right = 1.0
    if p.slips:
        f_left, rb.slip_l = slip_step(rb.slip_l, z_left, p.slip_p, p.slip_duration_s, p.period,
                                      p.slip_fraction)
        f_right, rb.slip_r = slip_step(rb.slip_r, z_right, p.slip_p, p.slip_duration_s,
                                       p.period, p.slip_fraction)
    return wheels_twist(vl, vr, rb.th, rb.w, p.dt, p.period, e_left, e_right, p.wheel_noise,
                        p.wheel_base_m, rb.gain_l, rb.gain_r, rb.base_k, f_left, f_right)
