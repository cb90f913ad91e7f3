"""Time the generated standalone simulator against sindyship's term-by-term path.

The model is the paper's LS model of the KCS (Tables 7-9).  Two measurements, each the best
of ``--repeat`` runs, the two sides interleaved so that a busy machine slows both alike:

(a) one call of the right-hand side of eq. 12-14: the generated ``rhs`` against
    ``sindyship.simulation._Integrator.rhs`` (``AbkowitzDynamics.accelerations`` term by
    term, plus the servo and the kinematics), on a single state and on a (7, 11) batch
    (target: 10 times faster);
(b) a 3200 s zig-zag 10/10 flown closed loop at the default step: the generated ``zigzag``
    against ``sindyship.simulation.simulate_batch`` (target: 3 times faster), and the
    largest difference between the two trajectories relative to each channel's size.

pysindy's ``SINDy.simulate`` integrates x' = f(x, u) for a given input signal; it cannot fly
a model with a mass matrix, a rudder servo and heading feedback (a closed-loop zig-zag), so
it is not compared.

Prints and saves ``benchmarks/results/export.json``.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import tempfile
import time
from pathlib import Path

import numpy as np

from sindyship.export import generate_python
from sindyship.model import paper_model
from sindyship.ships import load_ship
from sindyship.simulation import ConstantCommand, ZigZagCommand, integrator_for, simulate_batch

OUT = Path(__file__).parent / "results" / "export.json"


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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--calls", type=int, default=500)
    args = parser.parse_args()
    ship = load_ship("kcs")
    model = paper_model(ship, "LS")
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "kcs_ls_sim.py"
        path.write_text(generate_python(model))
        spec = importlib.util.spec_from_file_location("kcs_ls_sim", path)
        sim = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(sim)

    # (a) right-hand side
    rng = np.random.default_rng(0)
    n = 11
    U0, L = ship.U0, ship.L
    batch = np.vstack([U0 * rng.uniform(0.7, 1.0, n), U0 * rng.uniform(-0.1, 0.1, n),
                       U0 / L * rng.uniform(-0.4, 0.4, n), rng.normal(0, 500, (2, n)),
                       rng.uniform(-3, 3, n), rng.uniform(-0.5, 0.5, n)])
    commands = rng.uniform(-0.6, 0.6, n)
    one, one_cmd = batch[:, :1].copy(), commands[:1].copy()
    single = integrator_for(model.dynamics(), [ConstantCommand(0.0)])
    many = integrator_for(model.dynamics(), [ConstantCommand(0.0)] * n)
    members1, members11 = np.arange(1), np.arange(n)
    state1, cmd1 = one[:, 0].copy(), float(one_cmd[0])
    rhs_times = best_per_call({
        "sindyship_single": lambda: single.rhs(0.0, one, one_cmd, members1, None),
        "generated_single": lambda: sim.rhs(0.0, state1, cmd1),
        "sindyship_batch11": lambda: many.rhs(0.0, batch, commands, members11, None),
        "generated_batch11": lambda: sim.rhs(0.0, batch, commands),
    }, args.calls, args.repeat)
    check = np.max(np.abs(sim.rhs(0.0, batch, commands)
                          - many.rhs(0.0, batch, commands, members11, None)))

    # (b) a 3200 s zig-zag 10/10, closed loop, at the default step
    t = np.arange(3200.0)
    state0 = np.array([U0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    flight_times = {"sindyship": math.inf, "generated": math.inf}
    for _ in range(max(1, args.repeat // 2)):
        start = time.perf_counter()
        (reference,) = simulate_batch(model.dynamics(), [ZigZagCommand(math.radians(10.0),
                                                                       math.radians(10.0))],
                                      t, state0)
        flight_times["sindyship"] = min(flight_times["sindyship"], time.perf_counter() - start)
        start = time.perf_counter()
        flight = sim.zigzag(t, 10.0, 10.0, state0)
        flight_times["generated"] = min(flight_times["generated"], time.perf_counter() - start)
    scale = np.max(np.abs(reference.states), axis=1)
    difference = float(np.max(np.max(np.abs(flight.states - reference.states), axis=1) / scale))

    ratio_single = rhs_times["sindyship_single"] / rhs_times["generated_single"]
    ratio_batch = rhs_times["sindyship_batch11"] / rhs_times["generated_batch11"]
    ratio_flight = flight_times["sindyship"] / flight_times["generated"]
    result = {
        "model": "paper LS (Tables 7-9), KCS",
        "rhs_us": {k: v * 1e6 for k, v in rhs_times.items()},
        "rhs_ratio_single": ratio_single,
        "rhs_ratio_batch11": ratio_batch,
        "rhs_batch_max_abs_difference": float(check),
        "zigzag_3200s_seconds": flight_times,
        "zigzag_ratio": ratio_flight,
        "zigzag_step_s": sim.DEFAULT_STEP,
        "zigzag_max_relative_difference": difference,
        "target_rhs_ratio": 10.0,
        "target_zigzag_ratio": 3.0,
        "meets_target": {"rhs_single": ratio_single >= 10.0, "rhs_batch11": ratio_batch >= 10.0,
                         "zigzag": ratio_flight >= 3.0},
    }
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
