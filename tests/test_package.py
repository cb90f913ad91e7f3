"""The package's own names: ``import sindyship as ss`` gives every exported function, whatever
was imported before."""

from __future__ import annotations

import subprocess
import sys

import sindyship


def test_every_exported_name_is_what_its_module_defines():
    import importlib

    for name, module in sindyship._EXPORTS.items():
        assert getattr(sindyship, name) is getattr(importlib.import_module(module), name)
    assert sorted(sindyship._FUNCTIONS_OVER_MODULES) == ["diagnose", "refine"]


def test_a_function_named_as_its_module_stays_the_function_once_the_module_is_imported():
    """Importing ``sindyship.diagnose`` (the package of ``ss.compare`` and
    ``ss.diagnose_iteratively``) or ``sindyship.refine`` binds the module to the package;
    ``ss.diagnose`` and ``ss.refine`` must stay the functions, in a fresh process."""
    code = """
import importlib, types
import sindyship as ss
ss.diagnose_iteratively, ss.compare
import sindyship.diagnose.discovery
module = importlib.import_module("sindyship.refine")
assert isinstance(module, types.ModuleType) and module.refine is ss.refine
assert isinstance(ss.diagnose, types.FunctionType), type(ss.diagnose)
assert isinstance(ss.refine, types.FunctionType), type(ss.refine)
from sindyship.diagnose import diagnose, discovery
assert diagnose is ss.diagnose and isinstance(discovery, types.ModuleType)
ss.refine = print  # a user's own assignment is kept
assert ss.refine is print
print("ok")
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip() == "ok"


def test_the_package_pickles_by_name_so_a_function_using_it_goes_to_workers():
    """A notebook function that uses ``ss`` could not go to joblib's workers (cloudpickle
    dispatches on the module type, which the package's own class is not)."""
    import pickle

    import joblib

    import sindyship as ss

    assert pickle.loads(pickle.dumps(ss)) is ss

    def version(_):
        return ss.__version__, ss.load_ship("kcs").L

    assert joblib.Parallel(n_jobs=2)(joblib.delayed(version)(i) for i in range(2)) == \
        [(ss.__version__, 230.0)] * 2
