"""Modules imported at first use (mechgen.runtime.core.lazy_import), and the BLAS thread limit that must still
reach scipy's own OpenBLAS when that first use falls inside a one-thread limit (mechgen.runtime.core.threads)."""
import json
import os
import subprocess
import sys

import pytest

from mechgen.runtime.core.lazy_import import lazy_module


def _python(code: str) -> str:
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
                                                              "MKL_NUM_THREADS")}
    env["PYTHONPATH"] = os.pathsep.join(sys.path)
    return subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                          check=True).stdout.strip()


def test_the_module_is_imported_at_the_first_attribute_read_and_is_the_real_one():
    out = _python("import sys\nfrom mechgen.runtime.core.lazy_import import lazy_module\n"
                  "m = lazy_module('fractions')\nprint('fractions' in sys.modules, end=' ')\n"
                  "half = m.Fraction(1, 2)\nimport fractions\n"
                  "print('fractions' in sys.modules, type(half) is fractions.Fraction, repr(m))")
    assert out == "False True True <lazy module 'fractions' (imported)>"


def test_an_unknown_module_fails_at_first_use_with_the_import_error():
    missing = lazy_module("mechgen_no_such_module_xyz")
    with pytest.raises(ModuleNotFoundError, match="mechgen_no_such_module_xyz"):
        missing.anything


def test_a_first_use_of_lazy_scipy_inside_a_one_thread_limit_limits_scipys_blas_too():
    pytest.importorskip("threadpoolctl")
    out = _python("import sys, threadpoolctl\n"
                  "from mechgen.runtime.core.lazy_import import lazy_module\n"
                  "from mechgen.runtime.core.threads import blas_threads_for\n"
                  "sla = lazy_module('scipy.linalg')\nassert 'scipy.linalg' not in sys.modules\n"
                  "with blas_threads_for(4):\n"
                  "    sla.eigvals([[2.0, 1.0], [1.0, 3.0]])\n"
                  "    inside = sorted({i['num_threads'] for i in threadpoolctl.threadpool_info()"
                  " if i['user_api'] == 'blas'})\n"
                  "after = [i['num_threads'] for i in threadpoolctl.threadpool_info() if i['user_api'] == 'blas']\n"
                  "import json\nprint(json.dumps([inside, len(after),"
                  " [type(f).__name__ for f in sys.meta_path]]))")
    inside, libraries, finders = json.loads(out)
    assert inside == [1]
    assert libraries == 2                   # numpy's OpenBLAS and scipy's: both were seen
    assert "_ScipyWatch" not in finders     # the import watch is off the import path once the limit ends
