"""The model library, and where models come from.

A model is named in a scene (``model = ...``) or in Python (:func:`mechgen.load_model`) by a
*reference*, resolved by :func:`resolve` without running any model code:

* a built-in name (``"laval_rotor"``: one module per model family in this package),
* a path to a Python file (``"models/top.py"``, relative to the scene's folder or to ``base``),
  optionally with ``:attribute`` for one of several Models in the file (``"models/two.py:soft"``),
* ``"package.module:attribute"`` (``attribute`` defaults to ``model``),
* the name of an entry point in the group ``mechgen.models`` of an installed distribution,
  whose value is ``package.module:attribute``.

:meth:`ModelSource.load` then imports the module and returns its
:class:`~mechgen.symbolic.model.Model`. A model file is Python that the user chose to run;
a scene stays pure data. Errors while importing a model (a syntax error, an exception, a bad
declaration) become a :class:`~mechgen.errors.ModelError` naming the file and the line.
"""
from __future__ import annotations

import contextlib
import importlib
import importlib.util
import io
import os
import re
import sys
from dataclasses import dataclass
from pathlib import Path

from mechgen.errors import InputError, ModelError, did_you_mean

BUILTIN = ("balloon_string", "euler_bernoulli_beam", "follower_column", "fpu_chain", "laval_rotor", "moving_string",
           "spinning_shaft", "rotating_string", "spring_pendulum", "timoshenko_beam", "viscoelastic_impact",
           "ogive_penetration", "rate_state_slider", "rate_state_inertial", "friction_beam",
           "stick_slip_contact",
           "curved_beam_stiffness", "cosserat_rod", "van_der_pol", "duffing", "impact_oscillator", "belt_stick_slip",
           "van_der_pol_hopf", "phase_bar",
           "plane_poiseuille", "js_local", "js_channel", "js_local_reduced", "js_galerkin", "js_fluid", "js_fluid_reduced", "membrane_gravity",
           "annulus_gravity", "drum", "cracked_plate", "plane_block")
HERE = Path(__file__).resolve().parent
#: the entry-point group installed packages register their models under (value ``module:attribute``)
ENTRY_POINT_GROUP = "mechgen.models"
_MODULE_REF = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*\Z")
_ATTRIBUTE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_FILE_ATTRIBUTE = re.compile(r"\.py:([A-Za-z_][A-Za-z0-9_]*)\Z")
EXPECTED_REF = ("a built-in model name, a path to a .py file, package.module:attribute or the name of an "
                f"installed '{ENTRY_POINT_GROUP}' entry point")


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
        """Import the declaring module and return its Model (``Model.source`` set to :attr:`key`)."""
        with _printed() as printed:  # held back until the module is known to hold a Model
            if self.module is not None:
                module = _guarded(lambda: importlib.import_module(self.module), self.file, self.key, printed)
            else:
                module = _import_file(self.file, printed)
            model = _model_of(module, self, printed)
        if model.file is None and self.file is not None:
            model.file = str(self.file)
        model.source = self.key
        return model


def _model_of(module, source: ModelSource, printed: "_Captured | None" = None):
    """The module's Model: its attribute ``source.attribute``, else its only module-level Model."""
    from mechgen.symbolic.model import Model

    where = str(source.file or source.key)
    model = getattr(module, source.attribute, None)
    if isinstance(model, Model):
        return model
    found = {name: value for name, value in vars(module).items() if isinstance(value, Model)}
    if model is None and source.attribute == "model" and len(found) == 1:
        return next(iter(found.values()))
    if model is not None:
        message = f"{source.attribute!r} is a {type(model).__name__}, not a Model"
    elif found:
        message = f"the module defines no Model called {source.attribute!r} (it has {', '.join(sorted(found))})"
    else:
        message = "the module defines no Model"
    raise ModelError(message + (printed.note() if printed is not None else ""), file=where, key=source.attribute,
                     expected=f"a module-level `{source.attribute} = Model(...)` (mechgen.Model)")


def _line_in(tb, file: str | None) -> int | None:
    """The innermost line of traceback ``tb`` that lies in ``file``."""
    line = None
    while tb is not None:
        if file is not None and Path(tb.tb_frame.f_code.co_filename) == Path(file):
            line = tb.tb_lineno
        tb = tb.tb_next
    return line


def _guarded(run, file: Path | None, key: str, printed: "_Captured | None" = None):
    """``run()`` (an import), its errors turned into ModelErrors naming the model file and the line.

    Whatever the module raises on import is caught, ``SystemExit`` included (never a silent exit 0 of
    ``mechgen run``; only ``KeyboardInterrupt`` passes), and what it prints to stdout is held back
    (:func:`_printed`), so that a module that is not a model leaves no output of its own on stdout."""
    where = str(file) if file is not None else key
    with contextlib.nullcontext(printed) if printed is not None else _printed() as printed:
        try:
            return run()
        except SyntaxError as exc:
            at = f"line {exc.lineno}: " if exc.lineno else ""
            source = Path(exc.filename) if exc.filename else file
            raise ModelError(f"{at}syntax error: {exc.msg}", file=str(source or where),
                             expected="a model file that is valid Python") from None
        except ModelError as exc:
            line = _line_in(exc.__traceback__, str(file) if file else None)
            at = f"line {line}: " if line else ""
            raise ModelError(at + exc.message, file=where, key=exc.key, expected=exc.expected) from None
        except InputError:
            raise
        except (Exception, SystemExit) as exc:  # the user's module raised (or called sys.exit) while imported
            line = _line_in(exc.__traceback__, str(file) if file else None)
            at = f"line {line}: " if line else ""
            what = f"SystemExit({exc.code!r})" if isinstance(exc, SystemExit) else f"{type(exc).__name__}: {exc}"
            raise ModelError(f"{at}importing the model raised {what}{printed.note()}", file=where,
                             expected="a model module that imports without errors (and does not exit)") from None


class _Captured(io.StringIO):
    """What a model module printed to stdout while it was imported."""

    def note(self) -> str:
        """`` (it printed N characters, not shown)``, or '' when it printed nothing."""
        text = self.getvalue()
        return f" (it printed {len(text)} characters, not shown)" if text else ""


@contextlib.contextmanager
def _printed():
    """Hold back what an import prints to stdout (the results and summary own stdout); on success it goes to
    stderr, so a model's own prints stay visible; on failure the message says how much was held back."""
    captured = _Captured()
    failed = False
    try:
        with contextlib.redirect_stdout(captured):
            yield captured
    except BaseException:
        failed = True
        raise
    finally:
        if not failed and captured.getvalue():
            sys.stderr.write(captured.getvalue())


_FILE_MODULES: dict[tuple[str, bytes], object] = {}


def _import_file(path: Path, printed: "_Captured | None" = None):
    """Import a model file as a module of its own (once per path and content)."""
    from mechgen.codegen.cache import content_key

    data = path.read_bytes()
    memo = (str(path), data)
    if memo not in _FILE_MODULES:
        name = f"mechgen_user_{content_key(str(path).encode(), data)[:16]}"
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module  # as an import would (dataclasses, pickling and inspect look it up)
        try:
            _guarded(lambda: spec.loader.exec_module(module), path, str(path), printed)
        except BaseException:
            sys.modules.pop(name, None)
            raise
        _FILE_MODULES[memo] = module
    return _FILE_MODULES[memo]


def names() -> list[str]:
    """Names of the built-in models, sorted."""
    return sorted(BUILTIN)


def entry_points() -> dict[str, ModelSource]:
    """Models that installed distributions register in the entry-point group ``mechgen.models``, by name.

    A name a built-in model already has is left out (the built-in wins); nothing is imported.
    """
    from importlib.metadata import entry_points as installed

    found: dict[str, ModelSource] = {}
    for ep in sorted(installed(group=ENTRY_POINT_GROUP), key=lambda e: e.name):
        if ep.name in BUILTIN or ep.name in found:
            continue
        dist = getattr(ep, "dist", None)
        label = f"entry point of {dist.metadata['Name']} {dist.version}" if dist is not None else "entry point"
        try:
            source = _module_source(f"{ep.module}:{ep.attr or 'model'}")
        except InputError as exc:
            source = ModelSource(ep.value, f"{label} (broken: {exc.message})", None)
        else:
            source = ModelSource(source.key, f"{label} ({source.key})", source.file, source.module, source.attribute)
        found[ep.name] = source
    return found


def known() -> list[str]:
    """Names a scene can use without a path: the built-ins and the installed entry points."""
    return names() + sorted(entry_points())


def _module_source(ref: str) -> ModelSource:
    """``package.module:attribute`` as a source; the module is found, not imported."""
    module, _, attribute = ref.partition(":")
    attribute = attribute.strip() or "model"
    module = module.strip()
    if not _MODULE_REF.match(module) or not _ATTRIBUTE.match(attribute):
        raise InputError(f"model reference {ref!r} is not package.module:attribute", key="model",
                         expected="dotted Python names, then ':' and an attribute name")
    try:
        spec = importlib.util.find_spec(module)
    except ModuleNotFoundError:  # a parent package is missing
        spec = None
    except (ImportError, ValueError) as exc:
        raise InputError(f"cannot find module {module!r} of model {ref!r} ({type(exc).__name__}: {exc})",
                         key="model", expected="package.module:attribute of a module on the Python path") from None
    if spec is None:
        raise InputError(f"no module {module!r} for model {ref!r}", key="model",
                         expected="package.module:attribute of a module on the Python path (PYTHONPATH)")
    origin = Path(spec.origin) if spec.origin and spec.origin.endswith(".py") else None
    return ModelSource(f"{module}:{attribute}", "module", origin, module=module, attribute=attribute)


def is_path(ref: str) -> bool:
    """Whether a reference names a file (ends in .py or holds a path separator)."""
    return ref.endswith(".py") or "/" in ref or "\\" in ref


def resolve(ref: str, *, base: str | Path | None = None) -> ModelSource:
    """The :class:`ModelSource` a reference names (see the module doc); nothing is imported.

    A relative path is taken from ``base`` (a scene's folder), else from the current directory;
    a :class:`pathlib.Path` is always a path.
    """
    if isinstance(ref, os.PathLike):
        ref = os.fspath(ref)
        if not is_path(ref):
            ref = os.path.join(".", ref)
    if not isinstance(ref, str) or not ref:
        raise InputError(f"model reference {ref!r}", key="model", expected=EXPECTED_REF)
    if ref in BUILTIN:
        return ModelSource(ref, "built-in", HERE / f"{ref}.py", module=f"mechgen.models.{ref}")
    attribute = "model"
    in_file = _FILE_ATTRIBUTE.search(ref)
    if in_file:  # models/two.py:soft, one of several Models in a file
        ref, attribute = ref[:in_file.start() + 3], in_file.group(1)
    if is_path(ref):
        path = Path(ref).expanduser()
        if not path.is_absolute() and base is not None:
            path = Path(base) / path
        path = path.resolve()
        if not path.is_file():
            raise InputError(f"model file {ref!r} does not exist (looked for {path})", key="model",
                             expected="a path to a Python file (a scene's model path is relative to the scene's "
                             "folder; one given to mechgen show or load_model to the current directory)")
        key = str(path) if attribute == "model" else f"{path}:{attribute}"
        return ModelSource(key, "file", path, attribute=attribute)
    if ":" in ref:
        return _module_source(ref)
    registered = entry_points().get(ref)
    if registered is not None:
        return registered
    raise InputError(f"unknown model {ref!r}{did_you_mean(ref, known())}", key="model",
                     expected=f"one of {', '.join(known())}; or a path to a .py file or package.module:attribute")


def get(ref: str | os.PathLike, *, base: str | Path | None = None):
    """The :class:`~mechgen.symbolic.model.Model` a reference names (a built-in name, a path, module:attr)."""
    return resolve(ref, base=base).load()


def load_model(ref: str | os.PathLike, *, base: str | Path | None = None):
    """Public: the Model a reference names.

    ``ref`` is a built-in name (``"laval_rotor"``), a path to a ``.py`` file (relative to ``base``,
    else to the current directory), ``package.module:attribute`` or the name of an installed
    ``mechgen.models`` entry point. Importing a model file runs it: name only files you trust.

    Raises:
        InputError: no such model; ModelError: the model's file fails to import or declares no Model
            (the message names the file and, where Python gives one, the line).
    """
    return get(ref, base=base)


__all__ = ["BUILTIN", "ENTRY_POINT_GROUP", "ModelSource", "entry_points", "get", "is_path", "known", "load_model",
           "names", "resolve"]
