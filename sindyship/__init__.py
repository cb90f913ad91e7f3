"""sindyship: discover a ship's manoeuvring equations from trajectory data.

The names a notebook needs, from one place (each is loaded on first use, so
``import sindyship`` stays fast).  ``ss.refine`` and ``ss.diagnose`` are the functions,
also once their modules are imported, so the package's attribute never leads to those
modules: reach them and theirs by ``from sindyship.diagnose import discovery`` or
``importlib.import_module("sindyship.refine")`` (``import sindyship.refine as r`` gives the
function, and ``import sindyship.diagnose.discovery as d`` fails):

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
import sys
import types

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
    "evaluate_with_flights": "sindyship.evaluation",
    "evaluation_report": "sindyship.flight_reports",
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

#: Exported functions named as the module that defines them (``sindyship.refine`` is the
#: function; its module is ``importlib.import_module("sindyship.refine")``).
_FUNCTIONS_OVER_MODULES = frozenset(name for name, module in _EXPORTS.items()
                                    if module == f"{__name__}.{name}")


class _Package(types.ModuleType):
    """The package, whose attributes named as a submodule stay the exported functions: the
    import system binds a submodule to its package once it is imported, which would turn
    ``sindyship.diagnose`` from the function into the module behind a notebook's back."""

    def __setattr__(self, name: str, value) -> None:
        if name in _FUNCTIONS_OVER_MODULES and value is sys.modules.get(f"{__name__}.{name}"):
            return  # the import system's binding: the name goes on to the function
        super().__setattr__(name, value)

    def __reduce__(self):
        """Pickled by name, as a plain module is by cloudpickle: a function that uses ``ss``
        goes to joblib's and Dask's workers, which import the package there."""
        return importlib.import_module, (self.__name__,)


sys.modules[__name__].__class__ = _Package


def __getattr__(name: str):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'sindyship' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS))
