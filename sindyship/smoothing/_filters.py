"""The Savitzky-Golay filter of a record (the smoother ``savgol``)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import SindyshipInputError
from ..targets import savgol_points
from ..trajectory import Trajectory
from ._settings import _UNIFORM_TOLERANCE, SAVGOL_CHANNELS, SmoothingSetting


def _uniform_dt(record: Trajectory, what: str) -> float:
    t = record.t
    steps = np.diff(t)
    dt = float(np.median(steps))
    if not (dt > 0) or np.max(np.abs(steps - dt)) > _UNIFORM_TOLERANCE * dt:
        raise SindyshipInputError(
            f"{record.name or 'the record'}: {what} needs uniform sampling but the time step "
            f"varies from {steps.min():.6g} s to {steps.max():.6g} s; resample the record "
            "(--resample DT) or use method 'rts'."
        )
    return dt


def _savgol_record(record: Trajectory, setting: SmoothingSetting,
                   channels: Sequence[str] | None) -> Trajectory:
    from scipy.signal import savgol_filter

    name = record.name or "the record"
    dt = _uniform_dt(record, "Savitzky-Golay smoothing")
    points = savgol_points(setting.window, dt, setting.order, record.n_samples,
                           f"{name}: smoothing")
    data = record.data.copy()
    for column in SAVGOL_CHANNELS if channels is None else channels:
        if column == "t":
            raise SindyshipInputError("time cannot be smoothed; leave 't' out of channels.")
        if column not in data.columns:
            raise SindyshipInputError(f"{name}: there is no channel {column!r} to smooth.")
        values = data[column].to_numpy(dtype=float)
        if not np.all(np.isfinite(values)):
            raise SindyshipInputError(
                f"{name}: channel {column!r} has missing or infinite samples; the "
                "Savitzky-Golay filter needs every sample (use method 'rts')."
            )
        data[column] = savgol_filter(values, points, setting.order, mode="interp")
    meta = {**record.meta, "smoothing": {**setting.as_dict(), "points": points}}
    return Trajectory(data, name=record.name, meta=meta)
