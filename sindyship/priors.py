"""What a naval architect knows before the trials: the prior of physics-consistent fits.

The optimizer ``prior`` (:class:`~sindyship.optimizers.PriorRidge`) fits the coefficients of
eq. 18 by least squares drawn toward a prior, so that the combinations of coefficients the
trajectories cannot separate (v' and r' are tied in turns and zig-zags, and their cubic terms
become collinear: the paper's "parameter drift") take physically sensible values instead of
arbitrary ones.  This module builds that prior for a ship from its main dimensions alone, never
from its MMG coefficients:

Semi-empirical derivatives (:func:`semi_empirical_derivatives`)
    What a captive (towing-tank) test would measure, Prime I:

    - the linear sway and yaw derivatives Y'_v, Y'_r, N'_v, N'_r of Clarke, Gedling & Hine
      (1983), *The application of manoeuvring criteria in hull design using linear theory*,
      Trans. RINA 125, 45-68 (the regression on L, B, d and C_B that
      :func:`sindyship.ships.clarke_added_masses` uses for the added masses);
    - the non-linear hull derivatives X'_vv, X'_vr, Y'_vvv, Y'_vvr, Y'_vrr, Y'_rrr, N'_vvv,
      N'_vvr, N'_vrr, N'_rrr of Yoshimura & Masumoto (2012), *Hydrodynamic database and
      manoeuvring prediction method with medium high-speed merchant ships and fishing
      vessels*, Proc. MARSIM 2012 (Prime II, times d/L for Prime I).  Their X'_vr is the
      hull's force with the added-mass term m'_y v' r' inside, as a dynamometer measures it:
      1.91 C_B / (L / B) - 0.08 gives 441e-5 for the KCS and 1295e-5 for the KVLCC2 against
      their MMG models' 509e-5 and 1723e-5 (propeller included).  Fitted, with m'_y v' r'
      taken out, the estimates are -291e-5 and -170e-5 against -223e-5 and +258e-5: the
      difference of two large numbers, so the prior's width (half the captive value, 221e-5
      and 648e-5) is wide there.  Their X'_rr is left out: its sign differs between hull
      forms (-0.012 for the KCS of the paper's Table 3, +0.011 for the KVLCC2 of the MMG
      standard), so no regression on main dimensions sets it.

    Each has a standard deviation of half its value, at least a tenth of that of the
    largest estimate of its order (:func:`prior_widths`).

    The identified coefficients are not quite these: the regression target of eq. 16 moves
    the added-mass Coriolis and Munk terms to the right-hand side of eq. 14
    (:func:`sindyship.targets.coriolis`), so e.g. Y'_r(fitted) = Y'_r(captive) - X'_udot,
    N'_v(fitted) = N'_v(captive) + X'_udot - Y'_vdot and X'_vr(fitted) = X'_vr(captive) +
    Y'_vdot; :func:`prior_means` converts.  The paper's surge library (eq. 17a) has no
    ``v r``: use the library ``abkowitz-vr``, or X'_rr takes up X'_vr's share of the force
    in turns (v' is about -0.5 r' there) and can come out with the wrong sign (it does for
    the KCS at the default strength; :func:`coverage_note`).
Speed scaling (:func:`speed_relations`)
    A term ``du^k m`` describes how the force of the monomial ``m`` changes with the surge
    speed.  Quasi-steady forces scale with U^2 f(v/U, r L/U, delta), so with u' = 1 + du the
    term m = v^a r^b delta^c (Prime I, design speed) carries (1 + du)^(2 - a - b): the prior
    draws the coefficient of ``du^k m`` toward binom(2 - a - b, k) times that of ``m``
    (``du v`` toward ``v``, ``v^2 du`` toward 0, ``delta^2 du`` toward twice ``delta^2``).
Everything else
    The weak prior of :class:`~sindyship.optimizers.PriorRidge`: toward zero, one standard
    deviation being a term that alone explains as much force as there is.

Examples
--------
>>> from sindyship.ships import load_ship
>>> captive = semi_empirical_derivatives(load_ship("kcs"))
>>> {t: round(v * 1e5) for t, v in captive["Y"].items() if t in ("v", "r")}
{'v': -1230, 'r': 298}
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .errors import PriorCoverageNote
from .ships import Ship
from .terms import Term

__all__ = ["RELATIVE_WIDTH", "WIDTH_FLOOR", "PriorCoverageNote", "coverage_note",
           "estimates_outside", "prior_means", "prior_parameters", "prior_widths",
           "semi_empirical_derivatives", "speed_relations"]

#: The library with every term the prior has an estimate for: the paper's and X's ``v r``.
COMPLETE_LIBRARY = "abkowitz-vr"

#: Prior standard deviation of a semi-empirical derivative, as a share of its value.
RELATIVE_WIDTH = 0.5

#: The least prior standard deviation, as a share of the relative width times the largest
#: estimate of the same order (linear, or non-linear) of the ship (:func:`prior_widths`).
WIDTH_FLOOR = 0.1


def semi_empirical_derivatives(ship: Ship) -> dict[str, dict[str, float]]:
    """Captive-test derivatives estimated from L, B, d and C_B (Prime I).

    Returns
    -------
    dict
        ``{"X": {"v^2": ...}, "Y": {"v": ..., "r": ..., "v^3": ...}, "N": {...}}``, keyed by
        the canonical term text (:meth:`sindyship.terms.Term.canonical`); the hydrodynamic
        force a captive dynamometer measures (the convention of :mod:`sindyship.captive`).
    """
    p = ship.particulars
    k = p.d / p.L  # Prime II -> Prime I
    c_b = p.displacement / (p.L * p.B * p.d)
    l_b = p.L / p.B
    cb_lb = c_b / l_b
    clarke = math.pi * k**2
    b_l, b_t = p.B / p.L, p.B / p.d
    return {
        "X": {"v^2": k * (1.15 * cb_lb - 0.18), "v r": k * (1.91 * cb_lb - 0.08)},
        "Y": {
            "v": -clarke * (1.0 + 0.40 * c_b * b_t),
            "r": -clarke * (-0.5 + 2.2 * b_l - 0.080 * b_t),
            "v^3": k * (-0.185 * l_b + 0.48),
            "v^2 r": k * -0.75,
            "v r^2": -k * (0.26 * (1.0 - c_b) * l_b + 0.11),
            "r^3": k * -0.051,
        },
        "N": {
            "v": -clarke * (0.5 + 2.4 * k),
            "r": -clarke * (0.25 + 0.039 * b_t - 0.56 * b_l),
            "v^3": -k * (0.66 - 0.69 * c_b),
            "v^2 r": k * (1.55 * cb_lb - 0.76),
            "v r^2": k * (-0.075 * (1.0 - c_b) * l_b - 0.098),
            "r^3": k * (0.25 * cb_lb - 0.056),
        },
    }


def prior_means(ship: Ship) -> dict[str, dict[str, float]]:
    """The semi-empirical derivatives in the convention of the identified coefficients.

    Subtracts the added-mass Coriolis and Munk terms of :func:`sindyship.targets.coriolis`
    (with the ship's own added masses), which eq. 16 keeps out of the fitted force.
    """
    out = {dof: dict(terms) for dof, terms in semi_empirical_derivatives(ship).items()}
    inertia = ship.prime_i_inertia()
    x_udot, y_vdot, y_rdot = inertia["X_udot"], inertia["Y_vdot"], inertia["Y_rdot"]
    out["Y"]["r"] -= x_udot  # added-mass Coriolis X'_udot u' r'
    out["N"]["v"] += x_udot - y_vdot  # Munk moment -(X'_udot - Y'_vdot) u' v'
    out["N"]["r"] -= y_rdot  # Y'_rdot u' r'
    out["X"]["v r"] += y_vdot  # added-mass centripetal term -Y'_vdot v' r'
    return out


def _speed_exponent(term: Term) -> tuple[int, str] | None:
    """``(k, m)`` for a term ``du^k m`` whose monomial ``m`` is a plain product of v, r and
    delta (not a constant), else None."""
    powers: dict[str, int] = {}
    for factor in term.factors:
        if factor.function is not None or not isinstance(factor.base, str) or \
                factor.base not in ("du", "v", "r", "delta") or factor.power != int(factor.power):
            return None
        powers[factor.base] = powers.get(factor.base, 0) + int(factor.power)
    k = powers.pop("du", 0)
    if k == 0 or not powers:
        return None
    return k, Term(" ".join(f"{b}^{e}" if e > 1 else b for b, e in powers.items())).canonical()


def _binomial(e: int, k: int) -> float:
    """The generalised binomial coefficient (e choose k) for any integer e."""
    out = 1.0
    for i in range(k):
        out *= (e - i) / (i + 1)
    return out


def speed_relations(terms: Sequence[str]) -> list[tuple[int, int, float]]:
    """The speed-scaling relations among the columns of one degree of freedom.

    Returns
    -------
    list of (j, i, c)
        Column ``j`` (a term ``du^k m``) drawn toward ``c`` times column ``i`` (the term
        ``m``), for every such pair in ``terms``.

    Examples
    --------
    >>> speed_relations(["v", "du v", "du^2 v", "delta^2", "delta^2 du", "du"])
    [(1, 0, 1.0), (2, 0, 0.0), (4, 3, 2.0)]
    """
    canonical = {Term(t).canonical(): i for i, t in enumerate(terms)}
    out = []
    for j, text in enumerate(terms):
        found = _speed_exponent(Term(text))
        if found is None or found[1] not in canonical:
            continue
        k, monomial = found
        base = Term(monomial)
        degree = sum(int(f.power) for f in base.factors if f.base in ("v", "r"))
        out.append((j, canonical[monomial], _binomial(2 - degree, k)))
    return out


def prior_widths(ship: Ship, *, relative_width: float = RELATIVE_WIDTH
                 ) -> dict[str, dict[str, float]]:
    """The prior standard deviation of every semi-empirical derivative (Prime I).

    ``relative_width`` times its value, but at least :data:`WIDTH_FLOOR` times that of the
    largest estimate of the same order (the linear derivatives, or the non-linear ones, over
    X, Y and N): the regressions change sign inside the range of hull forms (X'_vv of
    Yoshimura & Masumoto at C_B / (L / B) = 0.157), so an estimate near zero says that the
    derivative is small, not that it is known to be zero.

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> widths = prior_widths(load_ship("kcs"))
    >>> round(widths["Y"]["v"] * 1e5), round(widths["N"]["r^3"] * 1e5)  # own share; floor
    (615, 198)
    """
    means = semi_empirical_derivatives(ship)
    largest = {order: max(abs(v) for terms in means.values() for t, v in terms.items()
                          if (Term(t).degree == 1) == (order == "linear"))
               for order in ("linear", "non-linear")}
    return {dof: {t: relative_width * max(abs(v), WIDTH_FLOOR * largest[
        "linear" if Term(t).degree == 1 else "non-linear"]) for t, v in terms.items()}
            for dof, terms in means.items()}


def prior_parameters(ship: Ship, dof: str, terms: Sequence[str], *,
                     relative_width: float = RELATIVE_WIDTH, speed: str = "design") -> dict:
    """The ``mean``, ``scale`` and ``relations`` of :class:`~sindyship.optimizers.PriorRidge`
    for one degree of freedom of a library.

    Parameters
    ----------
    ship : Ship
    dof : {"X", "Y", "N"}
    terms : sequence of str
        The library's terms of ``dof`` (the columns, in order).
    relative_width : float
        Standard deviation of a semi-empirical derivative as a share of its value
        (:func:`prior_widths`).
    speed : {"design", "instantaneous"}
        The library's speed form.  The semi-empirical derivatives are those of forces over
        U^2 in v/U and r L/U, which both forms share at the design speed; only the design
        form needs the speed relations (:func:`speed_relations`): in the instantaneous form
        every term already carries (U/U0)^2, so a term ``du^k m`` is drawn toward zero.

    Returns
    -------
    dict
        JSON-ready lists: ``mean`` and ``scale`` (None: the weak prior) per column, and the
        ``relations``.
    """
    means = prior_means(ship)[dof]
    widths = prior_widths(ship, relative_width=relative_width)[dof]
    mean = np.zeros(len(terms))
    scale = np.full(len(terms), np.nan)
    for j, text in enumerate(terms):
        canonical = Term(text).canonical()
        if canonical in means:
            mean[j], scale[j] = means[canonical], widths[canonical]
    relations = speed_relations(terms) if speed == "design" else []
    return {"mean": mean.tolist(),
            "scale": [float(x) if np.isfinite(x) else None for x in scale],
            "relations": [list(r) for r in relations]}


def estimates_outside(ship: Ship, terms: dict[str, Sequence[str]]) -> dict[str, list[str]]:
    """The semi-empirical derivatives that a library has no term for, per degree of freedom.

    Their share of the force goes to the library's other terms instead, so the prior cannot
    set them: without ``v r`` in X, X'_rr takes up X'_vr's share of the surge force in turns.

    Examples
    --------
    >>> from sindyship.library import load_library
    >>> from sindyship.ships import load_ship
    >>> library = load_library("abkowitz")
    >>> estimates_outside(load_ship("kcs"), {d: [t.text for t in library.terms[d]]
    ...                                      for d in "XYN"})
    {'X': ['v r']}
    """
    out = {}
    for dof, estimates in semi_empirical_derivatives(ship).items():
        have = {Term(t).canonical() for t in terms.get(dof, ())}
        missing = [t for t in estimates if t not in have]
        if missing:
            out[dof] = missing
    return out


def coverage_note(ship: Ship, library) -> str | None:
    """One sentence saying which estimates the library has no term for, and what to do; None
    when it has them all.

    Examples
    --------
    >>> from sindyship.library import load_library
    >>> from sindyship.ships import load_ship
    >>> print(coverage_note(load_ship("kcs"), load_library("abkowitz")))
    the library 'abkowitz' has no X term 'v r' for the prior's estimate, so other terms take \
up its force and can get the wrong sign; fit on the library 'abkowitz-vr', which has it.
    >>> coverage_note(load_ship("kcs"), load_library("abkowitz-vr")) is None
    True
    """
    missing = estimates_outside(ship, {dof: [t.text for t in terms]
                                       for dof, terms in library.terms.items()})
    if not missing:
        return None
    listed = "; ".join(f"{dof} {'term' if len(terms) == 1 else 'terms'} "
                       + ", ".join(repr(t) for t in terms) for dof, terms in missing.items())
    one = sum(len(terms) for terms in missing.values()) == 1
    remedy = (f"fit on the library {COMPLETE_LIBRARY!r}, which has "
              + ("it" if one else "them") if library.name == "abkowitz"
              else "add " + ("it" if one else "them") + " to the library")
    return (f"the library {library.name!r} has no {listed} for the prior's "
            f"{'estimate' if one else 'estimates'}, so other terms take up "
            f"{'its' if one else 'their'} force and can get the wrong sign; {remedy}.")
