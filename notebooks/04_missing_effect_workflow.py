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
# # Finding a missing physical effect
#
# The workflow sindyship is built for: compare an identified model with the measurements, see
# where it fails, learn which physical effect is missing, add it, and watch the error fall.
#
# Here the "measurements" hide an effect we know: a steady earth-fixed force (say wind on the
# superstructure, or a towline) pushes the ship from the north-east. The ship is the KCS with
# the same flow straightening on both sides of the rudder (gamma_R = 0.415), so that the
# rudder's own asymmetry does not answer for the hidden load. The diagnosis does not know what
# was hidden.

# %%
# %matplotlib inline
import os

from IPython.display import display

from sindyship import diagnose_plots
from sindyship.diagnose import before_after, compare, diagnose, force_residuals
from sindyship.effects import parse_effects, simulate_with_effects
from sindyship.identify import fit
from sindyship.manoeuvres import protocol_manoeuvres
from sindyship.ships import load_ship

FAST = os.environ.get("SINDYSHIP_FAST") == "1"
DURATION = 1000.0 if FAST else 2000.0

kcs = load_ship("kcs")
ship = kcs.with_rudder(gamma_R_stbd=0.415, gamma_R_port=0.415)
hidden = parse_effects(["load=0.002", "load_dir=45"])
plan = protocol_manoeuvres(DURATION)
train = simulate_with_effects(ship, plan["train"], hidden)
test = simulate_with_effects(ship, plan["test"], hidden)

# %% [markdown]
# ## 1. Identify and compare
# Least squares on the paper's Abkowitz library, then every manoeuvre flown the way it was
# recorded (zig-zags closed loop).

# %%
model = fit(train, ship, optimizer="ls")
comparisons = compare(model, test, kind="held-out")
for c in comparisons:
    e = c.errors
    print(f"{c.name:10s} mean {e['mean_distance_L']:.3f} L, max {e['max_distance_L']:.3f} L, "
          f"heading RMS {e['rms_heading_deg']:.1f} deg, diverged at {e['diverged_at_s']}")

# %%
worst = max(comparisons, key=lambda c: c.errors["mean_distance_L"])
display(diagnose_plots.plot_comparison(worst.record, {"identified (LS)": worst.flown},
                                       L=ship.L, errors=worst.errors))

# %% [markdown]
# ## 2. Where it fails
# The force residual (measured force of eq. 16 minus the model's) over time, with the
# manoeuvre's phases marked, and binned over the state. A residual that follows the heading
# points at something fixed to the earth rather than to the ship.

# %%
residuals = force_residuals(model, train)
display(diagnose_plots.plot_residual_time_series(residuals, train[1].name))
display(diagnose_plots.plot_residual_bins(residuals))

# %% [markdown]
# ## 3. Which effect is missing
# Every catalogued effect is scored by leave-one-manoeuvre-out cross-validation: how much of the
# remaining force error its terms explain on manoeuvres they were not fitted on. The best are
# confirmed by refitting and re-flying the training manoeuvres.

# %%
diagnosis = diagnose(train, ship, test=test, confirm=1)
print(diagnosis.report())
display(diagnose_plots.plot_ranking(diagnosis))

# %% [markdown]
# ## 4. Add it and watch the error fall

# %%
top = diagnosis.top.effect.name
change = before_after(train, ship, effects=[top], test=test)
print(change.report())
display(change.figure())
