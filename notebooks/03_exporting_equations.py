# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # Exporting the discovered equations
#
# A fitted model is more than a coefficient table: sindyship turns it into sympy equations
# (paper eq. 14 with the eq. 15 forces), LaTeX for a paper, and a standalone Python simulator
# that needs only numpy, to run the identified ship elsewhere (a controller design, a
# simulator, a colleague without sindyship). This notebook fits a sparse model, renders its
# equations, and flies the generated simulator beside sindyship's own.

# %%
import importlib.util
import os
import sys
import tempfile
import time
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from sindyship.export import coefficient_table_latex, equations_latex, generate_python
from sindyship.identify import fit
from sindyship.manoeuvres import Manoeuvre, fly, protocol_manoeuvres
from sindyship.mmg import MMGModel
from sindyship.ships import load_ship

FAST = os.environ.get("SINDYSHIP_FAST") == "1"
DURATION = 800.0 if FAST else 3200.0

ship = load_ship("kcs")
train = fly(MMGModel(ship), protocol_manoeuvres(DURATION)["train"])
model = fit(train, ship, optimizer="lasso")

# %% [markdown]
# ## The equations
# `print(model)` gives readable text; in a notebook the model renders itself as LaTeX.

# %%
print(model)

# %%
model

# %% [markdown]
# The same LaTeX as an `align` environment for a paper, and the coefficient table in the
# style of the paper's Tables 7-9 (booktabs, x 1e-5):

# %%
print(equations_latex(model, precision=3)[:600], "...")
print(coefficient_table_latex(model, precision=4)[:500], "...")

# %% [markdown]
# ## A simulator to take away
# `generate_python` writes a module with `rhs(t, state, delta_c)`, `simulate(...)` and
# `zigzag(...)`; it imports numpy only, never sindyship.

# %%
source = generate_python(model, source_note="notebook example")
print("\n".join(source.splitlines()[:25]))
folder = Path(tempfile.mkdtemp())
(folder / "kcs_lasso.py").write_text(source)
spec = importlib.util.spec_from_file_location("kcs_lasso", folder / "kcs_lasso.py")
kcs_lasso = importlib.util.module_from_spec(spec)
sys.modules["kcs_lasso"] = kcs_lasso
spec.loader.exec_module(kcs_lasso)

# %% [markdown]
# ## The generated simulator beside sindyship's
# A 10/10 zig-zag flown closed loop by both. They use the same integration scheme, so the
# tracks agree to rounding error. sindyship flies with numba-compiled loops where numba is
# installed, so the plain numpy module is slower here; `generate_python(model, compiled=True)`
# (`export --compile`) gives the module compiled loops of its own
# (`benchmarks/bench_export.py` times all three).

# %%
t = np.arange(DURATION)
state0 = np.array([ship.U0, 0, 0, 0, 0, 0, 0])
start = time.perf_counter()
generated = kcs_lasso.zigzag(t, 10.0, 10.0, state0)
t_generated = time.perf_counter() - start
start = time.perf_counter()
(library_run,) = fly(model.dynamics(), [Manoeuvre("zigzag", rudder=10, check=10,
                                                   duration=DURATION)])
t_library = time.perf_counter() - start
gap = np.max(np.hypot(generated.states[3] - library_run["x"],
                      generated.states[4] - library_run["y"]))
print(f"largest position difference {gap:.2e} m; generated {t_generated:.2f} s, "
      f"sindyship {t_library:.2f} s")

fig, ax = plt.subplots(figsize=(8, 3.5), layout="constrained")
ax.plot(t, np.degrees(library_run["psi"]), lw=2.5, color="0.7", label="sindyship")
ax.plot(t, np.degrees(generated.states[5]), ls="--", color="C3", label="generated module")
ax.plot(t, np.degrees(generated.delta_c), lw=0.8, color="C0", label="commanded rudder")
ax.set_xlabel("t [s]")
ax.set_ylabel("heading and rudder [deg]")
ax.grid(alpha=0.3)
ax.legend()
plt.show()

# %% [markdown]
# pysindy's `SINDy.simulate` cannot fly this model: the identified forces enter through a
# mass matrix with Coriolis terms (eq. 14), the rudder follows a servo with lag and rate
# limit, and a zig-zag needs heading feedback. The generated module does all three.
