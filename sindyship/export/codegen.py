"""A standalone simulator module for a model: its forces, accelerations and the kernel."""

from __future__ import annotations

import json
import math
import re
import textwrap
from collections.abc import Mapping
from typing import TYPE_CHECKING

import sympy
from sympy.printing.numpy import NumPyPrinter

from .. import __version__
from ..plausibility import MAX_REVOLUTION_RATIO
from ..targets import DOFS, abkowitz_mass_matrix
from ..terms import ANGLE_CHANNELS, SPEED_FLOOR, channel_scaling, read_over_speed
from . import _compiled
from ._runtime import RUNTIME
from .symbolic import (
    _active_terms,
    _coriolis_polynomials,
    check_model,
    coefficient_symbol,
    force_expressions,
)
from .text import _delays_words

if TYPE_CHECKING:
    from ..model import AbkowitzModel
    from ..ships import Ship


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
    """Free text made safe inside a generated docstring: one line (control characters become
    spaces), no backslash and no triple quote that could end the docstring."""
    line = " ".join(str(text).replace("\\", "/").split())
    return line.replace('"""', "'''")


def _wrap(text: str, indent: str = "") -> list[str]:
    return textwrap.wrap(text, width=92, initial_indent=indent, subsequent_indent=indent,
                         break_on_hyphens=False) or [indent.rstrip()]


def _literal(text: str) -> str:
    """A string as a double-quoted Python literal."""
    return json.dumps(str(text))


def _constant(value: float) -> str:
    """A float as Python source that reads back to the same double (NaN as ``math.nan``)."""
    value = float(value)
    return "math.nan" if math.isnan(value) else repr(value)


def _revolutions(ship: Ship) -> float:
    """The ship's propeller revolutions [rps], 0 for a ship file that gives none."""
    return float(ship.propeller.n_P) if ship.has_mmg else 0.0


def _example_lines(model: AbkowitzModel, channel_names: Mapping[str, str],
                   channels: Mapping[str, float] | None) -> list[str]:
    """The generated module's docstring example: a turn and the right-hand side.  Channels
    exported without a value are passed in SI: the propeller's design revolutions for ``n``
    where the ship file gives them; for any other the example is shown, not run."""
    unset = sorted(name for name in channel_names if name not in (channels or {}))
    design_n = getattr(getattr(model.ship, "propeller", None), "n_P", None)
    state = "np.tile([[U0], [0.0], [0.0], [0.0], [0.0], [0.0], [0.0]], 3)"
    lines = [">>> import numpy as np", ">>> t = np.arange(0.0, 120.0)"]
    if not unset:
        return [*lines, ">>> flight = simulate(t, np.radians(15.0), [U0, 0, 0, 0, 0, 0, 0])",
                ">>> flight.states.shape", "(7, 120)", f">>> rhs(0.0, {state}, 0.0).shape",
                "(7, 3)"]
    if unset == ["n"] and design_n is not None and math.isfinite(design_n):
        return [*lines,
                f">>> n = {_constant(design_n)}  # propeller revolutions [rps], the ship's design",
                ">>> flight = simulate(t, np.radians(15.0), [U0, 0, 0, 0, 0, 0, 0],",
                "...                   {'n': np.full(t.size, n)})",
                ">>> flight.states.shape", "(7, 120)",
                f">>> rhs(0.0, {state}, 0.0, {{'n': np.full(3, n)}}).shape", "(7, 3)"]
    given = ", ".join(unset)
    return [*_wrap(f"The library uses the channel{'s' if len(unset) > 1 else ''} {given}, "
                   "exported without a value: pass each over t, in SI (channels=...)."), "",
            *lines,
            ">>> channels = {name: your_values_over_t for name in CHANNEL_SCALING}"
            "  # doctest: +SKIP",
            ">>> flight = simulate(t, np.radians(15.0), [U0, 0, 0, 0, 0, 0, 0], channels)"
            "  # doctest: +SKIP"]


def _forces_source(channel_names: Mapping[str, str], body: list[str]) -> list[str]:
    """Body of the generated ``forces`` function: the channels, then ``body``
    (:func:`_forces_body`)."""
    return [f"    ch_{name} = {const} if channels is None else channels[{_literal(name)}]"
            for name, const in channel_names.items()] + body


#: Terms of a model (X, Y and N together) up to which the generated forces share their
#: common products (sympy cse).
CSE_MAX_TERMS = 600


def _forces_body(model: AbkowitzModel, channel_names: Mapping[str, str]) -> list[str]:
    """Lines computing and returning ``X, Y, N`` of eq. 15 from ``du, v, r, delta, psi`` and
    ``ch_<channel>``: sympy cse, terms in library order."""
    forces = force_expressions(model)
    rename = {sympy.Symbol(name, real=True): sympy.Symbol(f"ch_{name}", real=True)
              for name in channel_names}
    exprs = [forces[dof].xreplace(rename) for dof in DOFS]
    # no preprocessing: sympy's "basic" optimisations factor the sums first, which grows
    # faster than the terms, and the products the terms share are found without it; beyond
    # CSE_MAX_TERMS the search itself takes minutes, and each term is written out whole
    if sum(len(sympy.Add.make_args(e)) for e in exprs) <= CSE_MAX_TERMS:
        replacements, reduced = sympy.cse(exprs, symbols=sympy.numbered_symbols("p"))
    else:
        replacements, reduced = [], exprs
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


def _accelerations_body(forces_call: str, coriolis_lines: list[str],
                        speed_ratio: str | None = None) -> list[str]:
    """Lines of eq. 14 from SI ``u, v, r``: the forces (``forces_call``), the Coriolis terms,
    the inverse mass matrix, and the return of the SI accelerations.  With ``speed_ratio``
    (the expression of U/U0, the instantaneous speed form) the call reads ``ratio`` and the
    forces are multiplied by its square."""
    scaled = [] if speed_ratio is None else [
        "    # the instantaneous speed form: v, r over U, the forces times (U/U0)^2",
        f"    ratio = {speed_ratio}",
        f"    X, Y, N = {forces_call}",
        "    factor = ratio * ratio",
        "    X, Y, N = X * factor, Y * factor, N * factor",
    ]
    return [
        "    un = u / U0",
        "    vn = v / U0",
        "    rn = r * L / U0",
        *(scaled or [f"    X, Y, N = {forces_call}"]),
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


def _kernel_source() -> str:
    """The numerical kernel's source (:mod:`sindyship.simulation.kernels`) below its imports:
    the generated module flies with the very code the library runs."""
    import inspect

    from ..simulation import kernels

    text = inspect.getsource(kernels)
    return "\n\n" + text[text.index(kernels.KERNEL_MARK):]


def _provenance(model: AbkowitzModel) -> list[str]:
    """Docstring lines naming what the model was fitted on: its training records and, for a
    hybrid fit (``info["captive"]``), its captive tests."""
    info = model.info if isinstance(model.info, Mapping) else {}
    lines = []
    if info.get("training"):
        lines += _wrap(_docstring_text("Training records: "
                                       + ", ".join(map(str, info["training"])) + "."))
    captive = info.get("captive")
    if isinstance(captive, Mapping) and isinstance(captive.get("tests"), Mapping):
        tests = ", ".join(f"{kind} {count}" for kind, count in captive["tests"].items())
        lines += _wrap(_docstring_text(
            f"Captive tests fitted beside them: {tests} (share {captive.get('share')!r} of the "
            "regression's weight)."))
    return lines


def _delays_note(delays) -> str:
    """The module docstring's note on the channels a library delays: what ``simulate``,
    ``replay`` and ``zigzag`` do with them, and, for a delayed rudder, which angle ``state0``
    takes."""
    note = (f"Delayed channels (DELAYS): {_delays_words(delays)}.  simulate, replay and zigzag "
            "read each channel given to them (and simulate a delta_c array, replay a delta "
            "array) so; rhs takes the channels' values at the physics' time.")
    if "delta" in delays:  # sindyship starts a flight from the record's state, read so
        note += (f"  Give state0's rudder angle as the record's delta {delays['delta']:g} s "
                 "after t[0].")
    if "delta_c" in delays:
        note += ("  For a record without delta, give state0's rudder angle as its delta_c "
                 f"{delays['delta_c']:g} s after t[0].")
    return note


def generate_python(model: AbkowitzModel, *, source_note: str = "",
                    channels: Mapping[str, float] | None = None, compiled: bool = False) -> str:
    """Source of a standalone simulator module for a model (imports numpy only).

    The module holds the coefficients as named constants and in ``COEFFICIENTS`` (identifier ->
    value, every library term; read-only, as ``forces`` reads the constants), ``forces`` (eq.
    15, Prime I, built with sympy's common-subexpression elimination), ``rhs(t, state,
    delta_c)`` (eq. 14 with the protocol's Coriolis terms, the rudder servo of eq. 12-13 and the
    kinematics; state ``[u, v, r, x, y, psi, delta]`` SI, shape (7,) or (7, N)), ``simulate(t,
    delta_c, state0)``, ``replay(t, delta, state0)`` (the rudder angle itself prescribed, as a
    record's actual rudder is replayed) and ``zigzag(t, rudder_deg, check_deg, state0,
    first_sign=1)``. The
    integrator is the one of :mod:`sindyship.simulation` (fixed-step classical RK4 with step
    ``min(0.1, 0.25 T'_R) L / U0``, cubic Hermite outputs, steps split at command changes and at
    zig-zag check-angle crossings, the protocol's divergence rule), so the module flies a model
    as sindyship does.

    With ``compiled=True`` the module also holds the right-hand side and the RK4 step as
    scalar loops over the batch, compiled by numba (``numba.njit``, cached beside the module
    file) where numba can be imported when the module runs, and ``rhs``, ``simulate`` and
    ``zigzag`` run them (``replay`` runs the compiled right-hand side in the kernel's step;
    module constant ``COMPILED``); where it cannot, the module warns
    once and runs its numpy functions, which give the same numbers more slowly.

    Parameters
    ----------
    model : AbkowitzModel
    source_note : str
        A line for the module docstring (e.g. the model file it was made from).
    channels : dict, optional
        Constant values (library scaling) of extra channels the library uses besides the
        heading ``psi`` (e.g. ``n``), as for :meth:`AbkowitzModel.dynamics`.
    compiled : bool
        Add the numba-compiled right-hand side (numba stays optional where the module runs).

    Returns
    -------
    str
        Python source (passes ``ruff check``).

    Examples
    --------
    >>> import numpy as np
    >>> from sindyship import load_ship, paper_model
    >>> source = generate_python(paper_model(load_ship("kcs")))
    >>> namespace = {}
    >>> exec(compile(source, "kcs_sim.py", "exec"), namespace)  # doctest only
    >>> flight = namespace["zigzag"](np.arange(0.0, 60.0), 10.0, 10.0)
    >>> flight.states.shape, flight.diverged_at
    ((7, 60), None)
    """
    check_model(model)
    from ..errors import SindyshipInputError
    from ..simulation import default_step, integrator_for

    if {"x", "y", "delta_rate"} & model.library.sources:
        raise SindyshipInputError(
            "the model's terms use the position (x, y, or a shape of it such as a bank's pull) "
            "or the rudder rate, which the generated "
            "simulator does not pass to its forces; fly this model with sindyship evaluate "
            "instead."
        )
    if {"wind_app_speed", "wind_app_angle"} & set(model.library.variables):
        raise SindyshipInputError(
            "the model's terms use the apparent wind, which the generated simulator does not "
            "make from the flown motion; fly this model with sindyship evaluate instead."
        )
    instantaneous = model.library.speed == "instantaneous"
    # channels without a default value must be given when the module flies (NaN until then)
    defaults = {name: math.nan for name in model.recorded_channels} | dict(channels or {})
    dynamics = model.dynamics(defaults)
    integrator = integrator_for(dynamics, [])
    ship = model.ship
    channel_names = {name: f"CHANNEL_{name.upper()}" for name in sorted(model.library.channels)
                     if name != "psi"}
    over_speed = [name for name in channel_names if read_over_speed(name)]
    body = _forces_body(model, channel_names)  # shared by the numpy and the compiled forces
    Minv = model.inverse_mass
    M = abkowitz_mass_matrix(ship)
    optimizer = model.optimizer.get("name", "given")
    params = model.optimizer.get("params", {}) or {}

    doc = [f'"""Simulator of an Abkowitz manoeuvring model of the ship '
           f'{_docstring_text(repr(ship.name))}.', ""]
    facts = (
        f"Generated by sindyship {__version__} from an identified model: library "
        f"{model.library.name!r} ({', '.join(f'{d} {n}' for d, n in model.n_active().items())}"
        f" active terms), optimizer {optimizer!r}"
        + (f" with {', '.join(f'{k}={v!r}' for k, v in sorted(params.items()))}"
           if params else "")
        + f", rudder signal {model.rudder_signal!r}."
    )
    doc += _wrap(_docstring_text(facts))
    doc += _provenance(model)
    if source_note:
        doc += _wrap(_docstring_text(source_note))
    doc += [
        "",
        "Equations (Deogaonkar et al., eq. 12-15; Prime I with the design speed U0): the mass",
        "matrix times (du'/dt', dv'/dt', dr'/dt') equals the hydrodynamic forces of eq. 15 plus",
        "the Coriolis terms (rigid body plus added mass, with the Munk moment).  The rudder",
        "follows its command through a first-order servo with rate and angle limits (replay",
        "prescribes the rudder angle itself, as a record's actual rudder is replayed).",
        *(["In the library's instantaneous speed form, v and r (and the channels' speeds and",
           "rates, OVER_SPEED) are taken over the instantaneous speed U = sqrt(u^2 + v^2), at",
           "least SPEED_FLOOR U0, and the forces of eq. 15 are multiplied by (U/U0)^2."]
          if instantaneous else []),
        *(_wrap(_docstring_text(_delays_note(model.library.delays)))
          if model.library.delays else []),
        "",
        "The state is [u, v, r, x, y, psi, delta] in SI units: body-fixed surge and sway [m/s]",
        "(v positive to starboard), yaw rate [rad/s], earth-fixed x north and y east [m],",
        *(_compiled.NEEDS_COMPILED if compiled else _compiled.NEEDS_PLAIN),
        "",
        "Examples",
        "--------",
        *_example_lines(model, channel_names, channels),
        '"""',
    ]

    lines = [*doc, "", "from __future__ import annotations", "", "import math",
             *(_compiled.STDLIB_IMPORTS if compiled else []),
             "from collections.abc import Callable, Mapping, Sequence",
             "from types import MappingProxyType",
             "from typing import NamedTuple",
             "",
             "import numpy as np", *(_compiled.NUMBA_IMPORT if compiled else []), ""]
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
        f"N_SHIP = {_constant(_revolutions(ship))}  # propeller revolutions [rps] (0: none given)",
        f"MAX_REVOLUTION_RATIO = {_constant(MAX_REVOLUTION_RATIO)}  # larger n is in another unit",
        f"SPEED_FORM = {_literal(model.library.speed)}  # the forces over U0 or over U",
        "#: Recorded channel -> seconds it lags the physics: read that much later when flown",
        "DELAYS = MappingProxyType({" + ", ".join(
            f"{_literal(name)}: {_constant(seconds)}"
            for name, seconds in sorted(model.library.delays.items())) + "})",
        "DELAYED_ANGLES = (" + "".join(f"{_literal(name)}, " for name in ANGLE_CHANNELS
                                       if name in model.library.delays) + ")",
        *([f"SPEED_FLOOR = {_constant(SPEED_FLOOR)}  # least U/U0 the forces are scaled with",
           "#: Channels read over the speed U (their scaling with U0 divided by U/U0)",
           "OVER_SPEED = (" + "".join(f"{_literal(name)}, " for name in over_speed) + ")"]
          if instantaneous else []),
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
        lines += ["", "# Recorded channels: default values (library scaling; NaN: give them when",
                  "# flying) and the scaling from SI, value * factor + offset"]
        for name, const in channel_names.items():
            lines.append(f"{const} = {_constant((channels or {}).get(name, math.nan))}  # {name}")
        lines.append("CHANNEL_SCALING = {")
        for name in channel_names:
            factor, offset = channel_scaling(name, ship.L, ship.U0)
            lines.append(f"    {_literal(name)}: ({_constant(factor)}, {_constant(offset)}),")
        lines.append("}")
        lines.append("CHANNEL_DEFAULTS = {" + ", ".join(
            f"{_literal(name)}: {const}" for name, const in channel_names.items()) + "}")
    else:
        lines += ["", "CHANNEL_SCALING = {}  # the library uses no recorded channel",
                  "CHANNEL_DEFAULTS = {}"]
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
    lines += ["", "#: identifier -> value of every coefficient (Prime I), read-only: forces()",
              "#: reads the named constants above (change one of those to change the model)",
              "COEFFICIENTS = MappingProxyType({"]
    lines += [f"    {_literal(ident)}: {ident}," for ident, _, _ in entries]
    lines += ["})", "#: identifier -> (degree of freedom, term as written in the library)",
              "TERMS = {"]
    lines += [f"    {_literal(ident)}: ({_literal(dof)}, {_literal(text)}),"
              for ident, dof, text in entries]
    lines += ["}", "", ""]
    lines += [
        "def forces(du, v, r, delta, psi=0.0, channels=None):",
        '    """Hydrodynamic forces (X\', Y\', N\') of paper eq. 15, Prime I.',
        "",
        "    Parameters",
        "    ----------",
        "    du, v, r : float or ndarray",
        *(["        u / U0 - 1, v / U and r L / U (U the instantaneous speed; accelerations()",
           "        multiplies these forces by (U/U0)^2)."] if instantaneous else
          ["        u / U0 - 1, v / U0 and r L / U0."]),
        "    delta : float or ndarray",
        "        Rudder angle [rad].",
        "    psi : float or ndarray",
        "        Heading [rad] (used only by heading-dependent terms).",
        "    channels : mapping, optional",
        *(["        Recorded channels in the library's scaling, those in OVER_SPEED over U",
           "        (accelerations() passes them so); the default, the CHANNEL_ constants,",
           "        holds at U = U0."] if instantaneous else
          ["        Recorded channels in the library's scaling (default: the CHANNEL_ "
           "constants)."]),
        '    """',
        *_forces_source(channel_names, body),
        "",
        "",
        "def accelerations(u, v, r, delta, psi, branch=None, channels=None):",
        '    """Accelerations (du/dt, dv/dt, dr/dt) [SI] of paper eq. 14 from SI state values.',
        "",
        "    The hydrodynamic forces of eq. 15 plus the Coriolis terms (rigid body plus added",
        "    mass, with the Munk moment), times the inverse mass matrix; ``delta`` is the rudder",
        "    angle the forces see.  Vectorised over numpy arrays.",
        '    """',
        *(_accelerations_body("forces(un - 1.0, vn / ratio, rn / ratio, delta, psi, "
                              "_over_speed(channels, ratio))", coriolis_lines,
                              "np.maximum(np.sqrt(un * un + vn * vn), SPEED_FLOOR)")
          if instantaneous else
          _accelerations_body("forces(un - 1.0, vn, rn, delta, psi, channels)",
                              coriolis_lines)),
        *(["", "", "def _over_speed(channels, ratio):",
           '    """The channels (library scaling; None: the CHANNEL_ constants) with those in',
           '    OVER_SPEED over the instantaneous speed (divided by U/U0 = ``ratio``)."""',
           "    values = CHANNEL_DEFAULTS if channels is None else channels",
           "    return {name: value / ratio if name in OVER_SPEED else value",
           "            for name, value in values.items()}"] if instantaneous else []),
    ]
    runtime, tail = RUNTIME.rstrip(), []
    if compiled:
        runtime = _compiled.compiled_runtime(runtime)
        tail = _compiled.compiled_section(
            channel_names, body,
            _accelerations_body(_compiled.forces_call(channel_names,
                                                      over_speed if instantaneous else None),
                                coriolis_lines,
                                "max(math.sqrt(un * un + vn * vn), SPEED_FLOOR)"
                                if instantaneous else None))
    # Exotic libraries (long channel names, many factors) can make a line long.
    lines, tail = ([line if len(line) <= 99 else line + "  # noqa: E501" for line in part]
                   for part in (lines, tail))
    return ("\n".join(lines) + "\n" + _kernel_source() + runtime + "\n"
            + "".join(line + "\n" for line in tail))
