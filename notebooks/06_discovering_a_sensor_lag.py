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
# # Beyond the catalogue: discovering a lagging rudder sensor
#
# The catalogue of effects (`sindyship effects`) can only name what it holds. Real trials
# hold effects nobody catalogued. Here the "measurements" come from the KCS with the same
# flow straightening on both sides of the rudder, whose rudder-angle **sensor lags the rudder
# by 4 seconds**; the commanded angle is right. The workflow: the identified model fails, the
# catalogue explains nothing, the search beyond it names the lag, and the error falls.

# %%
# %matplotlib inline
import os

import matplotlib.pyplot as plt
import numpy as np

from sindyship.diagnose import diagnose, discover
from sindyship.effects import parse_effects, simulate_with_effects
from sindyship.flights import fly_like
from sindyship.identify import fit
from sindyship.manoeuvres import protocol_manoeuvres
from sindyship.ships import load_ship

FAST = os.environ.get("SINDYSHIP_FAST") == "1"
DURATION = 1000.0 if FAST else 3200.0

ship = load_ship("kcs").with_rudder(gamma_R_stbd=0.415, gamma_R_port=0.415)
plan = protocol_manoeuvres(duration=DURATION)
lag = parse_effects(["rudder_lag=4"])
train = simulate_with_effects(ship, plan["train"], lag)
test = simulate_with_effects(ship, plan["test"], lag)


def mean_distance(model, records):
    """Mean distance [ship lengths] of each held-out flight, or when it diverged (a diverged
    flight has failed: its distance before the divergence says nothing)."""
    rows = []
    for flown, record in zip(fly_like(model, records), records, strict=True):
        diverged = flown.meta.get("diverged_at")
        if diverged is not None:
            rows.append((record.name, f"diverged at {diverged:.0f} s"))
            continue
        d = np.hypot(flown["x"] - record["x"], flown["y"] - record["y"]) / ship.L
        rows.append((record.name, round(float(np.mean(d)), 3)))
    return rows


# %% [markdown]
# ## 1. The model fails
#
# The plain Abkowitz model, fitted on the lagging rudder angle, diverges on the held-out
# manoeuvres (a flight that diverged shows the time it did).

# %%
plain = fit(train, ship)
mean_distance(plain, test)

# %% [markdown]
# ## 2. Nothing in the catalogue explains it
#
# The diagnosis ranks the catalogued effects. None is meaningful, so it searches beyond the
# catalogue and reports under "Not in the catalogue".

# %%
diagnosis = diagnose(train, ship, confirm=0, fly_training=False)
print([(s.effect.name, round(s.explained_signal, 3), s.meaningful) for s in diagnosis.ranking])
print(diagnosis.verdict)

# %% [markdown]
# ## 3. Discovery names the lag
#
# `discover` refits the library with the rudder angle read later by every delay on a grid and
# judges each by its leave-one-manoeuvre-out force error; it also tries terms of pysindy
# feature libraries (heading, position, rudder, motion). The delay wins, estimated close to
# the 4 s hidden in the data.

# %%
found = discover(train, ship)
print(found.report())

# %%
curve = np.array(found.best.curve)
fig, ax = plt.subplots(figsize=(6, 3))
ax.plot(curve[:, 0], curve[:, 1], marker="o")
ax.set_xlabel("delay of the recorded rudder angle [s]")
ax.set_ylabel("cross-validated force error\n(relative to no delay)")
ax.set_yscale("log")
plt.show()

# %% [markdown]
# ## 4. Add it and watch the error fall
#
# The discovery becomes an effect file in the catalogue's format (`sindyship discover
# --out effect.toml` writes it; `fit --effects effect.toml` takes it). Refitted with it, the
# model flies the held-out manoeuvres again, as closely as a model fitted on data without the
# lag.

# %%
print(found.effect_toml())
corrected = fit(train, ship, library=found.library.extended(found.effect()))
clean = fit(simulate_with_effects(ship, plan["train"]), ship)
print("with the discovered delay:", mean_distance(corrected, test))
print("fitted without any lag:   ", mean_distance(clean, simulate_with_effects(ship, plan["test"])))
