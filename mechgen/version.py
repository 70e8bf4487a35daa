"""mechgen's version, in a module of its own so that any module can read it without importing the
package's ``__init__`` (the code generators stamp it into generated files), and the versions of the packages
that produce a run's numbers (recorded in every scene's JSON, so that a result can be reproduced)."""
from __future__ import annotations

import platform
from importlib import metadata

__version__ = "0.1.0"

#: the distributions whose versions a run records: the derivation (sympy, CasADi) and the numerics (numpy, scipy)
RECORDED = ("numpy", "scipy", "sympy", "casadi")


def versions() -> dict[str, str]:
    """``{"mechgen": ..., "python": ..., "numpy": ..., "scipy": ..., "sympy": ..., "casadi": ...}``, read from the
    installed distributions' metadata (nothing is imported; a missing one reads "not installed")."""
    out = {"mechgen": __version__, "python": platform.python_version()}
    for name in RECORDED:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out
