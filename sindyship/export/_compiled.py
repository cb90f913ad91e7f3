"""The compiled part of a generated simulator: numba scalar loops over a batch of states.

:func:`sindyship.export.generate_python` with ``compiled=True`` appends this section to the
module.  It holds the forces and accelerations of one state as scalar functions (the same
lines as the module's numpy ``forces`` and ``accelerations``), the kernel's right-hand side
(servo and kinematics) and classical RK4 step as loops over the columns of a batch, and an
integrator class that flies them with the kernel's own step logic.  Each is compiled by
``numba.njit`` (``cache=True`` beside the module file) when numba can be imported where the
module runs; without numba the module says so in one warning and runs its numpy functions,
which give the same numbers more slowly.

Nothing here imports numba: the generated text does.
"""

from __future__ import annotations

from collections.abc import Mapping
from string import Template

#: The module docstring's sentence on what the module needs, plain and compiled.
NEEDS_PLAIN = ["heading [rad] and actual rudder angle [rad] (positive turns to starboard).  This",
               "module needs only numpy; it does not import sindyship."]
NEEDS_COMPILED = [
    "heading [rad] and actual rudder angle [rad] (positive turns to starboard).  This",
    "module needs numpy; with numba it compiles its right-hand side (COMPILED says whether",
    "it did), without numba it runs the same equations with numpy.  It does not import",
    "sindyship.",
]

#: Standard-library imports the compiled section adds, and the optional numba import.
STDLIB_IMPORTS = ["import os", "import sys", "import warnings"]
NUMBA_IMPORT = ["", "try:  # optional: compiles the right-hand side", "    import numba",
                "except ImportError:", "    numba = None"]

# Places in the runtime's text where the compiled functions take over.
_RHS_ANCHOR = ("    state = np.asarray(state, dtype=float)\n"
               "    columns = state.reshape(N_STATE, -1)\n")
_RHS_DISPATCH = ("    if COMPILED:\n"
                 "        if channels is None:\n"
                 "            out = _rhs_as_given(state, delta_c)\n"
                 "            if out is not None:\n"
                 "                return out\n"
                 "        return _compiled_rhs(state, delta_c, channels)\n")
_FLY_ANCHOR = "    integ = _Integrator(_Model(series=series), [command], _SERVO)\n"
_FLY_COMPILED = ("    flier = _CompiledIntegrator if COMPILED else _Integrator\n"
                 "    integ = flier(_Model(series=series), [command], _SERVO)\n")

_SECTION = Template('''

# ---------------------------------------------------------------------------------------------
# The compiled right-hand side (numba): the arithmetic above as scalar loops over a batch
# ---------------------------------------------------------------------------------------------
#: Whether rhs(), simulate(), replay() and zigzag() run the numba-compiled functions below;
#: without numba they run the numpy functions above, which give the same numbers more slowly.
COMPILED = numba is not None
if not COMPILED:
    warnings.warn("numba is not installed: this simulator runs its numpy right-hand side "
                  "(the same results, slower); pip install numba to compile it", stacklevel=2)
# numba keeps the compiled code beside the module file and finds the module again by its name:
# source run without a file, or a module not registered in sys.modules, compiles every time
_CACHE = (os.path.isfile(globals().get("__file__") or "")
          and getattr(sys.modules.get(__name__), "__dict__", None) is globals())
_COMMANDED = RUDDER_INPUT == "commanded"
_T_SERVO = max(T_SERVO, 1e-9)  # as the kernel's integrator holds it
_CHANNEL_NAMES = tuple(CHANNEL_SCALING)
#: Default channel values (library scaling), one row per channel, shared by every state.
_CHANNEL_DEFAULTS = np.array([$defaults], dtype=float).reshape(len(_CHANNEL_NAMES), 1)


def _jit(function):
    """``function`` compiled by numba (nopython, cached beside the module) when numba is there."""
    return numba.njit(cache=_CACHE)(function) if COMPILED else function


@_jit
def _forces_one(du, v, r, delta, psi$params):
    """Forces (X', Y', N') of eq. 15 for one state (floats), as ``forces``."""
$forces


@_jit
def _accelerations_one(u, v, r, delta, psi$params):
    """Accelerations (du/dt, dv/dt, dr/dt) [SI] of eq. 14 for one state, as ``accelerations``."""
$accelerations


@_jit
def _rhs_columns(y, delta_c, channels, out):
    """d(state)/dt of the columns of ``y`` (7, k) into ``out``, as the kernel's
    ``_Integrator.rhs``: ``delta_c`` holds k commands or one for all, the rows of
    ``channels`` (library scaling) k values or one for all."""
    one_command = delta_c.shape[0] == 1
$one_channel    for j in range(y.shape[1]):
        command = delta_c[0] if one_command else delta_c[j]
$column        u = y[0, j]
        v = y[1, j]
        r = y[2, j]
        psi = y[5, j]
        delta = y[6, j]
        rudder = command if _COMMANDED else delta
        target = np.minimum(np.maximum(command, -DELTA_MAX), DELTA_MAX)
        rate = np.minimum(np.maximum((target - delta) / _T_SERVO, -RATE_MAX), RATE_MAX)
        a_u, a_v, a_r = _accelerations_one(u, v, r, rudder, psi$arguments)
        cos_psi = np.cos(psi)
        sin_psi = np.sin(psi)
        out[0, j] = a_u
        out[1, j] = a_v
        out[2, j] = a_r
        out[3, j] = u * cos_psi - v * sin_psi
        out[4, j] = u * sin_psi + v * cos_psi
        out[5, j] = r
        out[6, j] = rate


@_jit
def _rk4_columns(y, h, delta_c, channels, k1):
    """End of one classical RK4 step of length ``h`` from ``y`` (7, k) with the derivative
    ``k1`` at its start, as the kernel's ``_Integrator.step`` (the same operations in the
    same order)."""
    stage = np.empty_like(y)
    k2 = np.empty_like(y)
    k3 = np.empty_like(y)
    k4 = np.empty_like(y)
    half = 0.5 * h
    for i in range(N_STATE):
        for j in range(y.shape[1]):
            stage[i, j] = y[i, j] + half * k1[i, j]
    _rhs_columns(stage, delta_c, channels, k2)
    for i in range(N_STATE):
        for j in range(y.shape[1]):
            stage[i, j] = y[i, j] + half * k2[i, j]
    _rhs_columns(stage, delta_c, channels, k3)
    for i in range(N_STATE):
        for j in range(y.shape[1]):
            stage[i, j] = y[i, j] + h * k3[i, j]
    _rhs_columns(stage, delta_c, channels, k4)
    sixth = h / 6.0
    end = np.empty_like(y)
    for i in range(N_STATE):
        for j in range(y.shape[1]):
            end[i, j] = y[i, j] + sixth * (k1[i, j] + 2.0 * k2[i, j] + 2.0 * k3[i, j]
                                           + k4[i, j])
    return end


@_jit
def _rhs_commands(y, commands, out):
    """``_rhs_columns`` of a batch ``y`` (7, k) with the default channels into ``out``; False
    (nothing done) unless ``commands`` holds one command or k."""
    if y.shape[0] != N_STATE or (commands.shape[0] != 1 and commands.shape[0] != y.shape[1]):
        return False
    _rhs_columns(y, commands, _CHANNEL_DEFAULTS, out)
    return True


@_jit
def _rhs_one_command(y, command, out):
    """``_rhs_commands`` with one command for every column."""
    return _rhs_commands(y, np.full(1, command), out)


@_jit
def _rhs_one_state(y, command, out):
    """``_rhs_commands`` of one state ``y`` (7,) and its command into ``out`` (7,); False
    (nothing done) unless ``y`` has 7 values."""
    if y.shape[0] != N_STATE:
        return False
    column = np.empty((N_STATE, 1))
    column[:, 0] = y
    result = np.empty((N_STATE, 1))
    _rhs_one_command(column, command, result)
    out[:] = result[:, 0]
    return True


_ARRAY = np.ndarray
_FLOAT64 = np.dtype(np.float64)
_SCALARS = (float, np.float64)


def _rhs_as_given(state, delta_c):
    """``rhs`` with the default channels for arguments that need no conversion (a float64
    state of shape (7,) or (7, k), a float command or a float64 array of one or k), straight
    into the compiled loop; None for any other arguments (``_compiled_rhs`` converts them).
    The output array is made here: an array made by compiled code costs more to return."""
    if type(state) is not _ARRAY or state.dtype is not _FLOAT64:
        return None
    out = np.empty_like(state)
    if state.ndim == 2:
        if type(delta_c) is _ARRAY:
            if delta_c.dtype is _FLOAT64 and delta_c.ndim == 1 and _rhs_commands(state,
                                                                                delta_c, out):
                return out
        elif type(delta_c) in _SCALARS and _rhs_one_command(state, delta_c, out):
            return out
    elif state.ndim == 1 and type(delta_c) in _SCALARS and _rhs_one_state(state, delta_c,
                                                                            out):
        return out
    return None


def _channel_block(values, k):
    """Channel values (library scaling) as rows of ``k`` values, or of one for all states."""
    rows = [np.ravel(np.asarray(values[name], dtype=float)) for name in _CHANNEL_NAMES]
    width = k if any(row.size != 1 for row in rows) else 1
    block = [np.broadcast_to(row, (width,)) for row in rows]
    return np.array(block, dtype=float).reshape(len(_CHANNEL_NAMES), width)


def _compiled_rhs(state, delta_c, channels):
    """``rhs`` through the compiled loop (arguments as there)."""
    state = np.ascontiguousarray(state, dtype=float)
    columns = state.reshape(N_STATE, -1)
    commands = np.ascontiguousarray(delta_c, dtype=float).reshape(-1)
    if commands.shape[0] != 1 and commands.shape[0] != columns.shape[1]:
        raise ValueError(f"delta_c has {commands.shape[0]} values; give one, or one per state "
                         f"({columns.shape[1]})")
    if channels is None:
        block = _CHANNEL_DEFAULTS
    else:
        block = _channel_block(_scaled(channels), columns.shape[1])
    out = np.empty_like(columns)
    _rhs_columns(columns, commands, block, out)
    return out.reshape(state.shape)


class _CompiledIntegrator(_Integrator):
    """The kernel's integrator with the compiled right-hand side and RK4 step: the step
    logic (splitting, events, Hermite outputs) is the kernel's, the arithmetic compiled."""

    def _channels(self, t, members):
        model = self.dynamics
        if model.series is not None:
            return _channel_block(model.series.at(t, members), len(members))
        if model.values is not None:
            return _channel_block(model.values, len(members))
        return _CHANNEL_DEFAULTS

    def rhs(self, t, y, delta_c, members, branch, rate_time=None):
        y = np.ascontiguousarray(y, dtype=float)
        out = np.empty_like(y)
        _rhs_columns(y, np.ascontiguousarray(delta_c, dtype=float),
                     self._channels(t, members), out)
        if self.any_prescribed:  # a prescribed rudder moves at its own rate, not the servo's
            for j, m in enumerate(members):
                if self.prescribed[m]:
                    out[6, j] = self.commands[m].rate(t if rate_time is None else rate_time)
        return out

    def step(self, t, y, h, delta_c, members, branch, f0=None):
        if self.any_prescribed or self.dynamics.series is not None:
            # recorded channels change inside the step: the kernel's step, compiled rhs
            return super().step(t, y, h, delta_c, members, branch, f0=f0)
        k1 = self.rhs(t, y, delta_c, members, branch) if f0 is None else f0
        end = _rk4_columns(np.ascontiguousarray(y, dtype=float), float(h),
                           np.ascontiguousarray(delta_c, dtype=float),
                           self._channels(t, members), np.ascontiguousarray(k1, dtype=float))
        return end, k1
''')


def compiled_runtime(runtime: str) -> str:
    """The runtime's text with ``rhs`` and the flights going through the compiled functions
    when ``COMPILED``."""
    for anchor in (_RHS_ANCHOR, _FLY_ANCHOR):
        if runtime.count(anchor) != 1:
            raise AssertionError(f"the runtime lost the line {anchor.strip()!r}")
    runtime = runtime.replace(_RHS_ANCHOR, _RHS_DISPATCH + _RHS_ANCHOR)
    return runtime.replace(_FLY_ANCHOR, _FLY_COMPILED)


def compiled_section(channel_names: Mapping[str, str], forces_body: list[str],
                     accelerations_body: list[str]) -> list[str]:
    """Lines of the compiled section of a generated simulator.

    Parameters
    ----------
    channel_names : mapping
        Channel name -> name of its default-value constant in the module, in the order of
        ``CHANNEL_SCALING``.
    forces_body : list of str
        Lines computing ``X, Y, N`` from ``du, v, r, delta, psi`` and ``ch_<channel>`` and
        returning them (as in the module's ``forces``).
    accelerations_body : list of str
        Lines of eq. 14 from ``u, v, r, delta, psi`` that call ``_forces_one`` (as in the
        module's ``accelerations``).

    Returns
    -------
    list of str
    """
    params = "".join(f", ch_{name}" for name in channel_names)
    arguments = "".join(f", channels[{k}, c]" for k in range(len(channel_names)))
    text = _SECTION.substitute(
        defaults=", ".join(channel_names.values()),
        params=params,
        arguments=arguments,
        forces="\n".join(forces_body),
        accelerations="\n".join(accelerations_body),
        one_channel="    one_channel = channels.shape[1] == 1\n" if channel_names else "",
        column="        c = 0 if one_channel else j\n" if channel_names else "",
    )
    return text.splitlines()


def forces_call(channel_names: Mapping[str, str], over_speed=None) -> str:
    """The call of ``_forces_one`` in ``_accelerations_one``; with ``over_speed`` (the
    instantaneous speed form: the channels read over the speed) v, r and those channels
    divided by ``ratio``, U/U0."""
    if over_speed is None:
        return "_forces_one(un - 1.0, vn, rn, delta, psi{})".format(
            "".join(f", ch_{name}" for name in channel_names))
    return "_forces_one(un - 1.0, vn / ratio, rn / ratio, delta, psi{})".format(
        "".join(f", ch_{name} / ratio" if name in over_speed else f", ch_{name}"
                for name in channel_names))
