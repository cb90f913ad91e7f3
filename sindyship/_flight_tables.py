"""The tables the compiled flights (:mod:`sindyship._flights_compiled`) read: rudder commands
and identified models as flat arrays, each member's and each model's rows one after the
other.

The loop reads them as tuples, by position:

- commands (:func:`command_form`): ``(kind, start, times, angles, rates, param, level_start,
  levels)``: member m's kind (:data:`CONSTANT` ...), its steps' or samples' times, angles and
  slopes in ``[start[m], start[m + 1])``, ``param[m]`` = (angle or amplitude, check angle),
  a recorded zig-zag's leg angles in ``[level_start[m], level_start[m + 1])``;
- models (:func:`model_tables`): ``(extra_start, extra_kind, extra_source, extra_value,
  base_start, base_variable, base_function, factor_start, factor_base, factor_power,
  term_start, slots, weights, inertia, inverse_mass, U0, L, instantaneous, extra_over_speed,
  speed_floor)``: model p's variables beyond the state's, factor bases, factors and terms in
  ``[x_start[p], x_start[p + 1])``, as :func:`sindyship._forces_compiled.tables` gives them
  for one model; whether model p is in the instantaneous-speed form, and whether it reads
  each variable beyond the state's over the speed (:func:`sindyship.terms.read_over_speed`);
  the least speed ratio U/U0 of that form (:data:`sindyship.library.SPEED_FLOOR`);
- channels: ``(times, values)``, the recorded channels' rows (name, member, sample).
"""

from __future__ import annotations

import numpy as np

from ._forces_compiled import N_STATE_VARIABLES
from .library import SPEED_FLOOR
from .simulation import (
    ConstantCommand,
    PrescribedRudder,
    RecordedZigZag,
    StepCommand,
    ZigZagCommand,
)
from .terms import read_over_speed

#: Rudder commands the loop flies (any other kind is flown by the kernel).
CONSTANT, STEP, ZIGZAG, PRESCRIBED = range(4)
#: Where a variable beyond the state's comes from.
ZERO, SERIES, FIXED, POSITION_X, POSITION_Y, RUDDER_RATE = range(6)


def command_form(commands):
    """The commands as the loop's arrays, or None when one has no form in it (a feedback
    command, a subclass, a step command without steps, a replay of fewer than two samples)."""
    n = len(commands)
    kind = np.empty(n, dtype=np.int64)
    param = np.zeros((n, 2))
    start, level_start = [0], [0]
    times, angles, rates, levels = [], [], [], []
    for m, cmd in enumerate(commands):
        form = type(cmd)
        if form is ConstantCommand:
            kind[m], param[m, 0] = CONSTANT, float(cmd.angle)
        elif form in (ZigZagCommand, RecordedZigZag):
            kind[m], param[m] = ZIGZAG, (float(cmd.rudder), float(cmd.check))
            levels.extend(float(x) for x in getattr(cmd, "levels", ()))
        elif form is StepCommand and len(cmd.times):
            kind[m] = STEP
            times.append(cmd.times), angles.append(cmd.angles), rates.append(cmd.angles * 0.0)
        elif form is PrescribedRudder and len(cmd.times) >= 2:
            kind[m] = PRESCRIBED
            times.append(cmd.times), angles.append(cmd.angles)
            rates.append(np.append(cmd._rate, np.nan))
        else:
            return None
        start.append(start[-1] + (len(times[-1]) if kind[m] in (STEP, PRESCRIBED) else 0))
        level_start.append(len(levels))
    joined = [np.concatenate(a).astype(float) if a else np.zeros(1)
              for a in (times, angles, rates)]
    return (kind, np.array(start, dtype=np.int64), *joined, param,
            np.array(level_start, dtype=np.int64), np.array(levels + [0.0]))


def model_tables(parts, integ, n_members, L, U0):
    """The models' factor tables and variables, one after the other, and the recorded
    channels (each name one row, its members' values), or None when one has no form."""
    extra_kind, extra_source, extra_value, extra_start = [], [], [], [0]
    base_variable, base_function, base_start = [], [], [0]
    factor_base, factor_power, factor_start = [], [], [0]
    slot_tables, weights, term_start = [], [], [0]
    inertia, minv, rows, series_times = [], [], {}, None
    instantaneous, extra_over_speed = [], []
    for dynamics, start, stop in parts:
        model = getattr(dynamics, "model", None)
        if not getattr(model, "_compiled_flights", False) or model.ship.L != L \
                or model.ship.U0 != U0:
            return None
        names, (b_variable, b_function, f_base, f_power, term_slots) = model._compiled
        over_speed = model.library.speed == "instantaneous"
        instantaneous.append(over_speed)
        series = dynamics.series
        if series is not None:
            if series_times is not None and not np.array_equal(series.times, series_times):
                return None
            series_times = series.times
        for name in names[N_STATE_VARIABLES:]:
            kind, value = _variable_form(name, dynamics, integ)
            if kind is None:
                return None
            if kind == SERIES:  # the kernel reads the series' first rows, one per member
                if series.values[name].shape[0] < stop - start:
                    return None
                rows.setdefault(name, []).append((series.values[name][: stop - start], start,
                                                  stop))
            extra_kind.append(kind)
            extra_source.append(list(rows).index(name) if kind == SERIES else 0)
            extra_value.append(value)
            extra_over_speed.append(over_speed and read_over_speed(name))
        extra_start.append(len(extra_kind))
        base_variable.extend(b_variable), base_function.extend(b_function)
        base_start.append(len(base_variable))
        factor_base.extend(f_base), factor_power.extend(f_power)
        factor_start.append(len(factor_base))
        slot_tables.append((term_slots, len(f_base))), weights.append(model._weights)
        term_start.append(term_start[-1] + term_slots.shape[1])
        inertia.append(model._inertia), minv.append(model.inverse_mass)
    # each term's factors; a model whose terms have fewer factors than another's fills the
    # rest with its factor of one (its last)
    width = max(s.shape[0] for s, _ in slot_tables)
    slots = np.zeros((width, term_start[-1]), dtype=np.int64)
    for (s, one), first, last in zip(slot_tables, term_start[:-1], term_start[1:],
                                     strict=True):
        slots[:, first:last] = one
        slots[: s.shape[0], first:last] = s
    n_times = 1 if series_times is None else len(series_times)
    values = np.zeros((max(len(rows), 1), n_members, n_times))
    for row, pieces in enumerate(rows.values()):
        for piece, start, stop in pieces:
            values[row, start:stop] = piece
    as_int = [np.asarray(a, dtype=np.int64) for a in (
        extra_start, extra_kind, extra_source)]
    models = (*as_int, np.asarray(extra_value, dtype=float),
              np.asarray(base_start, dtype=np.int64), np.asarray(base_variable, dtype=np.int64),
              np.asarray(base_function, dtype=np.int64),
              np.asarray(factor_start, dtype=np.int64), np.asarray(factor_base, dtype=np.int64),
              np.asarray(factor_power, dtype=np.int64), np.asarray(term_start, dtype=np.int64),
              slots, np.ascontiguousarray(np.concatenate(weights, axis=1), dtype=float),
              np.array(inertia, dtype=float), np.array(minv, dtype=float), float(U0), float(L),
              np.asarray(instantaneous, dtype=np.int64),
              np.asarray(extra_over_speed + [False], dtype=np.int64), float(SPEED_FLOOR))
    channels = (np.zeros(1) if series_times is None else np.array(series_times, dtype=float),
                values)
    n_variables = N_STATE_VARIABLES + max(np.diff(extra_start), default=0)
    work = (np.empty(n_variables), np.empty(max(max(np.diff(base_start), default=0), 1)),
            np.ones(max(np.diff(factor_start), default=0) + 1), np.empty(3))
    return models, channels, work


def _variable_form(name, dynamics, integ):
    """Where the loop takes a variable beyond the state's from, as the kernel's dynamics
    would (:func:`sindyship._forces_compiled.run_accelerations`): ``(kind, fixed value)``,
    kind None for a variable the loop has no form for (a shape, one the dynamics refuse)."""
    if dynamics.series is not None and name in dynamics.series.values:
        return SERIES, 0.0
    if name in dynamics.channels:
        return FIXED, float(dynamics.channels[name])
    if name in ("x", "y"):
        return ((POSITION_X if name == "x" else POSITION_Y) if integ.uses_position
                else ZERO), 0.0
    if name == "delta_rate":
        return (RUDDER_RATE if integ.uses_rudder_rate else ZERO), 0.0
    return None, 0.0
