"""Identified models fly through the compiled loop exactly as the kernel flies them."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sindyship._forces_compiled import COMPILED
from sindyship.flights import _Stacked
from sindyship.library import TermLibrary
from sindyship.manoeuvres import Manoeuvre, fly
from sindyship.mmg import MMGModel
from sindyship.model import AbkowitzModel, paper_model
from sindyship.simulation import (
    ConstantCommand,
    FeedbackCommand,
    PrescribedRudder,
    RecordedZigZag,
    StepCommand,
    ZigZagCommand,
    default_step,
    integrate,
    integrator_for,
    simulate_batch,
)
from sindyship.trajectory import Trajectory

pytestmark = pytest.mark.skipif(not COMPILED, reason="numba is not installed")


def _model(kcs, *, extras: bool, signal: str = "actual", scale_n_r: float = 1.0):
    """The paper's LS model; with ``extras`` also a recorded channel, the rudder's rate and
    the position in its terms."""
    base = paper_model(kcs)
    terms = {dof: [t.text for t in base.library.terms[dof]] for dof in "XYN"}
    coefficients = {dof: dict(base.coefficients[dof]) for dof in "XYN"}
    coefficients["N"]["r"] *= scale_n_r
    if extras:
        terms["Y"] += ["depth", "delta_rate"]
        terms["N"] += ["x", "y"]
        coefficients["Y"].update(depth=2e-5, delta_rate=-1e-3)
        coefficients["N"].update(x=1e-9, y=-2e-9)
    library = TermLibrary("compiled-flights", "prime-I", "", terms)
    return AbkowitzModel(kcs, library, coefficients, rudder_signal=signal)


def _commands(record: Trajectory):
    """One command of every kind the loop flies."""
    degree = math.radians(1.0)
    return [ConstantCommand(20 * degree),
            StepCommand([0.0, 33.3, 90.05, 150.0], [5 * degree, -15 * degree, 0.0, 25 * degree]),
            ZigZagCommand(10 * degree, 10 * degree, 1),
            RecordedZigZag(20 * degree, 20 * degree, -1, levels=(19 * degree, 21.5 * degree)),
            PrescribedRudder(record.t, record["delta"])]


def _both(dynamics, commands, t, state0, step=None):
    """The kernel's flights and the compiled loop's, of the same batch."""
    h = default_step(dynamics.ship) if step is None else step
    reference = integrate(integrator_for(dynamics, commands), commands, t, state0, h, True,
                          dynamics.ship.L, dynamics.ship.U0)
    compiled = dynamics.fly_compiled(integrator_for(dynamics, commands), commands, t, state0,
                                     h, True, None)
    assert compiled is not None  # the loop flew them
    return reference, compiled


def _assert_same(reference, compiled, L):
    for ref, out in zip(reference, compiled, strict=True):
        assert ref.diverged_at == out.diverged_at
        np.testing.assert_array_equal(np.isnan(ref.states), np.isnan(out.states))
        scale = np.array([1.0, 1.0, 1.0, L, L, 1.0, 1.0])[:, None]  # positions against L
        np.testing.assert_allclose(out.states / scale, ref.states / scale, rtol=0, atol=1e-11)
        np.testing.assert_allclose(out.delta_c, ref.delta_c, rtol=0, atol=1e-12)


@pytest.fixture(scope="module")
def random_run(kcs):
    (run,) = fly(MMGModel(kcs), [Manoeuvre("random", rudder=25, duration=400, seed=3)])
    return run


@pytest.mark.parametrize("signal", ["actual", "commanded"])
def test_every_command_flies_as_the_kernel_flies_it(kcs, random_run, signal):
    model = _model(kcs, extras=True, signal=signal)
    dynamics = model.dynamics({"depth": 30.0})
    commands = _commands(random_run)
    t = np.arange(0.0, 400.5, 0.5)  # outputs inside steps: the Hermite interpolant
    state0 = random_run.state()[:, 0]
    reference, compiled = _both(dynamics, commands, t, state0)
    _assert_same(reference, compiled, kcs.L)
    # the zig-zags reversed several times, the replay kept its record's rudder
    assert np.sum(np.diff(np.sign(compiled[2].delta_c)) != 0) >= 3
    assert np.ptp(compiled[4].states[6]) > math.radians(5.0)


def test_replayed_records_stepping_together_fly_as_the_kernel_flies_them(kcs, random_run):
    """Every member replays a rudder changing at the same samples: the batch's step is cut
    there (the kernel's common change), on an output grid coarser than the records'."""
    model = _model(kcs, extras=False)
    commands = [PrescribedRudder(random_run.t, random_run["delta"] * k) for k in (0.5, 1, -1)]
    t = random_run.t[::3]
    reference, compiled = _both(model.dynamics(), commands, t, random_run.state()[:, 0],
                                step=2.7)
    _assert_same(reference, compiled, kcs.L)


def test_recorded_channels_and_stacked_models_fly_as_the_kernel_flies_them(kcs, random_run):
    ramp = random_run.data.copy()
    ramp["depth"] = np.linspace(0.0, 200.0, len(ramp))
    records = [Trajectory(ramp, name="ramp"), Trajectory(ramp.assign(depth=10.0), name="flat")]
    first = _model(kcs, extras=True).dynamics(records=records)
    second = _model(kcs, extras=False, scale_n_r=1.3).dynamics()
    stacked = _Stacked(((first, 0, 2), (second, 2, 4)))
    commands = [PrescribedRudder(random_run.t, random_run["delta"]),
                ZigZagCommand(math.radians(15.0), math.radians(5.0), 1),
                StepCommand([0.0, 100.0], [0.1, -0.2]), ConstantCommand(-0.3)]
    t = np.asarray(random_run.t, dtype=float)
    reference, compiled = _both(stacked, commands, t, random_run.state()[:, 0])
    _assert_same(reference, compiled, kcs.L)
    # the channel is flown: the ramp's and the flat record's flights part
    assert abs(compiled[0].states[4, -1] - compiled[1].states[4, -1]) > 1.0


def test_a_diverging_flight_stops_at_the_same_sample(kcs):
    model = _model(kcs, extras=False, scale_n_r=-2.0)  # yaw damping of the wrong sign
    commands = [ConstantCommand(math.radians(35.0)), ZigZagCommand(0.35, 0.35, -1)]
    t = np.arange(0.0, 2000.0, 1.0)
    state0 = np.array([kcs.U0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    reference, compiled = _both(model.dynamics(), commands, t, state0)
    _assert_same(reference, compiled, kcs.L)
    assert all(out.diverged_at is not None and out.diverged_at < 2000.0 for out in compiled)
    assert np.isnan(compiled[0].states[:, -1]).all()


def test_what_the_loop_cannot_fly_is_left_to_the_kernel(kcs):
    model = _model(kcs, extras=False)
    feedback = [FeedbackCommand(lambda t, state: -0.5 * state[5])]
    t = np.arange(0.0, 100.0, 1.0)
    state0 = np.array([kcs.U0, 0.0, 0.0, 0.0, 0.0, 0.3, 0.0])
    dynamics = model.dynamics()
    assert dynamics.fly_compiled(integrator_for(dynamics, feedback), feedback, t, state0,
                                 1.0, True, None) is None
    (flown,) = simulate_batch(dynamics, feedback, t, state0)
    assert abs(flown.states[5, -1]) < 0.3  # the kernel flew the feedback: the heading back


def test_progress_counts_every_second_flown(kcs):
    model = _model(kcs, extras=False)
    seconds = []
    t = np.arange(0.0, 1000.0, 1.0)
    simulate_batch(model.dynamics(), [ConstantCommand(0.2)], t,
                   np.array([kcs.U0, 0, 0, 0, 0, 0, 0.0]), on_step=seconds.append)
    assert len(seconds) >= 2  # reported in parts while flying
    assert sum(seconds) == pytest.approx(999.0)
