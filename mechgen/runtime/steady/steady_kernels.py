"""Batched evaluation of a steady form's kernels: u_ss, its Jacobian and parameter derivatives.

The steady equations r(u, u_s, u_ss; s, p) = 0 (kernels ``bvp_residual`` with output r and
``bvp_tangent`` with r_q, r_v, r_a) are linear in u_ss (Euler-Lagrange equations of a
first-order density), so at a batch of points

    H = r_a(u, u_s),   u_ss = -H^-1 r(u, u_s, 0),
    d u_ss / d(u, u_s) = -H^-1 [r_q, r_v]  at (u, u_s, u_ss),
    d u_ss / d p_j     = -H^-1 d r(u, u_s, u_ss; s(p), p) / d p_j  at fixed u_ss

(the last by the implicit function theorem, r(u, u_s, u_ss(p); s(p), p) = 0; the partial
derivative in p_j by central differences of the residual alone, with s moving with p when a
parameter sets the length). The kernels are called through prepared calls
(:meth:`mechgen.runtime.core.kernels.Kernel.bind`) on buffers kept per batch size, and the last few
batches are memoised, so f, f_y and f_p at the same points share one evaluation. Non-finite
kernel values give NaN results (callers test finiteness: a Newton step that leaves the
physical states is then shortened instead of stopping the run).
"""
from __future__ import annotations

import numpy as np

MEMO = 4           # batches remembered (collocation alternates between node and stage points)
REL_STEP = 1e-6    # relative central-difference step in a parameter


def batched_inverse(H: np.ndarray) -> np.ndarray:
    """Inverses of a stack (m, n, n): adjugates for n <= 3 (a few vectorised products instead of m LAPACK
    calls), numpy.linalg.inv otherwise; singular or non-finite matrices give NaN or Inf."""
    n = H.shape[-1]
    if n == 1:
        return 1.0 / H
    if n == 2:
        a, b, c, d = H[:, 0, 0], H[:, 0, 1], H[:, 1, 0], H[:, 1, 1]
        adj = np.stack([np.stack([d, -b], -1), np.stack([-c, a], -1)], -2)
        return adj / (a * d - b * c)[:, None, None]
    if n == 3:  # columns of the inverse: cross products of the rows, over the determinant
        a, b, c = H[:, 0].T, H[:, 1].T, H[:, 2].T
        out = np.empty_like(H)
        for k, (u, v) in enumerate(((b, c), (c, a), (a, b))):
            out[:, 0, k] = u[1] * v[2] - u[2] * v[1]
            out[:, 1, k] = u[2] * v[0] - u[0] * v[2]
            out[:, 2, k] = u[0] * v[1] - u[1] * v[0]
        det = a[0] * out[:, 0, 0] + a[1] * out[:, 1, 0] + a[2] * out[:, 2, 0]
        return out / det[:, None, None]
    try:
        return np.linalg.inv(H)
    except np.linalg.LinAlgError:
        out = np.full(H.shape, np.nan)
        for i, Hi in enumerate(H):
            try:
                out[i] = np.linalg.inv(Hi)
            except np.linalg.LinAlgError:
                pass
        return out


class _Batch:
    """Buffers and prepared kernel calls for batches of m points."""

    def __init__(self, residual, tangent, n: int, m: int, n_p: int):
        f = np.zeros
        self.q, self.v, self.zero, self.acc = f((m, n)), f((m, n)), f((m, n)), f((m, n))
        self.t, self.tp = f((m, 1)), f((m, 1))
        self.p, self.pp = f(n_p), f(n_p)
        z = f((m, 0))
        self.r0, self.rp = f((m, n)), f((m, n))
        self.tan0 = {"r_q": f((m, n * n)), "r_v": f((m, n * n)), "r_a": f((m, n * n)), "r_z": f((m, 0))}
        self.tan1 = {k: np.zeros_like(v) for k, v in self.tan0.items()}
        base = {"q": self.q, "v": self.v, "z": z}
        self.call_r0 = residual.bind({**base, "a": self.zero, "t": self.t, "p": self.p}, {"r": self.r0})
        self.call_h = tangent.bind({**base, "a": self.zero, "t": self.t, "p": self.p}, self.tan0)
        self.call_tan = tangent.bind({**base, "a": self.acc, "t": self.t, "p": self.p}, self.tan1)
        self.call_rp = residual.bind({**base, "a": self.acc, "t": self.tp, "p": self.pp}, {"r": self.rp})


class SteadyAccelerations:
    """u_ss and its derivatives from the steady residual and tangent kernels (see the module doc)."""

    def __init__(self, residual, tangent, n: int):
        self.residual, self.tangent, self.n = residual, tangent, int(n)
        self._batches: dict[tuple, _Batch] = {}
        self._memo: dict[bytes, dict] = {}

    def _batch(self, m: int, n_p: int) -> _Batch:
        key = (m, n_p)
        if key not in self._batches:
            if len(self._batches) > 16:
                self._batches.clear()
            self._batches[key] = _Batch(self.residual, self.tangent, self.n, m, n_p)
        return self._batches[key]

    def _entry(self, s, y, p) -> dict:
        """The memo entry of the batch (s, y, p): u_ss and H^-1, loading the buffers."""
        n = self.n
        s = np.ascontiguousarray(s, float).ravel()
        y = np.asarray(y, float)
        p = np.ascontiguousarray(p, float).ravel()
        key = s.tobytes() + np.ascontiguousarray(y).tobytes() + p.tobytes()
        hit = self._memo.get(key)
        if hit is not None:
            return hit
        m = y.shape[1]
        b = self._batch(m, p.size)
        b.q[...] = y[:n].T
        b.v[...] = y[n:].T
        b.t[:, 0] = s
        b.p[...] = p
        b.call_r0()
        b.call_h()
        H = b.tan0["r_a"].reshape(m, n, n)
        with np.errstate(all="ignore"):
            finite = np.isfinite(H).all(axis=(1, 2)) & np.isfinite(b.r0).all(axis=1)
            Hinv = np.full((m, n, n), np.nan)
            if finite.all():
                Hinv = batched_inverse(H)
            elif finite.any():
                Hinv[finite] = batched_inverse(H[finite])
            acc = -np.matmul(Hinv, b.r0[:, :, None])[:, :, 0]
        entry = {"acc": acc, "Hinv": Hinv, "s": s, "y": y.copy(), "p": p.copy(), "batch": b}
        if len(self._memo) >= MEMO:
            self._memo.pop(next(iter(self._memo)))
        self._memo[key] = entry
        return entry

    def _load(self, entry: dict) -> _Batch:
        """Point the batch's buffers at the entry's state (another batch of the same size may have used them)."""
        b, n = entry["batch"], self.n
        b.q[...] = entry["y"][:n].T
        b.v[...] = entry["y"][n:].T
        b.t[:, 0] = entry["s"]
        b.p[...] = entry["p"]
        b.acc[...] = entry["acc"]
        return b

    def accelerations(self, s, y, p) -> np.ndarray:
        """u_ss at the points: (m, n)."""
        return self._entry(s, y, p)["acc"]

    def jacobian(self, s, y, p) -> tuple[np.ndarray, np.ndarray]:
        """(u_ss (m, n), d u_ss / d(u, u_s) (m, n, 2n))."""
        entry = self._entry(s, y, p)
        if "jac" not in entry:
            n = self.n
            b = self._load(entry)
            b.call_tan()
            m = b.q.shape[0]
            rhs = np.concatenate([b.tan1["r_q"].reshape(m, n, n), b.tan1["r_v"].reshape(m, n, n)], axis=2)
            with np.errstate(all="ignore"):
                entry["jac"] = -np.matmul(entry["Hinv"], rhs)
        return entry["acc"], entry["jac"]

    def parameter_derivatives(self, s_of, y, p, cols) -> np.ndarray:
        """d u_ss / d p_j for j in ``cols`` at fixed (u, u_s): (m, n, len(cols)).

        ``s_of(p)`` gives the batch's positions s for a parameter vector (they move with a length
        parameter). Central differences of the residual at the actual u_ss, steps REL_STEP |p_j|
        (at least REL_STEP * 1e-3).
        """
        p = np.asarray(p, float).ravel()
        entry = self._entry(s_of(p), y, p)
        cols = [int(j) for j in cols]
        cached = entry.setdefault("dp", {})
        missing = [j for j in cols if j not in cached]
        if missing:
            b = self._load(entry)
            m = b.q.shape[0]
            for j in missing:
                step = REL_STEP * max(abs(p[j]), 1e-3)
                diff = np.zeros((m, self.n))
                for sign in (1.0, -1.0):
                    b.pp[...] = p
                    b.pp[j] += sign * step
                    b.tp[:, 0] = s_of(b.pp)
                    b.call_rp()
                    diff += sign * b.rp
                with np.errstate(all="ignore"):
                    cached[j] = -np.matmul(entry["Hinv"], diff[:, :, None] / (2 * step))[:, :, 0]
        return np.stack([cached[j] for j in cols], axis=2)
