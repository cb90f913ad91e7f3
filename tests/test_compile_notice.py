"""A first run that compiles the flight loops says so before it waits on them."""

from __future__ import annotations

import os
import subprocess
import sys
import types

import pytest

from sindyship import _compile_notice, reproduce
from sindyship._forces_compiled import COMPILED

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _compiles_first_in(env: dict) -> str:
    code = "from sindyship._compile_notice import compiles_first; print(compiles_first())"
    done = subprocess.run([sys.executable, "-c", code], env={**os.environ, **env}, cwd=ROOT,
                          capture_output=True, text=True, check=True)
    return done.stdout.strip()


@pytest.mark.skipif(not COMPILED, reason="numba is not installed")
def test_an_empty_numba_cache_means_the_loops_compile_unless_compiling_is_off(tmp_path):
    empty = {"NUMBA_CACHE_DIR": str(tmp_path), "PYTHONPATH": ROOT}
    assert _compiles_first_in(empty) == "True"
    assert _compiles_first_in({**empty, "SINDYSHIP_NO_COMPILE": "1"}) == "False"


def _dispatcher(index, source):
    cache_file = types.SimpleNamespace(_index_path=str(index))
    function = types.SimpleNamespace(__code__=types.SimpleNamespace(co_filename=str(source)))
    return types.SimpleNamespace(_cache=types.SimpleNamespace(_cache_file=cache_file),
                                 py_func=function)


def test_a_loop_counts_as_cached_only_with_an_index_as_new_as_its_source(tmp_path):
    source, index = tmp_path / "loop.py", tmp_path / "loop.nbi"
    source.write_text("x = 1\n")
    assert not _compile_notice._cached(_dispatcher(index, source))  # no index yet
    index.write_bytes(b"")
    os.utime(source, (1_000_000, 1_000_000))
    os.utime(index, (2_000_000, 2_000_000))
    assert _compile_notice._cached(_dispatcher(index, source))
    os.utime(source, (3_000_000, 3_000_000))  # the source changed after the compilation
    assert not _compile_notice._cached(_dispatcher(index, source))
    # a cache numba lays out otherwise: no notice rather than a wrong one
    assert _compile_notice._cached(types.SimpleNamespace(py_func=None))


def test_reproduce_says_it_compiles_before_its_first_step(monkeypatch):
    lines = []
    monkeypatch.setattr(reproduce, "compiles_first", lambda: True)
    reproduce.run(None, methods=("ls",), figures=False, diagnose_rounds=0,
                  refine_evaluations=0, progress=lines.append)
    assert lines[0].startswith("numba compiles the flight loops in this first run")
    assert lines[1].startswith("simulating the 8 training")
    monkeypatch.setattr(reproduce, "compiles_first", lambda: False)
    lines.clear()
    reproduce.run(None, methods=("ls",), figures=False, diagnose_rounds=0,
                  refine_evaluations=0, progress=lines.append)
    assert not any("compiles" in line for line in lines)
