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
# # Exploring term libraries
#
# An Abkowitz model writes the surge force X', sway force Y' and yaw moment N' as a Taylor
# series in du = u' - 1, v', r' and the rudder angle delta (paper eq. 15). sindyship keeps
# the terms as data: a TOML library file per term set, parsed by a whitelist grammar (never
# `eval`). This notebook shows what is in `abkowitz.toml`, how correlated its columns are on
# the paper's manoeuvres (the reason for the "parameter drift" the paper reports), and how an
# effect library adds terms.
#
# Set `SINDYSHIP_FAST=1` to run on shorter manoeuvres (the test suite does).

# %%
import os

import matplotlib.pyplot as plt
import numpy as np

from sindyship.identify import design
from sindyship.library import available_effects, load_effect, load_library
from sindyship.manoeuvres import fly, protocol_manoeuvres
from sindyship.mmg import MMGModel
from sindyship.ships import load_ship

FAST = os.environ.get("SINDYSHIP_FAST") == "1"
DURATION = 800.0 if FAST else 3200.0

# %% [markdown]
# ## What a library holds
# Each term is declared once; its numeric column, printed name, LaTeX and sympy expression
# all come from that one declaration.

# %%
library = load_library("abkowitz")
print(library.description)
for dof, terms in library.terms.items():
    print(dof, len(terms), "terms:", ", ".join(t.text for t in terms))

# %%
term = library.terms["Y"][15]
print(term.text, "->", term.identifier("Y"), "|", term.latex("Y"), "|", term.sympy())

# %% [markdown]
# ## The paper's training data and the feature columns
# The eight training manoeuvres of the protocol, flown by the KCS MMG simulator.

# %%
ship = load_ship("kcs")
train = fly(MMGModel(ship), protocol_manoeuvres(DURATION)["train"])
problems = design(train, ship, library)
print({dof: p.features.shape for dof, p in problems.items()})

# %% [markdown]
# ## Correlation and conditioning
# Columns that move together cannot be told apart by regression: their coefficients can
# trade off against each other with little change in the fit. The condition number of the
# standardised feature matrix measures how close the columns are to linear dependence.

# %%
fig, axes = plt.subplots(1, 3, figsize=(15, 4.8), layout="constrained")
for ax, (dof, problem) in zip(axes, problems.items(), strict=True):
    X = problem.features
    keep = X.std(axis=0) > 0
    corr = np.corrcoef(X[:, keep], rowvar=False)
    names = [t.identifier(dof) for t, k in zip(library.terms[dof], keep, strict=True) if k]
    image = ax.imshow(corr, vmin=-1, vmax=1, cmap="RdBu_r")
    ax.set_xticks(range(len(names)), names, rotation=90, fontsize=6)
    ax.set_yticks(range(len(names)), names, fontsize=6)
    Z = (X[:, keep] - X[:, keep].mean(axis=0)) / X[:, keep].std(axis=0)
    ax.set_title(f"{dof}': condition number {np.linalg.cond(Z):.0f}")
fig.colorbar(image, ax=axes, shrink=0.8, label="correlation between term columns")
plt.show()

# %% [markdown]
# Many pairs of columns correlate by more than 0.95 in magnitude, such as du^2 v and du r, or
# v^2 r and r^2 v (with opposite signs: in a steady turn v and r have opposite signs): on
# these manoeuvres the terms grow together, the columns are nearly proportional, and least
# squares can move weight between them. This is the parameter drift of the paper: different data or
# optimizers give very different coefficients with similar forces.

# %% [markdown]
# ## Adding an effect's terms
# The catalogue `libraries/effects/*.toml` holds candidate physical effects; extending a
# library adds each effect's terms per degree of freedom (skipping terms already there).

# %%
effects = available_effects()
print("catalogue:", ", ".join(effects))
if "asymmetry" in effects:
    extended = library.extended(load_effect("asymmetry"))
    added = {dof: [t.text for t in extended.terms[dof] if t not in library.terms[dof]]
             for dof in extended.terms}
    print(extended.name, added)
