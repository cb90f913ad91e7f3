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
# # Sparsity paths and model selection
#
# LASSO and STLSQ trade fit for sparsity through one number: the penalty alpha or the
# threshold. sindyship chooses it by leave-one-manoeuvre-out cross-validation (shuffled
# K-fold leaks neighbouring samples of smooth 1 Hz data and always picks the least penalty).
# Here we look at the whole path for the three equations, the cross-validation curve with the
# chosen point, and a Pareto view of active terms against error.

# %%
import os

import matplotlib.pyplot as plt
from IPython.display import display

from sindyship import plots
from sindyship.identify import fit
from sindyship.manoeuvres import fly, protocol_manoeuvres
from sindyship.mmg import MMGModel
from sindyship.ships import load_ship

FAST = os.environ.get("SINDYSHIP_FAST") == "1"
DURATION = 800.0 if FAST else 3200.0

ship = load_ship("kcs")
train = fly(MMGModel(ship), protocol_manoeuvres(DURATION)["train"])

# %%
lasso = fit(train, ship, optimizer="lasso")
stlsq = fit(train, ship, optimizer="stlsq")
print(lasso)
print(stlsq)

# %% [markdown]
# ## LASSO: coefficients against the penalty
# Each line is one term's coefficient relative to its largest value along the path; the
# dashed line is the penalty cross-validation chose. Noise-free data favour small penalties:
# the cross-validation curve is flat to the left of the chosen point.

# %%
for dof in ("X", "Y", "N"):
    names = [t.identifier(dof) for t in lasso.library.terms[dof]]
    display(plots.sparsity_path(lasso.estimators_[dof], names,
                                title=f"LASSO, {dof}' equation"))

# %% [markdown]
# ## STLSQ: coefficients against the threshold
# The threshold applies to standardised coefficients, so one value means the same for every
# term and every equation.

# %%
for dof in ("X", "Y", "N"):
    names = [t.identifier(dof) for t in stlsq.library.terms[dof]]
    display(plots.sparsity_path(stlsq.estimators_[dof], names,
                                title=f"STLSQ, {dof}' equation"))

# %% [markdown]
# ## Pareto view: active terms against cross-validation error

# %%
fig, axes = plt.subplots(1, 3, figsize=(14, 4), layout="constrained")
for ax, dof in zip(axes, ("X", "Y", "N"), strict=True):
    plots.pareto(lasso.estimators_[dof], ax=ax, label="LASSO")
    plots.pareto(stlsq.estimators_[dof], ax=ax, label="STLSQ")
    ax.set_title(f"{dof}' equation")
plt.show()
