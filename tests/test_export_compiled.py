"""The generated simulator with its numba-compiled right-hand side (``export --compile``).

The compiled module is checked against sindyship's term-by-term path and against the plain
generated module: its right-hand side to 1e-12 of each channel's size (measured about 1e-16),
its flights to the same 1e-9 as the plain module's (measured about 5e-14).  Without numba the
module runs its numpy path after one warning, checked in a subprocess that cannot import
numba.  Each compiled module compiles once (about 2 s), so the tests share two.
"""

from __future__ import annotations

import doctest
import importlib.util
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sindyship.export import generate_python
from sindyship.flights import fly_like_batch
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
from sindyship.targets import DOFS
from sindyship.trajectory import Trajectory

RTOL = 1e-9  # flights, relative to each channel's size (as tests/test_export.py)
RHS_RTOL = 1e-12  # one right-hand side


def relative_difference(a: np.ndarray, b: np.ndarray) -> float:
    """max |a - b| / (max |b| + tiny) over each state channel, the worst channel."""
    a, b = np.atleast_2d(a), np.atleast_2d(b)
    scale = np.max(np.abs(b), axis=1) + 1e-300
    return float(np.max(np.max(np.abs(a - b), axis=1) / scale))


def load_module(source: str, path: Path, register: bool = False):
    """The module of ``source`` written to ``path``; ``register``: as ``import`` does, in
    sys.modules under its name (numba's cache needs to find the module again)."""
    path.write_text(source)
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    if register:
        sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def needs_numba():
    return pytest.importorskip("numba", reason="numba is not installed (pip install numba)")


@pytest.fixture(scope="module")
def model(kcs):
    return paper_model(kcs, "LS")


@pytest.fixture(scope="module")
def compiled_sim(model, tmp_path_factory):
    needs_numba()
    folder = tmp_path_factory.mktemp("compiled")
    yield load_module(generate_python(model, compiled=True), folder / "kcs_fast.py",
                      register=True)
    sys.modules.pop("kcs_fast", None)


@pytest.fixture(scope="module")
def exotic(kcs):
    """A model on the commanded rudder with heading, abs and sign terms and the revolutions n."""
    base = load_library("abkowitz")
    terms = {dof: [t.text for t in base.terms[dof]] for dof in DOFS}
    terms["X"] += ["cos(psi)", "n"]
    terms["Y"] += ["sin(psi)", "abs(v) v", "sign(r) r^2"]
    terms["N"] += ["sin(psi)", "cos(psi) r", "abs(r) r"]
    library = TermLibrary("abkowitz+exotic", "prime-I", "test library", terms)
    paper = paper_model(kcs, "LS")
    coefficients = {dof: dict(paper.coefficients[dof]) for dof in DOFS}
    coefficients["X"].update({"cos(psi)": -2e-5, "n": 2e-5})
    coefficients["Y"].update({"sin(psi)": 3e-5, "abs(v) v": -0.01, "sign(r) r^2": 1e-4})
    coefficients["N"].update({"sin(psi)": -1e-5, "cos(psi) r": 2e-5, "abs(r) r": -2e-4})
    return AbkowitzModel(kcs, library, coefficients, rudder_signal="commanded")


@pytest.fixture(scope="module")
def exotic_sim(exotic, tmp_path_factory):
    needs_numba()
    folder = tmp_path_factory.mktemp("compiled_exotic")
    return load_module(generate_python(exotic, channels={"n": 2.9}, compiled=True),
                       folder / "exotic_fast.py")


def random_states(ship, rng, n):
    U0, L = ship.U0, ship.L
    states = np.vstack([U0 * rng.uniform(0.6, 1.1, n), U0 * rng.uniform(-0.2, 0.2, n),
                        U0 / L * rng.uniform(-0.5, 0.5, n), rng.normal(0, 500, (2, n)),
                        rng.uniform(-4, 4, n), rng.uniform(-0.6, 0.6, n)])
    return states, rng.uniform(-0.7, 0.7, n)


def test_compiled_rhs_equals_sindyship_single_and_batch(model, compiled_sim, seed, tmp_path):
    import numba

    assert compiled_sim.COMPILED is True
    assert isinstance(compiled_sim._rhs_columns, numba.core.dispatcher.Dispatcher)
    n = 11
    states, delta_c = random_states(model.ship, np.random.default_rng(seed), n)
    reference = integrator_for(model.dynamics(), [StepCommand([0.0], [0.0])] * n).rhs(
        0.0, states, delta_c, np.arange(n), None)
    batch = compiled_sim.rhs(0.0, states, delta_c)
    columns = np.column_stack([compiled_sim.rhs(0.0, states[:, j], delta_c[j])
                               for j in range(n)])
    assert compiled_sim._rhs_columns.signatures  # the compiled loop ran
    assert batch.shape == (7, n) and compiled_sim.rhs(0.0, states[:, 0], 0.1).shape == (7,)
    assert relative_difference(batch, reference) <= RHS_RTOL
    assert relative_difference(columns, reference) <= RHS_RTOL
    plain = load_module(generate_python(model), tmp_path / "kcs_plain.py")
    assert relative_difference(batch, plain.rhs(0.0, states, delta_c)) <= RHS_RTOL
    # one command for every state, a non-contiguous state, a wrong number of commands
    shared = compiled_sim.rhs(0.0, states[:, ::2], 0.3)
    assert relative_difference(shared, plain.rhs(0.0, states[:, ::2], 0.3)) <= RHS_RTOL
    with pytest.raises(ValueError, match="delta_c has 3 values"):
        compiled_sim.rhs(0.0, states, delta_c[:3])
    # compiled once and kept where numba keeps caches (beside the module, or NUMBA_CACHE_DIR)
    cache = Path(compiled_sim._rhs_columns._cache.cache_path)
    assert any(p.suffix == ".nbi" for p in cache.iterdir())


def test_arguments_that_need_no_conversion_take_the_short_way_with_the_same_result(
        model, compiled_sim, seed, tmp_path):
    """A float64 state and a float or float64 command go straight into the compiled loop
    (_rhs_as_given); every other form is converted first; both give the plain module's
    numbers."""
    plain = load_module(generate_python(model), tmp_path / "kcs_plain_forms.py")
    states, delta_c = random_states(model.ship, np.random.default_rng(seed), 5)
    short = [(states, delta_c), (states, 0.2), (states, np.float64(0.2)), (states, delta_c[:1]),
             (states[:, 0].copy(), 0.2), (np.asfortranarray(states), delta_c),
             (states[:, ::2], -0.1)]
    converted = [(states.astype(np.float32), delta_c), (states, delta_c.astype(np.float32)),
                 (states.tolist(), 0.2), (states, 1), (states[:, 0], delta_c[:1])]
    for state, command in short + converted:
        expected = plain.rhs(0.0, np.asarray(state, dtype=float), command)
        got = compiled_sim.rhs(0.0, state, command)
        assert got.shape == expected.shape and got.dtype == np.float64
        assert relative_difference(got, expected) <= RHS_RTOL
    for state, command in short:
        assert compiled_sim._rhs_as_given(state, command) is not None
    for state, command in converted:
        assert compiled_sim._rhs_as_given(state, command) is None
    with pytest.raises(ValueError, match="delta_c has 3 values"):
        compiled_sim.rhs(0.0, states, delta_c[:3])
    with pytest.raises(ValueError, match=r"state has shape \(6, 5\); give the 7 values"):
        compiled_sim.rhs(0.0, states[:6], 0.1)


def test_compiled_module_flies_held_out_manoeuvres_like_sindyship(model, compiled_sim):
    t = np.arange(3200.0)
    state0 = np.array([model.ship.U0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    reference = {r.name: r for r in fly(model.dynamics(), protocol_manoeuvres()["test"])}
    flights = {
        "tc15_port": compiled_sim.simulate(t, np.full(t.shape, np.radians(-15.0)), state0),
        "tc15_stbd": compiled_sim.simulate(t, np.radians(15.0), state0),
        "zz10_10": compiled_sim.zigzag(t, 10.0, 10.0, state0),
    }
    for name, flight in flights.items():
        ref = reference[name]
        assert flight.diverged_at is None
        assert relative_difference(flight.states, ref.state()) <= RTOL, name
        assert np.array_equal(flight.delta_c, ref["delta_c"]), name
    assert np.sum(np.diff(np.sign(flights["zz10_10"].delta_c)) != 0) >= 8


def test_compiled_step_feedback_and_divergence_match_sindyship(model, compiled_sim):
    t = np.arange(0.0, 600.0, 0.5)
    state0 = np.array([model.ship.U0, 0, 0, 0, 0, 0, 0])
    angles = np.where(t < 150.0, 0.2, np.where(t < 400.0, -0.1, 0.35))
    (ref,) = simulate_batch(model.dynamics(), [StepCommand([0.0, 150.0, 400.0],
                                                           [0.2, -0.1, 0.35])], t, state0)
    assert relative_difference(compiled_sim.simulate(t, angles, state0).states,
                               ref.states) <= RTOL

    def heading_hold(time, state):
        return float(np.clip(2.0 * (math.radians(20.0) - state[5]), -0.6, 0.6))

    (ref,) = simulate_batch(model.dynamics(), [FeedbackCommand(heading_hold)], t, state0)
    assert relative_difference(compiled_sim.simulate(t, heading_hold, state0).states,
                               ref.states) <= RTOL
    results = doctest.testmod(compiled_sim, verbose=False)
    assert results.attempted >= 4 and results.failed == 0


def test_compiled_exotic_terms_channels_and_commanded_rudder(exotic, exotic_sim, kcs, seed,
                                                            tmp_path):
    """Heading, abs and sign terms, the commanded rudder, and the revolutions n as a default,
    as values given to rhs, and as a time series over a flight."""
    assert exotic_sim.COMPILED is True and exotic_sim.RUDDER_INPUT == "commanded"
    n = 9
    states, delta_c = random_states(kcs, np.random.default_rng(seed), n)
    integ = integrator_for(exotic.dynamics({"n": 2.9}), [StepCommand([0.0], [0.0])] * n)
    reference = integ.rhs(0.0, states, delta_c, np.arange(n), None)
    assert relative_difference(exotic_sim.rhs(0.0, states, delta_c), reference) <= RHS_RTOL
    revolutions = {"n": np.linspace(1.5, 2.2, n)}  # SI [1/s], one value per state
    plain = load_module(generate_python(exotic, channels={"n": 2.9}), tmp_path / "plain.py")
    assert relative_difference(exotic_sim.rhs(0.0, states, delta_c, revolutions),
                               plain.rhs(0.0, states, delta_c, revolutions)) <= RHS_RTOL

    t = np.arange(0.0, 900.0)
    state0 = np.array([kcs.U0, 0, 0, 0, 0, 0.3, 0])
    (ref,) = simulate_batch(exotic.dynamics({"n": 2.9}),
                            [ZigZagCommand(math.radians(10.0), math.radians(10.0), -1)], t,
                            state0)
    flight = exotic_sim.zigzag(t, 10.0, 10.0, state0, first_sign=-1)
    assert relative_difference(flight.states, ref.states) <= RTOL
    (run,) = fly(MMGModel(kcs), [Manoeuvre("turning-circle", rudder=20, duration=300)])
    data = run.data.copy()
    data["n"] = np.linspace(1.5, 2.2, run.n_samples)
    record = Trajectory(data, name=run.name)
    (ours,) = fly_like_batch(exotic, [record])
    theirs = exotic_sim.simulate(record.t, record["delta_c"], record.state()[:, 0],
                                 {"n": data["n"].to_numpy()})
    assert ours.meta["diverged_at"] is None and theirs.diverged_at is None
    assert np.max(np.hypot(ours["x"] - theirs.states[3], ours["y"] - theirs.states[4])
                  ) / kcs.L < 1e-10


def test_source_run_without_a_file_compiles_without_a_cache(model):
    needs_numba()
    namespace: dict = {}
    exec(compile(generate_python(model, compiled=True), "kcs_fast.py", "exec"), namespace)
    assert namespace["COMPILED"] is True and namespace["_CACHE"] is False


FROM_CACHE = '''
import importlib.util, json, sys
import numpy as np
sys.path.insert(0, sys.argv[1])
import kcs_fast  # a new process imports the module: numba loads what the first one compiled
state = np.array([kcs_fast.U0, 0.3, 0.001, 0.0, 0.0, 0.2, 0.05])
imported = kcs_fast.rhs(0.0, state, 0.1)
spec = importlib.util.spec_from_file_location("unregistered", kcs_fast.__file__)
loose = importlib.util.module_from_spec(spec)  # not in sys.modules: compiles, no cache
spec.loader.exec_module(loose)
print(json.dumps({"cache": [kcs_fast._CACHE, loose._CACHE],
                  # one state and one command: the compiled _rhs_one_state, from the cache
                  "hits": sum(kcs_fast._rhs_one_state.stats.cache_hits.values()),
                  "same": loose.rhs(0.0, state, 0.1).tolist() == imported.tolist()}))
'''


def test_a_new_process_loads_the_compiled_code_from_the_cache(compiled_sim):
    compiled_sim.rhs(0.0, np.array([compiled_sim.U0, 0, 0, 0, 0, 0, 0]), 0.1)
    folder = Path(compiled_sim.__file__).parent
    done = subprocess.run([sys.executable, "-c", FROM_CACHE, str(folder)], capture_output=True,
                          text=True, timeout=120, cwd=folder)
    assert done.returncode == 0, done.stderr
    facts = json.loads(done.stdout)
    assert facts == {"cache": [True, False], "hits": 1, "same": True}


FALLBACK = '''
import importlib.util, json, sys
sys.modules["numba"] = None  # as if numba were not installed
import numpy as np
spec = importlib.util.spec_from_file_location("kcs_fast", sys.argv[1])
sim = importlib.util.module_from_spec(spec)
spec.loader.exec_module(sim)
state = np.array([sim.U0, 0.3, 0.001, 0.0, 0.0, 0.2, 0.05])
flight = sim.zigzag(np.arange(300.0), 10.0, 10.0)
print(json.dumps({"compiled": sim.COMPILED, "rhs": sim.rhs(0.0, state, 0.1).tolist(),
                  "heading": flight.states[5].tolist()}))
'''


def test_without_numba_the_compiled_module_runs_numpy_after_one_warning(model, tmp_path):
    generated = tmp_path / "kcs_fast.py"
    generated.write_text(generate_python(model, compiled=True))
    plain = load_module(generate_python(model), tmp_path / "kcs_plain.py")
    done = subprocess.run([sys.executable, "-c", FALLBACK, str(generated)], capture_output=True,
                          text=True, timeout=120, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    (notice,) = done.stderr.strip().splitlines()
    assert "numba is not installed" in notice and "pip install numba" in notice
    facts = json.loads(done.stdout)
    assert facts["compiled"] is False
    state = np.array([plain.U0, 0.3, 0.001, 0.0, 0.0, 0.2, 0.05])
    assert facts["rhs"] == plain.rhs(0.0, state, 0.1).tolist()  # the numpy path, exactly
    assert facts["heading"] == plain.zigzag(np.arange(300.0), 10.0, 10.0).states[5].tolist()


# ---------------------------------------------------------------------------------------------
# Command line
# ---------------------------------------------------------------------------------------------
def test_cmd_export_compile_writes_the_compiled_simulator(model, tmp_path, capsys):
    import argparse

    from sindyship.cli import export as export_verb
    from sindyship.errors import SindyshipInputError

    def args(*argv):
        parser = argparse.ArgumentParser(prog="sindyship")
        export_verb.add_parser(parser.add_subparsers(dest="verb"))
        return parser.parse_args(["export", *argv])

    saved = tmp_path / "model.json"
    model.save(saved)
    py = tmp_path / "sim.py"
    assert export_verb.run(args(str(saved), "--python", str(py), "--compile", "--json")) == 0
    assert json.loads(capsys.readouterr().out)["compiled"] is True
    source = py.read_text()
    assert "COMPILED = numba is not None" in source and "def _rhs_columns(" in source
    assert source == generate_python(model, source_note="Exported from model.json.",
                                     compiled=True)
    with pytest.raises(SindyshipInputError, match="give --python FILE too"):
        export_verb.run(args(str(saved), "--compile"))
