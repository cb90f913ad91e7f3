"""Which speed form the records need: the speed range they span, and the force error of the
library made non-dimensional with the design speed and with the instantaneous speed, each
leaving one manoeuvre out (:attr:`sindyship.library.TermLibrary.speed`)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ..identify import design
from ..library import DOFS, TermLibrary
from ..optimizers import GroupedProblem
from ..ships import Ship
from ..trajectory import Trajectory

__all__ = ["RANGE_MARGIN", "SPEED_FORM_GAIN", "SpeedForms", "speed_forms"]

#: The other speed form is recommended when it leaves this much less of the force error
#: (leave-one-manoeuvre-out, summed over X, Y and N).
SPEED_FORM_GAIN = 0.9
#: How far (as a share of U0) the held-out records' speeds may leave the training records'
#: range before the report says the choice was made on other speeds.
RANGE_MARGIN = 0.05


@dataclass(frozen=True)
class SpeedForms:
    """The records' speed range and both forms' force errors.

    Attributes
    ----------
    form : str
        The library's speed form.
    low, high : float
        The least and largest speed U/U0 of the records (U = sqrt(u^2 + v^2)).
    errors : dict of str to float
        Per form: the leave-one-manoeuvre-out force error of least squares, its sum of
        squares over the forces' summed over X, Y and N.
    recommended : str
        The form to fit with: the other one when it leaves at most :data:`SPEED_FORM_GAIN`
        times the error, else the library's.
    held_out : (float, float) or None
        The least and largest speed U/U0 of the held-out records (None without them): the
        choice is made on the training records, and the report says when the held-out ones
        leave their range by more than :data:`RANGE_MARGIN`.
    """

    form: str
    low: float
    high: float
    errors: dict
    recommended: str
    held_out: tuple[float, float] | None = None

    def to_json(self) -> dict:
        return {"form": self.form, "range": [self.low, self.high], "errors": dict(self.errors),
                "recommended": self.recommended,
                "held_out_range": None if self.held_out is None else list(self.held_out)}

    @property
    def held_out_outside(self) -> bool:
        """Whether the held-out records reach speeds outside the training records' range (by
        more than :data:`RANGE_MARGIN` of U0)."""
        return self.held_out is not None and (self.held_out[0] < self.low - RANGE_MARGIN
                                              or self.held_out[1] > self.high + RANGE_MARGIN)

    def text(self) -> str:
        """One sentence for the report."""
        other = "instantaneous" if self.form == "design" else "design"
        ratio = self.errors[other] / max(self.errors[self.form], 1e-300)
        span = f"the records span U/U0 {self.low:.2f} to {self.high:.2f}"
        if self.recommended == self.form:
            text = (f"Speed form: {self.form} (the forces over {_speed(self.form)}); {span}, "
                    f"and on manoeuvres left out the {other} form's force error is "
                    f"{_times(ratio)} times the {self.form} form's (a change needs "
                    f"{SPEED_FORM_GAIN:g} or less): keep the {self.form} form.")
        else:
            text = (f"Speed form: {self.form}; {span}, and on manoeuvres left out the {other} "
                    f"form's force error (forces over {_speed(other)}) is {_times(ratio)} times "
                    f"the {self.form} form's: fit with --speed {other}.")
        if self.held_out_outside:
            low, high = self.held_out
            text += (f" But the held-out records span U/U0 {low:.2f} to {high:.2f}, outside "
                     "the range this was judged on: " + (
                         "the design form reaches speeds its records never saw through its "
                         "du terms, the instantaneous form scales the forces with the speed "
                         "(fit both and judge them on the held-out records)."
                         if self.recommended == "design" else
                         "judge the fit on the held-out records."))
        return text


def _times(ratio: float) -> str:
    """A ratio of force errors to two decimals, or to as many as tell it from
    :data:`SPEED_FORM_GAIN` (0.9004 is not printed as a 0.90 that the gain would accept)."""
    for digits in range(2, 7):
        text = f"{ratio:.{digits}f}"
        if (float(text) <= SPEED_FORM_GAIN) == (ratio <= SPEED_FORM_GAIN):
            return text
    return f"{ratio:.6f}"


def _speed(form: str) -> str:
    return "U0" if form == "design" else "U = sqrt(u^2 + v^2), times (U/U0)^2"


def speed_forms(records: Sequence[Trajectory], ship: Ship, library: TermLibrary,
                settings: Mapping, test: Sequence[Trajectory] = ()) -> SpeedForms:
    """The records' speed range and the force error of both speed forms of ``library``.

    Parameters
    ----------
    records : sequence of Trajectory
        The training records as fitted.
    ship, library
    settings : mapping
        ``rudder_signal``, ``derivative`` and ``window`` of :func:`sindyship.identify.fit`.
    test : sequence of Trajectory
        The held-out records, whose speed range the report compares (never the choice).
    """
    low, high = _speed_range(records, ship)
    errors = {}
    for form in ("design", "instantaneous"):
        problems = design(records, ship, library.with_speed(form), **settings)
        total = 0.0
        for dof in DOFS:
            problem = problems[dof]
            grouped = GroupedProblem(problem.features, problem.target, problem.groups)
            residual = grouped.lomo_errors(np.arange(problem.features.shape[1]))
            total += float(residual @ residual) / max(float(problem.target @ problem.target),
                                                      1e-300)
        errors[form] = total
    other = "instantaneous" if library.speed == "design" else "design"
    recommended = other if errors[other] <= SPEED_FORM_GAIN * errors[library.speed] \
        else library.speed
    return SpeedForms(library.speed, low, high, errors, recommended,
                      _speed_range(test, ship) if test else None)


def _speed_range(records: Sequence[Trajectory], ship: Ship) -> tuple[float, float]:
    """The least and largest speed U/U0 (U = sqrt(u^2 + v^2)) over the records."""
    speeds = np.concatenate([np.hypot(r["u"], r["v"]) for r in records]) / ship.U0
    return float(np.min(speeds)), float(np.max(speeds))
