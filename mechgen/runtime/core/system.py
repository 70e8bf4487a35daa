"""A compiled system: the kernels of one model specialisation with its parameter values.

State of a lumped model: coordinates q (n), velocities v (n), internal
variables z (m), time t. Equations (see mechgen.symbolic.derive):

    r(q, v, a, z, t) = M(q) a - f(q, v, z, t) = 0,    dz/dt = g(q, v, z, t).

First-order form x = (q, v, z): dq/dt = v, dv/dt = a = -M^-1 r(q, v, 0, z, t), dz/dt = g,
with the exact Jacobian da/dx = -M^-1 dr/dx evaluated at the current a.
Chain models have the same interface with sparse (CSR) matrices.

Compiled systems are immutable (DESIGN.md): parameters, sizes and choices are fixed at
construction, and a new value gives a new system (:meth:`System.with_params`).
"""
from __future__ import annotations

import functools
import math
from collections import OrderedDict
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Callable

import numpy as np

from mechgen.errors import InputError, KernelError, did_you_mean
from mechgen.runtime.core.kernels import Kernel
from mechgen.runtime.core.meta import SystemMeta
from mechgen.runtime.core.pattern import Pattern, build_pattern, extent

#: dense mass matrices up to this size are solved by numpy's LAPACK call (scipy.linalg.solve's checks cost more
#: than the solve for a handful of coordinates)
SMALL_DENSE = 32


class Memo:
    """A bounded memo of values that are pure functions of their key (and of the frozen structure of the
    systems that share it): ``get(key, make)`` returns the value stored under ``key``, else ``make()``
    stored there. The oldest entries are dropped beyond ``size``; an entry is never replaced by another
    value, so dropping one only costs its recomputation."""

    def __init__(self, size: int = 64) -> None:
        self.size = size
        self._store: OrderedDict = OrderedDict()

    def get(self, key, make: Callable[[], object]):
        """The value under ``key`` (made once by ``make``)."""
        try:
            value = self._store[key]
        except KeyError:
            value = self._store[key] = make()
            if len(self._store) > self.size:
                self._store.popitem(last=False)
            return value
        self._store.move_to_end(key)
        return value

    def __len__(self) -> int:
        return len(self._store)


def read_only(mapping) -> MappingProxyType:
    """A read-only view of a mapping (a view stays the same view)."""
    return mapping if isinstance(mapping, MappingProxyType) else MappingProxyType(dict(mapping))


def frozen_vector(values) -> np.ndarray:
    """A read-only float copy of a parameter vector (1-D)."""
    out = np.array(values, dtype=float).reshape(-1)
    out.flags.writeable = False
    return out


def replacement_vector(system, params) -> np.ndarray | None:
    """``params`` as a frozen vector for ``system.with_param_vector``: None when it equals the system's own
    (the system itself serves), InputError naming the free parameters when its length is wrong."""
    params = frozen_vector(params)
    if params.shape != system.params.shape:
        raise InputError(f"{len(params)} parameter values for the {len(system.params)} free parameters of "
                         f"{system.metadata.model}", key="params",
                         expected=f"values of {', '.join(system.metadata.params) or 'none'}")
    return None if np.array_equal(params, system.params) else params


def number(name: str, value) -> float:
    """A finite real parameter value, else InputError naming the parameter."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InputError(f"parameter {name!r} = {value!r} is not a number", key=name, expected="a finite real number")
    out = float(value)
    if not math.isfinite(out):
        raise InputError(f"parameter {name!r} = {value!r} is not finite", key=name, expected="a finite real number")
    return out


def unknown_parameters(model, unknown: list, known) -> InputError:
    """The error for names that are no parameter of the compiled system."""
    return InputError(f"unknown parameter{'s' if len(unknown) > 1 else ''} {', '.join(map(repr, unknown))} "
                      f"for model {model}{did_you_mean(unknown[0], known)}", key=unknown[0],
                      expected="one of: " + (", ".join(sorted(known)) or "none"))


def with_values(system, values: dict, choice):
    """``system.with_params(**values)`` of a continuum (a FieldSystem or a PlaneSystem: free numeric parameters,
    runtime ``choices``, names folded into the kernels through ``rebuild``): a new system, the given one unchanged
    (itself when nothing changes). ``choice(name, value)`` validates a runtime choice's new value. Unknown names and
    a folded name without ``rebuild`` are InputErrors listing what is known."""
    from dataclasses import replace

    names = list(system.meta.get("params", []))
    folded = [*system.fixed, *(k for k in system.folded if k not in system.fixed)]
    unknown = [k for k in values if k not in names and k not in system.choices and k not in folded]
    if unknown:
        raise unknown_parameters(system.meta.get("model"), unknown, names + list(system.choices) + folded)
    hit = [k for k in values if k in folded and k not in names and k not in system.choices]
    if hit:
        if system.rebuild is None:
            raise folded_parameter(system.meta.get("model"), hit[0])
        return system.rebuild(system, dict(values))
    choices = {k: choice(k, v) for k, v in values.items() if k in system.choices and k not in names}
    out = system
    if any(choices[k] != system.choices[k] for k in choices):
        out = replace(system, choices={**system.choices, **choices})
    params = np.array(system.params)
    for name, value in values.items():
        if name in names:
            params[names.index(name)] = number(name, value)
    return out.with_param_vector(params)


def folded_parameter(model, name: str) -> InputError:
    """The error for a name folded into the kernels at compile time when no rebuild is wired."""
    return InputError(f"parameter {name!r} of model {model} was folded into the compiled kernels (a fixed value "
                      "or a structural choice), and this system was built without a way to recompile",
                      key=name, expected="a parameter kept free at compile time (mechgen.compile(..., free=[...])), "
                      "or a system from mechgen.compile, which recompiles for it")


@dataclass(frozen=True, eq=False)
class System:
    """Kernels plus numbers: the object every analysis works on. Immutable.

    ``params`` (the free parameters' values, in ``metadata.params`` order) is a read-only
    array, ``kernels`` and ``meta`` are read-only mappings (``metadata`` is the typed view of
    ``meta``, :class:`~mechgen.runtime.core.meta.SystemMeta`), and no attribute can be assigned
    after construction; :meth:`with_params` gives a
    new system. ``patterns`` is a memo, a pure function of the frozen kernels and ``sites``:
    the CSR patterns of sparse outputs and the prepared single-state kernel calls
    (:class:`BoundKernel`, whose arrays are scratch space); systems that differ only in
    their parameter values share it. ``rebuild(system, values)``, given by the compile
    layer, recompiles for names folded into the kernels (``folded``).
    """

    kernels: dict[str, Kernel]
    meta: dict
    params: np.ndarray
    sites: int = 0
    backend: str = "numpy"
    rebuild: Callable | None = field(default=None, repr=False)
    folded: tuple[str, ...] = ()
    #: the facts of the model it was compiled from (mechgen.scene.info.ModelInfo), set by the compile layer for
    #: a model given as an object (one a reference cannot find again); None: looked up by the model's reference
    facts: object = field(default=None, repr=False, compare=False)
    patterns: dict = field(init=False, repr=False)
    metadata: SystemMeta = field(init=False, repr=False)

    is_field = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "kernels", read_only(self.kernels))
        object.__setattr__(self, "meta", read_only(self.meta))
        object.__setattr__(self, "metadata", SystemMeta.of(self.meta))
        object.__setattr__(self, "params", frozen_vector(self.params))
        object.__setattr__(self, "sites", int(self.sites))
        object.__setattr__(self, "folded", tuple(self.folded))
        object.__setattr__(self, "patterns", {})

    # -- new systems ----------------------------------------------------------
    def with_param_vector(self, params) -> "System":
        """The same kernels with another vector of free parameter values (``meta['params']`` order)."""
        params = replacement_vector(self, params)
        if params is None:
            return self
        new = replace(self, params=params)
        object.__setattr__(new, "patterns", self.patterns)  # same kernels and sites: the same memo
        return new

    def with_params(self, **values) -> "System":
        """A new system with these parameter values (this one is unchanged; itself when no value changes).

        Free numeric parameters give a new parameter vector with the same kernels; a chain's
        number of sites (``meta['sites_param']``) a new size; a name folded into the kernels at
        compile time a recompiled system through ``rebuild`` (InputError without one); any other
        name an InputError listing the known ones.
        """
        names = list(self.metadata.params)
        sites_param = self.metadata.sites_param if self.is_lattice else None
        unknown = [k for k in values if k not in names and k != sites_param and k not in self.folded]
        if unknown:
            raise unknown_parameters(self.metadata.model, unknown,
                                     names + list(self.folded) + ([sites_param] if sites_param else []))
        folded = [k for k in values if k in self.folded]
        if folded:
            if self.rebuild is None:
                raise folded_parameter(self.metadata.model, folded[0])
            return self.rebuild(self, dict(values))
        params = np.array(self.params)
        for name, value in values.items():
            if name in names:
                params[names.index(name)] = number(name, value)
        out = self.with_param_vector(params)
        if sites_param in values:
            sites = values[sites_param]
            if isinstance(sites, bool) or not isinstance(sites, (int, np.integer)) or int(sites) < 1:
                raise InputError(f"parameter {sites_param!r} = {sites!r} is not a number of sites", key=sites_param,
                                 expected="an integer >= 1")
            if int(sites) != out.sites:
                out = replace(out, sites=int(sites))  # a fresh memo: patterns depend on the size
        return out

    def with_layout(self, layout) -> "System":
        """Segments and parts belong to continua; a lumped or chain system has none."""
        raise InputError(f"model {self.metadata.model} is not a continuum", key="segments",
                         expected="segments and parts only for continua")

    def param_values(self) -> dict:
        """The current values of the free parameters (and a chain's number of sites) by name."""
        out = {n: float(v) for n, v in zip(self.metadata.params, self.params)}
        if self.is_lattice and self.metadata.sites_param:
            out[self.metadata.sites_param] = self.sites
        return out

    # -- shape --------------------------------------------------------------
    @property
    def is_lattice(self) -> bool:
        """True for chain models (sparse matrices)."""
        return self.metadata.is_lattice

    @property
    def n(self) -> int:
        """Number of degrees of freedom."""
        return self.sites if self.is_lattice else len(self.metadata.coordinates)

    @property
    def m(self) -> int:
        """Number of internal variables."""
        return len(self.metadata.internal)

    @property
    def coordinates(self) -> list[str]:
        """Coordinate names (for a chain: name_1 .. name_N)."""
        if self.is_lattice:
            return [f"{self.metadata.coordinates[0]}_{i + 1}" for i in range(self.sites)]
        return list(self.metadata.coordinates)

    def sizes(self, kernel: str) -> dict:
        """Runtime sizes of ``kernel``."""
        if not self.is_lattice:
            return {}
        sizes = {"sites": self.sites}
        if "nnz" in self.kernels[kernel].spec["sizes"]:
            sizes["nnz"] = self.pattern(kernel).nnz
        return sizes

    def pattern(self, kernel: str) -> Pattern:
        """CSR pattern of ``kernel``'s sparse outputs (built once)."""
        if kernel not in self.patterns:
            self.patterns[kernel] = build_pattern(self.kernels[kernel].spec, self.sites)
        return self.patterns[kernel]

    # -- evaluation -----------------------------------------------------------
    def bound(self, kernel: str) -> "BoundKernel":
        """A prepared single-state evaluator of ``kernel`` (inputs and outputs allocated once, shared with the
        systems of other parameter values: it is pointed at this system's parameters on every call)."""
        key = ("bound", kernel)
        if key not in self.patterns:
            self.patterns[key] = BoundKernel(self, kernel)
        bound = self.patterns[key]
        bound.use(self.params)
        return bound

    def call(self, kernel: str, *, check: bool = True, **state) -> dict:
        """Evaluate ``kernel`` at a state (missing state entries are zero); ``check``: NaN/Inf raises KernelError."""
        k = self.kernels[kernel]
        inputs = {}
        for port in k.spec["inputs"]:
            name = port["name"]
            if name == "p":
                inputs[name] = self.params
            elif port["integer"]:
                inputs[name] = self.pattern(kernel).slots[name]
            elif name == "t":
                inputs[name] = np.atleast_1d(np.asarray(state.get("t", 0.0), dtype=float))
            else:
                length = self.m if name == "z" else self.n
                value = state.get(name)
                inputs[name] = np.zeros(length) if value is None else np.asarray(value, dtype=float)
        out = k.evaluate(inputs, self.sizes(kernel), check=check)
        return self._shape(kernel, out)

    def _shape(self, kernel: str, out: dict) -> dict:
        shaped = {}
        for port in self.kernels[kernel].spec["outputs"]:
            value = out[port["name"]]
            if port["sparse"]:
                shaped[port["name"]] = self.pattern(kernel).matrix(value)
            elif port["shape"] and value.ndim == 1:
                shaped[port["name"]] = value.reshape(port["shape"])
            else:
                shaped[port["name"]] = value
        return shaped

    def residual(self, q, v=None, a=None, z=None, t=0.0) -> np.ndarray:
        """r(q, v, a, z, t)."""
        return self.call("residual", q=q, v=v, a=a, z=z, t=t)["r"].ravel()

    def tangent(self, q, v=None, a=None, z=None, t=0.0) -> dict:
        """dr/dq, dr/dv, dr/da (and dr/dz): dense n x n, or CSR for chains."""
        return self.call("tangent", q=q, v=v, a=a, z=z, t=t)

    def linear(self, q=None, v=None, z=None, t=0.0) -> dict:
        """M, D, G, K of the linearisation at (q, v, z, t) (a = 0)."""
        mats = self.call("linear", q=q, v=v, z=z, t=t)
        if self.is_lattice:
            import scipy.sparse as sps

            mats["G"] = sps.csr_matrix((self.n, self.n))
        return mats

    def outputs(self, q, v=None, z=None, t=0.0) -> dict[str, float]:
        """Named outputs and energies at a state (NaN/Inf raises KernelError naming the output)."""
        raw = self.bound("outputs").evaluate(q=q, v=v, z=z, t=t)
        values = {k: float(val[0]) for k, val in raw.items()}
        bad = [k for k, val in values.items() if not np.isfinite(val)]
        if bad:
            raise KernelError(f"kernel outputs of {self.metadata.model} produced NaN/Inf in {', '.join(bad)} "
                              f"at q = {np.asarray(q).ravel()[:6].tolist()}")
        return values

    def outputs_series(self, t: np.ndarray, X: np.ndarray) -> dict[str, np.ndarray]:
        """Named outputs and energies at many states in one batched call of the outputs kernel: row k of X is
        (q, v, z) at time t[k]; each output an array over the rows (a chain's sites summed: one call a row)."""
        t, X = np.asarray(t, float), np.asarray(X, float)
        if self.is_lattice:
            rows = [self.outputs(x[:self.n], x[self.n:2 * self.n], x[2 * self.n:] if self.m else None, tk)
                    for tk, x in zip(t, X)]
            return {k: np.array([r[k] for r in rows], float) for k in (rows[0] if rows else {})}
        raw = self.evaluate_series("outputs", t, X)
        return {k: np.asarray(v, float).reshape(len(t), -1)[:, 0] for k, v in raw.items()}

    def evaluate_series(self, kernel: str, t: np.ndarray, X: np.ndarray) -> dict[str, np.ndarray]:
        """The outputs of a lumped kernel of (q, v, z, t) at many states in one batched call: row k of X starts
        with (q, v, z) at time t[k] (columns after them, integrals a run carries, are not read)."""
        n, m = self.n, self.m
        X = np.asarray(X, float)
        inputs = {"q": X[:, :n], "v": X[:, n:2 * n], "z": X[:, 2 * n:2 * n + m],
                  "t": np.asarray(t, float)[:, None], "p": self.params}
        wanted = {port["name"] for port in self.kernels[kernel].spec["inputs"]}
        return self.kernels[kernel].evaluate({k: v for k, v in inputs.items() if k in wanted})

    def force(self, q, t=0.0) -> np.ndarray:
        """Potential force -dV/dq."""
        return self.bound("force").evaluate(q=q, t=t)["f"].copy()

    # -- first-order form -----------------------------------------------------
    def split(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q, v, z) of a first-order state x."""
        n = self.n
        return x[:n], x[n:2 * n], x[2 * n:]

    def _solve(self, M, rhs):
        if not isinstance(M, np.ndarray):  # a scipy.sparse matrix (chains, lattices)
            import scipy.sparse.linalg as spla

            return spla.spsolve(M.tocsc(), rhs)
        if M.shape[0] <= SMALL_DENSE and np.isfinite(M).all() and np.isfinite(rhs).all():
            return np.linalg.solve(M, rhs)  # LAPACK's gesv without scipy's other checks (tens of microseconds)
        import scipy.linalg as sla

        return sla.solve(M, rhs, assume_a="sym") if rhs.ndim == 1 else sla.solve(M, rhs)

    def acceleration(self, q, v, z=None, t=0.0) -> tuple[np.ndarray, object]:
        """a = -M^-1 r(q, v, 0, z, t), and M."""
        if self.is_lattice:
            tan = self.call("tangent", q=q, v=v, z=z, t=t)
            M = tan["r_a"]
            return self._solve(M, -self.residual(q, v, None, z, t)), M
        state = {"q": q, "v": v, "z": z, "t": t}
        if "flow" in self.kernels:  # r and M in one call
            out = self.bound("flow").evaluate(**state)
            r, M = out["r"], out["M"].reshape(self.n, self.n)
        else:
            r = self.bound("residual").evaluate(**state)["r"]
            M = self.bound("tangent").evaluate(**state)["r_a"].reshape(self.n, self.n)
        return mass_solve(M, -r), M

    def rhs(self, t: float, x: np.ndarray) -> np.ndarray:
        """dx/dt of the first-order form (a smooth model without internal variables on the C backend: in one
        compiled call, mechgen.runtime.core.point_rhs)."""
        from mechgen.runtime.core.point_rhs import point_rhs

        fast = point_rhs(self)
        if fast is not None:
            return fast(t, np.asarray(x, dtype=float))
        q, v, z = self.split(x)
        a, _ = self.acceleration(q, v, z, t)
        n = q.size
        out = np.empty(np.size(x))
        out[:n], out[n:2 * n] = v, a
        if out.size > 2 * n:
            out[2 * n:] = self.bound("rates").evaluate(q=q, v=v, z=z, t=t)["g"]
        if not np.isfinite(out).all():
            raise KernelError(f"kernel residual/tangent of {self.metadata.model} gave NaN/Inf at t = {t}, "
                              f"x = {np.asarray(x)[:6]}")
        return out

    def jacobian(self, t: float, x: np.ndarray):
        """d(dx/dt)/dx, exact: da/dx = -M^-1 [r_q, r_v, r_z] at the current acceleration (a smooth model without
        internal variables on the C backend: in one compiled call, mechgen.runtime.core.point_rhs)."""
        from mechgen.runtime.core.point_rhs import point_rhs

        fast = point_rhs(self)
        if fast is not None and fast.J is not None:
            return fast.jacobian(t, np.asarray(x, dtype=float))
        q, v, z = self.split(x)
        a, _ = self.acceleration(q, v, z, t)
        n, m = self.n, self.m
        if self.is_lattice:
            tan = self.call("tangent", q=q, v=v, a=a, z=z, t=t)
        else:
            raw = self.bound("tangent").evaluate(q=q, v=v, a=a, z=z, t=t)
            tan = {k: raw[k].reshape(n, m if k == "r_z" else n) for k in raw}
        blocks = [tan["r_q"], tan["r_v"]] + ([tan["r_z"]] if m else [])
        if self.is_lattice:
            import scipy.sparse as sps
            import scipy.sparse.linalg as spla

            rhs = sps.hstack(blocks).tocsc()
            da = -spla.spsolve(tan["r_a"].tocsc(), rhs)
            top = sps.hstack([sps.csr_matrix((n, n)), sps.identity(n), sps.csr_matrix((n, m))])
            return sps.vstack([top, sps.csr_matrix(da)]).tocsc()
        da = -self._solve(tan["r_a"], np.hstack(blocks))
        J = np.zeros((2 * n + m, 2 * n + m))
        J[:n, n:2 * n] = np.eye(n)
        J[n:2 * n] = da
        if m:
            g = self.bound("rates_tangent").evaluate(q=q, v=v, z=z, t=t)
            J[2 * n:] = np.hstack([g["g_q"].reshape(m, n), g["g_v"].reshape(m, n), g["g_z"].reshape(m, m)])
        return J


@functools.cache
def lapack_dposv():
    """LAPACK's dposv through scipy, imported at the first solve (a scene that never solves with M starts without
    scipy.linalg, 0.2-0.3 s of import)."""
    from scipy.linalg.lapack import dposv

    return dposv


def mass_solve(M: np.ndarray, b: np.ndarray) -> np.ndarray:
    """M^-1 b for a mass matrix M = d2T/dv2: Cholesky (LAPACK dposv, one call, about 1 us for a handful of
    coordinates against 4 us for numpy's LU), and LU (numpy, which raises on a singular M) where M is not
    positive definite."""
    if not M.size:  # a model of internal variables only
        return np.zeros_like(b)
    _, x, info = lapack_dposv()(M, b)
    return x if info == 0 else np.linalg.solve(M, b)


class BoundKernel:
    """Single-state evaluation with preallocated arrays and a prepared call (the hot path).

    ``evaluate(q=..., v=...)`` copies the given state into the kernel's input
    arrays (absent entries are zero), calls the kernel and returns its output
    arrays (views that the next call overwrites; copy to keep them). The
    parameter input is a private copy of the (read-only) parameter vector last
    given to :meth:`use`.
    """

    def __init__(self, system: System, kernel: str) -> None:
        k = system.kernels[kernel]
        sizes = system.sizes(kernel)
        self.inputs: dict[str, np.ndarray] = {}
        for port in k.spec["inputs"]:
            name = port["name"]
            if name == "p":
                self.inputs[name] = np.array(system.params, dtype=float)
            elif port["integer"]:
                self.inputs[name] = system.pattern(kernel).slots[name]
            else:
                self.inputs[name] = np.zeros(extent(port["extent"], sizes))
        self.outputs = {p["name"]: np.zeros(extent(p["extent"], sizes)) for p in k.spec["outputs"]}
        self._params = system.params
        self._call = k.bind(self.inputs, self.outputs, sizes)

    def use(self, params: np.ndarray) -> None:
        """Evaluate with the parameter vector ``params`` from now on (a copy when it is another array)."""
        if params is not self._params:
            if "p" in self.inputs:
                self.inputs["p"][...] = params
            self._params = params

    def evaluate(self, **state) -> dict[str, np.ndarray]:
        """Outputs at ``state`` (q, v, a, z as arrays, t as a number)."""
        for name, arr in self.inputs.items():
            if name in ("p",) or name.startswith("slots"):
                continue
            value = state.get(name)
            if value is None:
                arr[...] = 0.0
            else:
                arr[...] = value
        self._call()
        return self.outputs
