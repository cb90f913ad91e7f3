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
# # Coefficients a naval architect can use: the prior path
#
# Turns and zig-zags tie the drift v' to the yaw rate r', so least squares can trade the
# coefficients of collinear terms against each other and still fly well, while its forces in
# captive (towing-tank) tests have the wrong sign. `optimizer="prior"` draws the coefficients
# toward what the main dimensions say (Clarke et al. 1983 for the linear derivatives,
# Yoshimura & Masumoto 2012 for the non-linear hull derivatives, forces that grow with the
# speed squared) with a weight `strength`. This notebook walks that weight from "the data
# decide everything" to "the prior decides everything" and shows what it does to the captive
# forces and to the held-out flights: the prior's analogue of a sparsity path.

# %%
import os

import matplotlib.pyplot as plt
import numpy as np
from IPython.display import display

from sindyship.captive import captive_tests
from sindyship.evaluation import distance_errors
from sindyship.flights import fly_like_batch
from sindyship.forces import compare_forces, plot_captive_forces
from sindyship.identify import design, fit, resolve_library
from sindyship.manoeuvres import fly, protocol_manoeuvres
from sindyship.mmg import MMGModel
from sindyship.priors import prior_means, semi_empirical_derivatives
from sindyship.reproduce import captive_agreement
from sindyship.ships import load_ship

FAST = os.environ.get("SINDYSHIP_FAST") == "1"
DURATION = 800.0 if FAST else 3200.0
STRENGTHS = [1e-8, 1e-6, 1e-5, 1e-3] if FAST else [1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3]

ship = load_ship("kcs")
plan = protocol_manoeuvres(DURATION)
flown = fly(MMGModel(ship), plan["train"] + plan["test"])
train, test = flown[: len(plan["train"])], flown[len(plan["train"]):]

# %% [markdown]
# ## What the main dimensions say
# The captive-test derivatives the prior starts from (Prime I, x 1e-5), and the same in the
# convention of the identified coefficients, which keep the added-mass Coriolis and Munk terms
# out of the fitted force (eq. 14 and 16).

# %%
captive_estimate = semi_empirical_derivatives(ship)
fitted_convention = prior_means(ship)
for dof in "XYN":
    for term, value in captive_estimate[dof].items():
        fitted_value = fitted_convention[dof][term]
        print(f"{dof}'_{term:6s} captive {value * 1e5:9.1f}   fitted {fitted_value * 1e5:9.1f}")

# %% [markdown]
# ## The path
# One least-squares fit (the paper's library) and one `prior` fit per strength, all on the
# paper's training set. The `prior` fits use the library `abkowitz-vr`: the paper's terms and
# the surge term `v r`, which the prior has an estimate of and eq. 17a leaves out. For each: the
# worst correlation of X, Y and N with the MMG's virtual captive forces over the static drift,
# pure yaw and combined drift-and-yaw tests, and the mean held-out distance.

# %%
paper_library, library = resolve_library("abkowitz"), resolve_library("abkowitz-vr")
models = {"ls": fit(train, ship, library=paper_library)}
problems = design(train, ship, library)
for strength in STRENGTHS:
    models[strength] = fit(train, ship, library=library, optimizer="prior",
                           params={"strength": strength}, problems=problems)
agreement = captive_agreement(models, ship)
sweeps = ("static-drift", "pure-yaw", "drift-yaw")


def worst_force(by_test):
    return min(by_test[t][f]["correlation"] for t in sweeps for f in "XYN")


def held_out(model):
    flights = fly_like_batch(model.dynamics(), test)
    return float(np.mean([distance_errors(f, r, ship.L)["mean_distance_L"]
                          for f, r in zip(flights, test, strict=True)]))


rows = {key: (worst_force(agreement[key]), held_out(model)) for key, model in models.items()}
for key, (worst, distance) in rows.items():
    print(f"{key!s:>8}: worst X/Y/N correlation {worst:+.2f}, "
          f"held-out mean distance {distance:.3f} L")

# %%
fig, (left, right) = plt.subplots(1, 2, figsize=(10, 3.5), sharex=True)
left.semilogx(STRENGTHS, [rows[s][0] for s in STRENGTHS], "o-", label="prior")
left.axhline(rows["ls"][0], color="k", ls="--", label="least squares")
left.set(xlabel="prior strength", ylabel="worst correlation with captive forces")
right.semilogx(STRENGTHS, [rows[s][1] for s in STRENGTHS], "o-", label="prior")
right.axhline(rows["ls"][1], color="k", ls="--", label="least squares")
right.set(xlabel="prior strength", ylabel="held-out mean distance [L]")
left.legend()
fig.tight_layout()

# %% [markdown]
# A small strength already gives the sway and yaw forces the right sign: the directions the
# data cannot tell apart carry almost no data weight, so a little prior decides them. A large
# strength overrides what the data do determine: the flights suffer, and the surge force in
# pure yaw takes the wrong sign again (the worst correlation falls back toward -1), because the
# prior has no estimate of X'_rr (its sign differs between hull forms) and holds it near zero
# against the records. The default (1e-5)
# sits where the forces have converged, the surge force too; on the full protocol its mean
# held-out distance is that of least squares (about 0.44 L both), better on the starboard
# turn and the zig-zag, worse on the port turn.
#
# ## The forces along the captive sweeps
# Least squares against the default `prior` fit: measured (markers) and predicted (lines).

# %%
captive = captive_tests(ship, "all", points=11)
for key in ("ls", 1e-5):
    figure = plot_captive_forces(compare_forces(models[key], captive),
                                 tests=["static-drift", "pure-yaw"])
    figure.suptitle(f"{key}: forces along the captive sweeps")
    display(figure)

# %% [markdown]
# The surge force in pure yaw needs the `v r` term: on the paper's library X'_rr stands in for
# X'_vr in turns (v' is about -0.5 r' there), and at the default strength the surge force in
# pure yaw comes out with the wrong sign.

# %%
on_paper_library = fit(train, ship, library=paper_library, optimizer="prior")
for key, model in (("abkowitz", on_paper_library), ("abkowitz-vr", models[1e-5])):
    correlation = captive_agreement({key: model}, ship)[key]["pure-yaw"]["X"]["correlation"]
    print(f"{key:12s}: pure-yaw X correlation {correlation:+.2f}")

# %% [markdown]
# The prior has no estimate of X'_rr itself (its sign differs between hull forms): given X'_vv
# and X'_vr, the data decide it. Only a manoeuvre that separates v' from r' (a pull-out, or a
# rotating-arm test) would pin it; `sindyship fit` names such terms in its identifiability
# report.

# %% [markdown]
# ## Zig-zags alone, and refining by the flights
# Three zig-zags tie v' to r' more tightly still. Least squares then returns sway and yaw
# forces of the wrong sign; the prior keeps them, but its estimates from main dimensions are
# not accurate enough to fly the turns well. `refine` takes the fitted coefficients as a start
# and lowers the error of the model's own flights of the training zig-zags (cut into segments
# flown from the measured state, with the prior kept in the cost; what `sindyship fit` does by
# default). The held-out turns are never flown while refining: the refined model is judged on
# them here. A refinement that would lose the hard-over turns the fit flies is refused, and
# `info["refined"]["stopped"]` says so.

# %%
from sindyship.refine import refine  # noqa: E402

zigzags = [r for r in train if r.name.startswith("zz")]
EVALUATIONS = 3 if FAST else 10
alone = {"ls": fit(zigzags, ship, library=paper_library),
         "prior": fit(zigzags, ship, library=library, optimizer="prior")}
alone["ls refined"] = refine(alone["ls"], zigzags, max_evaluations=EVALUATIONS)
alone["prior refined"] = refine(alone["prior"], zigzags, max_evaluations=EVALUATIONS)
agreement = captive_agreement(alone, ship)
for key in ("ls refined", "prior refined"):
    print(f"{key}: {alone[key].info['refined']['stopped']}")
for key, model in alone.items():
    flights = fly_like_batch(model.dynamics(), test)
    distances = " / ".join(f"{distance_errors(f, r, ship.L)['mean_distance_L']:.3f}"
                           for f, r in zip(flights, test, strict=True))
    print(f"{key:14s}: worst X/Y/N correlation {worst_force(agreement[key]):+.2f}, "
          f"held-out {distances} L")

# %% [markdown]
# What the cell above prints depends on the records and the search: a refinement by a few
# evaluations on these records can be kept (its stop reason says so) while it lowers the
# worst captive correlation and flies held-out turns worse, which is what a refinement by
# zig-zags alone risks. With the default 60 evaluations on the full protocol (3200 s;
# `benchmarks/bench_captive.py`) refining the prior fit on the zig-zags alone would lose the
# hard-over turns, so it is refused and keeps the prior fit and its captive correlations of
# 0.97 or above; least squares refined the same way keeps its wrong-signed forces. On all
# eight training records, the prior fit with the asymmetry the diagnosis names, refined,
# flies every held-out manoeuvre closer than a careful pysindy workflow with forces that
# agree with every captive test (the README).
