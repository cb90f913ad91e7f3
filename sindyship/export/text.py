"""The model as text and LaTeX: equations, the coefficient table, the exported document part."""

from __future__ import annotations

import math
import re
import textwrap
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from .. import __version__
from ..errors import SindyshipInputError
from ..targets import DOFS, abkowitz_mass_matrix
from ..terms import SPEED_FLOOR
from .symbolic import (
    _ACC_LATEX,
    _ACC_TEXT,
    _CORIOLIS_LATEX,
    _CORIOLIS_TEXT,
    _active_terms,
    _coriolis_polynomials,
    check_model,
)

if TYPE_CHECKING:
    from ..model import AbkowitzModel


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


def _equation_words(model: AbkowitzModel, dof: str, *, latex: bool, numeric: bool,
                    precision: int) -> tuple[str, list[str], int]:
    """Left-hand side text of eq. 14, its right-hand side as signed words (``["-0.1 v",
    "+ 0.2 r", ...]``) and how many of them, at the end, are Coriolis terms.  A library of the
    ``instantaneous`` speed form has its hydrodynamic terms bracketed and multiplied by
    (U/U0)^2, and each Coriolis term in v and r by the power of U/U0 that turns v/U and r L/U
    back into v/U0 and r L/U0."""
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
    hydrodynamic: list[tuple[float, str]] = []
    for term, value in _active_terms(model, dof):
        monomial = term.latex_term() if latex else term.text
        monomial = "" if monomial == "1" else monomial
        if monomial[:1].isdigit():  # a numeric factor: keep it apart from the coefficient
            monomial = (r"\cdot " if latex else "* ") + monomial
        if numeric:
            body = f"{number(abs(value), precision)} {monomial}".strip()
            hydrodynamic.append((math.copysign(1.0, value), body))
        else:
            name = term.latex(dof) if latex else term.identifier(dof)
            hydrodynamic.append((1.0, f"{name} {monomial}".strip()))
    instantaneous = model.library.speed == "instantaneous"
    ratio = r"\left(\frac{U}{U_0}\right)" if latex else "(U/U0)"
    names = _CORIOLIS_LATEX if latex else _CORIOLIS_TEXT
    coriolis_pieces: list[tuple[float, str]] = []
    for powers, value in _coriolis_polynomials(model.ship)[dof].terms():
        value = float(value)
        if value == 0.0:
            continue
        named = dict(zip(("u_total", "v", "r"), powers, strict=True))
        scale = powers[1] + powers[2] if instantaneous else 0
        factor = f"{ratio}{_power(scale, latex)} " if scale else ""
        body = f"{number(abs(value), precision)} {factor}{_monomial(named, names, latex)}"
        coriolis_pieces.append((math.copysign(1.0, value), body.strip()))
    words = _join(hydrodynamic) if hydrodynamic else []
    if instantaneous and words:
        words[0] = f"{ratio}^{{2}} [ {words[0]}" if latex else f"{ratio}^2 [{words[0]}"
        words[-1] += " ]" if latex else "]"
    words += _join(coriolis_pieces, first=not words)
    return lhs, words or ["0"], len(coriolis_pieces)


def _power(exponent: int, latex: bool) -> str:
    """An exponent as written after a factor (none for 1)."""
    if exponent == 1:
        return ""
    return f"^{{{exponent}}}" if latex else f"^{exponent}"


def _join(pieces: list[tuple[float, str]], first: bool = True) -> list[str]:
    """Signed pieces as words ``["-0.1 v", "+ 0.2 r", ...]`` (the first without a plus
    unless they continue a sum, ``first=False``)."""
    words = []
    for k, (sign, body) in enumerate(pieces):
        if k == 0 and first:
            words.append(("-" if sign < 0 else "") + body)
        else:
            words.append(("- " if sign < 0 else "+ ") + body)
    return words


def _delay_words(name: str, seconds: float) -> str:
    """How one recorded channel is out of step with the physics (:attr:`TermLibrary.delays`:
    a positive delay lags it, a negative one leads it)."""
    if seconds > 0:
        return f"the recorded {name} lags the physics by {seconds:g} s (read {seconds:g} s later)"
    return f"the recorded {name} leads the physics by {-seconds:g} s (read {-seconds:g} s earlier)"


def _delays_words(delays) -> str:
    """Which time the forces read each delayed channel of a record at."""
    return "; ".join(_delay_words(name, seconds) for name, seconds in sorted(delays.items()))


def _header(model: AbkowitzModel) -> str:
    """One line naming the model (names from files are flattened: no control characters)."""
    text = (f"Abkowitz model of {model.ship.name} (eq. 14-15, Prime I): library "
            f"{model.library.name}, optimizer {model.optimizer.get('name', 'given')}, "
            f"{model.rudder_signal} rudder")
    if model.library.speed == "instantaneous":
        text += ("; forces over the instantaneous speed U = sqrt(u^2 + v^2): v, r and the "
                 "channels' speeds and rates over U, every hydrodynamic term times (U/U0)^2, "
                 f"with U/U0 = |1 + du| / sqrt(1 - v^2) (from {SPEED_FLOOR:g} U0 up)")
    if model.library.delays:
        text += "; " + _delays_words(model.library.delays)
    return " ".join(text.split())


def equations_text(model: AbkowitzModel, precision: int = 4, *, width: int = 100) -> str:
    """The model's equations (paper eq. 14) as plain text, one block per degree of freedom.

    Each block reads ``mass-matrix row . accelerations = hydrodynamic terms + Coriolis
    terms`` with the library's term spelling (``du``, ``v^2 r``, ...) and u' written as
    ``(1 + du)`` in the Coriolis terms, which start a line of their own marked
    ``(Coriolis)``: a fitted ``v r`` and the Coriolis ``v r`` are two terms.  Meant for
    ``str(model)``.

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
    check_model(model)
    precision = _check_precision(precision)
    lines = textwrap.wrap(_header(model), width=width, subsequent_indent="    ")
    for dof in DOFS:
        lhs, words, n_coriolis = _equation_words(model, dof, latex=False, numeric=True,
                                                 precision=precision)
        first_coriolis = len(words) - n_coriolis if n_coriolis else None
        line = f"{dof}: {lhs} ="
        for k, word in enumerate(words):
            if k == first_coriolis:
                lines.append(line)
                line = "      (Coriolis) " + word
            elif len(line) + 1 + len(word) > width:
                lines.append(line)
                line = "      " + word
            else:
                line += " " + word
        lines.append(line)
    return "\n".join(lines)


#: Characters of rendered mathematics a LaTeX line of the equations holds (an estimate by
#: :func:`_rendered_length`): lines of every model tried fit an article's 345 pt text width at
#: 10 pt type (80 characters overran it by up to 15 pt).
LATEX_LINE_LENGTH = 68


def equations_latex(model: AbkowitzModel, precision: int = 4, *, numeric: bool = True,
                    line_length: int = LATEX_LINE_LENGTH) -> str:
    """The model's equations (paper eq. 14-15) as one LaTeX ``align`` environment.

    Each equation starts with its left-hand side (the mass-matrix row times the
    accelerations) on a line of its own; its hydrodynamic terms follow, indented, as many to a
    line as fit ``line_length`` (lines that fit an article's text width), and its Coriolis
    terms last, on a line of their own under a brace labelled "Coriolis" (in the yaw equation
    "Coriolis and Munk moment": a fitted N'_v excludes the Munk moment -(X'_udot - Y'_vdot) u' v',
    which eq. 14 moves to the right-hand side): a fitted ``v' r'`` and the Coriolis ``v' r'``
    are two terms.  Only an equation's last line is numbered.

    Parameters
    ----------
    model : AbkowitzModel
    precision : int
        Significant digits of every number (``1.234 \\times 10^{-5}`` form when small).
    numeric : bool
        Coefficients as numbers (default) or by name (``X'_{vv}``, as in Tables 7-9).
    line_length : int
        Most characters of rendered mathematics on a line (:data:`LATEX_LINE_LENGTH`; a term
        longer than that has a line of its own).

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
    >>> lines = tex.splitlines()
    >>> print(lines[1])
    &0.00885 \\dot{u}' = \\nonumber \\\\
    >>> print(lines[2].split(" + 0.00246")[0])
    &\\qquad -0.00227 \\Delta u' - 0.000508 \\Delta u'^{2}
    """
    check_model(model)
    precision = _check_precision(precision)
    if line_length < 1:
        raise SindyshipInputError(f"line_length must be at least 1, not {line_length}.")
    rows = [r"\begin{align}"]
    for dof in DOFS:
        lhs, words, n_coriolis = _equation_words(model, dof, latex=True, numeric=numeric,
                                                 precision=precision)
        hydrodynamic = words[:len(words) - n_coriolis]
        lines = [f"&{lhs} ="]
        for word in hydrodynamic:
            last = lines[-1]
            if len(lines) > 1 and (_rendered_length(last) + 1 + _rendered_length(word)
                                   <= line_length):
                lines[-1] = f"{last} {word}"
            else:
                lines.append(r"&\qquad " + word)
        if n_coriolis:
            coriolis = words[len(words) - n_coriolis:]
            label = ("Coriolis and Munk moment" if dof == "N" and "v'" in " ".join(coriolis)
                     else "Coriolis")
            chunks = [[]]
            for word in coriolis:  # as many to a brace as fit a line
                if chunks[-1] and (_rendered_length(" ".join([*chunks[-1], word]))
                                   > line_length - 8):
                    chunks.append([])
                chunks[-1].append(word)
            lines += [r"&\qquad \underbrace{" + " ".join(chunk) + r"}_{\text{" + label + "}}"
                      for chunk in chunks]
        rows += [line + r" \nonumber \\" for line in lines[:-1]]
        rows.append(lines[-1] + r" \\")
    notes = []  # unnumbered rows under the equations
    if model.library.speed == "instantaneous":  # what the variables are over
        notes.append(r"&\frac{U}{U_0} = \frac{|1 + \Delta u'|}{\sqrt{1 - v'^2}}, \qquad "
                     r"v' = \frac{v}{U}, \quad r' = \frac{r L}{U} \nonumber")
        notes.append(r"&\qquad \text{(the channels' speeds and rates over } U \text{ too; "
                     r"from } " f"{SPEED_FLOOR:g}" r"\,U_0 \text{ up)} \nonumber")
    if model.library.delays:  # which time a delayed channel is read at
        notes += [r"&\text{(" + _latex_text(_delay_words(name, seconds)) + r")} \nonumber"
                  for name, seconds in sorted(model.library.delays.items())]
    if notes:
        rows += [note + r" \\" for note in notes[:-1]] + [notes[-1]]
    else:
        rows[-1] = rows[-1].removesuffix(r" \\")
    rows.append(r"\end{align}")
    return "\n".join(rows)


def _rendered_length(tex: str) -> int:
    """About how many characters wide ``tex`` renders: commands count as one character
    (``\\Delta``, ``\\times``, ``\\dot{u}``), a fraction of U over U_0 as three,
    superscripts and subscripts as half, braces, spacing commands and a brace's label (set
    under it) not at all."""
    text = re.sub(r"_\{\\text\{[^{}]*\}\}", "", tex)  # a brace's label, set below it
    text = text.replace(r"\left(\frac{U}{U_0}\right)", "(U/U)")
    text = text.replace(r"\frac{U}{U_0}", "U/U")
    scripts = sum(len(m) for m in re.findall(r"[\^_]\{([^{}]*)\}", text))
    text = re.sub(r"[\^_]\{[^{}]*\}", "", text)
    text = re.sub(r"\\(?:qquad|quad|nonumber|left|right)", "", text)
    text = re.sub(r"\\[A-Za-z]+(?:\{[^{}]*\})?", "x", text)
    return len(text.replace("{", "").replace("}", "")) + (scripts + 1) // 2


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
    """The coefficients as booktabs ``tabular`` environments in the style of paper Tables 7-9:
    one per equation (a library's sixty-odd terms in one table run off a page).

    Values are Prime I times 1e5, every library term listed (zero coefficients as 0); the
    tables are separated by ``\\medskip``.

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
    >>> print(table.splitlines()[2])
    \\multicolumn{3}{l}{Surge force X', Prime I, $\\times 10^{-5}$} \\\\
    >>> print(table.splitlines()[3])
    Coefficient & paper-ls & Paper LS \\\\
    >>> [line for line in table.splitlines() if line.startswith("$Y'_{vvr}")]
    ["$Y'_{vvr}$ & $-230253$ & $-230253$ \\\\\\\\"]
    """
    check_model(model)
    precision = _check_precision(precision)
    heading = _latex_text(label if label is not None else model.optimizer.get("name", "model"))
    columns = ["Coefficient", heading]
    if reference is not None:
        columns.append(_latex_text(reference_label))
    rows = []
    for dof in DOFS:
        terms = model.library.terms[dof]
        parts = math.ceil(len(terms) / TABLE_ROWS)
        for part in range(parts):
            if rows:
                rows += ["", r"\medskip", ""]
            more = f" ({part + 1} of {parts})" if parts > 1 else ""
            rows += [
                r"\begin{tabular}{l" + "r" * (len(columns) - 1) + "}",
                r"\toprule",
                r"\multicolumn{" + str(len(columns)) + r"}{l}{" + _EQUATION_NAMES[dof] + more
                + r", Prime I, $\times 10^{-5}$} \\",
                " & ".join(columns) + r" \\",
                r"\midrule",
            ]
            rows += _table_rows(model, dof, terms[part * TABLE_ROWS:(part + 1) * TABLE_ROWS],
                                precision, reference)
            rows += [r"\bottomrule", r"\end{tabular}"]
    return "\n".join(rows)


def _table_rows(model, dof: str, terms, precision: int, reference) -> list[str]:
    """The table rows of ``terms`` of one equation."""
    rows = []
    for term in terms:
        cells = [f"${term.latex(dof)}$",
                 _table_number(model.coefficients[dof][term.text] * 1e5, precision)]
        if reference is not None:
            ref = reference.get(dof, {}).get(term.text)
            cells.append(_table_number(None if ref is None else float(ref) * 1e5, precision))
        rows.append(" & ".join(cells) + r" \\")
    return rows


#: Most rows of one coefficient table: an equation with more is split into tables of at most
#: this many (52 rows ran 34 pt off an article's page).
TABLE_ROWS = 40

#: The equations by name, for the tables' headings.
_EQUATION_NAMES = {"X": "Surge force X'", "Y": "Sway force Y'", "N": "Yaw moment N'"}



def latex_document_part(model: AbkowitzModel, precision: int = 4) -> str:
    """The LaTeX that ``sindyship export --latex`` writes: equations and coefficient table.

    Examples
    --------
    >>> from sindyship.model import paper_model
    >>> from sindyship.ships import load_ship
    >>> part = latex_document_part(paper_model(load_ship("kcs")))
    >>> part.count("{align}"), part.count("{tabular}"), part.count("toprule")
    (2, 6, 3)
    """
    return "\n".join([
        r"% Abkowitz model exported by sindyship " + __version__ + " (needs amsmath, booktabs)",
        "% " + _latex_text(_header(model)),
        "{\\allowdisplaybreaks  % the equations may break across pages",
        equations_latex(model, precision),
        "}",
        "",
        coefficient_table_latex(model, precision),
        "",
    ])
