"""A simulated campaign of free-running trials, flown as model-scale trials are run outdoors.

Records made by :func:`sindyship.manoeuvres.fly` start at the design speed with the rudder
already on its programme.  Trials logged on a lake do not: the model starts from rest, a
helmsman keeps the course by hand while the ship speeds up, and the manoeuvre begins at its
rudder execute; the revolutions differ from run to run, the wind blows several times faster
than the ship and in gusts, and a hard turn loses half the speed.  :func:`campaign_trials`
plans such a campaign (training and held-out runs of the KVLCC2 model) and :func:`fly_trials`
flies it with the MMG model and its effects, writing the channels a logger records (``n``,
``wind_speed``, ``wind_dir``) and sensor noise.  A model identified on it has to be flown as
the trials were run (:func:`sindyship.trials.flight_start`) and to hold across speed.

Examples
--------
>>> from sindyship.ships import load_ship
>>> plan = campaign_trials(seed=1)
>>> [t.name for t in plan["test"]]
['zz15_15', 'tc25_stbd', 'tc25_port']
>>> (run,) = fly_trials(load_ship("kvlcc2"), plan["test"][1:2], duration_scale=0.4)
>>> float(run["u"][0]) < 0.2 * load_ship("kvlcc2").U0, round(run.meta["execute_s"])
(True, 63)
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .effects import Effects, simulate_with_effects
from .manoeuvres import Manoeuvre
from .rudder_holds import reversals
from .trajectory import Trajectory

__all__ = ["CampaignTrial", "campaign_trials", "fly_trials"]

@dataclass(frozen=True)
class CampaignTrial:
    """One run of the campaign.

    Attributes
    ----------
    kind : {"zigzag", "turning-circle"}
    rudder, check : float
        Rudder angle and check angle [deg] (a turn's sign is its side).
    first_sign : int
        A zig-zag's first rudder side.
    approach_s, manoeuvre_s : float
        The course keeping by hand from rest, and the manoeuvre after the execute [s].
    rps : float
        Revolutions as a share of the design ``n_P``.
    wind, wind_dir : float
        Mean true wind [m/s] and the direction it comes from [deg].
    seed : int
    """

    kind: str
    rudder: float
    check: float
    first_sign: int
    approach_s: float
    manoeuvre_s: float
    rps: float
    wind: float
    wind_dir: float
    seed: int

    @property
    def name(self) -> str:
        return Manoeuvre(self.kind, rudder=self.rudder, check=self.check,
                         first_sign=self.first_sign).label


def campaign_trials(seed: int = 0) -> dict[str, list[CampaignTrial]]:
    """A campaign of the KVLCC2 model (7 m): training zig-zags 10/10 and 20/20 to both sides and
    35 deg turns to both sides; held out a 15/15 zig-zag and 25 deg turns.  Every run starts
    from rest with 120-180 s of course keeping by hand; revolutions 70-85 % of the design
    condition's 17.95 rps (at which the model would run half as fast again as U0); a gusty
    wind of 4-6 m/s (3-6 times the ship's speed) from a direction of its own.

    Parameters
    ----------
    seed : int
        Seed of ``numpy.random.default_rng`` for the revolutions, wind and helmsmen.
    """
    rng = np.random.default_rng(seed)
    specs = {
        "train": [("zigzag", 10, 10, 1, 240), ("zigzag", 10, 10, -1, 240),
                  ("zigzag", 20, 20, 1, 300), ("zigzag", 20, 20, -1, 300),
                  ("turning-circle", 35, 0, 1, 260), ("turning-circle", -35, 0, 1, 260)],
        "test": [("zigzag", 15, 15, 1, 270), ("turning-circle", 25, 0, 1, 300),
                 ("turning-circle", -25, 0, 1, 300)],
    }
    out = {}
    for part, rows in specs.items():
        out[part] = [CampaignTrial(kind, rudder, check, sign, float(rng.uniform(120, 180)),
                                   float(length), float(rng.uniform(0.70, 0.85)),
                                   float(rng.uniform(4.0, 6.0)), float(rng.uniform(0, 360)),
                                   int(rng.integers(2**31)))
                     for kind, rudder, check, sign, length in rows]
    return out


def fly_trials(ship, trials: Sequence[CampaignTrial], *, dt: float = 0.2, noise: float = 0.01,
               start_speed: float = 0.1, duration_scale: float = 1.0) -> list[Trajectory]:
    """Fly the campaign's runs with the MMG model of ``ship``, each from rest (``start_speed``
    times U0) with its own revolutions, wind and helmsman.

    Parameters
    ----------
    ship : Ship
        A ship with an MMG model (the built-in ``kvlcc2``).
    trials : sequence of CampaignTrial
    dt : float
        Sample interval [s].
    noise : float
        Sensor noise as a share of each channel's RMS (:func:`sindyship.effects.add_noise`).
    start_speed : float
        The speed the run starts from, over U0 (a model at rest: its propeller turning up).
    duration_scale : float
        Shortens every run (a quick look: the examples and tests).

    Returns
    -------
    list of Trajectory
        With ``meta["execute_s"]``, the time of the rudder execute.

    Warns
    -----
    UserWarning
        For a zig-zag whose commanded rudder reversed fewer than :data:`MIN_REVERSALS` times
        after its execute: the wind held the ship off its check angles (the record is kept).
    """
    out = []
    for trial in trials:
        approach = trial.approach_s * duration_scale
        duration = approach + trial.manoeuvre_s * duration_scale
        manoeuvre = Manoeuvre(trial.kind, rudder=trial.rudder, check=trial.check,
                              first_sign=trial.first_sign, duration=duration, dt=dt,
                              seed=trial.seed, name=trial.name, approach=approach)
        effects = Effects(wind=trial.wind, wind_dir=trial.wind_dir, gust=0.3, wind_wander=15.0,
                          rps=trial.rps, noise=noise, seed=trial.seed)
        (record,) = simulate_with_effects(
            ship, [manoeuvre], effects,
            state0=np.array([start_speed * ship.U0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]))
        out.append(Trajectory(record.data, name=trial.name,
                              meta={**record.meta, "execute_s": approach,
                                    "trial": dict(trial.__dict__)}))
        if trial.kind == "zigzag":
            _warn_unanswered(out[-1], trial, approach, duration - approach)
    return out


#: Fewest reversals of a zig-zag's commanded rudder after its execute: fewer, and the ship did
#: not reach its check angles (the wind held its heading), so the record is no zig-zag.
MIN_REVERSALS = 2


def _warn_unanswered(record: Trajectory, trial: CampaignTrial, execute: float,
                     flown: float) -> None:
    """Warn when a zig-zag's helm was not answered: its commanded rudder reversed fewer than
    :data:`MIN_REVERSALS` times after the execute (in a wind of 5 m/s, seven times the speed of
    the 7 m KVLCC2, a 15/15 zig-zag can hold its first rudder to the end)."""
    after = np.degrees(record["delta_c"][record.t >= execute])
    reversed_ = reversals(after, 0.5 * abs(trial.rudder))  # the rudder put over
    if reversed_ < MIN_REVERSALS:
        shortened = flown < trial.manoeuvre_s - 1e-9
        why = (f"in the {flown:.3g} s it was shortened to (duration_scale), or against a wind "
               f"of {trial.wind:.2g} m/s" if shortened else
               f"against a wind of {trial.wind:.2g} m/s from {trial.wind_dir:.0f} deg")
        warnings.warn(
            f"{trial.name}: the commanded rudder reversed {reversed_} time"
            f"{'' if reversed_ == 1 else 's'} in the {flown:.3g} s after the execute: the ship "
            f"did not reach its check angles ({why}), so the record is no zig-zag; fly it "
            "longer, another seed of campaign_trials, or with less wind.", stacklevel=3)
