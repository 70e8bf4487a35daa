"""mechgen's version, in a module of its own so that any module can read it without importing the
package's ``__init__`` (the code generators stamp it into generated files), and the versions of the packages
that produce a run's numbers (recorded in every scene's JSON, so that a result can be reproduced)."""
from __future__ import annotations

__version__ = "0.1.0"

#: the distributions whose versions a run records: the derivation (sympy, CasADi) and the numerics (numpy, scipy)
RECORDED = ("numpy", "scipy", "sympy", "casadi")


def versions() -> dict[str, str]:
    """``{"mechgen": ..., "python": ..., "numpy": ..., "scipy": ..., "sympy": ..., "casadi": ...}``: a package already
    imported by its ``__version__``, another by the name of its ``<name>-<version>.dist-info`` folder on sys.path
    (nothing is imported: sympy stays unloaded in a run from committed kernels; importlib.metadata, ~30 ms to
    import, only where neither answers); a missing one reads "not installed"."""
    import platform

    out = {"mechgen": __version__, "python": platform.python_version()}
    for name in RECORDED:
        out[name] = installed_version(name)
    return out


def installed_version(name: str) -> str:
    """The installed version of distribution ``name`` (module doc of :func:`versions`)."""
    import os
    import re
    import sys

    found = getattr(sys.modules.get(name), "__version__", None)
    if isinstance(found, str):
        return found
    pattern = re.compile(rf"{re.escape(name)}-([^-]+)\.dist-info", re.IGNORECASE)
    for entry in sys.path:
        try:
            names = os.listdir(entry or ".")
        except OSError:
            continue
        for folder in names:
            match = pattern.fullmatch(folder)
            if match:
                return match.group(1)
    from importlib import metadata

    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return "not installed"
