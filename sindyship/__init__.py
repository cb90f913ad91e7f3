"""sindyship: discover a ship's manoeuvring equations from trajectory data.

The names a notebook needs, from one place (each is loaded on first use, so
``import sindyship`` stays fast):

>>> import sindyship as ss
>>> ship = ss.load_ship("kcs")
>>> runs = ss.fly(ss.MMGModel(ship), [ss.Manoeuvre("zigzag", rudder=20, check=20, duration=600),
...                                   ss.Manoeuvre("turning-circle", rudder=35, duration=600)])
>>> model = ss.fit(runs, ship, optimizer="ls")
>>> sorted(ss.evaluate(model, runs))
['tc35_stbd', 'zz20_20']
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"

#: Public name -> the module that defines it.
_EXPORTS = {
    "AbkowitzModel": "sindyship.model",
    "paper_model": "sindyship.model",
    "MMGModel": "sindyship.mmg",
    "Manoeuvre": "sindyship.manoeuvres",
    "fly": "sindyship.manoeuvres",
    "protocol_manoeuvres": "sindyship.manoeuvres",
    "Ship": "sindyship.ships",
    "load_ship": "sindyship.ships",
    "Trajectory": "sindyship.trajectory",
    "read_csv": "sindyship.measurements",
    "write_csv": "sindyship.measurements",
    "fit": "sindyship.identify",
    "design": "sindyship.identify",
    "refine": "sindyship.refine",
    "make_optimizer": "sindyship.optimizers",
    "evaluate": "sindyship.evaluation",
    "compare": "sindyship.diagnose",
    "diagnose": "sindyship.diagnose",
    "diagnose_iteratively": "sindyship.diagnose",
    "before_after": "sindyship.diagnose",
    "force_residuals": "sindyship.diagnose",
    "load_effect": "sindyship.library",
    "available_effects": "sindyship.library",
    "simulate_with_effects": "sindyship.effects",
    "parse_effects": "sindyship.effects",
    "SindyshipInputError": "sindyship.errors",
}

__all__ = ["__version__", *sorted(_EXPORTS)]


def __getattr__(name: str):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'sindyship' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS))
