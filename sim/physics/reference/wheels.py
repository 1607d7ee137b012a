"""What the reference world's wheels carry between control periods (:class:`WheelState`;
the kernel keeps the same in its records). Their rules, the diff drive's kinematics and a
command as the wheels deliver it, live below both worlds in :mod:`sim.physics.motion`.
"""

from __future__ import annotations

from sim.physics.motion import (  # noqa: F401 (their home was here: re-exported)
    lag_wheel,
    slip_step,
    twist_to_wheels,
    wheel_twist,
    wheels_to_twist,
    wheels_twist,
)


class WheelState:
    """What the motors carry from one control period to the next at the latency and slip
    rungs (:mod:`sim.physics.fidelity`): each wheel's lagged speed [m/s], the wheel commands
    sent and not yet delivered, each wheel's slip time left [s]. All at rest when placed."""

    __slots__ = ("left", "right", "sent", "slip_left", "slip_right")

    def __init__(self) -> None:
        self.left = self.right = 0.0
        self.sent: list[tuple[float, float]] = []
        self.slip_left = self.slip_right = 0.0
