"""The model library, and where models come from.

A model is named in a scene (``model = ...``) or in Python (:func:`mechgen.load_model`) by a
*reference*, resolved by :func:`resolve` without running any model code:

* a built-in name (``"laval_rotor"``: one module per model family in this package),
* a path to a Python file (``"models/top.py"``, relative to the scene's folder or to ``base``),
* ``"package.module:attribute"`` (``attribute`` defaults to ``model``).

:meth:`ModelSource.load` then imports the module and returns its
:class:`~mechgen.symbolic.model.Model`. A model file is Python that the user chose to run;
a scene stays pure data.
"""
from __future__ import annotations

import importlib
import importlib.util
from dataclasses import dataclass
from pathlib import Path

from mechgen.errors import InputError

BUILTIN = ("balloon_string", "euler_bernoulli_beam", "follower_column", "fpu_chain", "laval_rotor", "moving_string",
           "spinning_shaft", "rotating_string", "spring_pendulum", "timoshenko_beam")
HERE = Path(__file__).resolve().parent


@dataclass(frozen=True)
class ModelSource:
    """Where a model is declared, found without running it.

    ``key`` is canonical (a built-in name, an absolute file path, or ``module:attribute``):
    ``resolve(key)`` gives the same source again in any process. ``file`` is the Python file
    that declares it (its bytes key the compile cache), None where it cannot be known
    before import. ``origin`` says where it came from, for listings and messages.
    """

    key: str
    origin: str
    file: Path | None
    module: str | None = None
    attribute: str = "model"

    def load(self):
        """Import the declaring module and return its Model."""
        if self.module is not None:
            module = importlib.import_module(self.module)
        else:
            module = _import_file(self.file)
        model = getattr(module, self.attribute, None)
        from mechgen.symbolic.model import Model

        if not isinstance(model, Model):
            raise InputError(f"{self.key} defines no Model called {self.attribute!r}", file=str(self.file or ""),
                             key="model", expected=f"a module-level `{self.attribute} = Model(...)`")
        if model.file is None and self.file is not None:
            model.file = str(self.file)
        return model


_FILE_MODULES: dict[tuple[str, bytes], object] = {}


def _import_file(path: Path):
    """Import a model file as a module of its own (once per path and content)."""
    from mechgen.codegen.cache import content_key

    data = path.read_bytes()
    memo = (str(path), data)
    if memo not in _FILE_MODULES:
        name = f"mechgen_user_{content_key(str(path).encode(), data)[:16]}"
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        _FILE_MODULES[memo] = module
    return _FILE_MODULES[memo]


def names() -> list[str]:
    """Names of the built-in models, sorted."""
    return sorted(BUILTIN)


def resolve(ref: str, *, base: str | Path | None = None) -> ModelSource:
    """The :class:`ModelSource` a reference names (see the module doc); nothing is imported."""
    if not isinstance(ref, str) or not ref:
        raise InputError(f"model reference {ref!r}", key="model",
                         expected="a built-in name, a path to a .py file or package.module:attribute")
    if ref in BUILTIN:
        return ModelSource(ref, "built-in", HERE / f"{ref}.py", module=f"mechgen.models.{ref}")
    if ref.endswith(".py") or "/" in ref or "\\" in ref:
        path = Path(ref)
        if not path.is_absolute() and base is not None:
            path = Path(base) / path
        path = path.resolve()
        if not path.is_file():
            raise InputError(f"model file {ref!r} does not exist (looked for {path})", key="model",
                             expected="a path to a Python file, relative to the scene")
        return ModelSource(str(path), "file", path)
    if ":" in ref:
        module, _, attribute = ref.partition(":")
        try:
            spec = importlib.util.find_spec(module)
        except (ImportError, ValueError):
            spec = None
        if spec is None:
            raise InputError(f"no module {module!r} for model {ref!r}", key="model",
                             expected="package.module:attribute of an importable module")
        origin = Path(spec.origin) if spec.origin and spec.origin.endswith(".py") else None
        return ModelSource(ref, "module", origin, module=module, attribute=attribute or "model")
    raise InputError(f"unknown model {ref!r}", key="model", expected=f"one of {', '.join(names())}, "
                     "a path to a .py file or package.module:attribute")


def get(ref: str, *, base: str | Path | None = None):
    """The :class:`~mechgen.symbolic.model.Model` a reference names (a built-in name, a path, module:attr)."""
    return resolve(ref, base=base).load()


def load_model(ref: str, *, base: str | Path | None = None):
    """Public: the Model a reference names (a built-in name, a path to a .py file, package.module:attribute)."""
    return get(ref, base=base)
