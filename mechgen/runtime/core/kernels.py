"""Loading built kernels and calling them: the one bridge from artefacts to numerics.

A :class:`Kernel` wraps one generated function (numpy, C or CasADi) behind the
same call: ``kernel.evaluate(inputs, sizes)`` with a dict of arrays (batched
ports may carry a leading batch axis) returning a dict of output arrays. For
tight loops, :meth:`Kernel.bind` prepares everything once and returns a
callable with no arguments (C: a vectorcall object, about 60 ns a call).
"""
from __future__ import annotations

import ctypes
import importlib.abc
import importlib.util
from pathlib import Path
from typing import Callable

import numpy as np

from mechgen.errors import KernelError
from mechgen.runtime.core.pattern import extent


class TextLoader(importlib.abc.SourceLoader):
    """Loads a module from given source text; ``path`` is its file name for tracebacks only.

    What runs is exactly the text the caller verified, never bytes read again from the file (which
    another process could have replaced in between).
    """

    def __init__(self, path: Path | str, source: str | bytes) -> None:
        self.path = str(path)
        self.data = source.encode("utf-8") if isinstance(source, str) else bytes(source)

    def get_filename(self, fullname: str) -> str:
        return self.path

    def get_data(self, path: str) -> bytes:
        return self.data


def load_module(path: Path, name: str, source: str | bytes | None = None):
    """Import a generated Python module (no sys.path or sys.modules changes).

    Args:
        path: the module's file (read when ``source`` is None; else only its name is used).
        name: the module name.
        source: the module's text, when the caller holds (and has verified) it.
    """
    if source is None:
        spec = importlib.util.spec_from_file_location(name, path)
    else:
        loader = TextLoader(path, source)
        spec = importlib.util.spec_from_loader(name, loader, origin=str(path))
        spec.has_location = True
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class Kernel:
    """One kernel: its spec and an implementation ``impl(ins, outs, sizes, nbatch)``; a C kernel also has the
    ``address`` of its function ``mg_<name>`` in the loaded library (the compiled time loops call it directly;
    None for the other backends)."""

    def __init__(self, spec: dict, impl: Callable, backend: str, binder: Callable | None = None,
                 address: int | None = None, function: Callable | None = None) -> None:
        self.spec = spec
        self.name = spec["name"]
        self.backend = backend
        self.address = address
        self._impl = impl
        self._binder = binder
        self._function = function
        self.output_names = [p["name"] for p in spec["outputs"]]
        #: (name, batched, integer) of each input port, in order
        self._ports = tuple((p["name"], bool(p["batched"]), bool(p["integer"])) for p in spec["inputs"])
        #: the port lengths of a kernel without sizes, once known (Kernel._lengths)
        self._fixed: tuple | None = None

    def casadi_function(self, sizes: dict | None = None):
        """The casadi.Function of a CasADi kernel at ``sizes`` (built once per sizes), to be called on CasADi
        symbols (mechgen.runtime.core.sundials builds dx/dt from them); other backends have none."""
        if self._function is None:
            raise KernelError(f"kernel {self.name} is a {self.backend} kernel; only CasADi kernels have a "
                              "casadi.Function")
        return self._function(dict(sizes or {}))

    def _lengths(self, sizes: dict) -> tuple[tuple, tuple]:
        """(input lengths, output lengths) at ``sizes``, in port order (those of a kernel without sizes once)."""
        if not sizes and self._fixed is not None:
            return self._fixed
        lengths = (tuple(extent(p["extent"], sizes) for p in self.spec["inputs"]),
                   tuple(extent(p["extent"], sizes) for p in self.spec["outputs"]))
        if not sizes:
            self._fixed = lengths
        return lengths

    def _arrays(self, inputs: dict, sizes: dict) -> tuple[list, int, bool]:
        """Input arrays in port order; a missing batched state port is zero. A batched port given as one row is
        repeated to the batch's rows (contiguous); one given as (nbatch, length) is passed as it is."""
        ins, nbatch, batched = [], 1, False
        for name, is_batched, integer in self._ports:
            if is_batched and not integer and name not in inputs:
                ins.append(None)
                continue
            arr = np.asarray(inputs[name], dtype=np.int64 if integer else np.float64)
            if is_batched and arr.ndim == 2:
                nbatch, batched = arr.shape[0], True
            ins.append(arr)
        for k, ((name, is_batched, _), length) in enumerate(zip(self._ports, self._lengths(sizes)[0])):
            arr = ins[k]
            if is_batched:
                if arr is None or not arr.size:
                    ins[k] = np.zeros((nbatch, length))
                    continue
                arr = arr.reshape(-1, length)
                if arr.shape[0] != nbatch:
                    arr = np.broadcast_to(arr, (nbatch, length))
                ins[k] = arr if arr.flags.c_contiguous else np.ascontiguousarray(arr)
            elif arr.size != length:
                raise KernelError(f"kernel {self.name}: input {name} has {arr.size} entries, expected {length}")
            elif not arr.flags.c_contiguous:
                ins[k] = np.ascontiguousarray(arr)
        return ins, nbatch, batched

    def evaluate(self, inputs: dict, sizes: dict | None = None, *, check: bool = True) -> dict:
        """Outputs for ``inputs`` (name -> array); batched ports may be (nbatch, length)."""
        sizes = sizes or {}
        ins, nbatch, batched = self._arrays(inputs, sizes)
        outs = [np.zeros((nbatch, length)) for length in self._lengths(sizes)[1]]
        rc = self._impl(ins, outs, sizes, nbatch)
        if rc:
            raise KernelError(f"kernel {self.name} returned error code {rc}")
        if check:
            for port, arr in zip(self.spec["outputs"], outs):
                if not np.isfinite(arr).all():
                    raise self._not_finite(port["name"], arr, inputs, nbatch, batched)
        if batched:
            return dict(zip(self.output_names, outs))
        return {name: a[0] for name, a in zip(self.output_names, outs)}

    def _not_finite(self, port: str, arr: np.ndarray, inputs: dict, nbatch: int, batched: bool) -> KernelError:
        """The error of an output with NaN/Inf: where (row-major entry, batch row) and the inputs."""
        shown = {k: np.asarray(v).ravel()[:6].tolist() for k, v in inputs.items() if not k.startswith("slots")}
        flat = arr.reshape(nbatch, -1)
        bad = int(np.flatnonzero(~np.isfinite(flat))[0])
        batch, entry = divmod(bad, flat.shape[1])
        where = f"entry {entry} of {flat.shape[1]}" + (f" in batch row {batch}" if batched else "")
        return KernelError(f"kernel {self.name} produced NaN/Inf in output {port} ({where}, row-major, = "
                           f"{flat.ravel()[bad]}) at inputs {shown}")

    def bind(self, inputs: dict, outputs: dict, sizes: dict | None = None) -> Callable[[], int]:
        """A no-argument callable evaluating into ``outputs`` (contiguous float64 arrays) in place."""
        sizes = sizes or {}
        ins = [np.ascontiguousarray(inputs[p["name"]]) for p in self.spec["inputs"]]
        outs = [outputs[p["name"]] for p in self.spec["outputs"]]
        first = self.spec["inputs"][0] if self.spec["inputs"] else None
        nbatch = ins[0].shape[0] if first and first["batched"] and ins[0].ndim == 2 else 1
        if self._binder is not None:
            return self._binder(ins, outs, sizes, nbatch)
        impl = self._impl
        shaped_in = [a.reshape(nbatch, -1) if p["batched"] else a for p, a in zip(self.spec["inputs"], ins)]
        shaped_out = [o.reshape(nbatch, -1) for o in outs]

        def call() -> int:
            for o in outs:
                o[...] = 0.0
            return impl(shaped_in, shaped_out, sizes, nbatch)

        return call


def numpy_kernels(module) -> dict[str, Kernel]:
    """Kernels of a generated numpy module."""
    def impl_of(fn):
        return lambda ins, outs, sizes, nbatch: fn(ins, outs, sizes) or 0

    return {name: Kernel(spec, impl_of(getattr(module, f"mg_{name}")), "numpy") for name, spec in module.SPEC.items()}


#: the address given for an empty array (a valid one, never read or written: the port has no entries)
EMPTY = np.zeros(1)
EMPTY.flags.writeable = False
EMPTY_ADDRESS = EMPTY.ctypes.data


def data_address(a: np.ndarray) -> int:
    """The address of a contiguous array's data: ctypes.addressof on its buffer (a third of numpy's
    ``a.ctypes.data``) for a writable one, numpy's for a read-only one (it exports no writable buffer), and
    EMPTY's for an empty one."""
    if not a.size:
        return EMPTY_ADDRESS
    if a.flags.writeable and a.flags.c_contiguous:
        return ctypes.addressof(ctypes.c_char.from_buffer(a))
    return a.ctypes.data


def c_kernels(lib: ctypes.CDLL, spec: dict, caller) -> dict[str, Kernel]:
    """Kernels of a loaded C library; ``caller.bind`` makes the prepared calls."""
    kernels = {}
    for name, kspec in spec.items():
        address = ctypes.cast(getattr(lib, f"mg_{name}"), ctypes.c_void_p).value
        size_names = kspec["sizes"]

        def binder(ins, outs, sizes, nbatch, address=address, size_names=size_names):
            ptrs_in = [data_address(a) for a in ins]
            ptrs_out = [data_address(o) for o in outs]
            return caller.bind(address, ptrs_in, ptrs_out, [int(sizes[n]) for n in size_names], nbatch,
                               (ins, outs, lib))

        def impl(ins, outs, sizes, nbatch, binder=binder):
            return binder(ins, outs, sizes, nbatch)()

        kernels[name] = Kernel(kspec, impl, "c", binder, address)
    return kernels


def casadi_kernels(module, spec: dict) -> dict[str, Kernel]:
    """Kernels of a generated CasADi module (one casadi.Function per kernel and size)."""
    kernels = {}
    for name, kspec in spec.items():
        builder = getattr(module, f"build_{name}")
        cache: dict = {}
        slot_names = [p["name"] for p in kspec["inputs"] if p["integer"]]

        def impl(ins, outs, sizes, nbatch, builder=builder, kspec=kspec, cache=cache, slot_names=slot_names):
            slots = {p["name"]: a for p, a in zip(kspec["inputs"], ins) if p["integer"]}
            key = tuple(sorted(sizes.items()))
            if key not in cache:
                cache[key] = builder(sizes, slots)
            fn = cache[key]
            real = [(p, a) for p, a in zip(kspec["inputs"], ins) if not p["integer"]]
            for b in range(nbatch):
                args = [a[b] if p["batched"] else a for p, a in real]
                res = fn(*args)
                res = res if isinstance(res, (list, tuple)) else [res]
                for o, r in zip(outs, res):
                    o[b] = np.asarray(r).ravel()
            return 0

        built: dict = {}  # casadi.Functions for symbolic use, apart from impl's (which carry slot ports)

        def function(sizes, builder=builder, built=built):
            key = tuple(sorted(sizes.items()))
            if key not in built:
                built[key] = builder(sizes, {})  # a kernel without integer slot ports (lumped)
            return built[key]

        kernels[name] = Kernel(kspec, impl, "casadi", function=function)
    return kernels
