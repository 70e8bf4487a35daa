"""A BVP as a square system F(u, lam) = 0 for continuation: collocation on a fixed mesh, or multiple shooting.

The problem is a :class:`mechgen.runtime.steady.bvp.BVP` (y' = f(s, y, p), g(y(a), y(b), p) = 0,
``p[unknown]`` solved for); lam = p[lam_index] is the continuation parameter and the other
parameters stay fixed. Mesh a = s_0 < ... < s_M = b, h_i = s_{i+1} - s_i. Three schemes:

* ``collocation``: 3-stage Lobatto IIIA (Hermite-Simpson), 4th order at the nodes.
  u = (y_0, ..., y_M, p_u); interval i::

      y_m = (y_i + y_{i+1})/2 - h (f_{i+1} - f_i)/8,
      r_i = y_{i+1} - y_i - h (f_i + 4 f(s_i + h/2, y_m) + f_{i+1})/6.

* ``gauss``: s-stage Gauss-Legendre collocation (c_j the Gauss points on [0, 1], a_jl and
  b_j the Runge-Kutta tableau), order 2s at the nodes, stage order s. The stage values are
  unknowns: u = (y_0, ..., y_M, Y_{0,1}, ..., Y_{M-1,s}, p_u); interval i::

      R^Y_ij = Y_ij - y_i - h sum_l a_jl f(s_i + c_j h, Y_il),   (stage rows)
      r_i    = y_{i+1} - y_i - h sum_j b_j f(s_i + c_j h, Y_ij).  (node rows)

  The Newton systems are condensed interval by interval: with J_ij = f_y at the stages
  and E_i = I - h (A x I) diag(J_i1 .. J_is), dY_i = E_i^-1 (rhs^Y_i + (1 x I) dy_i +
  h (A x I) f_q dq), so the node rows become y_{i+1} - (I + h sum_j b_j J_ij X_ij) y_i ...
  with X_i = E_i^-1 (1 x I): a block-bidiagonal system in the nodes (the Jacobian of the
  implicit Runge-Kutta step), factored by SuperLU with the continuation's border, and the
  stage increments follow by back-substitution. The stages are slaved to the nodes, so the
  arclength of a branch measures the nodes and parameters only (``arclength_weights``).
  The dense output is the collocation polynomial of each interval (order s + 1 uniformly).
* ``multiple_shooting``: the continuity conditions of the flows between the nodes
  (mechgen.runtime.steady.bvp.multiple_shoot), u = (Y_0, ..., Y_K, p_u).

The rows are the interval (or continuity) rows, then g, then (gauss) the stage rows; F_u
is a CSC matrix and F_lam a vector. For :func:`mechgen.runtime.steady.continuation.continuation`
the discretisation also offers ``evaluate(u, lam, jac)`` (the residual alone when ``jac``
is False, and the last point cached), ``bordered(J, F_lam, row)`` (a solver of the
bordered Newton system [[F_u, F_lam], [row]] that keeps the sparsity pattern between calls)
and ``arclength_weights``. Only the parameter columns the continuation needs (lam and the
unknown parameters) of f_p are evaluated when the problem's f_p takes ``cols``.
"""
from __future__ import annotations

import numpy as np

from mechgen.errors import ConvergenceError, InputError
from mechgen.runtime.core.lazy_import import lazy_module
from mechgen.runtime.steady.bvp import (BVP, BVPResult, BudgetSpent, IVPFailure, IVPOptions, ShootingResidual,
                                        full_parameters, ivp_options, mesh_nodes)

sps = lazy_module("scipy.sparse")
spla = lazy_module("scipy.sparse.linalg")

METHODS = ("collocation", "gauss", "multiple_shooting")

#: the integration of multiple shooting's flows unless told otherwise (rtol_ivp 1e-10, else the IVPOptions defaults)
IVP_DEFAULTS = IVPOptions(rtol_ivp=1e-10)


def gauss_tableau(stages: int):
    """Gauss-Legendre collocation on [0, 1]: points c (s,), matrix A (s, s), weights b (s,) and the
    power-basis coefficients Lc (s, s) of the Lagrange polynomials (ell_j(t) = sum_m Lc[j, m] t^m)."""
    x, w = np.polynomial.legendre.leggauss(int(stages))
    c, b = (x + 1) / 2, w / 2
    Lc = np.linalg.inv(np.vander(c, stages, increasing=True).T)
    powers = np.arange(1, stages + 1)
    A = (c[:, None] ** powers[None, :] / powers) @ Lc.T
    return c, A, b, Lc


class _Pattern:
    """The CSC structure of [[A_i, B_i, P_i] interval blocks; [G_a, G_b, G_p] rows] (size N = n (M + 1) + k),
    optionally bordered by a dense column and row; ``matrix(...)`` fills it in a fixed order."""

    def __init__(self, n: int, M: int, k: int, bordered: bool):
        N = n * (M + 1) + k
        self.shape = (N + 1, N + 1) if bordered else (N, N)
        i, r, c = np.meshgrid(np.arange(M), np.arange(n), np.arange(n), indexing="ij")
        rows, cols = [i * n + r, i * n + r], [i * n + c, (i + 1) * n + c]
        if k:
            i2, r2, c2 = np.meshgrid(np.arange(M), np.arange(n), np.arange(k), indexing="ij")
            rows.append(i2 * n + r2)
            cols.append(n * (M + 1) + c2)
        br, bc = np.meshgrid(np.arange(n + k), np.arange(n), indexing="ij")
        rows += [n * M + br, n * M + br]
        cols += [bc, n * M + bc]
        if k:
            pr, pc = np.meshgrid(np.arange(n + k), np.arange(k), indexing="ij")
            rows.append(n * M + pr)
            cols.append(n * (M + 1) + pc)
        if bordered:
            rows += [np.arange(N), np.full(N + 1, N)]
            cols += [np.full(N, N), np.arange(N + 1)]
        rows = np.concatenate([x.ravel() for x in rows])
        cols = np.concatenate([x.ravel() for x in cols])
        order = sps.csc_matrix((np.arange(rows.size, dtype=float) + 1, (rows, cols)), shape=self.shape)
        order.has_sorted_indices = True
        self.order = order.data.astype(np.int64) - 1
        self.indices, self.indptr = order.indices.copy(), order.indptr.copy()

    def matrix(self, parts) -> sps.csc_matrix:
        data = np.concatenate([np.ravel(x) for x in parts])[self.order]
        return sps.csc_matrix((data, self.indices, self.indptr), shape=self.shape)


def _lu(A: sps.csc_matrix):
    if not np.all(np.isfinite(A.data)):
        raise np.linalg.LinAlgError("the bordered Jacobian is not finite")
    try:
        lu = spla.splu(A, permc_spec="MMD_AT_PLUS_A")  # banded blocks + border: little fill
    except RuntimeError as exc:
        raise np.linalg.LinAlgError(str(exc)) from exc
    return lu


class _Blocks:
    """The (condensed) Jacobian: interval blocks A, B, P (unknown parameters), boundary rows, and for
    Gauss collocation the condensation (E^-1, X, Z, stage Jacobians)."""

    def __init__(self, **kw):
        self.__dict__.update(kw)


class DiscreteBVP:
    """A BVP discretised as F(u, lam) = 0, lam = p[lam_index] (see the module doc).

    ``method``: 'collocation' (Hermite-Simpson), 'gauss' (``stages`` Gauss-Legendre points per
    interval, default 4: order 8) or 'multiple_shooting' (``mesh`` the shooting nodes; its flows
    are integrated as ``ivp`` says, :data:`IVP_DEFAULTS` when None, with keyword ``overrides`` of
    single :class:`~mechgen.runtime.steady.bvp.IVPOptions`). The other parameters are fixed at ``p``.
    """

    def __init__(self, problem: BVP, lam_index: int, p, mesh, *, method: str = "collocation",
                 stages: int | None = None, ivp: IVPOptions | None = None, **overrides):
        ivp = IVPOptions.of(IVP_DEFAULTS if ivp is None else ivp, **overrides)
        if method not in METHODS:
            raise InputError(f"{problem.name}: unknown discretisation {method!r}", key="method",
                             expected="'collocation', 'gauss' or 'multiple_shooting'")
        self.problem, self.method = problem, method
        self.p = full_parameters(problem, p)
        if not (isinstance(lam_index, (int, np.integer)) and 0 <= lam_index < problem.n_p) \
                or lam_index in problem.unknown:
            raise InputError(f"{problem.name}: lam_index = {lam_index!r} (unknown parameters: "
                             f"{list(problem.unknown)}, n_p = {problem.n_p})", key="lam_index",
                             expected="the index of a fixed parameter")
        self.lam_index = int(lam_index)
        self.mesh = mesh_nodes(problem, mesh)
        n, M, k = problem.n, len(self.mesh) - 1, problem.k
        self.stages = 0
        if method == "gauss":
            self.stages = 4 if stages is None else int(stages)
            if not 1 <= self.stages <= 10:
                raise InputError(f"{problem.name}: {stages} Gauss stages", key="stages", expected="1 to 10")
            self.c, self.A, self.b, self.Lc = gauss_tableau(self.stages)
        label = {"collocation": "Hermite-Simpson collocation", "gauss": f"{self.stages}-stage Gauss collocation",
                 "multiple_shooting": "multiple shooting"}[method]
        self.name = f"{problem.name} ({label}, {M} intervals)"
        self.n_nodes = n * (M + 1)
        self.n_stages = n * self.stages * M
        self.n_unknowns = self.n_nodes + self.n_stages + k
        self.rows_g = n * M + n + k     # rows: intervals (n M), g (n + k), then the stage rows (Gauss)
        self.unk = list(problem.unknown)
        self.cols = self.unk + [self.lam_index]  # the parameter columns of f_p the Newton systems need
        if method == "multiple_shooting":
            opts = ivp_options(problem, ivp)
            self._ms = ShootingResidual(problem, self.mesh, opts)
        else:
            self._plain = _Pattern(n, M, k, bordered=False)
            self._border = _Pattern(n, M, k, bordered=True)
        self.arclength_weights = None
        if self.n_stages:
            w = np.ones(self.n_unknowns + 1)
            w[self.n_nodes:self.n_nodes + self.n_stages] = 0.0
            self.arclength_weights = w
        self._key, self._cache = None, {}

    # layout --------------------------------------------------------------------------
    def pack(self, Y, p=None, stages=None) -> np.ndarray:
        """u from node values Y (n, M + 1), the parameter vector (default: the fixed one) and, for Gauss
        collocation, the stage values (M, s, n) (default: Y interpolated linearly)."""
        Y = np.asarray(Y, float)
        q = self.p if p is None else full_parameters(self.problem, p)
        if Y.shape != (self.problem.n, len(self.mesh)):
            raise InputError(f"{self.name}: node values of shape {Y.shape}", key="Y",
                             expected=f"shape ({self.problem.n}, {len(self.mesh)})")
        parts = [Y.T.ravel()]
        if self.n_stages:
            if stages is None:
                stages = (Y[:, :-1, None] + (Y[:, 1:] - Y[:, :-1])[:, :, None] * self.c).transpose(1, 2, 0)
            parts.append(np.asarray(stages, float).ravel())
        return np.concatenate(parts + [q[self.unk]])

    def _stage_points(self) -> np.ndarray:
        """The Gauss points s_i + c_j h_i, interval-major (M s,)."""
        if not hasattr(self, "_st"):
            h = np.diff(self.mesh)
            self._st = (self.mesh[:-1, None] + h[:, None] * self.c[None, :]).ravel()
        return self._st

    def start(self, guess: BVPResult):
        """(u0, lam0) from a solution (or guess) given as a BVPResult (its dense output at the mesh and stages)."""
        n = self.problem.n
        Y = np.asarray(guess.sol(self.mesh), float).reshape(n, -1)
        self.problem.check(Y[:, 0], full_parameters(self.problem, guess.p))
        stages = None
        if self.n_stages:
            M = len(self.mesh) - 1
            stages = np.asarray(guess.sol(self._stage_points()), float).reshape(n, M, self.stages).transpose(1, 2, 0)
        return self.pack(Y, guess.p, stages), float(guess.p[self.lam_index])

    def unpack(self, u, lam):
        """(Y (n, M + 1), full p) from u and lam."""
        u = np.asarray(u, float)
        if u.shape != (self.n_unknowns,):
            raise InputError(f"{self.name}: u has shape {u.shape}", key="u", expected=f"({self.n_unknowns},)")
        n, M = self.problem.n, len(self.mesh) - 1
        q = self.p.copy()
        q[self.unk] = u[self.n_nodes + self.n_stages:]
        q[self.lam_index] = lam
        return u[: self.n_nodes].reshape(M + 1, n).T, q

    def _stage_values(self, u) -> np.ndarray:
        """Stage values (M, s, n) of Gauss collocation."""
        M = len(self.mesh) - 1
        return np.asarray(u, float)[self.n_nodes:self.n_nodes + self.n_stages].reshape(M, self.stages, -1)

    # f and its derivatives ----------------------------------------------------------------
    def _fp(self, s, Y, q) -> np.ndarray:
        """d f / d p at the points for the columns ``self.cols``: (n, len(cols), m)."""
        return self.problem.f_pv(s, Y, q, cols=self.cols)

    # residual and Jacobian ---------------------------------------------------------------
    def evaluate(self, u, lam, jac: bool = True):
        """(F, J, F_lam) at (u, lam); with ``jac`` False (F, None, None). J is the discretisation's own
        Jacobian (see :meth:`bordered`; :meth:`F_u` gives it as a matrix). NaN F where the
        residual cannot be evaluated."""
        key = (np.asarray(u, float).tobytes(), float(lam))
        if key != self._key:
            self._key, self._cache = key, {}
        cache = self._cache
        if "F" not in cache or (jac and "J" not in cache):
            with np.errstate(all="ignore"):
                if self.method == "multiple_shooting":
                    self._shooting(u, lam, cache)
                elif self.method == "gauss":
                    self._gauss(u, lam, cache, jac)
                else:
                    self._hermite_simpson(u, lam, cache, jac)
        if not jac:
            return cache["F"], None, None
        return cache["F"], cache.get("J"), cache.get("Fl")

    def _shooting(self, u, lam, cache):
        Y, q = self.unpack(u, lam)
        self._ms.opts["budget"].used = 0          # the budget is per evaluation here
        try:
            R, J, dl = self._ms.evaluate(np.asarray(u, float), q, extra_cols=[self.lam_index])
            cache.update(F=R, J=J, Fl=dl[:, 0])
        except (IVPFailure, BudgetSpent):
            nan = np.full(self.n_unknowns, np.nan)
            cache.update(F=nan, J=None, Fl=nan)

    def _hermite_simpson(self, u, lam, cache, jac):
        prob = self.problem
        Y, q = self.unpack(u, lam)
        n, k = prob.n, prob.k
        s = self.mesh
        h = np.diff(s)
        M = h.size
        sm = s[:-1] + 0.5 * h
        if "F" not in cache:
            F = prob.fv(s, Y, q)
            ym = 0.5 * (Y[:, 1:] + Y[:, :-1]) - 0.125 * h * (F[:, 1:] - F[:, :-1])
            Fm = prob.fv(sm, ym, q)
            R = np.empty(self.n_unknowns)
            R[: n * M] = (Y[:, 1:] - Y[:, :-1] - h / 6 * (F[:, :-1] + 4 * Fm + F[:, 1:])).T.ravel()
            R[n * M:] = prob.bc(Y[:, 0], Y[:, -1], q)
            cache.update(F=R, f_nodes=F, ym=ym)
        if not jac:
            return
        F, ym = cache["f_nodes"], cache["ym"]
        Jn = prob.f_yv(s, Y, q)
        Pn = self._fp(s, Y, q)
        Jm = prob.f_yv(sm, ym, q)
        Pm = self._fp(sm, ym, q)
        eye = np.eye(n)[:, :, None]
        Ji, Jj = Jn[:, :, :-1], Jn[:, :, 1:]
        A = -eye - h / 6 * (Ji + 4 * np.einsum("abm,bcm->acm", Jm, 0.5 * eye + 0.125 * h * Ji))
        B = eye - h / 6 * (Jj + 4 * np.einsum("abm,bcm->acm", Jm, 0.5 * eye - 0.125 * h * Jj))
        dym_dp = -0.125 * h * (Pn[:, :, 1:] - Pn[:, :, :-1])
        P = -h / 6 * (Pn[:, :, :-1] + 4 * (np.einsum("abm,bcm->acm", Jm, dym_dp) + Pm) + Pn[:, :, 1:])
        Ga, Gb, Gp = prob.bc_jac(Y[:, 0], Y[:, -1], q)
        blocks = _Blocks(A=A.transpose(2, 0, 1), B=B.transpose(2, 0, 1), P=P[:, :k, :].transpose(2, 0, 1),
                         Ga=Ga, Gb=Gb, Gp=Gp[:, self.unk])
        Fl = np.empty(self.n_unknowns)
        Fl[: n * M] = P[:, k, :].T.ravel()
        Fl[n * M:] = Gp[:, self.lam_index]
        cache.update(J=blocks, Fl=Fl)

    def _gauss(self, u, lam, cache, jac):
        prob = self.problem
        Y, q = self.unpack(u, lam)
        n, k, S = prob.n, prob.k, self.stages
        h = np.diff(self.mesh)
        M = h.size
        st = self._stage_points()
        Ys = self._stage_values(u)                              # (M, S, n)
        Yflat = Ys.reshape(M * S, n).T                          # (n, M S), interval-major
        if "F" not in cache:
            K = prob.fv(st, Yflat, q).T.reshape(M, S, n)        # f at the stages
            R = np.empty(self.n_unknowns)
            R[: n * M] = (Y[:, 1:].T - Y[:, :-1].T - h[:, None] * np.matmul(self.b, K)).ravel()
            R[n * M: self.rows_g] = prob.bc(Y[:, 0], Y[:, -1], q)
            RY = Ys - Y[:, :-1].T[:, None, :] - h[:, None, None] * np.matmul(self.A, K)
            R[self.rows_g:] = RY.ravel()
            cache.update(F=R, K=K)
        if not jac:
            return
        J = np.transpose(prob.f_yv(st, Yflat, q), (2, 0, 1)).reshape(M, S, n, n)
        Fq = np.transpose(self._fp(st, Yflat, q), (2, 0, 1)).reshape(M, S, n, k + 1)
        AJ = self.A[None, :, None, :, None] * J.transpose(0, 2, 1, 3)[:, None]          # [i, j, a, l, b]
        E = np.eye(S * n) - h[:, None, None] * AJ.reshape(M, S * n, S * n)
        try:
            Einv = np.linalg.inv(E)
        except np.linalg.LinAlgError:  # a singular stage system: no Newton step from here
            cache.update(J=None, Fl=None)
            return
        X = Einv.reshape(M, S * n, S, n).sum(axis=2)                                     # E^-1 (1 x I)
        D = h[:, None, None] * np.matmul(self.A, Fq.reshape(M, S, n * (k + 1))).reshape(M, S * n, k + 1)
        Z = Einv @ D                                                                      # E^-1 h (A x I) f_q
        bJ = self.b[None, :, None, None] * J
        bJX = (bJ @ X.reshape(M, S, n, n)).sum(axis=1)
        bJZ = (bJ @ Z.reshape(M, S, n, k + 1)).sum(axis=1)
        bFq = np.matmul(self.b, Fq.reshape(M, S, n * (k + 1))).reshape(M, n, k + 1)
        Pq = -h[:, None, None] * (bJZ + bFq)                                             # (M, n, k + 1)
        Ga, Gb, Gp = prob.bc_jac(Y[:, 0], Y[:, -1], q)
        blocks = _Blocks(A=-(np.eye(n) + h[:, None, None] * bJX), B=np.broadcast_to(np.eye(n), (M, n, n)),
                         P=Pq[:, :, :k], Ga=Ga, Gb=Gb, Gp=Gp[:, self.unk], Pl=Pq[:, :, k], Gl=Gp[:, self.lam_index],
                         J=J, bJ=bJ, Fq=Fq, D=D, Einv=Einv, X=X, Z=Z)
        Fl = np.empty(self.n_unknowns)
        Fl[: n * M] = (-h[:, None] * bFq[..., k]).ravel()
        Fl[n * M: self.rows_g] = Gp[:, self.lam_index]
        Fl[self.rows_g:] = -D[..., k].ravel()
        cache.update(J=blocks, Fl=Fl)

    # linear algebra --------------------------------------------------------------------
    def bordered(self, J, Fl, row):
        """A solver x = solve(rhs) of [[F_u, F_lam], [row^T]] x = rhs at the Jacobian J of :meth:`evaluate`
        (raises numpy.linalg.LinAlgError when singular or not finite)."""
        row = np.asarray(row, float)
        if self.method == "multiple_shooting":
            return _sparse_bordered(J, Fl, row)
        if self.method == "collocation":
            lu = _lu(self._border.matrix([J.A, J.B, J.P, J.Ga, J.Gb, J.Gp, Fl, row]))

            def solve(rhs):
                return _finite(lu.solve(np.asarray(rhs, float)))

            return solve
        n, M, S = self.problem.n, len(self.mesh) - 1, self.stages
        N0, N1 = self.n_nodes, self.n_nodes + self.n_stages
        wY = row[N0:N1].reshape(M, S * n)
        r_nodes = row[:N0].copy().reshape(M + 1, n)
        r_nodes[:-1] += np.matmul(J.X.transpose(0, 2, 1), wY[:, :, None])[:, :, 0]
        r_q = row[N1:] + np.tensordot(J.Z, wY, axes=([0, 1], [0, 1]))
        red = np.concatenate([r_nodes.ravel(), r_q])
        Fl_red = np.concatenate([J.Pl.ravel(), J.Gl])
        lu = _lu(self._border.matrix([J.A, J.B, J.P, J.Ga, J.Gb, J.Gp, Fl_red, red]))
        h = np.diff(self.mesh)
        G = self.rows_g

        def solve(rhs):
            rhs = np.asarray(rhs, float)
            Y0 = np.matmul(J.Einv, rhs[G:-1].reshape(M, S * n, 1))[:, :, 0]                 # E^-1 rhs^Y
            top = rhs[: n * M].reshape(M, n) + h[:, None] * np.matmul(J.bJ, Y0.reshape(M, S, n, 1))[..., 0].sum(1)
            r = np.concatenate([top.ravel(), rhs[n * M:G], [rhs[-1] - np.sum(wY * Y0)]])
            x = lu.solve(r)
            dy = x[:N0].reshape(M + 1, n)
            dq = x[N0:]
            dY = Y0 + np.matmul(J.X, dy[:-1, :, None])[:, :, 0] + J.Z @ dq
            return _finite(np.concatenate([x[:N0], dY.ravel(), x[N0:]]))

        return solve

    def _matrix(self, J) -> sps.csc_matrix:
        """F_u as a CSC matrix (for callers outside the continuation)."""
        if self.method == "multiple_shooting":
            return J
        plain = self._plain.matrix([J.A, J.B, J.P, J.Ga, J.Gb, J.Gp]) if self.method == "collocation" else None
        if plain is not None:
            return plain
        # Gauss: the uncondensed Jacobian (rows: node rows, g, stage rows; columns: nodes, stages, p_u)
        n, M, k, S = self.problem.n, len(self.mesh) - 1, self.problem.k, self.stages
        N0, N1, G = self.n_nodes, self.n_nodes + self.n_stages, self.rows_g
        h = np.diff(self.mesh)
        out = sps.lil_matrix((self.n_unknowns, self.n_unknowns))
        eye = np.eye(n)
        for i in range(M):
            rows = slice(i * n, (i + 1) * n)
            out[rows, i * n:(i + 1) * n] = -eye
            out[rows, (i + 1) * n:(i + 2) * n] = eye
            srows = slice(G + i * S * n, G + (i + 1) * S * n)
            for j in range(S):
                stage_row = slice(G + (i * S + j) * n, G + (i * S + j + 1) * n)
                out[rows, N0 + (i * S + j) * n:N0 + (i * S + j + 1) * n] = -h[i] * self.b[j] * J.J[i, j]
                out[stage_row, i * n:(i + 1) * n] = -eye
                for ll in range(S):
                    block = (eye if j == ll else 0.0) - h[i] * self.A[j, ll] * J.J[i, ll]
                    out[stage_row, N0 + (i * S + ll) * n:N0 + (i * S + ll + 1) * n] = block
            if k:
                out[rows, N1:] = -h[i] * np.einsum("j,jac->ac", self.b, J.Fq[i, :, :, :k])
                out[srows, N1:] = -J.D[i, :, :k]
        out[n * M:G, :n] = J.Ga
        out[n * M:G, n * M:N0] = J.Gb
        if k:
            out[n * M:G, N1:] = J.Gp
        return out.tocsc()

    def F(self, u, lam):
        return self.evaluate(u, lam, jac=False)[0]

    def F_u(self, u, lam):
        J = self.evaluate(u, lam)[1]
        return None if J is None else self._matrix(J)

    def F_lam(self, u, lam):
        return self.evaluate(u, lam)[2]

    # outputs -------------------------------------------------------------------------
    def to_result(self, u, lam, *, residual_norm: float | None = None, iterations: int = 0) -> BVPResult:
        """The BVPResult of a point (u, lam): node values, parameters and a dense output (cubic Hermite
        with f at the nodes for Hermite-Simpson, the collocation polynomials for Gauss, the
        integrator's for shooting)."""
        Y, q = self.unpack(u, lam)
        if residual_norm is None:
            residual_norm = float(np.linalg.norm(self.F(u, lam)))
        if self.method == "multiple_shooting":
            try:
                self._ms.opts["budget"].used = 0
                s, y, dense, _ = self._ms.dense(np.asarray(u, float), q)
            except (IVPFailure, BudgetSpent) as exc:
                raise ConvergenceError(f"{self.name}: the trajectory through this point fails: {exc}") from None
            return BVPResult(s, y, q, residual_norm, iterations, "multiple shooting", dense)
        if self.method == "gauss":
            K = self._cache["K"] if self._key == (np.asarray(u, float).tobytes(), float(lam)) else \
                self.problem.fv(self._stage_points(), self._stage_values(u).reshape(-1, self.problem.n).T,
                                q).T.reshape(len(self.mesh) - 1, self.stages, -1)
            return BVPResult(self.mesh.copy(), Y, q, residual_norm, iterations, "Gauss collocation (fixed mesh)",
                             _CollocationPolynomial(self.mesh, Y, K, self.Lc))
        F = self._cache["f_nodes"] if self._key == (np.asarray(u, float).tobytes(), float(lam)) else \
            self.problem.fv(self.mesh, Y, q)
        from scipy.interpolate import CubicHermiteSpline  # loaded on use: scipy.interpolate brings scipy.optimize

        spline = CubicHermiteSpline(self.mesh, Y, F, axis=1)
        return BVPResult(self.mesh.copy(), Y, q, residual_norm, iterations, "collocation (fixed mesh)", spline)

    def output(self, fun, grad=None):
        """Turn a boundary output fun(ya, yb, p) -> float into phi(u, lam), and, with
        grad(ya, yb, p) -> (d/dya (n,), d/dyb (n,), d/dp (n_p,)), its gradient
        (u, lam) -> (d phi/du (N,), d phi/dlam). Returns (phi, gradient or None)."""
        n, M = self.problem.n, len(self.mesh) - 1

        def phi(u, lam):
            Y, q = self.unpack(u, lam)
            return float(fun(Y[:, 0], Y[:, -1], q))

        if grad is None:
            return phi, None

        def gradient(u, lam):
            Y, q = self.unpack(u, lam)
            ga, gb, gp = (np.asarray(v, float).ravel() for v in grad(Y[:, 0], Y[:, -1], q))
            if ga.shape != (n,) or gb.shape != (n,) or gp.shape != (self.problem.n_p,):
                raise InputError(f"{self.name}: the output gradient has shapes {ga.shape}, {gb.shape}, {gp.shape}",
                                 key="grad", expected=f"({n},), ({n},), ({self.problem.n_p},)")
            g = np.zeros(self.n_unknowns)
            g[:n] += ga
            g[n * M: n * (M + 1)] += gb
            g[self.n_nodes + self.n_stages:] = gp[self.unk]
            return g, float(gp[self.lam_index])

        return phi, gradient


class _CollocationPolynomial:
    """The Gauss collocation solution as a piecewise polynomial: on [s_i, s_i + h], with t = (s - s_i)/h,
    y = y_i + h sum_j K_ij int_0^t ell_j (K_ij = f at the stages); (n,) for a scalar s, else (n, len(s))."""

    def __init__(self, mesh, Y, K, Lc):
        S = Lc.shape[0]
        h = np.diff(mesh)
        m = np.arange(S)
        # coefficient of (s - s_i)^(m + 1): sum_j K_ij Lc[j, m] / ((m + 1) h^m)
        coef = np.einsum("ija,jm->mia", K, Lc) / ((m + 1)[:, None, None] * h[None, :, None] ** m[:, None, None])
        c = np.concatenate([coef[::-1], Y[:, :-1].T[None]], axis=0)  # descending powers, constant last
        from scipy.interpolate import PPoly  # loaded on use: scipy.interpolate brings scipy.optimize

        self._pp = PPoly(c, np.asarray(mesh, float), extrapolate=True)

    def __call__(self, s):
        out = self._pp(np.asarray(s, float))
        return out.T if np.ndim(s) else out


def _finite(x):
    if not np.all(np.isfinite(x)):
        raise np.linalg.LinAlgError("the solution of the bordered system is not finite")
    return x


def _sparse_bordered(Fu, Fl, row):
    """Bordered solver for a plain sparse F_u (SuperLU)."""
    n = Fl.size
    A = sps.vstack([sps.hstack([Fu, sps.csc_matrix(Fl.reshape(n, 1))]),
                    sps.csr_matrix(row.reshape(1, n + 1))], format="csc")
    lu = _lu(A)
    return lambda rhs: _finite(lu.solve(np.asarray(rhs, float)))
