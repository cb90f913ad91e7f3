"""Time the generated standalone simulators against sindyship's term-by-term path.

The model is the paper's LS model of the KCS (Tables 7-9), exported twice: plain (numpy only)
and with ``compiled=True`` (``sindyship export --python FILE --compile``: the right-hand side
and the RK4 step as numba-compiled loops).  Each measurement is the best of ``--repeat`` runs,
the sides interleaved so that a busy machine slows them alike:

(a) one call of the right-hand side of eq. 12-14: the generated ``rhs`` of both modules
    against ``sindyship.simulation._Integrator.rhs`` (``AbkowitzDynamics.accelerations``
    term by term, plus the servo and the kinematics), on a single state and on a (7, 11)
    batch, the compiled one after its warm-up (target: the compiled module 10 times faster
    than sindyship); the compile time is reported apart: the first calls in a fresh folder
    (numba compiles and writes its cache) and the first call of a new process that finds the
    cache;
(b) a 3200 s zig-zag 10/10 flown closed loop at the default step: the generated ``zigzag``
    of both modules against ``sindyship.simulation.simulate_batch`` (target: the compiled
    module 3 times faster), and the largest difference between the trajectories relative to
    each channel's size.

pysindy's ``SINDy.simulate`` integrates x' = f(x, u) for a given input signal; it cannot fly
a model with a mass matrix, a rudder servo and heading feedback (a closed-loop zig-zag), so
it is not compared.  Without numba the compiled entries are null.

Prints and saves ``benchmarks/results/export.json``.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from sindyship.export import generate_python
from sindyship.model import paper_model
from sindyship.ships import load_ship
from sindyship.simulation import ConstantCommand, ZigZagCommand, integrator_for, simulate_batch

OUT = Path(__file__).parent / "results" / "export.json"
RHS_TARGET = 10.0
ZIGZAG_TARGET = 3.0
# a new process imports the compiled module and calls rhs once: numba loads its cache
FROM_CACHE = """
import sys, time
import numpy as np
start = time.perf_counter()
sys.path.insert(0, sys.argv[1])
import kcs_ls_fast as sim
sim.rhs(0.0, np.tile([[sim.U0], [0.0], [0.0], [0.0], [0.0], [0.0], [0.0]], 3), 0.0)
sim.zigzag(np.arange(10.0), 10.0, 10.0)
print(time.perf_counter() - start)
"""


def best_per_call(functions: dict, calls: int, repeat: int) -> dict[str, float]:
    """Best time per call [s] of each function, the functions measured in turn."""
    best = dict.fromkeys(functions, math.inf)
    for _ in range(repeat):
        for name, function in functions.items():
            start = time.perf_counter()
            for _ in range(calls):
                function()
            best[name] = min(best[name], (time.perf_counter() - start) / calls)
    return best


def load(path: Path, source: str):
    """The module of ``source`` written to ``path``, imported (in ``sys.modules``, where
    numba's cache finds it)."""
    path.write_text(source)
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def compile_times(fast, path: Path, batch: np.ndarray, commands: np.ndarray) -> dict:
    """Seconds of the first calls (numba compiles) and of a new process's first calls."""
    start = time.perf_counter()
    fast.rhs(0.0, batch, commands)
    rhs_first = time.perf_counter() - start
    start = time.perf_counter()
    fast.zigzag(np.arange(10.0), 10.0, 10.0)
    step_first = time.perf_counter() - start
    done = subprocess.run([sys.executable, "-c", FROM_CACHE, str(path.parent)], capture_output=True,
                          text=True, check=True)
    return {"rhs_first_call_s": rhs_first, "rk4_step_first_flight_s": step_first,
            "new_process_import_and_first_calls_s": float(done.stdout)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--calls", type=int, default=500)
    args = parser.parse_args()
    ship = load_ship("kcs")
    model = paper_model(ship, "LS")
    has_numba = importlib.util.find_spec("numba") is not None

    rng = np.random.default_rng(0)
    n = 11
    U0, L = ship.U0, ship.L
    batch = np.vstack([U0 * rng.uniform(0.7, 1.0, n), U0 * rng.uniform(-0.1, 0.1, n),
                       U0 / L * rng.uniform(-0.4, 0.4, n), rng.normal(0, 500, (2, n)),
                       rng.uniform(-3, 3, n), rng.uniform(-0.5, 0.5, n)])
    commands = rng.uniform(-0.6, 0.6, n)
    with tempfile.TemporaryDirectory() as folder:
        sim = load(Path(folder) / "kcs_ls_sim.py", generate_python(model))
        fast = compiled = None
        if has_numba:
            path = Path(folder) / "kcs_ls_fast.py"
            fast = load(path, generate_python(model, compiled=True))
            compiled = compile_times(fast, path, batch, commands)

    # (a) right-hand side
    one, one_cmd = batch[:, :1].copy(), commands[:1].copy()
    single = integrator_for(model.dynamics(), [ConstantCommand(0.0)])
    many = integrator_for(model.dynamics(), [ConstantCommand(0.0)] * n)
    members1, members11 = np.arange(1), np.arange(n)
    state1, cmd1 = one[:, 0].copy(), float(one_cmd[0])
    sides = {"sindyship": None, "generated": sim, "compiled": fast}
    functions = {}
    for side, module in sides.items():
        if side == "sindyship":
            functions["sindyship_single"] = lambda: single.rhs(0.0, one, one_cmd, members1, None)
            functions["sindyship_batch11"] = lambda: many.rhs(0.0, batch, commands, members11,
                                                              None)
        elif module is not None:
            functions[f"{side}_single"] = lambda m=module: m.rhs(0.0, state1, cmd1)
            functions[f"{side}_batch11"] = lambda m=module: m.rhs(0.0, batch, commands)
    rhs_times = best_per_call(functions, args.calls, args.repeat)
    reference_batch = many.rhs(0.0, batch, commands, members11, None)
    reference_single = single.rhs(0.0, one, one_cmd, members1, None)[:, 0]
    rhs_difference = {
        side: max(float(np.max(np.abs(module.rhs(0.0, batch, commands) - reference_batch))),
                  float(np.max(np.abs(module.rhs(0.0, state1, cmd1) - reference_single))))
        for side, module in sides.items() if module is not None}

    # (b) a 3200 s zig-zag 10/10, closed loop, at the default step
    t = np.arange(3200.0)
    state0 = np.array([U0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    flight_times = {side: math.inf for side, module in sides.items()
                    if side == "sindyship" or module is not None}
    flights = {}
    for _ in range(max(1, args.repeat // 2)):
        for side in flight_times:
            start = time.perf_counter()
            if side == "sindyship":
                (flights[side],) = simulate_batch(
                    model.dynamics(), [ZigZagCommand(math.radians(10.0), math.radians(10.0))],
                    t, state0)
            else:
                flights[side] = sides[side].zigzag(t, 10.0, 10.0, state0)
            flight_times[side] = min(flight_times[side], time.perf_counter() - start)
    reference = flights.pop("sindyship").states
    scale = np.max(np.abs(reference), axis=1)
    flight_difference = {
        side: float(np.max(np.max(np.abs(flight.states - reference), axis=1) / scale))
        for side, flight in flights.items()}

    def ratio(numerator: float, denominator: float | None) -> float | None:
        return None if denominator is None else numerator / denominator

    ratios = {
        side: {"rhs_single": ratio(rhs_times["sindyship_single"],
                                   rhs_times.get(f"{side}_single")),
               "rhs_batch11": ratio(rhs_times["sindyship_batch11"],
                                    rhs_times.get(f"{side}_batch11")),
               "zigzag": ratio(flight_times["sindyship"], flight_times.get(side))}
        for side in ("generated", "compiled")}
    targets = {"rhs_single": RHS_TARGET, "rhs_batch11": RHS_TARGET, "zigzag": ZIGZAG_TARGET}
    result = {
        "model": "paper LS (Tables 7-9), KCS",
        "sides": {"sindyship": "_Integrator.rhs with AbkowitzDynamics; simulate_batch",
                  "generated": "generate_python(model): numpy only",
                  "compiled": "generate_python(model, compiled=True): numba"},
        "numba": None if fast is None else sys.modules["numba"].__version__,
        "rhs_us": {k: v * 1e6 for k, v in rhs_times.items()},
        "ratio_to_sindyship": ratios,
        "rhs_max_abs_difference": rhs_difference,
        "compile_seconds": compiled,
        "zigzag_3200s_seconds": flight_times,
        "zigzag_step_s": sim.DEFAULT_STEP,
        "zigzag_max_relative_difference": flight_difference,
        "targets": {"rhs_ratio": RHS_TARGET, "zigzag_ratio": ZIGZAG_TARGET},
        "meets_target": {side: {k: v is not None and v >= targets[k]
                                for k, v in ratios[side].items()}
                         for side in ("generated", "compiled")},
    }
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
