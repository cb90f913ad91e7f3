"""Time integration of a manoeuvring model with a rudder servo and rudder commands.

One integrator flies every model (the MMG simulator and every identified Abkowitz model) and
every manoeuvre, so that a comparison between them differs only in the dynamics (identified
models fly in a compiled copy of its loop, :mod:`sindyship._flights_compiled`, with the same
numbers).  The state is ``[u, v, r, x, y, psi, delta]`` in SI units (body-fixed u, v [m/s],
yaw rate r [rad/s], earth-fixed x north and y east [m], heading psi [rad], actual rudder angle
delta [rad]).

Dynamics are any object with ``accelerations(u, v, r, delta, psi) -> (du/dt, dv/dt, dr/dt)``
(vectorised over numpy arrays), a ``ship`` (for L, U0 and the servo) and optionally a
``current`` (north, east) [m/s].  Several manoeuvres of one model are integrated together as
a batch: the right-hand side is evaluated on arrays, one column per manoeuvre.

The scheme is the classical fourth-order Runge-Kutta method on a fixed step that divides the
sample interval.  Rudder commands are piecewise constant: a step is split exactly at a
scheduled change (spiral steps, a random sequence, a pull-out) and at a heading event (the
zig-zag check angle), located by cubic Hermite interpolation of the heading inside the step.
A member whose state leaves the plausible range stops, and the time it diverged is reported
(see :func:`diverged`).
"""

from __future__ import annotations

from .integrator import default_step, integrator_for, servo_of, simulate_batch
from .kernels import (
    N_STATE,
    ChannelSeries,
    ConstantCommand,
    FeedbackCommand,
    PrescribedRudder,
    RudderCommand,
    SimulationResult,
    StepCommand,
    ZigZagCommand,
    _hermite,  # noqa: F401  (the benchmarks and tests use it)
    _Integrator,  # noqa: F401
    diverged,
    integrate,
)
from .recorded import RecordedZigZag

__all__ = [
    "N_STATE",
    "ChannelSeries",
    "ConstantCommand",
    "FeedbackCommand",
    "PrescribedRudder",
    "RecordedZigZag",
    "RudderCommand",
    "SimulationResult",
    "StepCommand",
    "ZigZagCommand",
    "default_step",
    "diverged",
    "integrate",
    "integrator_for",
    "servo_of",
    "simulate_batch",
]
