"""The runtime of a generated simulator (:func:`sindyship.export.generate_python`): the
model as the kernel flies it and the public functions, as source text appended to the
generated module after its constants and forces."""

RUNTIME = '''

# ---------------------------------------------------------------------------------------------
# The model as the kernel flies it, and the public functions
# ---------------------------------------------------------------------------------------------
class _Model:
    \"\"\"The generated dynamics in the form the kernel's integrator flies: recorded channels
    as time series (``series``, one row per flight) or values (``values``), library scaling.\"\"\"

    rudder_input = RUDDER_INPUT
    current = (0.0, 0.0)
    switching = None

    def __init__(self, series=None, values=None):
        self.series = series
        self.values = values
        self.time_varying = series is not None

    def accelerations(self, u, v, r, delta, psi, branch=None, t=None, members=None):
        channels = self.values if self.series is None else self.series.at(t, members)
        return accelerations(u, v, r, delta, psi, branch, channels)


def _scaled(channels):
    \"\"\"Channels given in SI (as in the measurement CSV) in the library's scaling; None
    keeps the CHANNEL_ constants, which must then have values.\"\"\"
    if channels is None:
        unset = sorted(name for name, value in CHANNEL_DEFAULTS.items() if math.isnan(value))
        if unset:
            raise ValueError(f"give the channel {unset[0]!r} (channels=...): the model's "
                             "library uses it, and it was exported without a value")
        return None
    missing = sorted(set(CHANNEL_SCALING) - set(channels))
    if missing:
        raise ValueError(f"give the channel {missing[0]!r} (the model's library uses it)")
    unknown = sorted(set(channels) - set(CHANNEL_SCALING))
    if unknown:
        used = ", ".join(sorted(CHANNEL_SCALING)) or "none"
        raise ValueError(f"the model's library uses no channel {unknown[0]!r} (it uses: "
                         f"{used}); check the name")
    if "n" in channels and N_SHIP > 0.0:
        largest = float(np.max(np.abs(np.asarray(channels["n"], dtype=float)), initial=0.0))
        if largest > MAX_REVOLUTION_RATIO * N_SHIP:
            raise ValueError(f"channel 'n' reaches {largest:g}, {largest / N_SHIP:.3g} times "
                             f"the ship's propeller revolutions {N_SHIP:g} rps; give n in rps "
                             "(rpm divided by 60)")
    return {name: np.asarray(channels[name], dtype=float) * factor + offset
            for name, (factor, offset) in CHANNEL_SCALING.items()}


def _read_late(t, channels):
    \"\"\"Recorded channels over ``t`` as the forces read them: a channel the library delays
    (``DELAYS``: it lags the physics by that many seconds; a negative delay leads it) read
    that much later, held at its first or last value beyond the record's ends, angles
    unwrapped first (as sindyship's evaluate reads a record).  Constants and channels not
    delayed are returned as given.\"\"\"
    if channels is None or not DELAYS:
        return channels
    out = dict(channels)
    for name, seconds in DELAYS.items():
        if name in out and np.ndim(out[name]):
            values = np.asarray(out[name], dtype=float)
            angle = name in DELAYED_ANGLES and np.all(np.isfinite(values))
            moved = np.interp(t + seconds, t, np.unwrap(values) if angle else values)
            out[name] = np.mod(moved, 2.0 * math.pi) if name == "wind_dir" else moved
    return out


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
        Commanded rudder angle held at each output time [rad] (of ``replay``: the angle
        replayed).
    diverged_at : float or None
        Time of the first output sample where the state left the plausible range.
    \"\"\"

    t: np.ndarray
    states: np.ndarray
    delta_c: np.ndarray
    diverged_at: float | None


def rhs(t, state, delta_c, channels=None):
    \"\"\"Time derivative of the state (paper eq. 12-14 and the kinematics).

    Parameters
    ----------
    t : float
        Time [s] (the model is time invariant).
    state : array_like, shape (7,) or (7, N)
        ``[u, v, r, x, y, psi, delta]`` (SI).
    delta_c : float or ndarray of shape (N,)
        Commanded rudder angle [rad].
    channels : mapping of str to float or ndarray of shape (N,), optional
        The recorded channels the library uses, SI as in the measurement CSV (default: the
        CHANNEL_ constants), at the physics' time: a channel in ``DELAYS`` as recorded that
        many seconds after ``t``.

    Returns
    -------
    ndarray
        d(state)/dt, the shape of ``state``.
    \"\"\"
    if np.ndim(state) not in (1, 2) or np.shape(state)[0] != N_STATE:
        raise ValueError(f"state has shape {np.shape(state)}; give the {N_STATE} values "
                         "[u, v, r, x, y, psi, delta] (SI), or one column of them per state")
    state = np.asarray(state, dtype=float)
    columns = state.reshape(N_STATE, -1)
    commands = np.broadcast_to(np.asarray(delta_c, dtype=float), columns.shape[1]).copy()
    members = np.arange(columns.shape[1])
    model = _Model(values=_scaled(channels))
    out = _Integrator(model, [], _SERVO).rhs(t, columns, commands, members, None)
    return out.reshape(state.shape)


def _fly(command, t, state0, step, check_divergence, channels):
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.size == 0:
        raise ValueError("t must be a one-dimensional array of output times")
    if t.size > 1 and np.any(np.diff(t) <= 0):
        raise ValueError("output times must increase")
    y = np.array([U0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0] if state0 is None else state0,
                 dtype=float)
    if y.shape != (N_STATE,) or not np.all(np.isfinite(y)):
        raise ValueError(f"state0 has shape {y.shape}; give {N_STATE} finite values "
                         "[u, v, r, x, y, psi, delta] (SI)")
    h_max = DEFAULT_STEP if step is None else float(step)
    scaled = _scaled(channels)  # first: a name the library does not use
    for name, values in (channels or {}).items():
        if np.ndim(values) and np.shape(values) != t.shape:
            raise ValueError(f"channel {name!r} has shape {np.shape(values)}; give one value "
                             f"per output time {t.shape}, or a constant")
    if DELAYS and scaled is not None:
        scaled = _scaled(_read_late(t, channels))
    series = None if scaled is None else ChannelSeries(t, {
        name: np.broadcast_to(values, t.shape)[None, :] for name, values in scaled.items()})
    integ = _Integrator(_Model(series=series), [command], _SERVO)
    (result,) = integrate(integ, [command], t, y, h_max, check_divergence, L, U0)
    return Flight(result.t, result.states, result.delta_c, result.diverged_at)


def simulate(t, delta_c, state0=None, channels=None, *, step=None, check_divergence=True):
    \"\"\"Fly the model with a commanded rudder through the servo (paper eq. 12-14).

    Parameters
    ----------
    t : array_like, shape (N,)
        Increasing output times [s]; the first is the initial time.
    delta_c : float, array_like of shape (N,), or callable
        Commanded rudder angle [rad]: one value per output time, held until the next
        sample where it changes (zero-order hold; read ``DELAYS["delta_c"]`` seconds later
        where the library delays it, as recorded); a constant; or a function
        ``f(t, state) -> angle`` evaluated at the start of every integration step and held
        over it (feedback control).
    state0 : array_like, shape (7,), optional
        Initial ``[u, v, r, x, y, psi, delta]`` (SI); default straight ahead at U0.
    channels : mapping of str to array_like of shape (N,), optional
        The recorded channels the library uses, over ``t``, SI as in the measurement CSV,
        interpolated at the integrator's stage times (default: the CHANNEL_ constants); a
        channel in ``DELAYS`` is read that many seconds later, as recorded.
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
        return _fly(FeedbackCommand(delta_c), t, state0, step, check_divergence, channels)
    angles = _read_late(t, {"delta_c": _angles("delta_c", delta_c, t)})["delta_c"]
    return _fly(StepCommand(t, angles), t, state0, step, check_divergence, channels)


def replay(t, delta, state0=None, channels=None, *, step=None, check_divergence=True):
    \"\"\"Fly the model with its rudder angle prescribed, bypassing the servo: a record's
    actual rudder angle replayed, as sindyship evaluate flies a record that holds no commanded
    rudder (a turn from its execute).

    Parameters
    ----------
    t : array_like, shape (N,)
        Increasing output times [s]; the first is the initial time.
    delta : float or array_like of shape (N,)
        Rudder angle [rad], one value per output time, linear between them (read
        ``DELAYS["delta"]`` seconds later where the library delays it, as recorded); or a
        constant.  Replayed as given, also beyond the rudder limit ``DELTA_MAX``.
    state0 : array_like, shape (7,), optional
        Initial ``[u, v, r, x, y, psi, delta]`` (SI); default straight ahead at U0.  Its
        rudder angle is the replayed one at ``t[0]``, whatever it holds.
    channels, step, check_divergence
        As for ``simulate``.

    Returns
    -------
    Flight
        Its ``delta_c`` holds the replayed angle at each output time.

    Raises
    ------
    ValueError
        For a ``delta`` that is a function (``simulate`` takes one, as a commanded rudder),
        not one finite angle per output time, or beyond a quarter turn (degrees).
    \"\"\"
    if callable(delta):
        raise ValueError("replay takes the rudder angle as an array over t or a constant, not "
                         "a function; simulate takes a function f(t, state) as the command")
    t = np.asarray(t, dtype=float)
    angles = _read_late(t, {"delta": _angles("delta", delta, t)})["delta"]
    flight = _fly(PrescribedRudder(t, angles), t, state0, step, check_divergence, channels)
    flown = np.isfinite(flight.states[6])  # the angle at each output time, none after divergence
    return flight._replace(delta_c=np.where(flown, angles, np.nan))


def _angles(name, values, t):
    \"\"\"Rudder angles [rad], one per output time (a constant repeated), checked.\"\"\"
    angles = np.asarray(values, dtype=float)
    if angles.ndim == 0:
        angles = np.full(t.shape, float(angles))
    if angles.shape != t.shape:
        raise ValueError(
            f"{name} has shape {angles.shape}; give one angle per output time {t.shape}"
        )
    if not np.all(np.isfinite(angles)):
        raise ValueError(f"{name} must be finite")
    if np.max(np.abs(angles), initial=0.0) > 0.5 * math.pi:
        raise ValueError(f"{name} reaches {np.max(np.abs(angles)):g} rad, more than a quarter "
                         "turn: give the rudder angle in radians (np.radians(degrees))")
    return angles


def zigzag(t, rudder_deg, check_deg, state0=None, first_sign=1, channels=None, *, step=None,
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
    channels : mapping of str to array_like of shape (N,), optional
        As for ``simulate``.

    step, check_divergence
        As for ``simulate``.

    Returns
    -------
    Flight

    Raises
    ------
    ValueError
        For a rudder angle outside 1 deg to the rudder limit ``DELTA_MAX``, a check angle
        outside 1 to 180 deg, or a first side other than +1 and -1.
    \"\"\"
    if first_sign not in (1, -1):
        raise ValueError(f"first_sign is {first_sign!r}; give +1 (first rudder to starboard) "
                         "or -1 (to port)")
    limit = math.degrees(DELTA_MAX)
    for name, angle, most in (("rudder_deg", rudder_deg, limit), ("check_deg", check_deg, 180.0)):
        if not (math.isfinite(angle) and 1.0 <= angle <= most):
            raise ValueError(f"{name} is {angle!r}; give 1 to {most:g} degrees (zigzag takes "
                             "degrees, simulate radians; the rudder stops at DELTA_MAX)")
    command = ZigZagCommand(math.radians(rudder_deg), math.radians(check_deg), first_sign)
    return _fly(command, t, state0, step, check_divergence, channels)
'''
