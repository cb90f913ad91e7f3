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
  changes and zig-zag check angles), so that it flies a model as sindyship does.
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

import json
import math
import re
import textwrap
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np
import sympy
from sympy.printing.numpy import NumPyPrinter

from . import __version__
from .errors import SindyshipInputError
from .targets import DOFS, abkowitz_mass_matrix, coriolis
from .terms import Term

if TYPE_CHECKING:
    from .model import AbkowitzModel
    from .ships import Ship

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

#: The non-dimensional accelerations of paper eq. 14 (du'/dt', dv'/dt', dr'/dt').
ACCELERATIONS = tuple(sympy.Symbol(name, real=True) for name in ("u_dot'", "v_dot'", "r_dot'"))
_ACC_TEXT = ("u_dot'", "v_dot'", "r_dot'")
_ACC_LATEX = (r"\dot{u}'", r"\dot{v}'", r"\dot{r}'")
_DU, _V, _R = (sympy.Symbol(name, real=True) for name in ("du", "v", "r"))
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
    out = {}
    for dof in DOFS:
        total: sympy.Expr = sympy.Integer(0)
        for term, value in _active_terms(model, dof):
            coef = sympy.Float(value) if numeric else coefficient_symbol(dof, term)
            total = total + coef * term.sympy()
        out[dof] = total
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
    Inertia values are numbers; coefficients are symbols unless ``numeric``.

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
    M = abkowitz_mass_matrix(model.ship)
    forces = force_expressions(model, numeric=numeric)
    extra = coriolis_expressions(model.ship)
    out = {}
    for i, dof in enumerate(DOFS):
        lhs = sum((sympy.Float(M[i, j]) * ACCELERATIONS[j] for j in range(3) if M[i, j] != 0.0),
                  sympy.Integer(0))
        out[dof] = sympy.Eq(lhs, forces[dof] + extra[dof], evaluate=False)
    return out


# ---------------------------------------------------------------------------------------------
# Text and LaTeX
# ---------------------------------------------------------------------------------------------
def _check_precision(precision: int) -> int:
    if isinstance(precision, bool) or not isinstance(precision, int | np.integer) \
            or not 1 <= precision <= 17:
        raise SindyshipInputError(
            f"precision must be a whole number of significant digits from 1 to 17, not "
            f"{precision!r}."
        )
    return int(precision)


def _number_text(value: float, precision: int) -> str:
    return f"{value:.{precision}g}"


def _number_latex(value: float, precision: int) -> str:
    """A number in LaTeX with ``precision`` significant digits (``2.5 \\times 10^{-5}``)."""
    text = f"{value:.{precision}g}"
    if "e" in text:
        mantissa, exponent = text.split("e")
        text = rf"{mantissa} \times 10^{{{int(exponent)}}}"
    return text


def _monomial(powers: Mapping[str, int], names: Mapping[str, str], latex: bool) -> str:
    words = []
    for name, power in powers.items():
        if power == 0:
            continue
        sup = "" if power == 1 else (f"^{{{power}}}" if latex else f"^{power}")
        words.append(names[name] + sup)
    return " ".join(words)


def _equation_pieces(model: AbkowitzModel, dof: str, *, latex: bool, numeric: bool,
                     precision: int) -> tuple[str, list[tuple[float, str]]]:
    """Left-hand side text and the signed right-hand-side pieces (sign, body) of eq. 14."""
    M = abkowitz_mass_matrix(model.ship)
    i = DOFS.index(dof)
    number = _number_latex if latex else _number_text
    acc = _ACC_LATEX if latex else _ACC_TEXT
    lhs_parts = []
    for j in range(3):
        if M[i, j] != 0.0:
            sign = "-" if M[i, j] < 0 else "+"
            lhs_parts.append((sign, f"{number(abs(M[i, j]), precision)} {acc[j]}"))
    lhs = " ".join(f"{s} {b}" for s, b in lhs_parts).removeprefix("+ ")
    if lhs.startswith("- "):
        lhs = "-" + lhs[2:]
    pieces: list[tuple[float, str]] = []
    for term, value in _active_terms(model, dof):
        monomial = term.latex_term() if latex else term.text
        monomial = "" if monomial == "1" else monomial
        if monomial[:1].isdigit():  # a numeric factor: keep it apart from the coefficient
            monomial = (r"\cdot " if latex else "* ") + monomial
        if numeric:
            body = f"{number(abs(value), precision)} {monomial}".strip()
            pieces.append((math.copysign(1.0, value), body))
        else:
            name = term.latex(dof) if latex else term.identifier(dof)
            pieces.append((1.0, f"{name} {monomial}".strip()))
    names = _CORIOLIS_LATEX if latex else _CORIOLIS_TEXT
    for powers, value in _coriolis_polynomials(model.ship)[dof].terms():
        value = float(value)
        if value == 0.0:
            continue
        named = dict(zip(("u_total", "v", "r"), powers, strict=True))
        body = f"{number(abs(value), precision)} {_monomial(named, names, latex)}"
        pieces.append((math.copysign(1.0, value), body.strip()))
    return lhs, pieces


def _join(pieces: list[tuple[float, str]]) -> list[str]:
    """Signed pieces as words ``["-0.1 v", "+ 0.2 r", ...]`` (the first without a plus)."""
    words = []
    for k, (sign, body) in enumerate(pieces):
        if k == 0:
            words.append(("-" if sign < 0 else "") + body)
        else:
            words.append(("- " if sign < 0 else "+ ") + body)
    return words or ["0"]


def _header(model: AbkowitzModel) -> str:
    return (f"Abkowitz model of {model.ship.name} (eq. 14-15, Prime I): library "
            f"{model.library.name}, optimizer {model.optimizer.get('name', 'given')}, "
            f"{model.rudder_signal} rudder")


def equations_text(model: AbkowitzModel, precision: int = 4, *, width: int = 100) -> str:
    """The model's equations (paper eq. 14) as plain text, one block per degree of freedom.

    Each block reads ``mass-matrix row . accelerations = hydrodynamic terms + Coriolis
    terms`` with the library's term spelling (``du``, ``v^2 r``, ...) and u' written as
    ``(1 + du)`` in the Coriolis terms.  Meant for ``str(model)``.

    Parameters
    ----------
    model : AbkowitzModel
    precision : int
        Significant digits of every number.
    width : int
        Lines are wrapped at this many characters.

    Examples
    --------
    >>> from sindyship.model import paper_model
    >>> from sindyship.ships import load_ship
    >>> text = equations_text(paper_model(load_ship("kcs")), precision=3)
    >>> [line[:3] for line in text.splitlines() if line[1:3] == ": "]
    ['X: ', 'Y: ', 'N: ']
    """
    precision = _check_precision(precision)
    lines = textwrap.wrap(_header(model), width=width, subsequent_indent="    ")
    for dof in DOFS:
        lhs, pieces = _equation_pieces(model, dof, latex=False, numeric=True,
                                       precision=precision)
        line = f"{dof}: {lhs} ="
        for word in _join(pieces):
            if len(line) + 1 + len(word) > width:
                lines.append(line)
                line = "      " + word
            else:
                line += " " + word
        lines.append(line)
    return "\n".join(lines)


def equations_latex(model: AbkowitzModel, precision: int = 4, *, numeric: bool = True,
                    terms_per_line: int = 4) -> str:
    """The model's equations (paper eq. 14-15) as one LaTeX ``align`` environment.

    Parameters
    ----------
    model : AbkowitzModel
    precision : int
        Significant digits of every number (``1.234 \\times 10^{-5}`` form when small).
    numeric : bool
        Coefficients as numbers (default) or by name (``X'_{vv}``, as in Tables 7-9).
    terms_per_line : int
        Right-hand-side terms per printed line; continuation lines are ``\\nonumber``.

    Returns
    -------
    str
        ``\\begin{align} ... \\end{align}`` (needs amsmath); variables are primed Prime I
        quantities, ``\\Delta u' = u' - 1``, and u' = 1 + Delta u' in the Coriolis terms.

    Examples
    --------
    >>> from sindyship.model import paper_model
    >>> from sindyship.ships import load_ship
    >>> tex = equations_latex(paper_model(load_ship("kcs")), precision=3)
    >>> print(tex.splitlines()[1].split(" - 0.000508")[0])
    0.00885 \\dot{u}' &= -0.00227 \\Delta u'
    """
    precision = _check_precision(precision)
    if terms_per_line < 1:
        raise SindyshipInputError(f"terms_per_line must be at least 1, not {terms_per_line}.")
    rows = [r"\begin{align}"]
    for n, dof in enumerate(DOFS):
        lhs, pieces = _equation_pieces(model, dof, latex=True, numeric=numeric,
                                       precision=precision)
        words = _join(pieces)
        chunks = [words[k:k + terms_per_line] for k in range(0, len(words), terms_per_line)]
        last = n == len(DOFS) - 1
        for k, chunk in enumerate(chunks):
            start = f"{lhs} &= " if k == 0 else r"&\quad "
            end = "" if (last and k == len(chunks) - 1) else (
                r" \\" if k == len(chunks) - 1 else r" \nonumber \\")
            rows.append(start + " ".join(chunk) + end)
    rows.append(r"\end{align}")
    return "\n".join(rows)


def _latex_text(text: str) -> str:
    """Plain text made safe inside LaTeX (special characters escaped)."""
    table = {"\\": r"\textbackslash{}", "&": r"\&", "%": r"\%", "$": r"\$", "#": r"\#",
             "_": r"\_", "{": r"\{", "}": r"\}", "~": r"\textasciitilde{}",
             "^": r"\textasciicircum{}"}
    return "".join(table.get(c, c) for c in str(text))


def _table_number(value: float, precision: int) -> str:
    """A table entry x 1e-5 with at least ``precision`` significant digits (integers kept)."""
    if value is None or not math.isfinite(value):
        return "--"
    if value == 0.0:
        return "$0$"
    decimals = max(0, precision - 1 - math.floor(math.log10(abs(value))))
    text = f"{value:.{decimals}f}"
    return f"${text}$"


def coefficient_table_latex(model: AbkowitzModel, precision: int = 4, *,
                            reference: Mapping[str, Mapping[str, float]] | None = None,
                            label: str | None = None, reference_label: str = "Reference") -> str:
    """The coefficients as a booktabs ``tabular`` in the style of paper Tables 7-9.

    Values are Prime I times 1e5, one block per degree of freedom, every library term
    listed (zero coefficients as 0).

    Parameters
    ----------
    model : AbkowitzModel
    precision : int
        Significant digits (integer digits are always kept, as in the paper's tables).
    reference : dict, optional
        ``{"X": {term: value}, ...}`` Prime I values printed beside the model's (e.g. the
        paper's LS column or :func:`sindyship.taylor.taylor_reference`); a missing or NaN
        value prints as ``--``.
    label, reference_label : str
        Column headings (default: the optimizer's name, and ``"Reference"``).

    Examples
    --------
    >>> from sindyship.model import paper_model
    >>> from sindyship.ships import load_ship
    >>> model = paper_model(load_ship("kcs"))
    >>> table = coefficient_table_latex(model, reference=model.coefficients,
    ...                                 reference_label="Paper LS")
    >>> print(table.splitlines()[3])
    Coefficient & paper-ls & Paper LS \\\\
    >>> [line for line in table.splitlines() if line.startswith("$Y'_{vvr}")]
    ["$Y'_{vvr}$ & $-230253$ & $-230253$ \\\\\\\\"]
    """
    precision = _check_precision(precision)
    heading = _latex_text(label if label is not None else model.optimizer.get("name", "model"))
    columns = ["Coefficient", heading]
    if reference is not None:
        columns.append(_latex_text(reference_label))
    rows = [
        r"\begin{tabular}{l" + "r" * (len(columns) - 1) + "}",
        r"\toprule",
        r"\multicolumn{" + str(len(columns)) + r"}{l}{Prime I, $\times 10^{-5}$} \\",
        " & ".join(columns) + r" \\",
    ]
    for dof in DOFS:
        rows.append(r"\midrule")
        for term in model.library.terms[dof]:
            cells = [f"${term.latex(dof)}$",
                     _table_number(model.coefficients[dof][term.text] * 1e5, precision)]
            if reference is not None:
                ref = reference.get(dof, {}).get(term.text)
                cells.append(_table_number(None if ref is None else float(ref) * 1e5,
                                           precision))
            rows.append(" & ".join(cells) + r" \\")
    rows += [r"\bottomrule", r"\end{tabular}"]
    return "\n".join(rows)


# ---------------------------------------------------------------------------------------------
# The generated simulator
# ---------------------------------------------------------------------------------------------
class _Printer(NumPyPrinter):
    """numpy code with the module imported as ``np``."""

    def _module_format(self, fqn: str, register: bool = True) -> str:
        return "np." + fqn.removeprefix("numpy.") if fqn.startswith("numpy.") else fqn


def _code(printer: NumPyPrinter, expr: sympy.Expr) -> str:
    """Python source of an expression, with spaces around the products."""
    return re.sub(r"(?<![*])[*](?![*])", " * ", printer.doprint(expr))


def _docstring_text(text: str) -> str:
    """Free text made safe inside a generated docstring."""
    return str(text).replace("\\", "/").replace('"""', "'''")


def _wrap(text: str, indent: str = "") -> list[str]:
    return textwrap.wrap(text, width=92, initial_indent=indent, subsequent_indent=indent,
                         break_on_hyphens=False) or [indent.rstrip()]


def _literal(text: str) -> str:
    """A string as a double-quoted Python literal."""
    return json.dumps(str(text))


def _constant(value: float) -> str:
    """A float as Python source that reads back to the same double."""
    return repr(float(value))


def _forces_source(model: AbkowitzModel, channel_names: Mapping[str, str]) -> list[str]:
    """Body of the generated ``forces`` function: sympy cse of eq. 15, library order."""
    forces = force_expressions(model)
    rename = {sympy.Symbol(name, real=True): sympy.Symbol(const, real=True)
              for name, const in channel_names.items()}
    exprs = [forces[dof].xreplace(rename) for dof in DOFS]
    replacements, reduced = sympy.cse(exprs, symbols=sympy.numbered_symbols("p"),
                                      optimizations="basic")
    printer = _Printer({"fully_qualified_modules": True})
    lines = []
    if replacements:
        lines.append("    # Products shared by the terms (sympy cse)")
    for symbol, expr in replacements:
        lines.append(f"    {symbol} = {_code(printer, expr)}")
    for dof, expr in zip(DOFS, reduced, strict=True):
        order = {coefficient_symbol(dof, term): k
                 for k, (term, _) in enumerate(_active_terms(model, dof))}
        parts = []
        for arg in sympy.Add.make_args(expr):
            coefs = [s for s in arg.free_symbols if s in order]
            if len(coefs) == 1 and (arg.is_Mul or arg.is_Symbol):
                coef = coefs[0]
                rest = arg / coef
                text = str(coef) if rest == 1 else f"{coef} * {_code(printer, rest)}"
                parts.append((order[coef], text))
            elif arg != 0:
                parts.append((len(order), _code(printer, arg)))
        parts.sort()
        lines.append(f"    # {dof}' (paper eq. 15)")
        if not parts:
            lines.append(f"    {dof} = 0.0 * du")
            continue
        lines.append(f"    {dof} = (")
        for k, (_, text) in enumerate(parts):
            lines.append(f"        {'' if k == 0 else '+ '}{text}")
        lines.append("    )")
    lines.append("    return X, Y, N")
    return lines


def _coriolis_source(ship: Ship) -> tuple[list[str], list[str]]:
    """Constants and rhs lines of the Coriolis terms, from :func:`sindyship.targets.coriolis`."""
    names = {"u_total": "un", "v": "vn", "r": "rn"}
    constants, lines = [], []
    for dof, poly in _coriolis_polynomials(ship).items():
        parts = []
        for powers, value in poly.terms():
            factors = []
            tag = ""
            for var, power in zip(("u_total", "v", "r"), powers, strict=True):
                factors += [names[var]] * power
                tag += {"u_total": "U", "v": "V", "r": "R"}[var] * power
            const = f"C_{dof}_{tag}"
            constants.append(f"{const} = {_constant(float(value))}")
            parts.append(" * ".join([const, *factors]))
        lines.append(f"    {dof}_c = " + (" + ".join(parts) if parts else "0.0 * un"))
    return constants, lines


_RUNTIME = '''

# ---------------------------------------------------------------------------------------------
# The model as the kernel flies it, and the public functions
# ---------------------------------------------------------------------------------------------
class _Model:
    \"\"\"The generated dynamics in the form the kernel's integrator flies.\"\"\"

    rudder_input = RUDDER_INPUT
    current = (0.0, 0.0)
    switching = None
    accelerations = staticmethod(accelerations)


_SERVO = (T_SERVO, RATE_MAX, DELTA_MAX)


class Flight(NamedTuple):
    \"\"\"States of one simulated manoeuvre at the output times.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Output times [s].
    states : ndarray, shape (7, N)
        ``[u, v, r, x, y, psi, delta]`` (SI); NaN after a divergence.
    delta_c : ndarray, shape (N,)
        Commanded rudder angle held at each output time [rad].
    diverged_at : float or None
        Time of the first output sample where the state left the plausible range.
    \"\"\"

    t: np.ndarray
    states: np.ndarray
    delta_c: np.ndarray
    diverged_at: float | None


def rhs(t, state, delta_c):
    \"\"\"Time derivative of the state (paper eq. 12-14 and the kinematics).

    Parameters
    ----------
    t : float
        Time [s] (the model is time invariant).
    state : array_like, shape (7,) or (7, N)
        ``[u, v, r, x, y, psi, delta]`` (SI).
    delta_c : float or ndarray of shape (N,)
        Commanded rudder angle [rad].

    Returns
    -------
    ndarray
        d(state)/dt, the shape of ``state``.
    \"\"\"
    state = np.asarray(state, dtype=float)
    columns = state.reshape(N_STATE, -1)
    commands = np.broadcast_to(np.asarray(delta_c, dtype=float), columns.shape[1]).copy()
    members = np.arange(columns.shape[1])
    out = _Integrator(_Model, [], _SERVO).rhs(t, columns, commands, members, None)
    return out.reshape(state.shape)


def _fly(command, t, state0, step, check_divergence):
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.size == 0:
        raise ValueError("t must be a one-dimensional array of output times")
    if t.size > 1 and np.any(np.diff(t) <= 0):
        raise ValueError("output times must increase")
    y = np.array([U0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0] if state0 is None else state0,
                 dtype=float).reshape(N_STATE)
    h_max = DEFAULT_STEP if step is None else float(step)
    integ = _Integrator(_Model, [command], _SERVO)
    (result,) = integrate(integ, [command], t, y, h_max, check_divergence, L, U0)
    return Flight(result.t, result.states, result.delta_c, result.diverged_at)


def simulate(t, delta_c, state0=None, *, step=None, check_divergence=True):
    \"\"\"Fly the model with a commanded rudder through the servo (paper eq. 12-14).

    Parameters
    ----------
    t : array_like, shape (N,)
        Increasing output times [s]; the first is the initial time.
    delta_c : float, array_like of shape (N,), or callable
        Commanded rudder angle [rad]: one value per output time, held until the next
        sample where it changes (zero-order hold); a constant; or a function
        ``f(t, state) -> angle`` evaluated at the start of every integration step and held
        over it (feedback control).
    state0 : array_like, shape (7,), optional
        Initial ``[u, v, r, x, y, psi, delta]`` (SI); default straight ahead at U0.
    step : float, optional
        Runge-Kutta step [s]; default ``DEFAULT_STEP``.  States at output times inside a
        step come from its cubic Hermite interpolant; steps are split exactly where the
        command changes.
    check_divergence : bool
        Stop at the first output sample where the state is implausible (``diverged``).

    Returns
    -------
    Flight
    \"\"\"
    t = np.asarray(t, dtype=float)
    if callable(delta_c):
        return _fly(FeedbackCommand(delta_c), t, state0, step, check_divergence)
    angles = np.asarray(delta_c, dtype=float)
    if angles.ndim == 0:
        angles = np.full(t.shape, float(angles))
    if angles.shape != t.shape:
        raise ValueError(
            f"delta_c has shape {angles.shape}; give one angle per output time {t.shape}"
        )
    if not np.all(np.isfinite(angles)):
        raise ValueError("delta_c must be finite")
    return _fly(StepCommand(t, angles), t, state0, step, check_divergence)


def zigzag(t, rudder_deg, check_deg, state0=None, first_sign=1, *, step=None,
           check_divergence=True):
    \"\"\"Fly a zig-zag closed loop: rudder +-rudder_deg, reversed at +-check_deg of heading.

    The rudder is reversed exactly when the heading change from its initial value reaches
    the check angle (located by bisection on the step's Hermite interpolant).

    Parameters
    ----------
    t : array_like, shape (N,)
        Increasing output times [s].
    rudder_deg, check_deg : float
        Rudder amplitude and heading check angle [deg].
    state0 : array_like, shape (7,), optional
        Initial state (SI); default straight ahead at U0.
    first_sign : int
        +1: first rudder to starboard; -1: to port.
    step, check_divergence
        As for ``simulate``.

    Returns
    -------
    Flight
    \"\"\"
    command = ZigZagCommand(math.radians(rudder_deg), math.radians(check_deg), first_sign)
    return _fly(command, t, state0, step, check_divergence)
'''


def _kernel_source() -> str:
    """The numerical kernel's source (:mod:`sindyship.simulation.kernels`) below its imports:
    the generated module flies with the very code the library runs."""
    import inspect

    from .simulation import kernels

    text = inspect.getsource(kernels)
    return "\n\n" + text[text.index(kernels.KERNEL_MARK):]


def generate_python(model: AbkowitzModel, *, source_note: str = "",
                    channels: Mapping[str, float] | None = None) -> str:
    """Source of a standalone simulator module for a model (imports numpy only).

    The module holds the coefficients as named constants and in ``COEFFICIENTS``
    (identifier -> value, every library term), ``forces`` (eq. 15, Prime I, built with
    sympy's common-subexpression elimination), ``rhs(t, state, delta_c)`` (eq. 14 with the
    protocol's Coriolis terms, the rudder servo of eq. 12-13 and the kinematics; state
    ``[u, v, r, x, y, psi, delta]`` SI, shape (7,) or (7, N)), ``simulate(t, delta_c,
    state0)`` and ``zigzag(t, rudder_deg, check_deg, state0, first_sign=1)``.  The
    integrator is the one of :mod:`sindyship.simulation` (fixed-step classical RK4 with
    step ``min(0.1, 0.25 T'_R) L / U0``, cubic Hermite outputs, steps split at command
    changes and at zig-zag check-angle crossings, the protocol's divergence rule), so the
    module flies a model as sindyship does.

    Parameters
    ----------
    model : AbkowitzModel
    source_note : str
        A line for the module docstring (e.g. the model file it was made from).
    channels : dict, optional
        Constant values (library scaling) of extra channels the library uses besides the
        heading ``psi`` (e.g. ``n``), as for :meth:`AbkowitzModel.dynamics`.

    Returns
    -------
    str
        Python source (passes ``ruff check``).

    Examples
    --------
    >>> from sindyship.model import paper_model
    >>> from sindyship.ships import load_ship
    >>> source = generate_python(paper_model(load_ship("kcs")))
    >>> namespace = {}
    >>> exec(compile(source, "kcs_sim.py", "exec"), namespace)  # doctest only
    >>> flight = namespace["zigzag"](np.arange(0.0, 60.0), 10.0, 10.0)
    >>> flight.states.shape, flight.diverged_at
    ((7, 60), None)
    """
    from .simulation import default_step, integrator_for

    dynamics = model.dynamics(channels)  # checks that every channel has a value
    integrator = integrator_for(dynamics, [])
    ship = model.ship
    channel_names = {name: f"CHANNEL_{name.upper()}" for name in sorted(model.library.channels)
                     if name != "psi"}
    Minv = model.inverse_mass
    M = abkowitz_mass_matrix(ship)
    optimizer = model.optimizer.get("name", "given")
    params = model.optimizer.get("params", {}) or {}
    training = model.info.get("training") if isinstance(model.info, Mapping) else None

    doc = [f'"""Simulator of an Abkowitz manoeuvring model of the ship {ship.name!r}.', ""]
    facts = (
        f"Generated by sindyship {__version__} from an identified model: library "
        f"{model.library.name!r} ({', '.join(f'{d} {n}' for d, n in model.n_active().items())}"
        f" active terms), optimizer {optimizer!r}"
        + (f" with {', '.join(f'{k}={v!r}' for k, v in sorted(params.items()))}"
           if params else "")
        + f", rudder signal {model.rudder_signal!r}."
    )
    doc += _wrap(_docstring_text(facts))
    if training:
        doc += _wrap(_docstring_text("Training records: " + ", ".join(map(str, training))
                                     + "."))
    if source_note:
        doc += _wrap(_docstring_text(source_note))
    doc += [
        "",
        "Equations (Deogaonkar et al., eq. 12-15; Prime I with the design speed U0): the mass",
        "matrix times (du'/dt', dv'/dt', dr'/dt') equals the hydrodynamic forces of eq. 15 plus",
        "the Coriolis terms (rigid body plus added mass, with the Munk moment).  The rudder",
        "follows its command through a first-order servo with rate and angle limits.",
        "",
        "The state is [u, v, r, x, y, psi, delta] in SI units: body-fixed surge and sway [m/s]",
        "(v positive to starboard), yaw rate [rad/s], earth-fixed x north and y east [m],",
        "heading [rad] and actual rudder angle [rad] (positive turns to starboard).  This",
        "module needs only numpy; it does not import sindyship.",
        "",
        "Examples",
        "--------",
        ">>> import numpy as np",
        ">>> t = np.arange(0.0, 120.0)",
        ">>> flight = simulate(t, np.radians(15.0), [U0, 0, 0, 0, 0, 0, 0])",
        ">>> flight.states.shape",
        "(7, 120)",
        ">>> rhs(0.0, np.tile([[U0], [0.0], [0.0], [0.0], [0.0], [0.0], [0.0]], 3), 0.0).shape",
        "(7, 3)",
        '"""',
    ]

    lines = [*doc, "", "from __future__ import annotations", "", "import math",
             "from collections.abc import Callable, Sequence", "from typing import NamedTuple",
             "",
             "import numpy as np", ""]
    lines += [
        "# ---------------------------------------------------------------------------------",
        "# Ship, rudder servo and integration",
        "# ---------------------------------------------------------------------------------",
        f"SHIP = {_literal(ship.name)}",
        f"L = {_constant(ship.L)}  # length between perpendiculars [m]",
        f"U0 = {_constant(ship.U0)}  # design speed [m/s]",
        f"T_SERVO = {_constant(integrator.T)}  # servo time constant T'_R L / U0 [s] (eq. 12)",
        f"RATE_MAX = {_constant(integrator.rate_max)}  # rudder rate limit [rad/s] (eq. 13)",
        f"DELTA_MAX = {_constant(integrator.delta_max)}  # largest rudder angle [rad]",
        f"RUDDER_INPUT = {_literal(integrator.rudder_input)}  # rudder angle the forces see",
        f"DEFAULT_STEP = {_constant(default_step(ship))}  # Runge-Kutta step [s]",
        "",
        "# Mass matrix of eq. 14 (Prime I) and its inverse",
        "MASS_MATRIX = (",
        *(f"    ({', '.join(_constant(x) for x in row)})," for row in M),
        ")",
        f"INV_UU = {_constant(Minv[0, 0])}",
        f"INV_VV = {_constant(Minv[1, 1])}",
        f"INV_VR = {_constant(Minv[1, 2])}",
        f"INV_RV = {_constant(Minv[2, 1])}",
        f"INV_RR = {_constant(Minv[2, 2])}",
        f"ACC_SCALE = {_constant(ship.U0 * ship.U0 / ship.L)}  # U0^2 / L [m/s^2]",
        "",
        "# Coriolis terms (Prime I): C_<dof>_<factors> multiplies u', v', r' as named",
    ]
    coriolis_constants, coriolis_lines = _coriolis_source(ship)
    lines += coriolis_constants
    if channel_names:
        lines += ["", "# Channels held constant (library scaling)"]
        for name, const in channel_names.items():
            lines.append(f"{const} = {_constant((channels or {})[name])}  # {name}")
    lines += [
        "",
        "# ---------------------------------------------------------------------------------",
        "# Identified coefficients, Prime I (paper eq. 15)",
        "# ---------------------------------------------------------------------------------",
    ]
    entries = []
    for dof in DOFS:
        for term in model.library.terms[dof]:
            ident = term.identifier(dof)
            lines.append(f"{ident} = {_constant(model.coefficients[dof][term.text])}"
                         f"  # {dof}: {term.text}")
            entries.append((ident, dof, term.text))
    lines += ["", "#: identifier -> value of every coefficient (Prime I)", "COEFFICIENTS = {"]
    lines += [f"    {_literal(ident)}: {ident}," for ident, _, _ in entries]
    lines += ["}", "#: identifier -> (degree of freedom, term as written in the library)",
              "TERMS = {"]
    lines += [f"    {_literal(ident)}: ({_literal(dof)}, {_literal(text)}),"
              for ident, dof, text in entries]
    lines += ["}", "", ""]
    lines += [
        "def forces(du, v, r, delta, psi=0.0):",
        '    """Hydrodynamic forces (X\', Y\', N\') of paper eq. 15, Prime I.',
        "",
        "    Parameters",
        "    ----------",
        "    du, v, r : float or ndarray",
        "        u / U0 - 1, v / U0 and r L / U0.",
        "    delta : float or ndarray",
        "        Rudder angle [rad].",
        "    psi : float or ndarray",
        "        Heading [rad] (used only by heading-dependent terms).",
        '    """',
        *_forces_source(model, channel_names),
        "",
        "",
        "def accelerations(u, v, r, delta, psi, branch=None):",
        '    """Accelerations (du/dt, dv/dt, dr/dt) [SI] of paper eq. 14 from SI state values.',
        "",
        "    The hydrodynamic forces of eq. 15 plus the Coriolis terms (rigid body plus added",
        "    mass, with the Munk moment), times the inverse mass matrix; ``delta`` is the rudder",
        "    angle the forces see.  Vectorised over numpy arrays.",
        '    """',
        "    un = u / U0",
        "    vn = v / U0",
        "    rn = r * L / U0",
        "    X, Y, N = forces(un - 1.0, vn, rn, delta, psi)",
        "    # Coriolis terms, rigid body plus added mass (right-hand side of eq. 14)",
        *coriolis_lines,
        "    X = X + X_c",
        "    Y = Y + Y_c",
        "    N = N + N_c",
        "    a_u = INV_UU * X",
        "    a_v = INV_VV * Y + INV_VR * N",
        "    a_r = INV_RV * Y + INV_RR * N",
        "    return a_u * ACC_SCALE, a_v * ACC_SCALE, a_r * ACC_SCALE / L",
    ]
    # Exotic libraries (long channel names, many factors) can make a line long.
    lines = [line if len(line) <= 99 else line + "  # noqa: E501" for line in lines]
    return "\n".join(lines) + "\n" + _kernel_source() + _RUNTIME.rstrip() + "\n"


def latex_document_part(model: AbkowitzModel, precision: int = 4) -> str:
    """The LaTeX that ``sindyship export --latex`` writes: equations and coefficient table.

    Examples
    --------
    >>> from sindyship.model import paper_model
    >>> from sindyship.ships import load_ship
    >>> part = latex_document_part(paper_model(load_ship("kcs")))
    >>> part.count("{align}"), part.count("{tabular}"), part.count("toprule")
    (2, 2, 1)
    """
    return "\n".join([
        r"% Abkowitz model exported by sindyship " + __version__ + " (needs amsmath, booktabs)",
        "% " + _header(model).replace("%", r"\%"),
        equations_latex(model, precision),
        "",
        coefficient_table_latex(model, precision),
        "",
    ])
