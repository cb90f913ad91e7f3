"""A zig-zag flown as a logged trial steered it (closed loop, each leg's own rudder angle)."""

from __future__ import annotations

from .kernels import ZigZagCommand


class RecordedZigZag(ZigZagCommand):
    """A closed-loop zig-zag whose legs hold the rudder angles a logged trial held.

    The reversals come from the flight's own heading at the check angle, as in any zig-zag;
    leg k holds ``levels[k]`` (the last one thereafter), so plateaus a degree off the nominal
    angle are flown as they were steered.

    Examples
    --------
    >>> import numpy as np
    >>> command = RecordedZigZag(0.17, 0.17, 1, levels=(0.16, 0.18))
    >>> command.reset(np.zeros(7))
    >>> command.value(0.0, None), (command.on_event(), command.value(9.0, None))[1]
    (0.16, -0.18)
    """

    def __init__(self, rudder: float, check: float, first_sign: int = 1, *,
                 levels: tuple[float, ...] = ()):
        super().__init__(rudder, check, first_sign)
        self.levels = tuple(levels)
        self.leg = 0  # the leg flown: the reversals so far

    def reset(self, state0):
        super().reset(state0)
        self.leg = 0

    def value(self, t, state):
        if not self.levels:
            return super().value(t, state)
        return self.sign * self.levels[min(self.leg, len(self.levels) - 1)]

    def on_event(self):
        super().on_event()
        self.leg += 1

