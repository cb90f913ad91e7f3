"""The Abkowitz derivatives implied by the MMG model: its Taylor expansion (a reference).

An exact least-squares fit of the Abkowitz model (paper eq. 14-16) to MMG data converges,
near steady straight-ahead motion, to the Taylor coefficients of the force the regression
targets measure:

    F_abk(du, v', r', delta) = M_abk a_MMG(u', v', r', delta) - C_abk(u', v', r'),

with a_MMG = M_MMG^-1 F_MMG the accelerations of the MMG model (paper eq. 1, Prime II;
non-dimensional accelerations are the same in both prime systems), M_abk the Prime I mass
matrix of eq. 14 and C_abk the protocol's Coriolis terms (rigid body plus added mass).  The
coefficient of du^a v'^b r'^c delta^d is the Taylor coefficient of F_abk about u' = 1,
v' = r' = delta = 0.  The MMG rudder switches its flow straightening factor gamma_R at that
point, so the expansion uses the mean gamma_R (0.415 for the KCS), which is also what central
differences there see (docs/protocol.md).

The MMG physics is written once, in :func:`sindyship.mmg.force_components`.  Here it is
evaluated, unchanged, on two kinds of values that numpy routes its ufuncs to (numpy's
``__array_ufunc__`` protocol): sympy expressions (:func:`mmg_sympy`) and truncated
multivariate Taylor series (:class:`TaylorSeries`), which give every Taylor coefficient
exactly to rounding, in milliseconds (sympy's own ``series`` needs about a minute per force
and has no expansion of ``atan2``).

Examples
--------
>>> from sindyship.library import load_library
>>> from sindyship.ships import load_ship
>>> reference = taylor_reference(load_ship("kcs"), load_library("abkowitz"))
>>> round(reference["Y"]["v"] * 1e5, 1), round(reference["N"]["delta"] * 1e5, 2)
(-1292.5, 133.72)
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable, Mapping
from functools import lru_cache
from itertools import product

import numpy as np
import pandas as pd
import sympy

from .library import TermLibrary, load_library
from .mmg import force_components, mass_matrix
from .ships import Ship
from .targets import DOFS, abkowitz_mass_matrix, coriolis
from .terms import CORE_VARIABLES, Term

__all__ = [
    "TaylorSeries",
    "implied_forces",
    "mmg_sympy",
    "reference_table",
    "taylor_reference",
]


# ---------------------------------------------------------------------------------------------
# Truncated multivariate Taylor series
# ---------------------------------------------------------------------------------------------
@lru_cache(maxsize=16)
def _basis(n_vars: int, order: int) -> tuple:
    """Monomials of total degree <= order (by degree), and the product table of their pairs."""
    monomials = sorted((e for e in product(range(order + 1), repeat=n_vars) if sum(e) <= order),
                       key=lambda e: (sum(e), tuple(-x for x in e)))
    index = {e: k for k, e in enumerate(monomials)}
    left, right, target = [], [], []
    for i, a in enumerate(monomials):
        for j, b in enumerate(monomials):
            s = tuple(x + y for x, y in zip(a, b, strict=True))
            if sum(s) <= order:
                left.append(i)
                right.append(j)
                target.append(index[s])
    return tuple(monomials), index, np.array(left), np.array(right), np.array(target)


class TaylorSeries:
    """A multivariate polynomial truncated at a total degree: Taylor arithmetic (a jet).

    Arithmetic, powers and the numpy ufuncs that the MMG forces use (``sqrt``, ``sin``,
    ``cos``, ``exp``, ``arctan2``, ...) act on the truncated series, so a function of
    ``TaylorSeries.variable`` values returns its own Taylor polynomial about the expansion
    point.

    Parameters
    ----------
    coefficients : array_like
        One coefficient per monomial of :attr:`monomials`.
    n_vars, order : int
        Number of variables and the truncation degree.

    Examples
    --------
    >>> x = TaylorSeries.variable(0, n_vars=2, order=3)
    >>> y = TaylorSeries.variable(1, n_vars=2, order=3)
    >>> s = np.sin(x + 2.0 * y)
    >>> s.coefficient((1, 0)), s.coefficient((0, 1)), round(s.coefficient((1, 2)), 6)
    (1.0, 2.0, -2.0)
    >>> round(np.arctan2(y, 1.0 + x).coefficient((1, 1)), 12)  # d2/dx dy atan2(y, 1 + x)
    -1.0
    """

    __slots__ = ("c", "n_vars", "order")

    def __init__(self, coefficients, n_vars: int, order: int):
        self.c = np.asarray(coefficients, dtype=float)
        self.n_vars = n_vars
        self.order = order

    # ------------------------------------------------------------------ construction
    @property
    def monomials(self) -> tuple[tuple[int, ...], ...]:
        """Exponent tuples of the coefficients, by total degree."""
        return _basis(self.n_vars, self.order)[0]

    @classmethod
    def constant(cls, value: float, n_vars: int, order: int) -> TaylorSeries:
        """The series of a constant."""
        c = np.zeros(len(_basis(n_vars, order)[0]))
        c[0] = value
        return cls(c, n_vars, order)

    @classmethod
    def variable(cls, k: int, n_vars: int, order: int, value: float = 0.0) -> TaylorSeries:
        """The k-th variable, expanded about ``value``."""
        out = cls.constant(value, n_vars, order)
        out.c[_basis(n_vars, order)[1][tuple(int(i == k) for i in range(n_vars))]] = 1.0
        return out

    def coefficient(self, exponents: tuple[int, ...]) -> float:
        """Coefficient of the monomial with these exponents (0 beyond the order)."""
        index = _basis(self.n_vars, self.order)[1]
        k = index.get(tuple(exponents))
        return 0.0 if k is None else float(self.c[k])

    def _new(self, c) -> TaylorSeries:
        return TaylorSeries(c, self.n_vars, self.order)

    def _lift(self, other) -> TaylorSeries:
        if isinstance(other, TaylorSeries):
            return other
        return TaylorSeries.constant(float(other), self.n_vars, self.order)

    # ------------------------------------------------------------------ arithmetic
    def __add__(self, other):
        if isinstance(other, TaylorSeries):
            return self._new(self.c + other.c)
        c = self.c.copy()
        c[0] += float(other)
        return self._new(c)

    __radd__ = __add__

    def __neg__(self):
        return self._new(-self.c)

    def __pos__(self):
        return self

    def __sub__(self, other):
        return self + (-other)

    def __rsub__(self, other):
        return (-self) + other

    def __mul__(self, other):
        if not isinstance(other, TaylorSeries):
            return self._new(self.c * float(other))
        _, _, left, right, target = _basis(self.n_vars, self.order)
        return self._new(np.bincount(target, weights=self.c[left] * other.c[right],
                                     minlength=len(self.c)))

    __rmul__ = __mul__

    def __truediv__(self, other):
        if not isinstance(other, TaylorSeries):
            return self._new(self.c / float(other))
        return self * other._power(-1.0)

    def __rtruediv__(self, other):
        return self._power(-1.0) * float(other)

    def __pow__(self, exponent):
        exponent = float(exponent)
        if exponent.is_integer() and exponent >= 0:
            out = self._lift(1.0)
            for _ in range(int(exponent)):
                out = out * self
            return out
        return self._power(exponent)

    # ------------------------------------------------------------------ functions
    def _compose(self, derivatives: Callable[[float, int], list[float]]) -> TaylorSeries:
        """f(self) from f's Taylor coefficients about the constant part (Horner's scheme)."""
        a0 = float(self.c[0])
        h = self._new(self.c.copy())
        h.c[0] = 0.0
        coefs = derivatives(a0, self.order)
        out = self._lift(coefs[-1])
        for c in reversed(coefs[:-1]):
            out = out * h + c
        return out

    def _power(self, p: float) -> TaylorSeries:
        return self._compose(lambda a, n: [_binomial(p, j) * a ** (p - j) for j in range(n + 1)])

    def sqrt(self) -> TaylorSeries:
        return self._power(0.5)

    def exp(self) -> TaylorSeries:
        return self._compose(lambda a, n: [math.exp(a) / math.factorial(j) for j in range(n + 1)])

    def sin(self) -> TaylorSeries:
        return self._compose(lambda a, n: [math.sin(a + j * math.pi / 2) / math.factorial(j)
                                           for j in range(n + 1)])

    def cos(self) -> TaylorSeries:
        return self._compose(lambda a, n: [math.cos(a + j * math.pi / 2) / math.factorial(j)
                                           for j in range(n + 1)])

    def arctan2(self, x) -> TaylorSeries:
        """atan2(self, x): atan2(y0, x0) + atan((y x0 - x y0) / (x x0 + y y0))."""
        x = self._lift(x)
        y0, x0 = float(self.c[0]), float(x.c[0])
        z = (self * x0 - x * y0) / (x * x0 + self * y0)  # no constant part
        atan = z._compose(lambda a, n: [0.0 if j % 2 == 0 else (-1.0) ** (j // 2) / j
                                        for j in range(n + 1)])
        return atan + math.atan2(y0, x0)

    # ------------------------------------------------------------------ numpy protocol
    _UFUNCS: dict[str, Callable] = {
        "add": operator.add, "subtract": operator.sub, "multiply": operator.mul,
        "true_divide": operator.truediv, "divide": operator.truediv, "power": operator.pow,
        "negative": operator.neg, "positive": operator.pos, "square": lambda a: a * a,
        "sqrt": lambda a: a.sqrt(), "exp": lambda a: a.exp(), "sin": lambda a: a.sin(),
        "cos": lambda a: a.cos(), "arctan2": lambda y, x: _as_series(y, x).arctan2(x),
    }

    def __array_ufunc__(self, ufunc, method, *inputs, **kwargs):
        function = self._UFUNCS.get(ufunc.__name__)
        if method != "__call__" or kwargs or function is None:
            return NotImplemented
        args = [a if isinstance(a, TaylorSeries) else float(a) for a in inputs]
        return function(*args)

    def __repr__(self) -> str:
        return f"TaylorSeries(order={self.order}, constant={self.c[0]!r})"


def _as_series(a, like) -> TaylorSeries:
    return a if isinstance(a, TaylorSeries) else like._lift(a)


def _binomial(p: float, j: int) -> float:
    out = 1.0
    for i in range(j):
        out *= (p - i) / (i + 1)
    return out


# ---------------------------------------------------------------------------------------------
# sympy values for numpy-style code
# ---------------------------------------------------------------------------------------------
class _Symbolic:
    """A sympy expression that numpy ufuncs and arithmetic act on symbolically."""

    __slots__ = ("expr",)
    _UFUNCS: dict[str, Callable] = {
        "add": operator.add, "subtract": operator.sub, "multiply": operator.mul,
        "true_divide": operator.truediv, "divide": operator.truediv, "power": operator.pow,
        "negative": operator.neg, "positive": operator.pos, "square": lambda a: a * a,
        "sqrt": sympy.sqrt, "exp": sympy.exp, "sin": sympy.sin, "cos": sympy.cos,
        "arctan2": sympy.atan2, "absolute": sympy.Abs,
    }

    def __init__(self, expr):
        self.expr = sympy.sympify(expr)

    def __array_ufunc__(self, ufunc, method, *inputs, **kwargs):
        function = self._UFUNCS.get(ufunc.__name__)
        if method != "__call__" or kwargs or function is None:
            return NotImplemented
        args = [a.expr if isinstance(a, _Symbolic) else sympy.Float(float(a)) for a in inputs]
        return _Symbolic(function(*args))

    def __add__(self, other):
        return np.add(self, other)

    def __radd__(self, other):
        return np.add(other, self)

    def __sub__(self, other):
        return np.subtract(self, other)

    def __rsub__(self, other):
        return np.subtract(other, self)

    def __mul__(self, other):
        return np.multiply(self, other)

    def __rmul__(self, other):
        return np.multiply(other, self)

    def __truediv__(self, other):
        return np.true_divide(self, other)

    def __rtruediv__(self, other):
        return np.true_divide(other, self)

    def __pow__(self, other):
        return _Symbolic(self.expr ** (other.expr if isinstance(other, _Symbolic) else other))

    def __neg__(self):
        return _Symbolic(-self.expr)


def _unwrap(value):
    if isinstance(value, _Symbolic):
        return value.expr
    # a numpy scalar as a Python number: older sympy reads numpy 2's repr as text
    return sympy.sympify(value.item() if isinstance(value, np.generic) else value)


def _with_gamma(ship: Ship, gamma_R: float | None) -> Ship:
    g = ship.rudder.gamma_R_mean if gamma_R is None else float(gamma_R)
    return ship.with_rudder(gamma_R_stbd=g, gamma_R_port=g)


def mmg_sympy(ship: Ship, gamma_R: float | None = None, *,
              symbols: tuple | None = None) -> dict[str, tuple[sympy.Expr, ...]]:
    """The MMG forces (paper eq. 2-11, Prime II with U0) as sympy expressions.

    :func:`sindyship.mmg.force_components` itself is evaluated on sympy symbols (numpy
    routes its ufuncs to sympy), so this is the simulator's physics, not a second copy.

    Parameters
    ----------
    ship : Ship
    gamma_R : float, optional
        The flow straightening factor, fixed (default: the mean of the port and starboard
        values, the Taylor expansion point of docs/protocol.md).
    symbols : tuple of 4 sympy symbols, optional
        (u', v', r', delta); default real symbols ``u, v, r, delta``.

    Returns
    -------
    dict
        ``{"hull": (X, Y, N), "propeller": ..., "rudder": ..., "coriolis": ...}``.

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> parts = mmg_sympy(load_ship("kcs"))
    >>> u, v, r, delta = sympy.symbols("u v r delta", real=True)
    >>> parts["coriolis"][1]  # -m' u' r' (rigid body, paper eq. 11)
    -0.18228*r*u
    """
    if symbols is None:
        symbols = sympy.symbols("u v r delta", real=True)
    u, v, r, delta = (_Symbolic(s) for s in symbols)
    parts = force_components(_with_gamma(ship, gamma_R), u, v, r, delta, starboard=True)
    return {name: tuple(_unwrap(x) for x in xyz) for name, xyz in parts.items()}


def implied_forces(ship: Ship, du, v, r, delta, *, gamma_R: float | None = None) -> tuple:
    """The Abkowitz force the MMG implies: M_abk a_MMG - C_abk, Prime I (paper eq. 14, 16).

    This is what the regression targets of eq. 16 measure on noise-free MMG data, as a
    function of the state.

    Parameters
    ----------
    ship : Ship
    du, v, r : float, ndarray, TaylorSeries or sympy values
        u' - 1, v' and r' (over the design speed U0).
    delta : same
        Rudder angle [rad].
    gamma_R : float, optional
        Fix the flow straightening factor; by default (None) the MMG switches it with the
        sign of beta_R as the simulator does (numbers only).

    Returns
    -------
    tuple
        (X', Y', N') in Prime I.

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> X, Y, N = implied_forces(load_ship("kcs"), 0.0, 0.0, 0.0, 0.0)
    >>> round(float(X) * 1e5, 3), float(Y), float(N)  # thrust slightly exceeds resistance
    (0.019, 0.0, 0.0)
    """
    u = 1.0 + du
    if gamma_R is None:
        parts = force_components(ship, u, v, r, delta)
    else:
        parts = force_components(_with_gamma(ship, gamma_R), u, v, r, delta, starboard=True)
    totals = [sum(part[i] for part in parts.values()) for i in range(3)]
    transfer = (abkowitz_mass_matrix(ship) @ np.linalg.inv(mass_matrix(ship))).tolist()
    C = coriolis(ship, u, v, r)
    return tuple(sum(transfer[i][j] * totals[j] for j in range(3)) - C[i] for i in range(3))


def _polynomial_exponents(term: Term) -> tuple[tuple[int, ...], float] | None:
    """(exponents of du, v, r, delta; numeric factor) of a polynomial term, else None."""
    exponents = [0] * len(CORE_VARIABLES)
    scale = 1.0
    for function, base, power in term.factors:
        if function is not None:
            return None
        if isinstance(base, str):
            if base not in CORE_VARIABLES:
                return None
            exponents[CORE_VARIABLES.index(base)] += power
        else:
            scale *= float(base) ** power
    return tuple(exponents), scale


def taylor_reference(ship: Ship, library: TermLibrary | str = "abkowitz", *,
                     gamma_R: float | None = None) -> dict[str, dict[str, float]]:
    """Abkowitz coefficients implied by the MMG model: the Taylor reference.

    The Taylor coefficients of :func:`implied_forces` about u' = 1, v' = r' = delta = 0
    with the mean gamma_R, for the library's terms (Prime I).

    Parameters
    ----------
    ship : Ship
    library : TermLibrary or str
        The terms to give values for; a term that is not a polynomial in du, v, r and
        delta (``abs(v) v``, ``sin(psi)``, ...) gets NaN.
    gamma_R : float, optional
        Flow straightening factor of the expansion (default the mean of the two).

    Returns
    -------
    dict
        ``{"X": {term: value}, "Y": ..., "N": ...}``.

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> reference = taylor_reference(load_ship("kcs"))
    >>> round(reference["Y"]["delta"] * 1e5, 2), reference["Y"]["du"]  # symmetric in Y
    (-256.91, 0.0)
    """
    if isinstance(library, str):
        library = load_library(library)
    polynomial = {dof: {t.text: _polynomial_exponents(t) for t in library.terms[dof]}
                  for dof in DOFS}
    degrees = [sum(p[0]) for terms in polynomial.values() for p in terms.values() if p]
    order = max([1, *degrees])
    n = len(CORE_VARIABLES)
    du, v, r, delta = (TaylorSeries.variable(k, n, order) for k in range(n))
    series = implied_forces(ship, du, v, r, delta,
                            gamma_R=ship.rudder.gamma_R_mean if gamma_R is None else gamma_R)
    out: dict[str, dict[str, float]] = {}
    for dof, jet in zip(DOFS, series, strict=True):
        out[dof] = {}
        for text, poly in polynomial[dof].items():
            out[dof][text] = math.nan if poly is None else jet.coefficient(poly[0]) / poly[1]
    return out


def reference_table(ship: Ship, models: Mapping[str, object], *,
                    library: TermLibrary | str | None = None) -> pd.DataFrame:
    """The Taylor reference beside models' coefficients, Prime I x 1e-5 (Tables 7-9 units).

    Parameters
    ----------
    ship : Ship
    models : dict of str to AbkowitzModel
        Column name -> model.
    library : TermLibrary or str, optional
        The rows; default the first model's library (else ``abkowitz``).  Terms a model
        lacks are NaN in its column.

    Returns
    -------
    pandas.DataFrame
        Columns ``equation``, ``term``, ``name``, ``taylor_1e-5`` and ``<model>_1e-5``.

    Examples
    --------
    >>> from sindyship.model import paper_model
    >>> from sindyship.ships import load_ship
    >>> kcs = load_ship("kcs")
    >>> table = reference_table(kcs, {"paper_ls": paper_model(kcs, "LS")})
    >>> row = table[(table.equation == "N") & (table.term == "r")].iloc[0]
    >>> round(float(row["taylor_1e-5"]), 1), round(float(row["paper_ls_1e-5"]), 2)
    (-251.8, -215.66)
    """
    if library is None:
        library = next(iter(models.values())).library if models else "abkowitz"
    if isinstance(library, str):
        library = load_library(library)
    reference = taylor_reference(ship, library)
    rows = []
    for dof in DOFS:
        for term in library.terms[dof]:
            row = {"equation": dof, "term": term.text, "name": term.identifier(dof),
                   "taylor_1e-5": reference[dof][term.text] * 1e5}
            for name, model in models.items():
                value = model.coefficients.get(dof, {}).get(term.text, math.nan)
                row[f"{name}_1e-5"] = value * 1e5
            rows.append(row)
    return pd.DataFrame(rows)
