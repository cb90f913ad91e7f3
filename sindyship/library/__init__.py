"""Term libraries and effects: their TOML files, the library variables, and the pysindy library.

A *term library* (``libraries/<name>.toml``) declares the terms of the surge force X, sway
force Y and yaw moment N of a manoeuvring model; the built-in ``abkowitz`` library holds the
paper's eq. 15 / 17 (16 surge, 22 sway and 22 yaw terms), ``abkowitz-noconst`` the same
without the constant terms and ``abkowitz-vr`` the same with the surge term ``v r`` of the MMG
hull model (the library of the physics-consistent fit, :mod:`sindyship.priors`).  An *effect*
(``libraries/effects/<name>.toml``) is a catalogued physical effect: a paragraph on its
physics, the data channels it needs, and the extra terms per degree of freedom that model it;
:meth:`TermLibrary.extended` adds effects to a library.
Every term is declared once, in these files, and its column, name, LaTeX and generated code
all come from that declaration (:class:`sindyship.terms.Term`).  The files are untrusted
input: their terms are read by the whitelist parser of :mod:`sindyship.terms`.

Using the library with pysindy
------------------------------
:class:`AbkowitzFeatureLibrary` is a pysindy feature library.  pysindy fits one term set for
all the columns of ``x_dot``, whereas eq. 15 gives each degree of freedom its own term set
(surge is even in v, r and delta; sway and yaw are not).  ``GeneralizedLibrary`` with
``inputs_per_library`` does not help: it chooses the *inputs* each sub-library sees, not the
*equations* that use it, and fitting X, Y and N together on the union of their terms would
put terms into equations that eq. 15 leaves out.  The recommended way is therefore one
``SINDy`` per degree of freedom, each with that equation's terms, the motion state
``x = [du, v, r]``, the rudder (and any further channels) as control input
``u = [delta, ...]`` in the order of ``input_names``, and the regression target of that
equation (paper eq. 16) as a one-column ``x_dot``.  pysindy accepts an ``x_dot`` with fewer
columns than ``x`` in ``fit`` and ``predict``; give the left-hand side to ``print`` with
``lhs=["X'"]``.  (``SINDy.simulate`` needs one equation per state and is not meant for this
use; sindyship simulates fitted models with its own equations of motion, eq. 14.)

>>> import numpy as np
>>> import pysindy as ps
>>> from sindyship.library import DOFS, AbkowitzFeatureLibrary, load_library
>>> library = load_library("abkowitz")
>>> rng = np.random.default_rng(0)
>>> x = rng.uniform(-0.2, 0.2, size=(300, 3))  # du, v, r
>>> u = rng.uniform(-0.6, 0.6, size=(300, 1))  # delta [rad]
>>> values = dict(zip(library.input_names, np.hstack([x, u]).T))
>>> models = {}
>>> for dof in DOFS:
...     terms = library.terms[dof]
...     true_coef = rng.normal(size=len(terms))
...     target = feature_matrix(terms, values) @ true_coef  # here: exactly in the library
...     models[dof] = ps.SINDy(
...         feature_library=AbkowitzFeatureLibrary.for_dof(library, dof),
...         optimizer=ps.STLSQ(threshold=0.0, alpha=0.0),
...     ).fit(x, t=1.0, x_dot=target[:, None], u=u, feature_names=list(library.input_names))
...     assert np.allclose(models[dof].coefficients()[0], true_coef)
>>> models["Y"].predict(x, u=u).shape
(300, 1)
>>> models["X"].get_feature_names()[:4]
['1', 'du', 'du^2', 'v^2']
"""

from __future__ import annotations

from ._checks import DOFS
from ._files import (
    PAPER_LIBRARY,
    available_effects,
    available_libraries,
    builtin_library_dir,
    load_effect,
    load_library,
    names_a_file,
    read_from_builtin,
)
from ._objects import Effect, TermLibrary
from ._variables import (
    SPEED_FACTOR,
    SPEED_FLOOR,
    SPEED_FORMS,
    apparent_wind,
    derived_variables,
    feature_matrix,
    motion_variables,
    nondimensional_variables,
    record_variables,
    rescaled_to_speed,
    speed_ratio,
)

__all__ = [
    "DOFS",
    "AbkowitzFeatureLibrary",
    "Effect",
    "TermLibrary",
    "available_effects",
    "available_libraries",
    "builtin_library_dir",
    "feature_matrix",
    "load_effect",
    "load_library",
    "names_a_file",
    "read_from_builtin",
    "PAPER_LIBRARY",
    "nondimensional_variables",
    "record_variables",
    "SPEED_FACTOR",
    "SPEED_FLOOR",
    "SPEED_FORMS",
    "apparent_wind",
    "derived_variables",
    "motion_variables",
    "rescaled_to_speed",
    "speed_ratio",
]


def __getattr__(name: str):
    """``AbkowitzFeatureLibrary`` on first use: it subclasses pysindy's feature library, and
    importing pysindy (with scikit-learn) takes longer than everything else the library does."""
    if name == "AbkowitzFeatureLibrary":
        from ._pysindy import AbkowitzFeatureLibrary

        globals()[name] = AbkowitzFeatureLibrary
        return AbkowitzFeatureLibrary
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    """The module's names, ``AbkowitzFeatureLibrary`` included before its first use."""
    return sorted({*globals(), *__all__})
