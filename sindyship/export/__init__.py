"""Export an identified Abkowitz model: sympy equations, text, LaTeX and a standalone simulator.

Everything here is made from one declaration per term (:class:`sindyship.terms.Term`) and
from the same inertia and Coriolis functions the identification uses
(:func:`sindyship.targets.abkowitz_mass_matrix`, :func:`sindyship.targets.coriolis`), so the
printed equations, the LaTeX and the generated code say exactly what the model computes.

* :func:`model_equations` gives paper eq. 14 per degree of freedom as :class:`sympy.Eq`:
  the mass-matrix row times the accelerations equals the hydrodynamic force of eq. 15 plus the
  Coriolis terms of the reproduction protocol (rigid body plus added mass, with the Munk
  moment), all in Prime I with u' = 1 + du.
* :func:`equations_text`, :func:`equations_latex` (an ``align`` environment) and
  :func:`coefficient_table_latex` (booktabs, x 1e-5 as in paper Tables 7-9) display a model.
* :func:`generate_python` writes a module that needs only numpy: named coefficients, the
  right-hand side of eq. 14 with the rudder servo of eq. 12-13 and the kinematics, and the
  same fixed-step RK4 integrator as :mod:`sindyship.simulation` (steps split at command
  changes and zig-zag check angles), so that it flies a model as sindyship does; with
  ``compiled=True`` it also carries the right-hand side and the RK4 step as loops that numba
  compiles where the module runs (:mod:`sindyship.export._compiled`; numba stays optional).
* ``sindyship export`` is :mod:`sindyship.cli.export`.

Examples
--------
>>> from sindyship.model import paper_model
>>> from sindyship.ships import load_ship
>>> model = paper_model(load_ship("kcs"), "LS")
>>> eq = model_equations(model)["Y"]
>>> sorted(str(s) for s in eq.lhs.free_symbols)
["r_dot'", "v_dot'"]
>>> print(equations_text(model, precision=3).splitlines()[1][:47])
X: 0.00885 u_dot' = -0.00227 du - 0.000508 du^2
"""

from __future__ import annotations

from .codegen import generate_python
from .symbolic import (
    ACCELERATIONS,
    coefficient_symbol,
    coriolis_expressions,
    force_expressions,
    model_equations,
)
from .text import coefficient_table_latex, equations_latex, equations_text, latex_document_part

__all__ = [
    "ACCELERATIONS",
    "coefficient_symbol",
    "coefficient_table_latex",
    "coriolis_expressions",
    "equations_latex",
    "equations_text",
    "force_expressions",
    "generate_python",
    "latex_document_part",
    "model_equations",
]
