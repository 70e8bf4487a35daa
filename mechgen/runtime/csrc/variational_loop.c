/* mechgen variational_loop.c: the time loop of a Gauss-Legendre variational integrator in C (C99).
 *
 * The rules are those of mechgen/runtime/core/variational.py (its module doc has the equations): one step
 * of length h from (q_k, p_k) at t_k solves for the stage velocities V_i (i < s)
 *
 *     R_i(V) = p(Q_i, V_i, t_k + c_i h) - p_k - h sum_j a_ij F(Q_j, V_j, t_k + c_j h) = 0,
 *     Q_i = q_k + h sum_j a_ij V_j,
 *
 * by Newton with dR_i/dV_j = h a_ij p_q(i) + d_ij p_v(i) - h^2 sum_l a_il a_lj F_q(l) - h a_ij F_v(j), stopping
 * at the first correction below rtol * max|V| (or below stall * max|V| and no longer halving); the point
 * evaluated last is accepted, and q_{k+1} = q_k + h sum_i b_i V_i, p_{k+1} = p_k + h sum_i b_i F_i.
 * p, F and their Jacobians come from the model's own compiled ``lagrangian`` kernel, called through its address
 * with the mechgen ABI int mg_NAME(const double *const *in, double *const *out, const long *sizes, long nbatch);
 * inputs (q, v, z, t, p) (z empty, p the parameters), outputs (mom = p, F, mom_q = p_q, mom_v = p_v, F_q, F_v),
 * matrices row-major n x n.
 *
 * With the model's ``energy_rates`` kernel (``rates``, not NULL: inputs (q, v, z, t, p), outputs g = (Q.v,
 * v.dR/dv, -dL/dt) and the excess), the three integrals W of the energy balance (mechgen.analyses.energy_balance)
 * advance by the same quadrature, W += h sum_i b_i g(Q_i, V_i, t_k + c_i h): the Gauss method applied to W' = g.
 *
 * Entry point: mgv_run(...) advances ``steps`` steps from global step k0 (t = (k0 + j) h) and copies q, p, W and
 * the velocity guess sum_i b_i V_i into the records after every global step that is a multiple of save_every
 * or equals ``total``. Returns 0, a kernel's nonzero code (> 0), -1 when the state became NaN/Inf, -2 when
 * Newton did not converge in max_newton iterations, -3 for a singular Jacobian; *done holds the steps taken.
 */
#include <math.h>
#include <stddef.h>

typedef int (*mgv_fn)(const double *const *in, double *const *out, const long *sizes, long nbatch);

static const long mgv_no_sizes[1] = {0}; /* a lumped kernel has no runtime sizes */

/* LU factorisation with partial pivoting of the m x m row-major A, in place; 1 when singular */
static int mgv_lu(double *A, long m, long *piv)
{
    long i, j, k, r;
    for (k = 0; k < m; ++k) {
        double big = 0.0;
        r = k;
        for (i = k; i < m; ++i)
            if (fabs(A[i * m + k]) > big) {
                big = fabs(A[i * m + k]);
                r = i;
            }
        if (big == 0.0) return 1;
        piv[k] = r;
        if (r != k)
            for (j = 0; j < m; ++j) {
                double tmp = A[k * m + j];
                A[k * m + j] = A[r * m + j];
                A[r * m + j] = tmp;
            }
        for (i = k + 1; i < m; ++i) {
            double f = A[i * m + k] / A[k * m + k];
            A[i * m + k] = f;
            for (j = k + 1; j < m; ++j) A[i * m + j] -= f * A[k * m + j];
        }
    }
    return 0;
}

static void mgv_solve(const double *A, long m, const long *piv, double *x)
{
    long i, j;
    for (i = 0; i < m; ++i) {
        double tmp = x[piv[i]];
        x[piv[i]] = x[i];
        x[i] = tmp;
    }
    for (i = 1; i < m; ++i)
        for (j = 0; j < i; ++j) x[i] -= A[i * m + j] * x[j];
    for (i = m - 1; i >= 0; --i) {
        for (j = i + 1; j < m; ++j) x[i] -= A[i * m + j] * x[j];
        x[i] /= A[i * m + i];
    }
}

/* p, F, p_q, p_v, F_q, F_v of stage i at (Q_i, V_i, t) into the stage arrays */
static int mgv_eval(mgv_fn lag, const double *par, long n, const double *Q, const double *V, double t, double *P,
                    double *F, double *pq, double *pv, double *Fq, double *Fv)
{
    const double *in[5];
    double *out[6];
    double tt = t, z = 0.0;
    long j;
    for (j = 0; j < n; ++j) P[j] = F[j] = 0.0;
    for (j = 0; j < n * n; ++j) pq[j] = pv[j] = Fq[j] = Fv[j] = 0.0;
    in[0] = Q;
    in[1] = V;
    in[2] = &z;
    in[3] = &tt;
    in[4] = par;
    out[0] = P;
    out[1] = F;
    out[2] = pq;
    out[3] = pv;
    out[4] = Fq;
    out[5] = Fv;
    return lag(in, (double *const *)out, mgv_no_sizes, 1);
}

/* the stage residual R (s n) and Jacobian J (s n x s n) at the stage velocities V; the stage forces stay in F */
static int mgv_system(mgv_fn lag, const double *par, long n, long s, const double *A, const double *c, double h,
                      double t, const double *q, const double *p, const double *V, double *Q, double *P, double *F,
                      double *pq, double *pv, double *Fq, double *Fv, double *R, double *J)
{
    long i, j, l, a, b, m = s * n, nn = n * n;
    int rc;
    for (i = 0; i < s; ++i)
        for (a = 0; a < n; ++a) {
            double sum = q[a];
            for (j = 0; j < s; ++j) sum += h * A[i * s + j] * V[j * n + a];
            Q[i * n + a] = sum;
        }
    for (i = 0; i < s; ++i) {
        rc = mgv_eval(lag, par, n, &Q[i * n], &V[i * n], t + c[i] * h, &P[i * n], &F[i * n], &pq[i * nn],
                      &pv[i * nn], &Fq[i * nn], &Fv[i * nn]);
        if (rc) return rc;
    }
    for (i = 0; i < s; ++i)
        for (a = 0; a < n; ++a) {
            double sum = P[i * n + a] - p[a];
            for (j = 0; j < s; ++j) sum -= h * A[i * s + j] * F[j * n + a];
            R[i * n + a] = sum;
        }
    for (i = 0; i < s; ++i)
        for (j = 0; j < s; ++j)
            for (a = 0; a < n; ++a)
                for (b = 0; b < n; ++b) {
                    double e = h * A[i * s + j] * pq[i * nn + a * n + b] - h * A[i * s + j] * Fv[j * nn + a * n + b];
                    if (i == j) e += pv[i * nn + a * n + b];
                    for (l = 0; l < s; ++l) e -= h * h * A[i * s + l] * A[l * s + j] * Fq[l * nn + a * n + b];
                    J[(i * n + a) * m + j * n + b] = e;
                }
    return 0;
}

/* W += h sum_i b_i g(Q_i, V_i, t + c_i h) over the stages (g: the three powers of the energy balance) */
static int mgv_powers(mgv_fn rates, const double *par, long n, long s, const double *b, const double *c, double h,
                      double t, const double *Q, const double *V, double *W)
{
    const double *in[5];
    double *out[2];
    double g[3], excess, tt, z = 0.0;
    long i, j;
    int rc;
    for (i = 0; i < s; ++i) {
        tt = t + c[i] * h;
        g[0] = g[1] = g[2] = excess = 0.0;
        in[0] = &Q[i * n];
        in[1] = &V[i * n];
        in[2] = &z;
        in[3] = &tt;
        in[4] = par;
        out[0] = g;
        out[1] = &excess;
        rc = rates(in, (double *const *)out, mgv_no_sizes, 1);
        if (rc) return rc;
        for (j = 0; j < 3; ++j) W[j] += h * b[i] * g[j];
    }
    return 0;
}

static double mgv_maxabs(const double *x, long m)
{
    double big = 0.0;
    long i;
    for (i = 0; i < m; ++i) {
        if (isnan(x[i])) return x[i];
        if (fabs(x[i]) > big) big = fabs(x[i]);
    }
    return big;
}

int mgv_run(mgv_fn lag, mgv_fn rates, const double *par, long n, long s, const double *A, const double *b,
            const double *c, double h, long k0, long steps, long total, long save_every, double rtol, double stall,
            long max_newton, double *q, double *p, double *V, double *W, double *work, long *piv, double *rec_q,
            double *rec_p, double *rec_v, double *rec_w, double *rec_t, long *nrec, long *done, long *newton)
{
    long m = s * n, nn = n * n, j, i, a, it;
    double *Q = work, *P = Q + m, *F = P + m, *R = F + m, *pq = R + m, *pv = pq + s * nn, *Fq = pv + s * nn;
    double *Fv = Fq + s * nn, *J = Fv + s * nn;
    int rc;
    *done = 0;
    for (j = 0; j < steps; ++j) {
        long k = k0 + j;
        double t = (double)k * h, previous = INFINITY;
        int accepted = 0;
        for (it = 1; it <= max_newton; ++it) {
            double size, scale;
            rc = mgv_system(lag, par, n, s, A, c, h, t, q, p, V, Q, P, F, pq, pv, Fq, Fv, R, J);
            if (rc) return rc;
            if (mgv_lu(J, m, piv)) return -3;
            mgv_solve(J, m, piv, R);
            size = mgv_maxabs(R, m);
            scale = mgv_maxabs(V, m);
            if (!isfinite(size) || !isfinite(scale)) return -1;
            if (scale < 1e-300) scale = 1e-300;
            if (size <= rtol * scale || (size <= stall * scale && size > 0.5 * previous) || size == 0.0) {
                accepted = 1;
                break;
            }
            for (i = 0; i < m; ++i) V[i] -= R[i];
            previous = size;
        }
        if (!accepted) return -2;
        *newton += it;
        if (rates) {
            rc = mgv_powers(rates, par, n, s, b, c, h, t, Q, V, W);
            if (rc) return rc;
        }
        for (a = 0; a < n; ++a) {
            double dq = 0.0, dp = 0.0;
            for (i = 0; i < s; ++i) {
                dq += b[i] * V[i * n + a];
                dp += b[i] * F[i * n + a];
            }
            q[a] += h * dq;
            p[a] += h * dp;
        }
        *done = j + 1;
        if ((k + 1) % save_every == 0 || k + 1 == total) {
            if (!isfinite(mgv_maxabs(q, n)) || !isfinite(mgv_maxabs(p, n))) return -1;
            for (a = 0; a < n; ++a) {
                double v = 0.0;
                for (i = 0; i < s; ++i) v += b[i] * V[i * n + a];
                rec_q[*nrec * n + a] = q[a];
                rec_p[*nrec * n + a] = p[a];
                rec_v[*nrec * n + a] = v;
            }
            for (a = 0; a < 3; ++a) rec_w[*nrec * 3 + a] = W[a];
            rec_t[*nrec] = (double)(k + 1) * h;
            ++*nrec;
        }
    }
    return 0;
}
