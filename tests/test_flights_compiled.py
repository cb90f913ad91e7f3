"""Identified models fly through the compiled loop exactly as the kernel flies them."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sindyship._flights_compiled import STEPS_PER_REPORT
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


def _model(kcs, *, extras: bool, signal: str = "actual", scale_n_r: float = 1.0,
           linear: bool = False, speed: str = "design"):
    """The paper's LS model (its linear terms alone with ``linear``); with ``extras`` also
    two recorded channels, the rudder's rate and the position in its terms."""
    base = paper_model(kcs)
    terms = {dof: [t.text for t in base.library.terms[dof]
                   if not linear or t.text in ("du", "v", "r", "delta")] for dof in "XYN"}
    coefficients = {dof: {t: base.coefficients[dof][t] for t in terms[dof]} for dof in "XYN"}
    coefficients["N"]["r"] *= scale_n_r
    if extras:
        terms["Y"] += ["depth", "delta_rate"]
        terms["N"] += ["x", "y", "gust"]
        coefficients["Y"].update(depth=2e-5, delta_rate=-1e-3)
        coefficients["N"].update(x=1e-9, y=-2e-9, gust=2e-5)
    if linear:
        terms["Y"].append("depth")
        coefficients["Y"]["depth"] = -3e-5
    library = TermLibrary("compiled-flights", "prime-I", "", terms, speed=speed)
    return AbkowitzModel(kcs, library, coefficients, rudder_signal=signal)


def _records(run: Trajectory) -> list[Trajectory]:
    """Two records of a run with recorded channels: a ramp and a constant."""
    n = len(run.t)
    ramp = run.data.assign(depth=np.linspace(0.0, 200.0, n), gust=np.sin(0.05 * run.t))
    return [Trajectory(ramp, name="ramp"),
            Trajectory(ramp.assign(depth=10.0, gust=0.5), name="flat")]


def _commands(record: Trajectory):
    """One command of every kind the loop flies."""
    degree = math.radians(1.0)
    return [ConstantCommand(20 * degree),
            StepCommand([0.0, 33.3, 90.05, 150.0], [5 * degree, -15 * degree, 0.0, 25 * degree]),
            ZigZagCommand(10 * degree, 10 * degree, 1),
            RecordedZigZag(20 * degree, 20 * degree, -1, levels=(19 * degree, 21.5 * degree)),
            PrescribedRudder(record.t, record["delta"])]


def _zigzag_legs(commands) -> list[tuple]:
    """Each zig-zag command's side, reversals so far (a recorded zig-zag's) and rudder angle:
    the leg it is on."""
    return [(c.sign, getattr(c, "leg", None), c.value(0.0, None)) for c in commands
            if isinstance(c, ZigZagCommand)]


def _both(dynamics, commands, t, state0, step=None, check=True):
    """The kernel's flights and the compiled loop's, of the same batch; the loop leaves every
    zig-zag command on the leg the kernel left it on."""
    h = default_step(dynamics.ship) if step is None else step
    reference = integrate(integrator_for(dynamics, commands), commands, t, state0, h, check,
                          dynamics.ship.L, dynamics.ship.U0)
    legs = _zigzag_legs(commands)
    compiled = dynamics.fly_compiled(integrator_for(dynamics, commands), commands, t, state0,
                                     h, check, None)
    assert compiled is not None  # the loop flew them
    assert _zigzag_legs(commands) == legs
    return reference, compiled


#: Whether numpy's sine and cosine are the C library's here (then the loop's numbers are the
#: kernel's bit for bit; elsewhere they may differ in the last bits).
SAME_LIBM = all(np.array_equal(f(np.linspace(-7.0, 7.0, 1001)),
                               [g(x) for x in np.linspace(-7.0, 7.0, 1001)])
                for f, g in ((np.sin, math.sin), (np.cos, math.cos)))


def _assert_same(reference, compiled, L):
    for ref, out in zip(reference, compiled, strict=True):
        assert ref.diverged_at == out.diverged_at
        np.testing.assert_array_equal(np.isnan(ref.states), np.isnan(out.states))
        if SAME_LIBM:
            np.testing.assert_array_equal(out.states, ref.states)
            np.testing.assert_array_equal(out.delta_c, ref.delta_c)
            continue
        scale = np.array([1.0, 1.0, 1.0, L, L, 1.0, 1.0])[:, None]  # positions against L
        np.testing.assert_allclose(out.states / scale, ref.states / scale, rtol=0, atol=1e-11)
        np.testing.assert_allclose(out.delta_c, ref.delta_c, rtol=0, atol=1e-12)


@pytest.fixture(scope="module")
def random_run(kcs):
    (run,) = fly(MMGModel(kcs), [Manoeuvre("random", rudder=25, duration=400, seed=3)])
    return run


@pytest.mark.parametrize(("signal", "speed"), [("actual", "design"), ("commanded", "design"),
                                               ("actual", "instantaneous")])
def test_every_command_flies_as_the_kernel_flies_it(kcs, random_run, signal, speed):
    """Also in the instantaneous-speed form (its forces over U^2, v and r and the channels
    read over the speed U, the Coriolis terms over U0), which the kernel alone had flown."""
    model = _model(kcs, extras=True, signal=signal, speed=speed)
    dynamics = model.dynamics({"depth": 30.0, "gust": 0.2})
    commands = _commands(random_run)
    t = np.arange(0.0, 400.5, 0.5)  # outputs inside steps: the Hermite interpolant
    state0 = random_run.state()[:, 0]
    reference, compiled = _both(dynamics, commands, t, state0)
    _assert_same(reference, compiled, kcs.L)
    if speed == "instantaneous":  # the flights leave U0: the speed factor is exercised
        speeds = [np.hypot(*out.states[:2]) / kcs.U0 for out in compiled]
        assert min(float(np.min(s)) for s in speeds) < 0.8
        return
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
    """Three models side by side: two read the same recorded channel (one of them a second
    one too), their terms have different numbers of factors, one diverges while the others
    fly on."""
    records = _records(random_run)
    first = _model(kcs, extras=True).dynamics(records=records)
    linear = _model(kcs, extras=False, linear=True).dynamics(records=records[::-1])
    unstable = _model(kcs, extras=False, scale_n_r=-2.0, speed="instantaneous").dynamics()
    stacked = _Stacked(((first, 0, 2), (linear, 2, 4), (unstable, 4, 5)))
    commands = [PrescribedRudder(random_run.t, random_run["delta"]),
                ZigZagCommand(math.radians(15.0), math.radians(5.0), 1),
                StepCommand([0.0, 100.0], [0.1, -0.2]), ConstantCommand(-0.3),
                ConstantCommand(0.6)]
    t = np.asarray(random_run.t, dtype=float)
    reference, compiled = _both(stacked, commands, t, random_run.state()[:, 0])
    _assert_same(reference, compiled, kcs.L)
    assert all(out.diverged_at is None for out in compiled[:4])
    assert compiled[4].diverged_at is not None
    # the channels are flown: the ramp's and the flat record's flights part
    assert abs(compiled[0].states[4, -1] - compiled[1].states[4, -1]) > 1.0


def test_changes_on_step_ends_staggered_replays_and_a_late_start(kcs, random_run):
    """A scheduled change that falls on a step's end (the next step's first stage is not
    the last one's end), replays on grids half a sample apart (no common step), outputs from
    t = 100 s, and no divergence test."""
    model = _model(kcs, extras=False)
    t = np.arange(100.0, 400.0, 1.0)
    shifted = random_run.t + 100.5
    replays = [PrescribedRudder(random_run.t + 100.0, random_run["delta"]),
               PrescribedRudder(shifted, random_run["delta"][::-1])]
    for commands in ([StepCommand([100.0, 110.0, 150.0], [0.2, -0.2, 0.3]), *replays],
                     replays):  # with only replays, each is split at its own samples
        reference, compiled = _both(model.dynamics(), commands, t, random_run.state()[:, 0],
                                    step=2.0, check=False)
        _assert_same(reference, compiled, kcs.L)


def test_a_diverging_flight_stops_at_the_same_sample(kcs):
    model = _model(kcs, extras=False, scale_n_r=-2.0)  # yaw damping of the wrong sign
    commands = [ConstantCommand(math.radians(35.0)), ZigZagCommand(0.35, 0.35, -1),
                ConstantCommand(0.0)]
    t = np.arange(0.0, 2000.0, 1.0)
    state0 = np.array([[kcs.U0, kcs.U0, 0.0]] + [[0.0] * 3] * 6)  # the last one at rest
    reference, compiled = _both(model.dynamics(), commands, t, state0)
    _assert_same(reference, compiled, kcs.L)
    assert all(out.diverged_at is not None and out.diverged_at < 2000.0 for out in compiled)
    assert np.isnan(compiled[0].states[:, -1]).all()
    assert compiled[2].diverged_at == 0.0  # out of range from the start


def test_what_the_loop_cannot_fly_is_left_to_the_kernel(kcs, random_run):
    t = np.arange(0.0, 100.0, 1.0)
    state0 = np.array([kcs.U0, 0.0, 0.0, 0.0, 0.0, 0.3, 0.0])
    design = _model(kcs, extras=False).dynamics()
    feedback = [FeedbackCommand(lambda t, state: -0.5 * state[5])]
    one_sample = [PrescribedRudder(np.array([0.0]), np.array([0.1]))]
    for dynamics, commands in ((design, feedback), (design, one_sample)):
        assert dynamics.fly_compiled(integrator_for(dynamics, commands), commands, t, state0,
                                     1.0, True, None) is None
    (flown,) = simulate_batch(design, feedback, t, state0)
    assert abs(flown.states[5, -1]) < 0.3  # the kernel flew the feedback: the heading back


def test_the_loop_flies_and_reports_progress_in_parts(kcs, monkeypatch):
    import sindyship.simulation.integrator as integrator

    def no_kernel(*args, **kwargs):
        raise AssertionError("the kernel flew a flight the compiled loop flies")

    monkeypatch.setattr(integrator, "integrate", no_kernel)
    model = _model(kcs, extras=False)
    seconds = []
    t = np.arange(0.0, 1000.0, 1.0)
    (flown,) = simulate_batch(model.dynamics(), [ConstantCommand(0.2)], t,
                              np.array([kcs.U0, 0, 0, 0, 0, 0, 0.0]), on_step=seconds.append)
    n_steps = math.ceil(999.0 / default_step(kcs))
    assert 2 <= len(seconds) <= math.ceil(n_steps / STEPS_PER_REPORT)
    assert sum(seconds) == pytest.approx(999.0)
    assert flown.states[2, -1] > 0.0  # turning to starboard
