"""Exported models: sympy equations, text, LaTeX and the generated standalone simulator.

The generated module is checked against sindyship's own term-by-term path
(:class:`sindyship.model.AbkowitzDynamics` flown by :mod:`sindyship.simulation`): both use
the same RK4 scheme, so their trajectories agree to rounding (asserted: 1e-9 of each
channel's magnitude; measured about 5e-13).
"""

from __future__ import annotations

import argparse
import doctest
import importlib.util
import json
import math
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import sympy

from sindyship.cli import export as export_verb
from sindyship.errors import SindyshipInputError
from sindyship.export import (
    ACCELERATIONS,
    coefficient_symbol,
    coefficient_table_latex,
    coriolis_expressions,
    equations_latex,
    equations_text,
    force_expressions,
    generate_python,
    model_equations,
)
from sindyship.flights import flown_as, flown_part, fly_like_batch
from sindyship.library import TermLibrary, load_library
from sindyship.manoeuvres import Manoeuvre, fly, protocol_manoeuvres
from sindyship.mmg import MMGModel
from sindyship.model import AbkowitzModel, paper_model
from sindyship.simulation import (
    FeedbackCommand,
    StepCommand,
    ZigZagCommand,
    integrator_for,
    simulate_batch,
)
from sindyship.targets import DOFS, abkowitz_mass_matrix, coriolis
from sindyship.trajectory import Trajectory

ROOT = Path(__file__).resolve().parents[1]
RTOL = 1e-9  # the generated integrator against sindyship's, relative to each channel's size


@pytest.fixture(scope="module")
def model(kcs):
    return paper_model(kcs, "LS")


def relative_difference(a: np.ndarray, b: np.ndarray) -> float:
    """max |a - b| / (max |b| + tiny) over each state channel, the worst channel."""
    a, b = np.atleast_2d(a), np.atleast_2d(b)
    scale = np.max(np.abs(b), axis=1) + 1e-300
    return float(np.max(np.max(np.abs(a - b), axis=1) / scale))


def load_module(source: str, path: Path):
    path.write_text(source)
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# ---------------------------------------------------------------------------------------------
# Round trip: the generated module, in a clean interpreter, against sindyship's path
# ---------------------------------------------------------------------------------------------
RUNNER = '''
import importlib.util, json, sys
from pathlib import Path

generated, numpy_dir, out = Path(sys.argv[1]), sys.argv[2], Path(sys.argv[3])
sys.path.append(numpy_dir)  # numpy only: without site, no .pth file (no editable install)
import numpy as np

spec = importlib.util.spec_from_file_location("kcs_sim", generated)
sim = importlib.util.module_from_spec(spec)
spec.loader.exec_module(sim)
t = np.arange(3200.0)
state0 = np.array([sim.U0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
flights = {
    "tc15_port": sim.simulate(t, np.full(t.shape, np.radians(-15.0)), state0),
    "tc15_stbd": sim.simulate(t, np.full(t.shape, np.radians(15.0)), state0),
    "zz10_10": sim.zigzag(t, 10.0, 10.0, state0),
}
for name, flight in flights.items():
    np.save(out / f"{name}.npy", flight.states)
    np.save(out / f"{name}_cmd.npy", flight.delta_c)
loaded = sorted({m.split(".")[0] for m in sys.modules})
try:
    import sindyship.model  # noqa: F401
    importable = True
except ImportError:
    importable = False
(out / "facts.json").write_text(json.dumps({
    "sindyship_importable": importable, "loaded": loaded,
    "diverged": [f.diverged_at for f in flights.values()],
}))
'''


@pytest.fixture(scope="module")
def round_trip(model, tmp_path_factory):
    folder = tmp_path_factory.mktemp("round_trip")
    generated = folder / "kcs_sim.py"
    generated.write_text(generate_python(model, source_note="paper LS coefficients"))
    runner = folder / "runner.py"
    runner.write_text(RUNNER)
    numpy_dir = str(Path(np.__file__).resolve().parents[1])
    env = {"PATH": "/usr/bin:/bin"}  # no PYTHONPATH, no user site
    done = subprocess.run([sys.executable, "-I", "-S", str(runner), str(generated), numpy_dir,
                           str(folder)], capture_output=True, text=True, env=env, cwd=folder,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    facts = json.loads((folder / "facts.json").read_text())
    flown = {name: (np.load(folder / f"{name}.npy"), np.load(folder / f"{name}_cmd.npy"))
             for name in ("tc15_port", "tc15_stbd", "zz10_10")}
    reference = {r.name: r for r in fly(model.dynamics(), protocol_manoeuvres()["test"])}
    return facts, flown, reference


def test_generated_module_runs_without_sindyship(round_trip):
    facts, _, _ = round_trip
    assert facts["sindyship_importable"] is False
    assert "sindyship" not in facts["loaded"]
    assert facts["diverged"] == [None, None, None]


@pytest.mark.parametrize("name", ["tc15_port", "tc15_stbd", "zz10_10"])
def test_generated_module_flies_held_out_manoeuvres_like_sindyship(round_trip, name):
    _, flown, reference = round_trip
    states, command = flown[name]
    ref = reference[name]
    assert states.shape == (7, 3200)
    assert relative_difference(states, ref.state()) <= RTOL
    assert np.array_equal(command, ref["delta_c"])
    if name == "zz10_10":  # the zig-zag was flown closed loop: the rudder reversed
        assert np.sum(np.diff(np.sign(command)) != 0) >= 8


def test_step_and_feedback_commands_match_sindyship(model, tmp_path):
    sim = load_module(generate_python(model), tmp_path / "sim_steps.py")
    t = np.arange(0.0, 600.0, 0.5)
    state0 = np.array([model.ship.U0, 0, 0, 0, 0, 0, 0])
    angles = np.where(t < 150.0, 0.2, np.where(t < 400.0, -0.1, 0.35))  # changes at samples
    change = [0.0, 150.0, 400.0]
    (ref_steps,) = simulate_batch(model.dynamics(), [StepCommand(change, [0.2, -0.1, 0.35])], t,
                                  state0)
    flight = sim.simulate(t, angles, state0)
    assert relative_difference(flight.states, ref_steps.states) <= RTOL

    def heading_hold(time, state):  # feedback: steer towards 20 deg of heading
        return float(np.clip(2.0 * (math.radians(20.0) - state[5]), -0.6, 0.6))

    (ref_fb,) = simulate_batch(model.dynamics(), [FeedbackCommand(heading_hold)], t, state0)
    flight = sim.simulate(t, heading_hold, state0)
    assert relative_difference(flight.states, ref_fb.states) <= RTOL
    assert np.ptp(flight.delta_c) > 0.5  # the command did follow the heading


def test_commanded_rudder_and_heading_terms_match_sindyship(kcs, tmp_path):
    """A model on the commanded rudder, with heading (environment) terms, ports exactly."""
    base = load_library("abkowitz")
    terms = {dof: [t.text for t in base.terms[dof]] for dof in DOFS}
    terms["X"].append("cos(psi)")
    terms["Y"] += ["sin(psi)", "abs(v) v"]
    terms["N"] += ["sin(psi)", "cos(psi) r"]
    library = TermLibrary("abkowitz+env", "prime-I", "test library", terms)
    paper = paper_model(kcs, "LS")
    coefficients = {dof: dict(paper.coefficients[dof]) for dof in DOFS}
    coefficients["X"]["cos(psi)"] = -2e-5
    coefficients["Y"].update({"sin(psi)": 3e-5, "abs(v) v": -0.01})
    coefficients["N"].update({"sin(psi)": -1e-5, "cos(psi) r": 2e-5})
    env = AbkowitzModel(kcs, library, coefficients, rudder_signal="commanded")
    source = generate_python(env)
    assert "np.sin(psi)" in source and "abs(v)" in source
    sim = load_module(source, tmp_path / "sim_env.py")
    assert sim.RUDDER_INPUT == "commanded"
    t = np.arange(0.0, 900.0)
    state0 = np.array([kcs.U0, 0, 0, 0, 0, 0.3, 0])
    refs = simulate_batch(env.dynamics(), [StepCommand([0.0], [math.radians(15.0)]),
                                           ZigZagCommand(math.radians(10.0),
                                                         math.radians(10.0), -1)], t, state0)
    assert relative_difference(sim.simulate(t, math.radians(15.0), state0).states,
                               refs[0].states) <= RTOL
    assert relative_difference(sim.zigzag(t, 10.0, 10.0, state0, first_sign=-1).states,
                               refs[1].states) <= RTOL


def test_sparse_and_diverging_models_match_sindyship(kcs, tmp_path):
    """Zero coefficients are left out; a diverging model stops at the same sample."""
    lasso = paper_model(kcs, "Lasso")
    sim = load_module(generate_python(lasso), tmp_path / "sim_lasso.py")
    assert "X_rr *" not in (tmp_path / "sim_lasso.py").read_text()  # the paper's X'_rr = 0
    t = np.arange(600.0)
    state0 = np.array([kcs.U0, 0, 0, 0, 0, 0, 0])
    (ref,) = simulate_batch(lasso.dynamics(), [ZigZagCommand(math.radians(20.0),
                                                             math.radians(20.0))], t, state0)
    assert relative_difference(sim.zigzag(t, 20.0, 20.0, state0).states, ref.states) <= RTOL

    paper = paper_model(kcs, "LS")
    coefficients = {dof: dict(paper.coefficients[dof]) for dof in DOFS}
    coefficients["N"]["r"] = 0.004  # yaw-unstable: the turn runs away
    unstable = AbkowitzModel(kcs, paper.library, coefficients)
    sim = load_module(generate_python(unstable), tmp_path / "sim_unstable.py")
    t = np.arange(300.0)
    (ref,) = simulate_batch(unstable.dynamics(), [StepCommand([0.0], [0.17])], t, state0)
    flight = sim.simulate(t, 0.17, state0)
    assert ref.diverged_at is not None and flight.diverged_at == ref.diverged_at
    valid = ref.valid
    assert np.all(np.isnan(flight.states[:, ~valid])) and np.all(np.isnan(flight.delta_c[~valid]))
    assert relative_difference(flight.states[:, valid], ref.states[:, valid]) <= RTOL


def test_rhs_is_vectorised_and_equals_sindyship(model, tmp_path, seed):
    sim = load_module(generate_python(model), tmp_path / "sim_rhs.py")
    rng = np.random.default_rng(seed)
    n = 11
    U0, L = model.ship.U0, model.ship.L
    states = np.vstack([U0 * rng.uniform(0.6, 1.1, n), U0 * rng.uniform(-0.2, 0.2, n),
                        U0 / L * rng.uniform(-0.5, 0.5, n), rng.normal(0, 500, (2, n)),
                        rng.uniform(-4, 4, n), rng.uniform(-0.6, 0.6, n)])
    delta_c = rng.uniform(-0.7, 0.7, n)
    batch = sim.rhs(0.0, states, delta_c)
    columns = np.column_stack([sim.rhs(0.0, states[:, j], delta_c[j]) for j in range(n)])
    reference = integrator_for(model.dynamics(), [StepCommand([0.0], [0.0])] * n).rhs(
        0.0, states, delta_c, np.arange(n), None)
    assert batch.shape == (7, n)
    assert relative_difference(batch, reference) <= 1e-13
    assert relative_difference(columns, reference) <= 1e-13
    assert sim.rhs(0.0, states[:, 0], delta_c[0]).shape == (7,)


def test_generated_constants_and_coefficients(model, tmp_path):
    sim = load_module(generate_python(model), tmp_path / "sim_consts.py")
    expected = {term.identifier(dof): model.coefficients[dof][term.text]
                for dof in DOFS for term in model.library.terms[dof]}
    assert sim.COEFFICIENTS == expected  # exact: every double reads back unchanged
    assert sim.Y_vvr == model.coefficients["Y"]["v^2 r"]
    assert sim.TERMS["N_vrd"] == ("N", "v r delta")
    assert sim.DEFAULT_STEP == pytest.approx(0.1 * model.ship.L / model.ship.U0, rel=1e-15)
    assert sim.T_SERVO == pytest.approx(model.ship.L / model.ship.U0, rel=1e-15)
    assert sim.RATE_MAX == pytest.approx(math.radians(5.0), rel=1e-15)
    assert sim.MASS_MATRIX == tuple(map(tuple, abkowitz_mass_matrix(model.ship).tolist()))
    results = doctest.testmod(sim, verbose=False)
    assert results.attempted >= 4 and results.failed == 0


def test_generated_module_passes_ruff(model, kcs, tmp_path):
    # the environment's own ruff, also where its bin folder is not on PATH
    beside = Path(sys.executable).with_name("ruff")
    ruff = str(beside) if beside.exists() else shutil.which("ruff")
    if ruff is None:
        pytest.skip("ruff is not installed")
    long_term = "wind_speed^2 cos(wind_dir) sin(psi) abs(v) v r delta du"
    terms = {dof: ["du", "v", "r", "delta", long_term] for dof in DOFS}
    exotic = AbkowitzModel(kcs, TermLibrary("a-rather-long-library-name", "prime-I", "", terms),
                           {dof: {t: -1.2345678901234567e-5 for t in terms[dof]} for dof in DOFS})
    sources = {
        "kcs_sim.py": generate_python(model, source_note='A note, "quoted", with a \\ in it.'),
        "exotic_sim.py": generate_python(exotic, channels={"wind_speed": 0.5, "wind_dir": 1.0}),
        "kcs_fast.py": generate_python(model, compiled=True),
        "exotic_fast.py": generate_python(exotic, compiled=True),
    }
    for name, source in sources.items():
        (tmp_path / name).write_text(source)
    done = subprocess.run([ruff, "check", "--no-cache", "--config", str(ROOT / "pyproject.toml"),
                           *sorted(sources)], capture_output=True, text=True, cwd=tmp_path)
    assert done.returncode == 0, done.stdout + done.stderr


def test_the_generated_simulator_flies_recorded_channels(kcs, tmp_path):
    """A model whose library uses the revolutions n: the generated module takes them as a time
    series over t (SI) and flies as sindyship does with the record's channel."""
    base = paper_model(kcs)
    terms = {dof: [t.text for t in base.library.terms[dof]] for dof in DOFS}
    terms["X"].append("n")
    library = TermLibrary("with-n", "prime-I", "", terms)
    coefficients = {dof: dict(base.coefficients[dof]) for dof in DOFS}
    coefficients["X"]["n"] = 2e-5  # surge force per unit of n' = n L / U0
    with_n = AbkowitzModel(kcs, library, coefficients)
    source = generate_python(with_n)
    assert "CHANNEL_N = math.nan" in source and "CHANNEL_SCALING" in source
    sim = load_module(source, tmp_path / "sim_n.py")
    # its docstring example passes the ship's design revolutions (it had failed, asking for n)
    assert doctest.testmod(sim).failed == 0 and ">>> n = " in sim.__doc__
    (run,) = fly(MMGModel(kcs), [Manoeuvre("turning-circle", rudder=20, duration=300)])
    n = np.linspace(1.5, 2.2, run.n_samples)  # revolutions [rps] that change in the record
    data = run.data.copy()
    data["n"] = n
    record = Trajectory(data, name=run.name)
    (ours,) = fly_like_batch(with_n, [record])
    theirs = sim.simulate(record.t, record["delta_c"], record.state()[:, 0], {"n": n})
    assert ours.meta["diverged_at"] is None and theirs.diverged_at is None
    assert np.max(np.hypot(ours["x"] - theirs.states[3], ours["y"] - theirs.states[4])
                  ) / kcs.L < 1e-10
    with pytest.raises(ValueError, match="channel 'n'"):
        sim.simulate(record.t, 0.0, None, {})
    with pytest.raises(ValueError, match=r"^the model's library uses no channel 'rpm' \(it "
                       r"uses: n\); check the name"):
        sim.simulate(record.t, 0.0, None, {"n": n, "rpm": n})
    with pytest.raises(ValueError, match=r"^channel 'n' has shape \(5,\); give one value per "
                       r"output time"):
        sim.simulate(record.t, 0.0, None, {"n": n[:5]})
    assert sim.simulate(record.t, 0.0, None, {"n": 1.8}).diverged_at is None  # a constant
    # revolutions in rpm (60 times the rps) are refused, as export's --channel refuses them
    with pytest.raises(ValueError, match=r"^channel 'n' reaches 132, 68\.6 times the ship's "
                       r"propeller revolutions 1\.92524 rps; give n in rps \(rpm divided by "
                       r"60\)$"):
        sim.simulate(record.t, 0.0, None, {"n": 60.0 * n})
    with pytest.raises(ValueError, match="give n in rps"):
        sim.rhs(0.0, record.state()[:, 0], 0.0, {"n": 116.0})
    # without channels the exported default is taken, and one never given is asked for (it
    # had flown NaN, a flight that looked diverged at its first step)
    for call in (lambda: sim.simulate(record.t, 0.0), lambda: sim.rhs(0.0, record.state()[:, 0],
                                                                      0.0)):
        with pytest.raises(ValueError, match="give the channel 'n' .*exported without a value"):
            call()
    given = load_module(generate_python(with_n, channels={"n": 1.8 * kcs.L / kcs.U0}),
                        tmp_path / "sim_n_given.py")
    flight = given.simulate(record.t, record["delta_c"], record.state()[:, 0])
    steady = sim.simulate(record.t, record["delta_c"], record.state()[:, 0],
                          {"n": np.full(run.n_samples, 1.8)})
    assert flight.diverged_at is None
    assert np.allclose(flight.states, steady.states, rtol=0, atol=1e-9 * kcs.L)
    # the command line takes the default in SI, as channels= and the CSV do (it had taken the
    # library's n L/U0, and n=1.8 flew a ship with its propeller nearly stopped)
    from sindyship.cli import main

    with_n.save(tmp_path / "with_n.json")
    assert main(["export", str(tmp_path / "with_n.json"), "--python",
                 str(tmp_path / "sim_n_cli.py"), "--channel", "n=1.8"]) == 0
    cli = load_module((tmp_path / "sim_n_cli.py").read_text(), tmp_path / "sim_n_cli_run.py")
    assert cli.CHANNEL_N == pytest.approx(1.8 * kcs.L / kcs.U0, rel=1e-12)
    assert np.allclose(cli.simulate(record.t, record["delta_c"], record.state()[:, 0]).states,
                       flight.states, rtol=0, atol=1e-9 * kcs.L)
    # a value in the library's n L/U0, as the option once took, is refused as another unit
    assert main(["export", str(tmp_path / "with_n.json"), "--python",
                 str(tmp_path / "sim_n_old.py"), "--channel", "n=35.86"]) == 2
    assert not (tmp_path / "sim_n_old.py").exists()


@pytest.mark.parametrize("compiled", [False, True])
def test_an_instantaneous_speed_model_flies_as_sindyship_flies_it(kcs, tmp_path, compiled):
    """The instantaneous speed form (v, r and the revolutions over U, forces times (U/U0)^2),
    the KVLCC2's default, had been refused: the generated module flies a 35 deg turn that
    loses 30 % of its speed and a zig-zag as sindyship does, plain and compiled."""
    if compiled and importlib.util.find_spec("numba") is None:
        pytest.skip("numba is not installed: the compiled path does not run")
    from sindyship.identify import fit

    train = fly(MMGModel(kcs), protocol_manoeuvres(duration=600)["train"])
    fitted = fit(train, kcs, speed="instantaneous", effects=["crossflow"])
    terms = {dof: [t.text for t in fitted.library.terms[dof]] for dof in DOFS}
    terms["X"].append("n")
    library = TermLibrary("instantaneous-with-n", "prime-I", "", terms, speed="instantaneous")
    coefficients = {dof: dict(fitted.coefficients[dof]) for dof in DOFS}
    coefficients["X"]["n"] = 2e-5  # per unit of n L / U over the speed
    model = AbkowitzModel(kcs, library, coefficients)
    n = kcs.propeller.n_P
    sim = load_module(generate_python(model, channels={"n": n * kcs.L / kcs.U0},
                                      compiled=compiled), tmp_path / f"sim_u{int(compiled)}.py")
    assert sim.SPEED_FORM == "instantaneous" and sim.OVER_SPEED == ("n",)
    t = np.arange(0.0, 900.0)
    state0 = np.array([kcs.U0, 0, 0, 0, 0, 0, 0])
    refs = simulate_batch(model.dynamics({"n": n * kcs.L / kcs.U0}),
                          [StepCommand([0.0], [math.radians(35.0)]),
                           ZigZagCommand(math.radians(20.0), math.radians(20.0), 1)], t, state0)
    assert refs[0].diverged_at is None and np.min(refs[0].states[0]) < 0.75 * kcs.U0
    assert relative_difference(sim.simulate(t, math.radians(35.0), state0).states,
                               refs[0].states) <= RTOL
    assert relative_difference(sim.zigzag(t, 20.0, 20.0, state0).states,
                               refs[1].states) <= RTOL
    assert doctest.testmod(sim).failed == 0
    # revolutions that change over a record, in SI, as sindyship flies the record
    (run,) = fly(MMGModel(kcs), [Manoeuvre("turning-circle", rudder=-30, duration=600)])
    data = run.data.copy()
    data["n"] = np.linspace(1.0, 1.3, run.n_samples) * n
    record = Trajectory(data, name=run.name)
    (ours,) = fly_like_batch(model, [record])
    theirs = sim.simulate(record.t, record["delta_c"], record.state()[:, 0], {"n": data["n"]})
    assert ours.meta["diverged_at"] is None and theirs.diverged_at is None
    assert np.max(np.hypot(ours["x"] - theirs.states[3], ours["y"] - theirs.states[4])
                  ) / kcs.L < 1e-9


def test_the_generated_simulator_refuses_a_wrong_state_or_an_angle_in_degrees(kcs, tmp_path):
    """A six-value state raised numpy's "cannot reshape", 15 "rad" (degrees given by
    mistake) flew hard over, and a zig-zag took a first side of 0, a rudder beyond its limit
    (the servo clipped it) and radians: each is one clear sentence now."""
    sim = load_module(generate_python(paper_model(kcs)), tmp_path / "sim_checks.py")
    t = np.arange(0.0, 10.0)
    with pytest.raises(ValueError, match=r"^state0 has shape \(6,\); give 7 finite values"):
        sim.simulate(t, 0.1, [kcs.U0, 0, 0, 0, 0, 0])
    with pytest.raises(ValueError, match=r"^state has shape \(14,\); give the 7 values"):
        sim.rhs(0.0, np.zeros(14), 0.1)
    with pytest.raises(ValueError, match=r"^delta_c reaches 15 rad, more than a quarter turn: "
                       r"give the rudder angle in radians"):
        sim.simulate(t, 15.0)
    assert sim.simulate(t, np.radians(15.0)).diverged_at is None
    for args, kwargs, message in (((t, 10, 10), {"first_sign": 0}, r"^first_sign is 0; give"),
                                  ((t, 40, 10), {}, r"^rudder_deg is 40; give 1 to 35 degrees"),
                                  ((t, 0.2, 0.2), {}, r"^rudder_deg is 0.2; give 1 to 35 "
                                   r"degrees \(zigzag takes degrees, simulate radians"),
                                  ((t, 10, 0), {}, r"^check_deg is 0; give 1 to 180 degrees")):
        with pytest.raises(ValueError, match=message):
            sim.zigzag(*args, **kwargs)


@pytest.mark.parametrize(("options", "message"), [
    (["--channel", "N=1.93", "--python", "sim.py"],
     "--channel N: the model's library uses no channel of that name (it uses: none)"),
    (["--channel", "n=1.93"], "--channel sets the simulator's default value"),
])
def test_export_refuses_a_channel_the_model_does_not_use(model, tmp_path, capsys, options,
                                                          message):
    from sindyship.cli import main

    path = tmp_path / "model.json"
    model.save(path)
    assert main(["export", str(path), *[str(tmp_path / o) if o.endswith(".py") else o
                                         for o in options]]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "sim.py").exists()

def _symbols():
    return {name: sympy.Symbol(name, real=True) for name in ("du", "v", "r", "delta")}


def test_model_equations_equal_the_model_numerically(model, seed):
    """Eq. 14 as sympy: left mass-matrix row, right forces (term by term) plus Coriolis."""
    eqs = model_equations(model, numeric=True)
    symbolic = model_equations(model)
    M = abkowitz_mass_matrix(model.ship)
    rng = np.random.default_rng(seed)
    values = {"du": rng.uniform(-0.3, 0.1, 8), "v": rng.uniform(-0.2, 0.2, 8),
              "r": rng.uniform(-0.5, 0.5, 8), "delta": rng.uniform(-0.6, 0.6, 8)}
    forces = model.forces_from_values(values)
    extra = coriolis(model.ship, 1.0 + values["du"], values["v"], values["r"])
    s = _symbols()
    names = list(s)
    for i, dof in enumerate(DOFS):
        for j, acc in enumerate(ACCELERATIONS):
            assert float(eqs[dof].lhs.coeff(acc)) == M[i, j]
        rhs = sympy.lambdify([s[n] for n in names], eqs[dof].rhs, "numpy")
        got = rhs(*(values[n] for n in names))
        want = forces[dof] + extra[i]
        assert np.allclose(got, want, rtol=1e-13, atol=1e-16)
        active = {coefficient_symbol(dof, t) for t in model.library.terms[dof]
                  if model.coefficients[dof][t.text] != 0.0}
        assert symbolic[dof].rhs.free_symbols - set(s.values()) == active
    assert force_expressions(model, numeric=True)["X"].subs({x: 0 for x in s.values()}) == 0
    assert set(coriolis_expressions(model.ship)["X"].free_symbols) == {s["r"], s["v"]}


def test_instantaneous_equations_are_what_the_model_computes(kcs):
    """A model of the instantaneous speed form reads v, r over U and scales its forces with
    (U/U0)^2: the sympy, text and LaTeX equations say so (they printed the design form, off
    by the speed factor and with Coriolis terms in the wrong speed), and the sympy right-hand
    sides equal the model's forces plus Coriolis at flown states."""
    from sindyship.identify import fit
    from sindyship.model import coriolis_of_values

    train = fly(MMGModel(kcs), protocol_manoeuvres(duration=600)["train"])
    model = fit(train, kcs, speed="instantaneous")
    eqs = model_equations(model, numeric=True)
    u = kcs.U0 * np.array([0.7, 1.0, 0.45, -0.3])  # the last astern
    v = kcs.U0 * np.array([-0.1, 0.02, 0.2, 0.05])
    r = kcs.U0 / kcs.L * np.array([0.3, -0.05, -0.6, 0.1])
    delta = np.array([0.1, -0.3, 0.6, 0.0])
    values = model.flight_variables(u, v, r, delta, np.zeros(4), {})
    forces = model.forces_from_values(values)
    extra = coriolis_of_values(kcs, values)
    s = _symbols()
    for i, dof in enumerate(DOFS):
        rhs = sympy.lambdify([s[n] for n in s], eqs[dof].rhs, "numpy")
        got = rhs(*(values[n] for n in s))
        assert np.allclose(got, forces[dof] + extra[i], rtol=1e-12, atol=1e-16), dof
    text = equations_text(model, precision=3)
    assert "U/U0 = |1 + du| / sqrt(1 - v^2) (from 0.05 U0 up)" in " ".join(text.split())
    assert text.count("= (U/U0)^2 [") == 3 and "(Coriolis) + 0.0159 (U/U0)^2 v r" in text
    tex = equations_latex(model, precision=3)
    assert tex.count(r"\left(\frac{U}{U_0}\right)^{2} [") == 3
    assert r"&\frac{U}{U_0} = \frac{|1 + \Delta u'|}{\sqrt{1 - v'^2}}" in tex


def _parse_align(tex: str) -> list[sympy.Eq]:
    """Equations of an ``align`` environment, read back with sympy's LaTeX parser.

    sympy reads ``\\Delta u'`` as the product Delta * u' and ``\\dot{u}`` as dot * u, so
    Delta and dot are set to 1 and the primed/unprimed names mapped to the model's symbols.
    Its parser also stops, silently, at a prime after a braced argument, so the paper's
    ``\\dot{u}'`` is read as ``\\dot{u}``.
    """
    from sympy.parsing.latex import parse_latex

    body = tex.split(r"\begin{align}")[1].split(r"\end{align}")[0]
    equations, current = [], ""
    body = re.sub(r"\\underbrace\{(.*?)\}_\{\\text\{[^{}]*\}\}", r"\1", body)  # Coriolis
    for line in body.split(r"\\"):
        line = line.replace(r"\nonumber", "").replace(r"\qquad", "").replace("&", "")
        line = re.sub(r"(\\dot\{[a-z]\})'", r"\1", line).strip()
        if not line:
            continue
        if "=" in line and current:
            equations.append(current)
            current = ""
        current += " " + line
    equations.append(current)
    s = _symbols()
    rename = {sympy.Symbol("Delta"): 1, sympy.Symbol("dot"): 1,
              sympy.Symbol("u'"): s["du"], sympy.Symbol("v'"): s["v"],
              sympy.Symbol("r'"): s["r"], sympy.Symbol("delta"): s["delta"],
              sympy.Symbol("u"): ACCELERATIONS[0], sympy.Symbol("v"): ACCELERATIONS[1],
              sympy.Symbol("r"): ACCELERATIONS[2]}
    parsed = [parse_latex(eq.strip()) for eq in equations]
    assert all(isinstance(eq, sympy.Eq) for eq in parsed)
    return [eq.xreplace(rename) for eq in parsed]


def test_latex_equations_read_back_to_the_model(model, seed):
    """Checked numerically at random points (structural equality is fragile with Floats).

    With 17 significant digits every coefficient reads back as the same double.  (sympy's
    LaTeX parser takes about 4 s for the 66 terms, so only this precision is read back.)
    """
    pytest.importorskip("antlr4")
    rtol = 1e-13
    parsed = _parse_align(equations_latex(model, 17))
    exact = model_equations(model, numeric=True)
    assert len(parsed) == 3
    rng = np.random.default_rng(seed)
    s = _symbols()
    names = [s["du"], s["v"], s["r"], s["delta"], *ACCELERATIONS]
    point = [rng.uniform(-0.3, 0.1, 20), rng.uniform(-0.2, 0.2, 20), rng.uniform(-0.5, 0.5, 20),
             rng.uniform(-0.6, 0.6, 20), *rng.uniform(-0.1, 0.1, (3, 20))]
    for eq, dof in zip(parsed, DOFS, strict=True):
        assert eq.free_symbols <= set(names)
        for side in ("lhs", "rhs"):
            want = getattr(exact[dof], side)
            got = sympy.lambdify(names, getattr(eq, side))(*point)
            terms = sympy.Add.make_args(sympy.expand(want))
            size = sum(np.abs(sympy.lambdify(names, t)(*point)) for t in terms)
            assert np.all(np.abs(got - sympy.lambdify(names, want)(*point)) <= rtol * size)


def test_latex_numbers_have_the_requested_precision(model):
    tex = equations_latex(model, 4)
    assert ("&0.008853 \\dot{u}' = \\nonumber \\\\\n"
            "&\\qquad -0.002265 \\Delta u' - 0.0005081 \\Delta u'^{2}") in tex
    assert r"- 3.071 \times 10^{-5} r'^{2} \Delta u'" in tex  # X'_rru, as in Table 7
    assert r"&\qquad 4.32 \times 10^{-6} - 0.0002212 \Delta u'" in tex  # Y'_0
    assert (r"&\qquad \underbrace{- 0.008853 (1 + \Delta u') r'}_{\text{Coriolis}} \\"
            in tex)  # Coriolis, u' = 1 + du, on a line of its own
    assert r"}_{\text{Coriolis and Munk moment}}" in tex
    lines = tex.splitlines()[1:-1]
    numbered = [line for line in lines if not line.endswith(r"\nonumber \\")]
    assert len(numbered) == 3 and all(r"\underbrace" in line for line in numbered)


def test_latex_lines_fit_an_article_page(model):
    """Every line of the equations holds at most LATEX_LINE_LENGTH characters of rendered
    mathematics, which pdflatex fits in an article's text width for every model tried; the
    first line of each equation is its left-hand side alone, whatever its width."""
    from sindyship.export.text import LATEX_LINE_LENGTH, _rendered_length

    assert _rendered_length(r"- 3.071 \times 10^{-5} r'^{2} \Delta u'") == 22
    assert _rendered_length(r"\left(\frac{U}{U_0}\right)^{2} [ -0.1 v'") == 16
    tex = equations_latex(model, 4)
    lines = tex.splitlines()[1:-1]
    bodies = [line.removesuffix(r" \\").removesuffix(r" \nonumber") for line in lines]
    assert max(_rendered_length(body) for body in bodies) <= LATEX_LINE_LENGTH
    assert sum(line.endswith(r"= \nonumber \\") for line in lines) == 3
    short = equations_latex(model, 4, line_length=10).splitlines()[1:-1]
    terms = sum(len(model.coefficients[dof]) - list(model.coefficients[dof].values()).count(0)
                for dof in DOFS)
    # a term a line, each left-hand side its own, and a brace for each of the Coriolis terms
    # (X: v' r' and r'^2; Y: u' r'; N: u' r' and the Munk moment)
    assert len(short) == 3 + terms + 5


def test_symbolic_latex_names_every_active_coefficient(model):
    tex = equations_latex(model, numeric=False)
    for dof in DOFS:
        for term in model.library.terms[dof]:
            active = model.coefficients[dof][term.text] != 0.0
            assert (term.latex(dof) + " ") in tex or (term.latex(dof) + " \\") in tex \
                or not active
    assert tex.count(r"\\") >= 2 and tex.startswith(r"\begin{align}")


def test_coefficient_table_lists_every_coefficient(model):
    reference = {dof: {t: v * 2 for t, v in model.coefficients[dof].items()} for dof in DOFS}
    reference["N"]["v r delta"] = math.nan
    table = coefficient_table_latex(model, 4, reference=reference, reference_label="Twice")
    lines = table.splitlines()
    assert lines[0] == r"\begin{tabular}{lrr}" and lines[-1] == r"\end{tabular}"
    assert r"\toprule" in lines and r"\bottomrule" in lines and lines.count(r"\midrule") == 3
    rows = [line for line in lines if line.startswith("$")]
    assert len(rows) == 16 + 22 + 22
    for dof in DOFS:
        for term in model.library.terms[dof]:
            (row,) = [line for line in rows if line.startswith(f"${term.latex(dof)}$ ")]
            cells = [c.strip(" $\\") for c in row.split("&")]
            value = model.coefficients[dof][term.text] * 1e5
            assert float(cells[1]) == pytest.approx(value, rel=5e-4, abs=1e-9)
            if dof == "N" and term.text == "v r delta":
                assert cells[2] == "--"
            else:
                assert float(cells[2]) == pytest.approx(2 * value, rel=5e-4, abs=1e-9)
    assert "$-199408$" in table  # Y'_vvv: integer digits kept, as in Table 8


def test_equations_text_lists_every_active_term(model):
    text = equations_text(model, precision=4)
    lines = text.splitlines()
    assert lines[0].startswith("Abkowitz model") and all(len(x) <= 100 for x in lines)
    blocks = " ".join(lines[1:]).replace("      ", " ")
    assert blocks.count("u_dot'") == 1 and blocks.count("r_dot'") == 2
    assert "- 1.994 v^3" in blocks and "- 0.008853 (1 + du) r" in blocks
    # the Coriolis terms start a line of their own, one per equation, after every fitted term
    marked = [x for x in lines if x.lstrip().startswith("(Coriolis) ")]
    assert len(marked) == 3 and "(1 + du) r" in marked[1]
    assert lines.index(marked[0]) < [i for i, x in enumerate(lines) if x.startswith("Y:")][0]
    with pytest.raises(SindyshipInputError, match="precision"):
        equations_text(model, precision=0)


# ---------------------------------------------------------------------------------------------
# Command line
# ---------------------------------------------------------------------------------------------
def _args(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="sindyship")
    export_verb.add_parser(parser.add_subparsers(dest="verb"))
    return parser.parse_args(["export", *argv])


def test_cmd_export_writes_latex_and_python(model, tmp_path, capsys):
    saved = tmp_path / "model.json"
    model.save(saved)
    tex, py = tmp_path / "out" / "eqs.tex", tmp_path / "out" / "sim.py"
    assert export_verb.run(_args(str(saved), "--latex", str(tex), "--python", str(py),
                            "--precision", "6", "--json")) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["active_terms"] == {"X": 15, "Y": 22, "N": 22}
    assert r"\begin{align}" in tex.read_text() and r"\toprule" in tex.read_text()
    assert "-0.00226510" not in tex.read_text() and "-0.0022651" in tex.read_text()
    # the two files and nothing else (before importing sim.py writes its byte code there)
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["eqs.tex", "sim.py"]
    sim = load_module(py.read_text(), py)
    assert sim.COEFFICIENTS["N_uv"] == model.coefficients["N"]["du v"]
    # forces() reads the named constants: a change to COEFFICIENTS had been silently ignored
    with pytest.raises(TypeError, match="does not support item assignment"):
        sim.COEFFICIENTS["N_uv"] = 0.0
    assert export_verb.run(_args(str(saved))) == 0
    printed = capsys.readouterr().out.splitlines()
    assert [line for line in printed if line.startswith("X: ")][0].startswith(
        "X: 0.008853 u_dot' = -0.002265 du - 0.0005081 du^2 + 0.002459 v^2")


def test_export_refuses_a_precision_out_of_range_when_parsing(model, tmp_path, capsys):
    from sindyship.cli import main

    model.save(tmp_path / "m.json")
    with pytest.raises(SystemExit) as stop:
        main(["export", str(tmp_path / "m.json"), "--precision", "0"])
    assert stop.value.code == 2
    assert "--precision" in capsys.readouterr().err


@pytest.mark.parametrize(("argv", "message"), [
    (["missing.json"], "no such model file"),
    (["{model}", "--latex", "same.txt", "--python", "same.txt"], "two different files"),
    (["{model}", "--python", "{folder}"], "is a folder"),
    (["{model}", "--channel", "n"], "NAME=VALUE"),
])
def test_cmd_export_rejects_bad_input(model, tmp_path, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    model.save(tmp_path / "m.json")
    terms = {dof: ["du", "v", "r", "delta"] for dof in DOFS}
    terms["X"].append("n")
    with_n = AbkowitzModel(model.ship, TermLibrary("with-n", "prime-I", "", terms),
                           {dof: {t: 1e-4 for t in terms[dof]} for dof in DOFS})
    with_n.save(tmp_path / "n.json")
    (tmp_path / "folder").mkdir()
    argv = [a.format(model="m.json", model_n="n.json", folder="folder") for a in argv]
    with pytest.raises(SindyshipInputError, match=message):
        export_verb.run(_args(*argv))


def test_hostile_names_stay_text_in_latex_and_python(tmp_path, protocol_runs):
    """A ship name with newlines, a LaTeX command and a triple quote: the LaTeX keeps it on the
    comment line, escaped, and the generated module parses and holds the name exactly."""
    import ast

    from sindyship.export import latex_document_part
    from sindyship.identify import fit
    from sindyship.ships import load_ship

    evil = 'evil\n\\input{/etc/passwd}\n""" ; import os'
    (tmp_path / "evil.toml").write_text(
        f"name = {json.dumps(evil)}\n[particulars]\nL = 230.0\nB = 32.2\nd = 10.8\n"
        "displacement = 52030.0\nrho = 1025.0\nU0 = 12.348\nx_G = -3.404\n[mass]\nk_zz = 0.25\n")
    ship = load_ship(tmp_path / "evil.toml")
    assert ship.name == evil
    model = fit(protocol_runs["train"][:3], ship)
    tex = latex_document_part(model)
    assert not any(line.lstrip().startswith("\\input") for line in tex.splitlines())
    source = generate_python(model)
    ast.parse(source)
    namespace: dict = {}
    exec(compile(source, "evil_sim.py", "exec"), namespace)
    assert namespace["SHIP"] == evil


def test_a_long_equation_is_split_into_tables_that_fit_a_page(protocol_runs, kcs):
    """With four effects the sway and yaw equations hold 52 terms each, whose one table ran
    34 pt off an article's page: tables of at most TABLE_ROWS rows, every term once."""
    from sindyship.export.text import TABLE_ROWS
    from sindyship.identify import fit

    model = fit(protocol_runs["train"], kcs,
                effects=["environment", "asymmetry", "higher_order", "crossflow"])
    table = coefficient_table_latex(model, 4)
    tables = table.split(r"\end{tabular}")[:-1]
    assert all(part.count(r" \\") - 2 <= TABLE_ROWS for part in tables)
    assert sum(len(model.library.terms[dof]) for dof in DOFS) == sum(
        line.startswith("$") for line in table.splitlines())
    long = [dof for dof in DOFS if len(model.library.terms[dof]) > TABLE_ROWS]
    assert long and table.count("(1 of 2)") == len(long) == table.count("(2 of 2)")
    coriolis = equations_latex(model, 17, line_length=30)
    assert coriolis.count(r"}_{\text{Coriolis}}") > 2  # a brace a line when they do not fit


@pytest.mark.parametrize("compiled", [False, True])
def test_a_model_with_delayed_channels_flies_its_record_as_sindyship_flies_it(kcs, tmp_path,
                                                                              compiled):
    """A library that delays a channel (a lagging sensor, as ``discover`` finds) had its
    delay left out of every export: the generated module read the revolutions and the
    commanded rudder as given, and its text and LaTeX never said the forces read them later."""
    if compiled and importlib.util.find_spec("numba") is None:
        pytest.skip("numba is not installed: the compiled path does not run")
    base = paper_model(kcs)
    terms = {dof: [t.text for t in base.library.terms[dof]] for dof in DOFS}
    terms["X"].append("n")
    delays = {"n": 4.0, "delta_c": 1.5}
    library = TermLibrary("paper-with-lagging-n", "prime-I", "", terms, delays=delays)
    coefficients = {dof: dict(base.coefficients[dof]) for dof in DOFS}
    coefficients["X"]["n"] = 1e-5
    model = AbkowitzModel(kcs, library, coefficients, rudder_signal="commanded")
    (run,) = fly(MMGModel(kcs), [Manoeuvre("random", rudder=20, duration=300, seed=3)])
    data = run.data.copy()
    n = kcs.propeller.n_P
    data["n"] = n * (1.0 + 0.3 * np.sin(run.t / 40.0))  # revolutions that change quickly
    record = Trajectory(data, name=run.name)
    sim = load_module(generate_python(model, compiled=compiled),
                      tmp_path / f"sim_delay{int(compiled)}.py")
    assert dict(sim.DELAYS) == delays and sim.DELAYED_ANGLES == ("delta_c",)
    (ours,) = fly_like_batch(model, [record])
    part = flown_part(record)  # the part sindyship flies, from its flight start
    theirs = sim.simulate(part.t, part["delta_c"], part.state()[:, 0], {"n": part["n"]})
    assert ours.meta["diverged_at"] is None and theirs.diverged_at is None
    gap = np.hypot(ours["x"] - theirs.states[3], ours["y"] - theirs.states[4]) / kcs.L
    assert np.max(gap) < 1e-9
    # read as given (no delay), the same record flies measurably elsewhere
    undelayed = AbkowitzModel(kcs, TermLibrary("paper-with-n", "prime-I", "", terms),
                              coefficients, rudder_signal="commanded")
    (plain,) = fly_like_batch(undelayed, [record])
    assert np.max(np.hypot(ours["x"] - plain["x"], ours["y"] - plain["y"])) / kcs.L > 1e-3
    # and every export says so
    said = ("the recorded delta_c lags the physics by 1.5 s (read 1.5 s later); the recorded "
            "n lags the physics by 4 s (read 4 s later)")
    doc = " ".join(sim.__doc__.split())
    assert f"Delayed channels (DELAYS): {said}." in doc
    assert "For a record without delta, give state0's rudder angle as its delta_c 1.5 s" in doc
    assert said in " ".join(equations_text(model).split())
    latex = equations_latex(model)
    assert r"\text{(the recorded delta\_c lags the physics by 1.5 s (read 1.5 s later))}" in latex
    assert r"\text{(the recorded n lags the physics by 4 s (read 4 s later))}" in latex


def test_a_delayed_rudder_flies_as_sindyship_flies_it_from_the_state_its_docstring_asks(
        kcs, tmp_path):
    """A lagging rudder sensor (the delay discover searches with the actual rudder), and a
    lagging delta_c in a record without delta: the module flies the record as sindyship does
    from the state0 its docstring asks for (the rudder as recorded DELAYS later)."""
    base = paper_model(kcs)
    terms = {dof: [t.text for t in base.library.terms[dof]] for dof in DOFS}
    (run,) = fly(MMGModel(kcs), [Manoeuvre("random", rudder=20, duration=300, seed=3)])
    commanded_only = Trajectory(run.data.drop(columns="delta"), name=run.name)
    for delays, signal, record in (({"delta": 3.0}, "actual", run),
                                   ({"delta_c": 2.0}, "commanded", commanded_only)):
        library = TermLibrary("paper-late-rudder", "prime-I", "", terms, delays=delays)
        model = AbkowitzModel(kcs, library, base.coefficients, rudder_signal=signal)
        sim = load_module(generate_python(model), tmp_path / f"sim_{signal}.py")
        (ours,) = fly_like_batch(model, [record])
        part = flown_part(record)
        (name, seconds), = delays.items()
        state0 = part.state()[:, 0]
        assert abs(np.interp(part.t[0] + seconds, part.t, part[name]) - state0[6]) > 1e-3
        state0[6] = np.interp(part.t[0] + seconds, part.t, part[name])  # as the doc asks
        theirs = sim.simulate(part.t, part["delta_c"], state0)
        gap = np.hypot(ours["x"] - theirs.states[3], ours["y"] - theirs.states[4]) / kcs.L
        assert np.max(gap) < 1e-9, delays
        doc = " ".join(sim.__doc__.split())
        whose = "the record's" if name == "delta" else "its"
        assert f"give state0's rudder angle as {whose} {name} {seconds:g} s after t[0]" in (
            doc.lower())
    leading = TermLibrary("paper-early-rudder", "prime-I", "", terms, delays={"delta_c": -2.0})
    text = equations_text(AbkowitzModel(kcs, leading, base.coefficients), width=400)
    assert "the recorded delta_c leads the physics by 2 s (read 2 s earlier)" in text


@pytest.mark.parametrize("compiled", [False, True])
def test_replay_flies_a_record_of_the_actual_rudder_as_sindyship_flies_it(kcs, tmp_path,
                                                                          compiled):
    """A record that holds only the actual rudder (as the MARIN trials) is flown by sindyship
    with that angle prescribed, bypassing the servo; ``replay`` flies it the same, also where
    the library delays the rudder (read that much later), and passing the record's rudder to
    ``simulate`` as a command flies it elsewhere (through the servo's lag)."""
    if compiled and importlib.util.find_spec("numba") is None:
        pytest.skip("numba is not installed: the compiled path does not run")
    base = paper_model(kcs)
    terms = {dof: [t.text for t in base.library.terms[dof]] for dof in DOFS}
    (run,) = fly(MMGModel(kcs), [Manoeuvre("random", rudder=20, duration=300, seed=3)])
    actual_only = Trajectory(run.data.drop(columns="delta_c"), name=run.name)
    for delays in ({}, {"delta": 3.0}):
        library = TermLibrary("paper-replayed", "prime-I", "", terms, delays=delays)
        model = AbkowitzModel(kcs, library, base.coefficients, rudder_signal="actual")
        sim = load_module(generate_python(model, compiled=compiled),
                          tmp_path / f"sim_replay{int(compiled)}{len(delays)}.py")
        (ours,) = fly_like_batch(model, [actual_only])
        assert flown_as(actual_only)["flown_as"] == "replay-actual"
        part = flown_part(actual_only)
        theirs = sim.replay(part.t, part["delta"], part.state()[:, 0])
        assert theirs.diverged_at is None
        gap = np.hypot(ours["x"] - theirs.states[3], ours["y"] - theirs.states[4]) / kcs.L
        assert np.max(gap) < 1e-9, delays
        late = np.interp(part.t + delays.get("delta", 0.0), part.t, part["delta"])
        np.testing.assert_allclose(theirs.states[6], late, atol=1e-12)  # the angle, no servo
        np.testing.assert_array_equal(theirs.delta_c, late)  # at the same output times
    commanded = sim.simulate(part.t, part["delta"], part.state()[:, 0])
    assert np.max(np.abs(commanded.states[6] - theirs.states[6])) > math.radians(1.0)
    with pytest.raises(ValueError, match="delta reaches 20 rad, more than a quarter turn"):
        sim.replay(part.t, np.full(part.t.shape, 20.0))
    with pytest.raises(ValueError, match=r"delta has shape \(3,\); give one angle per output"):
        sim.replay(part.t, [0.0, 0.1, 0.2])
    with pytest.raises(ValueError, match="replay takes the rudder angle as an array over t or "
                       "a constant, not a function"):
        sim.replay(part.t, lambda time, state: 0.1)
