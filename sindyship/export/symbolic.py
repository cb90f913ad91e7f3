"""The model as sympy: coefficient symbols, the forces of eq. 15 and the equations of eq. 14."""

from __future__ import annotations

from typing import TYPE_CHECKING

import sympy

from ..targets import DOFS, abkowitz_mass_matrix, coriolis
from ..terms import Term

if TYPE_CHECKING:
    from ..model import AbkowitzModel
    from ..ships import Ship


#: The non-dimensional accelerations of paper eq. 14 (du'/dt', dv'/dt', dr'/dt').
ACCELERATIONS = tuple(sympy.Symbol(name, real=True) for name in ("u_dot'", "v_dot'", "r_dot'"))
_ACC_TEXT = ("u_dot'", "v_dot'", "r_dot'")
_ACC_LATEX = (r"\dot{u}'", r"\dot{v}'", r"\dot{r}'")
_DU, _V, _R = (sympy.Symbol(name, real=True) for name in ("du", "v", "r"))
#: U/U0 of the ``instantaneous`` speed form, in its own variables (v = v/U): |u|/U =
#: |cos(beta)| and v/U = sin(beta), so U/U0 = |u/U0| / sqrt(1 - (v/U)^2), ahead or astern; the
#: model holds U/U0 at :data:`sindyship.library.SPEED_FLOOR` or more, where its v/U is no
#: longer sin(beta), so the expression holds from that speed up.
SPEED_RATIO = sympy.Abs(1 + _DU) / sympy.sqrt(1 - _V**2)
#: How the Coriolis terms' total surge speed u' = 1 + du is written.
_U_TOTAL = sympy.Symbol("u_total", real=True)
_CORIOLIS_TEXT = {"u_total": "(1 + du)", "v": "v", "r": "r"}
_CORIOLIS_LATEX = {"u_total": r"(1 + \Delta u')", "v": "v'", "r": "r'"}


# ---------------------------------------------------------------------------------------------
# sympy equations (paper eq. 14-15)
# ---------------------------------------------------------------------------------------------
def coefficient_symbol(dof: str, term: Term) -> sympy.Symbol:
    """The sympy symbol of a coefficient, named by :meth:`Term.identifier` (``Y_vvr``).

    Examples
    --------
    >>> coefficient_symbol("Y", Term("v^2 r"))
    Y_vvr
    """
    return sympy.Symbol(term.identifier(dof), real=True)


def check_model(model) -> None:
    """Refuse anything but an identified model (an MMG model, a saved model's dictionary).

    Examples
    --------
    >>> check_model({"coefficients": {}})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    TypeError: model must be an identified AbkowitzModel (sindyship.fit makes one, ...
    """
    if not all(hasattr(model, name) for name in ("library", "coefficients", "ship")):
        hint = (" (for a saved model's dictionary, AbkowitzModel.from_dict(it))"
                if isinstance(model, dict) else "")
        raise TypeError("model must be an identified AbkowitzModel (sindyship.fit makes one, "
                        f"AbkowitzModel.load reads one){hint}, not {type(model).__name__}.")


def _active_terms(model: AbkowitzModel, dof: str) -> list[tuple[Term, float]]:
    """The terms of ``dof`` with a non-zero coefficient, in library order."""
    return [(term, model.coefficients[dof][term.text]) for term in model.library.terms[dof]
            if model.coefficients[dof][term.text] != 0.0]


def force_expressions(model: AbkowitzModel, numeric: bool = False) -> dict[str, sympy.Expr]:
    """Hydrodynamic forces X', Y', N' of paper eq. 15 (Prime I) as sympy expressions.

    Parameters
    ----------
    model : AbkowitzModel
    numeric : bool
        If True the coefficients are numbers (:class:`sympy.Float`, the exact double);
        otherwise symbols named like ``X_vv`` (:func:`coefficient_symbol`).  Zero
        coefficients are left out either way.

    Returns
    -------
    dict
        ``{"X": expr, "Y": expr, "N": expr}`` in the library's variables (``du``, ``v``,
        ``r``, ``delta`` and any channels such as ``psi``), real symbols.

    Examples
    --------
    >>> from sindyship.model import paper_model
    >>> from sindyship.ships import load_ship
    >>> forces = force_expressions(paper_model(load_ship("kcs")))
    >>> len(forces["X"].args), len(forces["Y"].args)  # X'_0 of the paper is 0
    (15, 22)
    >>> forces["Y"].has(sympy.Symbol("Y_vvr", real=True))
    True
    """
    check_model(model)
    out = {}
    for dof in DOFS:
        # one Add of every term: adding them one at a time re-sorts the sum each time,
        # quadratic in the number of terms
        out[dof] = sympy.Add(*(
            (sympy.Float(float(value)) if numeric else coefficient_symbol(dof, term))
            * term.sympy() for term, value in _active_terms(model, dof)))
    return out


def _coriolis_polynomials(ship: Ship) -> dict[str, sympy.Poly]:
    """Coriolis terms of :func:`sindyship.targets.coriolis` as polynomials in (u', v', r')."""
    exprs = coriolis(ship, _U_TOTAL, _V, _R)
    return {dof: sympy.Poly(expr, _U_TOTAL, _V, _R) for dof, expr in zip(DOFS, exprs,
                                                                         strict=True)}


def coriolis_expressions(ship: Ship) -> dict[str, sympy.Expr]:
    """Coriolis terms of the protocol on the right-hand side of eq. 14, with u' = 1 + du.

    They come from :func:`sindyship.targets.coriolis` evaluated on sympy symbols.

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> c = coriolis_expressions(load_ship("kcs"))
    >>> sorted(str(s) for s in c["N"].free_symbols)
    ['du', 'r', 'v']
    """
    exprs = coriolis(ship, 1 + _DU, _V, _R)
    return {dof: sympy.sympify(expr) for dof, expr in zip(DOFS, exprs, strict=True)}


def model_equations(model: AbkowitzModel, numeric: bool = False) -> dict[str, sympy.Eq]:
    """Paper eq. 14, one equation per degree of freedom, in Prime I.

    The left-hand side is the mass-matrix row (:func:`sindyship.targets.abkowitz_mass_matrix`)
    times the accelerations :data:`ACCELERATIONS`; the right-hand side the force of eq. 15
    (:func:`force_expressions`) plus the Coriolis terms (:func:`coriolis_expressions`).
    Inertia values are numbers; coefficients are symbols unless ``numeric``.  A library of
    the ``instantaneous`` speed form reads v, r (and the channels' speeds and rates) over the
    instantaneous speed U: its forces are multiplied by (U/U0)^2 and its Coriolis terms take
    (U/U0) v and (U/U0) r, with U/U0 = :data:`SPEED_RATIO` (exact while the ship makes
    :data:`sindyship.library.SPEED_FLOOR` U0 or more, where the model's flights floor it).

    Examples
    --------
    >>> from sindyship.model import paper_model
    >>> from sindyship.ships import load_ship
    >>> eqs = model_equations(paper_model(load_ship("kcs")), numeric=True)
    >>> round(float(eqs["X"].lhs.coeff(ACCELERATIONS[0])) * 1e5, 2)
    885.32
    >>> point = {sympy.Symbol(n, real=True): 0.0 for n in ("du", "v", "r", "delta")}
    >>> float(eqs["X"].rhs.subs(point))  # X'_0 of the paper is 0
    0.0
    """
    check_model(model)
    M = abkowitz_mass_matrix(model.ship)
    forces = force_expressions(model, numeric=numeric)
    extra = coriolis_expressions(model.ship)
    if model.library.speed == "instantaneous":
        forces = {dof: SPEED_RATIO**2 * force for dof, force in forces.items()}
        extra = {dof: term.subs({_V: SPEED_RATIO * _V, _R: SPEED_RATIO * _R},
                                simultaneous=True) for dof, term in extra.items()}
    out = {}
    for i, dof in enumerate(DOFS):
        lhs = sum((sympy.Float(float(M[i, j])) * ACCELERATIONS[j] for j in range(3)
                   if M[i, j] != 0.0), sympy.Integer(0))
        out[dof] = sympy.Eq(lhs, forces[dof] + extra[dof], evaluate=False)
    return out
