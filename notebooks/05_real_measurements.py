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
# # Real measurements: the KVLCC2 at MARIN
#
# Six free-running model tests of the KVLCC2 tanker (SIMMAN 2008), converted to full scale
# (L = 320 m): turning circles at +-35 deg and zig-zags 10/10 and 20/20 to both sides. Real data
# bring real trouble: three significant figures, a time column that loses resolution, roll that a
# 3-DOF model ignores. We identify on the zig-zags and test on the turning circles.
#
# The data are not part of sindyship (the README's MARIN section says where they are
# published); this notebook reads them from the folder in `SINDYSHIP_MARIN_DIR` and stops
# early, saying so, when they are absent.

# %%
# %matplotlib inline
import os

import numpy as np
from IPython.display import display

from sindyship import diagnose_plots
from sindyship.diagnose import compare, diagnose
from sindyship.identify import fit
from sindyship.manoeuvres import turning_figures
from sindyship.marin import MARIN_FILES, default_marin_dir, read_marin
from sindyship.measurements import trajectory_from_frame
from sindyship.ships import load_ship

FAST = os.environ.get("SINDYSHIP_FAST") == "1"
folder = default_marin_dir()
HAVE_DATA = folder is not None
print("MARIN data:", folder if HAVE_DATA else "absent - the rest of this notebook is skipped")

# %% [markdown]
# ## Loading
# The loader establishes our sign convention (MARIN's positive rudder turns the ship to port,
# so `tc_35` is a port turn here) and rebuilds time from the uniform sample interval. We
# resample to 1 s, which is plenty for a ship with a time scale L/U0 of 40 s.

# %%
ship = load_ship("kvlcc2").scaled(45.7)
records = {}
if HAVE_DATA:
    for key, filename in MARIN_FILES.items():
        raw = read_marin(folder / filename)
        records[key] = trajectory_from_frame(raw.data, name=key, resample=1.0)
    for key, rec in records.items():
        rudder = np.degrees(rec.rudder)
        print(f"{key:7s} {rec.n_samples} samples, {rec.duration:.0f} s, "
              f"rudder {rudder.min():.1f} .. {rudder.max():.1f} deg")

# %% [markdown]
# ## The measured turning circles
# Advance and tactical diameter from the rudder execute point, in ship lengths.

# %%
if HAVE_DATA:
    for key in ("tc_35", "tc_-35"):
        figures = turning_figures(records[key], ship.L)
        print(key, {k: round(v, 2) for k, v in figures.items() if k.endswith("_L")})

# %% [markdown]
# ## Identify on the zig-zags, fly the turning circles
# Measured accelerations need smoothing: we use a 21 s Savitzky-Golay derivative.

# %%
if HAVE_DATA:
    train = [records[k] for k in ("zz_10", "zz_-10", "zz_20", "zz_-20")]
    test = [records[k] for k in ("tc_35", "tc_-35")]
    model = fit(train, ship, optimizer="ls", derivative="savgol", window=21.0)
    for c in compare(model, test, kind="held-out"):
        print(c.name, {k: v for k, v in c.errors.items() if v is not None})
    c = compare(model, test[:1], kind="held-out")[0]
    display(diagnose_plots.plot_comparison(c.record, {"identified on zig-zags": c.flown},
                                           L=ship.L, errors=c.errors))

# %% [markdown]
# ## What the diagnosis says
# Effects whose channels the data lack (wind, water depth) are listed as not testable, with the
# channel to record. Read the ranking with the warnings it prints: zig-zags sweep a narrow range
# of headings, so heading terms can stand in for slow drift.

# %%
if HAVE_DATA and not FAST:
    diagnosis = diagnose(train, ship, test=test, derivative="savgol", window=21.0, confirm=1)
    print(diagnosis.report())
    display(diagnose_plots.plot_ranking(diagnosis))
