/* mechgen radau_loop.c: the compiled Radau IIA loop of a smooth lumped system (C99).
 *
 * Integrates x = (q, v, z, w) with dq/dt = v, dv/dt = a = -M^-1 r(q, v, 0, z, t) (M = dr/da),
 * d(z, w)/dt = rates(q, v, z, t) (w: `extra` integrals after the internal variables, whose rates follow dz/dt
 * in the rates kernel's output), from the model's own compiled kernels called through their addresses with the
 * mechgen ABI int mg_NAME(const double *const *in, double *const *out, const long *sizes, long nbatch), and its
 * Jacobian
 *
 *     J = [[0, I, 0, 0], [-M^-1 r_q, -M^-1 r_v, -M^-1 r_z, 0], [g_q, g_v, g_z, 0], [0, 0, 0, 0]]
 *
 * from the `tangent` kernel (r_q, r_v, r_a = M, r_z at the current acceleration a) and `rates_tangent`
 * (g_q, g_v, g_z); the integrals' rows are zero, as mechgen/runtime/integration/augmented.py borders them.
 * Stepped by the implicit Radau IIA method of order 5 (3 stages) exactly as scipy.integrate.Radau steps it
 * (scipy/integrate/_ivp/radau.py, scipy 1.17, BSD-3-Clause: the transformed Newton system with one real LU of
 * MU_REAL/h I - J and one complex LU of MU_COMPLEX/h I - J, at most NEWTON_MAXITER iterations with the
 * convergence-rate test, the error estimate with its extra solve after a rejection, the predictive (Gustafsson)
 * step-size controller, the Jacobian re-evaluated when Newton converged slowly or failed with an old one, the
 * LUs redone when h changes; the collocation dense output; the initial step of select_initial_step with order 3).
 * Dense LU with partial pivoting (real and complex) of the nx x nx matrices: O(nx^3) per factorisation.
 *
 * Entry points: mgr_run(problem, state) runs from the state (state->work NULL: from the start, allocating the
 * workspace it keeps between calls) until t_end, a slice of steps or an error, and returns a code (MGR_*);
 * mgr_free(state) releases the workspace; mgr_layout(i) the sizes of the structs the Python side mirrors.
 */
#include <complex.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dense_lu.h"

typedef int (*mgr_fn)(const double *const *in, double *const *out, const long *sizes, long nbatch);

#define MGR_PORTS 8
#define MGR_PICKS 4
#define MGR_NEWTON_MAXITER 6
#define MGR_MIN_FACTOR 0.2
#define MGR_MAX_FACTOR 10.0

enum { MGR_IN_Q = 0, MGR_IN_V = 1, MGR_IN_A = 2, MGR_IN_Z = 3, MGR_IN_T = 4, MGR_IN_P = 5 };

enum {
    MGR_DONE = 0,          /* t_end reached */
    MGR_SLICE = 5,         /* `slice` steps done: the caller checks its clock and calls again */
    MGR_E_KERNEL = -1,     /* a kernel returned nonzero (err_kind, err_rc) */
    MGR_E_RHS = -2,        /* dx/dt is NaN/Inf at (err_t, err_x) */
    MGR_E_JAC = -3,        /* the Jacobian is NaN/Inf at (err_t, err_x) */
    MGR_E_SINGULAR = -5,   /* M (err_kind 0) or a Newton matrix (err_kind 1) is singular at (err_t, err_x) */
    MGR_E_SMALL = -6,      /* the step size fell below 10 ulp of t (err_t) */
    MGR_E_BUDGET = -9,     /* more than budget_left steps */
    MGR_E_MEMORY = -11,
    MGR_E_INPUT = -12
};

/* which kernel (err_kind of MGR_E_KERNEL) */
enum { MGR_K_FLOW = 0, MGR_K_RESIDUAL = 1, MGR_K_TANGENT = 2, MGR_K_RATES = 3, MGR_K_RATES_TANGENT = 4, MGR_NK = 5 };

typedef struct {
    mgr_fn fn;                 /* NULL: absent */
    long nin, nout;
    long ports[MGR_PORTS];     /* MGR_IN_* of each input */
    long out_len[MGR_PORTS];   /* entries of each output */
    long pick[MGR_PICKS];      /* outputs used: flow r, M; residual r; tangent r_a, r_q, r_v, r_z; rates g;
                                  rates_tangent g_q, g_v, g_z (-1: not used) */
} mgr_kernel;

typedef struct {
    long n, m, extra;          /* x = (q[n], v[n], z[m], w[extra]) */
    mgr_kernel kernels[MGR_NK];   /* by MGR_K_*: flow (or residual and tangent's r_a) gives dv/dt */
    const double *p;
    double rtol, atol, t_end;
    long n_eval;               /* samples at t_eval (sorted, in [0, t_end]) written to s_x (n_eval x nx) */
    const double *t_eval;
    double *s_x;
    long budget_left;          /* accepted steps allowed (-1: no limit) */
    long slice;                /* return MGR_SLICE after this many steps in one call (0: never) */
    const double *atol_v;      /* nx absolute tolerances, one per state (NULL: atol for every state) */
} mgr_problem;

typedef struct {
    double t;
    double *x;                 /* nx: x0 on the first call, then the state at t */
    long steps, nfev, njev, nlu, i_eval, counted;
    long err_kind, err_rc;
    double err_t;
    double *err_x;             /* nx */
    void *work;                /* the workspace kept between calls (NULL before the first) */
    double h_last;             /* the latest accepted step's size */
} mgr_state;

long mgr_layout(long which);
long mgr_layout(long which)
{
    switch (which) {
    case 0: return (long)sizeof(mgr_kernel);
    case 1: return (long)sizeof(mgr_problem);
    case 2: return (long)sizeof(mgr_state);
    default: return -1;
    }
}

/* ---- scipy/integrate/_ivp/radau.py's constants ---- */
static const double C[3] = {0.15505102572168222, 0.6449489742783178, 1.0};
static const double E[3] = {-10.048809399827414, 1.382142733160748, -0.3333333333333333};
static const double MU_REAL = 3.637834252744496;
#define MU_COMPLEX (2.6810828736277523 - 3.050430199247411 * I)
static const double T[3][3] = {
    {0.09443876248897524, -0.14125529502095421, 0.03002919410514742},
    {0.25021312296533332, 0.20412935229379994, -0.38294211275726192},
    {1.0, 1.0, 0.0}};
static const double TI[3][3] = {
    {4.17871859155190428, 0.32768282076106237, 0.52337644549944951},
    {-4.17871859155190428, -0.32768282076106237, 0.47662355450055044},
    {0.50287263494578682, -2.57192694985560522, 0.59603920482822492}};
static const double P[3][3] = {
    {10.048809399827414, -25.62959144707664, 15.580782047249224},
    {-1.382142733160748, 10.296258113743303, -8.914115380582556},
    {0.3333333333333333, -2.6666666666666665, 3.3333333333333335}};

/* the workspace: the solver's state between steps (scipy's Radau attributes) and scratch */
typedef struct {
    long n, m, nx;
    double t, t_old, h_abs, h_abs_old, err_old;
    int has_old, has_sol, current_jac, lu_valid;
    double *y, *f, *y_old, *Z, *Q, *J, *LUr, *scale, *F, *W, *dW, *Z0, *ytmp, *fr, *err, *ZE, *y_new, *f_new;
    double *M, *B, *zeros;
    double _Complex *LUc, *fc;
    long *piv_r, *piv_c;
    double *kout[MGR_NK][MGR_PORTS];
    double *mem;
} mgr_work;

static int kcall(const mgr_problem *P_, mgr_state *S, mgr_work *w, long kind, const double *x, const double *a,
                 double t)
{
    const mgr_kernel *k = &P_->kernels[kind];
    const double *in[MGR_PORTS];
    double tt = t;
    long sizes = 0, i;
    int rc;
    for (i = 0; i < k->nin; ++i) {
        switch (k->ports[i]) {
        case MGR_IN_Q: in[i] = x; break;
        case MGR_IN_V: in[i] = x + w->n; break;
        case MGR_IN_A: in[i] = a != NULL ? a : w->zeros; break;
        case MGR_IN_Z: in[i] = w->m ? x + 2 * w->n : w->zeros; break;
        case MGR_IN_T: in[i] = &tt; break;
        default: in[i] = P_->p != NULL ? P_->p : w->zeros; break;
        }
    }
    rc = k->fn(in, w->kout[kind], &sizes, 1);
    if (rc != 0) {
        S->err_kind = kind;
        S->err_rc = rc;
        S->err_t = t;
        return MGR_E_KERNEL;
    }
    return 0;
}

static const double *picked(mgr_work *w, const mgr_problem *P_, long kind, long j)
{
    return w->kout[kind][P_->kernels[kind].pick[j]];
}

static void fail_at(mgr_state *S, mgr_work *w, double t, const double *x)
{
    S->err_t = t;
    memcpy(S->err_x, x, (size_t)w->nx * sizeof(double));
}

/* mg_lu_factor (dense_lu.h) over the complex numbers (pivot on |Re| + |Im|, as LAPACK's zgetrf) */
static int lu_complex(long n, double _Complex *A, long *piv)
{
    long i, j, k, p;
    double big;
    double _Complex l, s;
    for (k = 0; k < n; ++k) {
        p = k;
        big = fabs(creal(A[k * n + k])) + fabs(cimag(A[k * n + k]));
        for (i = k + 1; i < n; ++i)
            if (fabs(creal(A[i * n + k])) + fabs(cimag(A[i * n + k])) > big) {
                big = fabs(creal(A[i * n + k])) + fabs(cimag(A[i * n + k]));
                p = i;
            }
        piv[k] = p;
        if (big == 0.0)
            return 1;
        if (p != k)
            for (j = 0; j < n; ++j) {
                s = A[k * n + j];
                A[k * n + j] = A[p * n + j];
                A[p * n + j] = s;
            }
        for (i = k + 1; i < n; ++i) {
            l = A[i * n + k] /= A[k * n + k];
            if (l != 0.0)
                for (j = k + 1; j < n; ++j)
                    A[i * n + j] -= l * A[k * n + j];
        }
    }
    return 0;
}

static void solve_complex(long n, const double _Complex *A, const long *piv, double _Complex *b)
{
    long i, j;
    double _Complex s;
    for (i = 0; i < n; ++i) {
        if (piv[i] != i) {
            s = b[i];
            b[i] = b[piv[i]];
            b[piv[i]] = s;
        }
        for (j = 0; j < i; ++j)
            b[i] -= A[i * n + j] * b[j];
    }
    for (i = n - 1; i >= 0; --i) {
        s = b[i];
        for (j = i + 1; j < n; ++j)
            s -= A[i * n + j] * b[j];
        b[i] = s / A[i * n + i];
    }
}

/* M (n x n) = dr/da at a = 0 into w->M and r at a = 0 into w->B: the flow kernel's one call, or residual + tangent */
static int mass_and_residual(const mgr_problem *P_, mgr_state *S, mgr_work *w, double t, const double *x)
{
    long n = w->n, i;
    int rc;
    if (P_->kernels[MGR_K_FLOW].fn != NULL) {
        if ((rc = kcall(P_, S, w, MGR_K_FLOW, x, NULL, t)) != 0)
            return rc;
        memcpy(w->M, picked(w, P_, MGR_K_FLOW, 1), (size_t)(n * n) * sizeof(double));
        for (i = 0; i < n; ++i)
            w->B[i] = -picked(w, P_, MGR_K_FLOW, 0)[i];
        return 0;
    }
    if ((rc = kcall(P_, S, w, MGR_K_RESIDUAL, x, NULL, t)) != 0)
        return rc;
    for (i = 0; i < n; ++i)
        w->B[i] = -picked(w, P_, MGR_K_RESIDUAL, 0)[i];
    if ((rc = kcall(P_, S, w, MGR_K_TANGENT, x, NULL, t)) != 0)
        return rc;
    memcpy(w->M, picked(w, P_, MGR_K_TANGENT, 0), (size_t)(n * n) * sizeof(double));
    return 0;
}

/* f = dx/dt at (t, x) = (v, -M^-1 r(q, v, 0, z, t), rates); MGR_E_RHS when NaN/Inf, MGR_E_SINGULAR for M */
static int rhs(const mgr_problem *P_, mgr_state *S, mgr_work *w, double t, const double *x, double *f)
{
    long n = w->n, nz = w->nx - 2 * n, i;
    int rc;
    if (n > 0) {   /* n = 0: a model of internal variables only, dx/dt = rates */
        if ((rc = mass_and_residual(P_, S, w, t, x)) != 0)
            return rc;
        if (mg_lu_factor(n, w->M, w->piv_r + w->nx)) {
            fail_at(S, w, t, x);
            S->err_kind = 0;
            return MGR_E_SINGULAR;
        }
        mg_lu_apply(n, w->M, w->piv_r + w->nx, w->B);
        memcpy(f, x + n, (size_t)n * sizeof(double));
        memcpy(f + n, w->B, (size_t)n * sizeof(double));
    }
    if (nz > 0) {
        if ((rc = kcall(P_, S, w, MGR_K_RATES, x, NULL, t)) != 0)
            return rc;
        memcpy(f + 2 * n, picked(w, P_, MGR_K_RATES, 0), (size_t)nz * sizeof(double));
    }
    S->nfev++;
    for (i = 0; i < w->nx; ++i)
        if (!isfinite(f[i])) {
            fail_at(S, w, t, x);
            return MGR_E_RHS;
        }
    return 0;
}

/* J = d(dx/dt)/dx at (t, x) with f = dx/dt there (module doc) into w->J */
static int jacobian(const mgr_problem *P_, mgr_state *S, mgr_work *w, double t, const double *x, const double *f)
{
    long n = w->n, m = w->m, nx = w->nx, cols = 2 * n + m, i, j, k;
    const double *blk;
    int rc;
    memset(w->J, 0, (size_t)(nx * nx) * sizeof(double));
    if (n == 0)   /* internal variables only: no mass rows */
        goto rates_rows;
    if ((rc = kcall(P_, S, w, MGR_K_TANGENT, x, f + n, t)) != 0)
        return rc;
    memcpy(w->M, picked(w, P_, MGR_K_TANGENT, 0), (size_t)(n * n) * sizeof(double));
    for (k = 0; k < 2 + (m > 0); ++k) {   /* B (n x cols) = [r_q, r_v, r_z] */
        long width = k < 2 ? n : m;
        blk = picked(w, P_, MGR_K_TANGENT, 1 + k);
        for (i = 0; i < n; ++i)
            for (j = 0; j < width; ++j)
                w->B[i * cols + k * n + j] = blk[i * width + j];
    }
    if (mg_lu_factor(n, w->M, w->piv_r + nx)) {
        fail_at(S, w, t, x);
        S->err_kind = 0;
        return MGR_E_SINGULAR;
    }
    for (j = 0; j < cols; ++j) {          /* column j of -M^-1 B */
        for (i = 0; i < n; ++i)
            w->ytmp[i] = w->B[i * cols + j];
        mg_lu_apply(n, w->M, w->piv_r + nx, w->ytmp);
        for (i = 0; i < n; ++i)
            w->J[(n + i) * nx + j] = -w->ytmp[i];
    }
    for (i = 0; i < n; ++i)
        w->J[i * nx + n + i] = 1.0;
rates_rows:
    if (m > 0) {
        if ((rc = kcall(P_, S, w, MGR_K_RATES_TANGENT, x, NULL, t)) != 0)
            return rc;
        for (k = 0; k < 3; ++k) {
            long width = k < 2 ? n : m;
            blk = picked(w, P_, MGR_K_RATES_TANGENT, k);
            for (i = 0; i < m; ++i)
                for (j = 0; j < width; ++j)
                    w->J[(2 * n + i) * nx + k * n + j] = blk[i * width + j];
        }
    }
    S->njev++;
    for (i = 0; i < nx * nx; ++i)
        if (!isfinite(w->J[i])) {
            fail_at(S, w, t, x);
            return MGR_E_JAC;
        }
    return 0;
}

/* scipy's norm: the root mean square of a[i] / scale[i % nx] over `count` entries */
/* the absolute tolerance of state j: scipy's atol, a scalar or one per state */
static double abs_tol(const mgr_problem *P_, long j)
{
    return P_->atol_v ? P_->atol_v[j] : P_->atol;
}

static double rms(const double *a, const double *scale, long count, long nx)
{
    long i;
    double s = 0.0, r;
    for (i = 0; i < count; ++i) {
        r = a[i] / scale[i % nx];
        s += r * r;
    }
    return sqrt(s / (double)count);
}

/* the LUs of MU_REAL/h I - J and MU_COMPLEX/h I - J (scipy's self.lu, counted in nlu) */
static int factorise(mgr_state *S, mgr_work *w, double h, double t)
{
    long nx = w->nx, i;
    for (i = 0; i < nx * nx; ++i) {
        w->LUr[i] = -w->J[i];
        w->LUc[i] = -w->J[i];
    }
    for (i = 0; i < nx; ++i) {
        w->LUr[i * nx + i] += MU_REAL / h;
        w->LUc[i * nx + i] += MU_COMPLEX / h;
    }
    S->nlu += 2;
    if (mg_lu_factor(nx, w->LUr, w->piv_r) || lu_complex(nx, w->LUc, w->piv_c)) {
        fail_at(S, w, t, w->y);
        S->err_kind = 1;
        return MGR_E_SINGULAR;
    }
    w->lu_valid = 1;
    return 0;
}

/* scipy's solve_collocation_system from w->Z0 into w->Z: *converged, *n_iter, *rate (-1: none) */
static int collocation(const mgr_problem *P_, mgr_state *S, mgr_work *w, double t, double h, double tol,
                       int *converged, int *n_iter, double *rate)
{
    long nx = w->nx, i, j;
    int k, rc;
    double dW_norm, dW_norm_old = -1.0, Mr = MU_REAL / h;
    double _Complex Mc = MU_COMPLEX / h;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < nx; ++j) {
            w->W[i * nx + j] = TI[i][0] * w->Z0[j] + TI[i][1] * w->Z0[nx + j] + TI[i][2] * w->Z0[2 * nx + j];
            w->Z[i * nx + j] = w->Z0[i * nx + j];
        }
    *converged = 0;
    *rate = -1.0;
    for (k = 0; k < MGR_NEWTON_MAXITER; ++k) {
        *n_iter = k + 1;
        for (i = 0; i < 3; ++i) {
            for (j = 0; j < nx; ++j)
                w->ytmp[j] = w->y[j] + w->Z[i * nx + j];
            if ((rc = rhs(P_, S, w, t + h * C[i], w->ytmp, w->F + i * nx)) != 0)
                return rc;
        }
        for (j = 0; j < nx; ++j) {
            const double F0 = w->F[j], F1 = w->F[nx + j], F2 = w->F[2 * nx + j];
            w->fr[j] = F0 * TI[0][0] + F1 * TI[0][1] + F2 * TI[0][2] - Mr * w->W[j];
            w->fc[j] = F0 * (TI[1][0] + TI[2][0] * I) + F1 * (TI[1][1] + TI[2][1] * I)
                       + F2 * (TI[1][2] + TI[2][2] * I) - Mc * (w->W[nx + j] + w->W[2 * nx + j] * I);
        }
        mg_lu_apply(nx, w->LUr, w->piv_r, w->fr);
        solve_complex(nx, w->LUc, w->piv_c, w->fc);
        for (j = 0; j < nx; ++j) {
            w->dW[j] = w->fr[j];
            w->dW[nx + j] = creal(w->fc[j]);
            w->dW[2 * nx + j] = cimag(w->fc[j]);
        }
        dW_norm = rms(w->dW, w->scale, 3 * nx, nx);
        if (dW_norm_old >= 0.0)
            *rate = dW_norm / dW_norm_old;
        if (*rate >= 0.0 && (*rate >= 1.0 || pow(*rate, MGR_NEWTON_MAXITER - k) / (1.0 - *rate) * dW_norm > tol))
            break;
        for (i = 0; i < 3 * nx; ++i)
            w->W[i] += w->dW[i];
        for (i = 0; i < 3; ++i)
            for (j = 0; j < nx; ++j)
                w->Z[i * nx + j] = T[i][0] * w->W[j] + T[i][1] * w->W[nx + j] + T[i][2] * w->W[2 * nx + j];
        if (dW_norm == 0.0 || (*rate >= 0.0 && *rate / (1.0 - *rate) * dW_norm < tol)) {
            *converged = 1;
            break;
        }
        dW_norm_old = dW_norm;
    }
    return 0;
}

/* scipy's predict_factor (has_old: h_abs_old and error_norm_old are known) */
static double predict_factor(double h_abs, double h_abs_old, int has_old, double error_norm, double error_norm_old)
{
    double multiplier = 1.0;
    if (has_old && error_norm != 0.0)
        multiplier = h_abs / h_abs_old * pow(error_norm_old / error_norm, 0.25);
    return fmin(1.0, multiplier) * pow(error_norm, -0.25);
}

/* the collocation polynomial of the last step at tt: y_old + Q (x, x^2, x^3), x = (tt - t_old) / h */
static void dense(const mgr_work *w, double tt, double *out)
{
    long nx = w->nx, j;
    double x = (tt - w->t_old) / (w->t - w->t_old), p0 = x, p1 = p0 * x, p2 = p1 * x;
    for (j = 0; j < nx; ++j)
        out[j] = (w->Q[3 * j] * p0 + w->Q[3 * j + 1] * p1 + w->Q[3 * j + 2] * p2) + w->y_old[j];
}

/* Z0: the last step's collocation polynomial at t + h C (minus y), or zero before the first step */
static void predict_stages(mgr_work *w, double t, double h)
{
    long nx = w->nx, i, j;
    if (!w->has_sol) {
        memset(w->Z0, 0, (size_t)(3 * nx) * sizeof(double));
        return;
    }
    for (i = 0; i < 3; ++i) {
        dense(w, t + h * C[i], w->Z0 + i * nx);
        for (j = 0; j < nx; ++j)
            w->Z0[i * nx + j] -= w->y[j];
    }
}

/* the error estimate of an accepted Newton solve (scipy's Radau._step_impl): error = LU_real^-1 (f + ZE), ZE =
 * Z^T E / h; after a rejection the estimate is refined with one more solve at y + error */
static int error_estimate(const mgr_problem *P_, mgr_state *S, mgr_work *w, double t, double h, int rejected,
                          double *error_norm)
{
    long nx = w->nx, j;
    int rc;
    for (j = 0; j < nx; ++j) {
        w->y_new[j] = w->y[j] + w->Z[2 * nx + j];
        w->ZE[j] = (w->Z[j] * E[0] + w->Z[nx + j] * E[1] + w->Z[2 * nx + j] * E[2]) / h;
        w->err[j] = w->f[j] + w->ZE[j];
    }
    mg_lu_apply(nx, w->LUr, w->piv_r, w->err);
    for (j = 0; j < nx; ++j)
        w->scale[j] = abs_tol(P_, j) + fmax(fabs(w->y[j]), fabs(w->y_new[j])) * P_->rtol;
    *error_norm = rms(w->err, w->scale, nx, nx);
    if (rejected && *error_norm > 1.0) {
        for (j = 0; j < nx; ++j)
            w->ytmp[j] = w->y[j] + w->err[j];
        if ((rc = rhs(P_, S, w, t, w->ytmp, w->err)) != 0)
            return rc;
        for (j = 0; j < nx; ++j)
            w->err[j] += w->ZE[j];
        mg_lu_apply(nx, w->LUr, w->piv_r, w->err);
        *error_norm = rms(w->err, w->scale, nx, nx);
    }
    return 0;
}

/* Newton on the collocation system at step h, re-evaluating J once when it fails with an old one */
static int newton(const mgr_problem *P_, mgr_state *S, mgr_work *w, double t, double h, double tol, int *converged,
                  int *n_iter, double *rate)
{
    long j;
    int rc;
    for (j = 0; j < w->nx; ++j)
        w->scale[j] = abs_tol(P_, j) + fabs(w->y[j]) * P_->rtol;
    for (;;) {
        if (!w->lu_valid && (rc = factorise(S, w, h, t)) != 0)
            return rc;
        if ((rc = collocation(P_, S, w, t, h, tol, converged, n_iter, rate)) != 0)
            return rc;
        if (*converged || w->current_jac)
            return 0;
        if ((rc = jacobian(P_, S, w, t, w->y, w->f)) != 0)
            return rc;
        w->current_jac = 1;
        w->lu_valid = 0;
    }
}

/* a step being tried: its size and what its Newton solve and error estimate gave */
typedef struct {
    double t_new, h_abs, h_abs_old, err_old, error_norm, safety, rate;
    int has_old, n_iter;
} mgr_trial;

/* scipy's Radau._step_impl up to an accepted step (max_step = inf): Newton at h, halving h when it fails,
 * the error estimate, and the step shrunk by the predicted factor while the error exceeds 1 */
static int attempt(const mgr_problem *P_, mgr_state *S, mgr_work *w, mgr_trial *tr)
{
    double t = w->t, h, min_step = 10.0 * fabs(nextafter(t, INFINITY) - t);
    double tol = fmax(10.0 * DBL_EPSILON / P_->rtol, fmin(0.03, sqrt(P_->rtol)));
    int rejected = 0, converged, rc;
    tr->h_abs = w->h_abs;
    tr->h_abs_old = w->h_abs_old;
    tr->err_old = w->err_old;
    tr->has_old = w->has_old;
    if (tr->h_abs < min_step) {
        tr->h_abs = min_step;
        tr->has_old = 0;
    }
    for (;;) {
        if (tr->h_abs < min_step) {
            S->err_t = t;
            return MGR_E_SMALL;
        }
        tr->t_new = t + tr->h_abs;
        if (tr->t_new - P_->t_end > 0)
            tr->t_new = P_->t_end;
        h = tr->t_new - t;
        tr->h_abs = fabs(h);
        predict_stages(w, t, h);
        if ((rc = newton(P_, S, w, t, h, tol, &converged, &tr->n_iter, &tr->rate)) != 0)
            return rc;
        if (!converged) {
            tr->h_abs *= 0.5;
            w->lu_valid = 0;
            continue;
        }
        tr->safety = 0.9 * (2 * MGR_NEWTON_MAXITER + 1) / (2 * MGR_NEWTON_MAXITER + tr->n_iter);
        if ((rc = error_estimate(P_, S, w, t, h, rejected, &tr->error_norm)) != 0)
            return rc;
        if (tr->error_norm <= 1.0)
            return 0;
        tr->h_abs *= fmax(MGR_MIN_FACTOR, tr->safety * predict_factor(tr->h_abs, tr->h_abs_old, tr->has_old,
                                                                      tr->error_norm, tr->err_old));
        w->lu_valid = 0;
        rejected = 1;
    }
}

/* one accepted step of scipy's Radau._step_impl: attempt(), then the next step size, when to redo J and the LUs,
 * f at the new point and the collocation polynomial Q = Z^T P of the dense output */
static int radau_step(const mgr_problem *P_, mgr_state *S, mgr_work *w)
{
    long nx = w->nx, i, j;
    double factor;
    int recompute_jac, rc;
    mgr_trial tr;
    if ((rc = attempt(P_, S, w, &tr)) != 0)
        return rc;
    recompute_jac = tr.n_iter > 2 && tr.rate > 1e-3;
    factor = fmin(MGR_MAX_FACTOR, tr.safety * predict_factor(tr.h_abs, tr.h_abs_old, tr.has_old, tr.error_norm,
                                                             tr.err_old));
    if (!recompute_jac && factor < 1.2)
        factor = 1.0;
    else
        w->lu_valid = 0;
    if ((rc = rhs(P_, S, w, tr.t_new, w->y_new, w->f_new)) != 0)
        return rc;
    if (recompute_jac && (rc = jacobian(P_, S, w, tr.t_new, w->y_new, w->f_new)) != 0)
        return rc;
    w->current_jac = recompute_jac;
    w->h_abs_old = w->h_abs;
    w->err_old = tr.error_norm;
    w->has_old = 1;
    w->h_abs = tr.h_abs * factor;
    memcpy(w->y_old, w->y, (size_t)nx * sizeof(double));
    memcpy(w->y, w->y_new, (size_t)nx * sizeof(double));
    memcpy(w->f, w->f_new, (size_t)nx * sizeof(double));
    w->t_old = w->t;
    w->t = tr.t_new;
    for (j = 0; j < nx; ++j)   /* Q = Z^T P */
        for (i = 0; i < 3; ++i)
            w->Q[3 * j + i] = w->Z[j] * P[0][i] + w->Z[nx + j] * P[1][i] + w->Z[2 * nx + j] * P[2][i];
    w->has_sol = 1;
    return 0;
}

/* scipy's select_initial_step(order = 3) from (t, y, f) */
static int initial_step(const mgr_problem *P_, mgr_state *S, mgr_work *w, double *h_out)
{
    long nx = w->nx, j;
    double interval = fabs(P_->t_end - w->t), d0, d1, d2, h0, h1;
    int rc;
    for (j = 0; j < nx; ++j)
        w->scale[j] = abs_tol(P_, j) + fabs(w->y[j]) * P_->rtol;
    d0 = rms(w->y, w->scale, nx, nx);
    d1 = rms(w->f, w->scale, nx, nx);
    h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    h0 = fmin(h0, interval);
    for (j = 0; j < nx; ++j)
        w->ytmp[j] = w->y[j] + h0 * w->f[j];
    if ((rc = rhs(P_, S, w, w->t + h0, w->ytmp, w->f_new)) != 0)
        return rc;
    for (j = 0; j < nx; ++j)
        w->err[j] = w->f_new[j] - w->f[j];
    d2 = rms(w->err, w->scale, nx, nx) / h0;
    if (d1 <= 1e-15 && d2 <= 1e-15)
        h1 = fmax(1e-6, h0 * 1e-3);
    else
        h1 = pow(0.01 / fmax(d1, d2), 1.0 / 4.0);
    *h_out = fmin(fmin(100 * h0, h1), interval);
    return 0;
}

static long kernel_entries(const mgr_kernel *k)
{
    long j, total = 0;
    if (k->fn == NULL)
        return 0;
    for (j = 0; j < k->nout; ++j)
        total += k->out_len[j];
    return total;
}

/* what the kernels must give: n x n M, n r, nz rates, the tangent's blocks, m x (2n + m) rates_tangent */
static int check_problem(const mgr_problem *P_)
{
    long n = P_->n, m = P_->m, nz = P_->m + P_->extra, k, i;
    const mgr_kernel *K = P_->kernels;
    const long need[MGR_NK][MGR_PICKS] = {
        {n, n * n, -1, -1}, {n, -1, -1, -1}, {n * n, n * n, n * n, n * m}, {nz, -1, -1, -1}, {m * n, m * n, m * m, -1}};
    if (n < 0 || m < 0 || P_->extra < 0 || 2 * n + nz < 1 || P_->rtol <= 0 || P_->n_eval < 0
        || (P_->n_eval > 0 && P_->s_x == NULL))
        return 1;
    if ((n > 0 && (K[MGR_K_TANGENT].fn == NULL || (K[MGR_K_FLOW].fn == NULL && K[MGR_K_RESIDUAL].fn == NULL)))
        || (nz > 0 && K[MGR_K_RATES].fn == NULL) || (m > 0 && K[MGR_K_RATES_TANGENT].fn == NULL))
        return 1;
    for (k = 0; k < MGR_NK; ++k) {
        if (K[k].fn == NULL)
            continue;
        if (K[k].nin < 0 || K[k].nin > MGR_PORTS || K[k].nout < 1 || K[k].nout > MGR_PORTS)
            return 1;
        for (i = 0; i < K[k].nin; ++i)
            if (K[k].ports[i] < MGR_IN_Q || K[k].ports[i] > MGR_IN_P)
                return 1;
        for (i = 0; i < MGR_PICKS; ++i) {
            if (need[k][i] < 0 || (k == MGR_K_TANGENT && i == 3 && m == 0))
                continue;
            if (K[k].pick[i] < 0 || K[k].pick[i] >= K[k].nout || K[k].out_len[K[k].pick[i]] != need[k][i])
                return 1;
        }
    }
    return 0;
}

void mgr_free(mgr_state *S);
void mgr_free(mgr_state *S)
{
    mgr_work *w = S != NULL ? (mgr_work *)S->work : NULL;
    if (w == NULL)
        return;
    free(w->mem);
    free(w->LUc);
    free(w->piv_r);
    free(w);
    S->work = NULL;
}

/* the workspace, and the start: f0, J0, the initial step */
static int setup(const mgr_problem *P_, mgr_state *S)
{
    long n = P_->n, m = P_->m, nx = 2 * n + m + P_->extra, total, k, j;
    mgr_work *w = (mgr_work *)calloc(1, sizeof(mgr_work));
    double *p;
    int rc;
    if (w == NULL)
        return MGR_E_MEMORY;
    S->work = w;
    w->n = n;
    w->m = m;
    w->nx = nx;
    total = 29 * nx + 2 * nx * nx + n * n + n * (2 * n + m);   /* the MGR_TAKEs below */
    for (k = 0; k < MGR_NK; ++k)
        total += kernel_entries(&P_->kernels[k]);
    w->mem = (double *)calloc((size_t)total, sizeof(double));
    w->LUc = (double _Complex *)calloc((size_t)(nx * nx + nx), sizeof(double _Complex));
    w->piv_r = (long *)calloc((size_t)(3 * nx + n), sizeof(long));
    if (w->mem == NULL || w->LUc == NULL || w->piv_r == NULL)
        return MGR_E_MEMORY;
    w->fc = w->LUc + nx * nx;
    w->piv_c = w->piv_r + nx + n;
    p = w->mem;
#define MGR_TAKE(name, count) do { w->name = p; p += (count); } while (0)
    MGR_TAKE(y, nx); MGR_TAKE(f, nx); MGR_TAKE(y_old, nx); MGR_TAKE(Z, 3 * nx); MGR_TAKE(Q, 3 * nx);
    MGR_TAKE(scale, nx); MGR_TAKE(F, 3 * nx); MGR_TAKE(W, 3 * nx); MGR_TAKE(dW, 3 * nx); MGR_TAKE(Z0, 3 * nx);
    MGR_TAKE(ytmp, nx); MGR_TAKE(fr, nx); MGR_TAKE(err, nx); MGR_TAKE(ZE, nx); MGR_TAKE(y_new, nx);
    MGR_TAKE(f_new, nx); MGR_TAKE(zeros, nx); MGR_TAKE(J, nx * nx); MGR_TAKE(LUr, nx * nx); MGR_TAKE(M, n * n);
    MGR_TAKE(B, n * (2 * n + m));
    for (k = 0; k < MGR_NK; ++k)
        for (j = 0; j < P_->kernels[k].nout && P_->kernels[k].fn != NULL; ++j)
            MGR_TAKE(kout[k][j], P_->kernels[k].out_len[j]);
#undef MGR_TAKE
    w->t = S->t;
    memcpy(w->y, S->x, (size_t)nx * sizeof(double));
    if ((rc = rhs(P_, S, w, w->t, w->y, w->f)) != 0)
        return rc;
    if ((rc = initial_step(P_, S, w, &w->h_abs)) != 0)
        return rc;
    if ((rc = jacobian(P_, S, w, w->t, w->y, w->f)) != 0)
        return rc;
    w->current_jac = 1;
    return 0;
}

/* the samples of t_eval in (t_old, t] (the first step's also t = t_old) from the last step's dense output */
static void sample(const mgr_problem *P_, mgr_state *S, const mgr_work *w)
{
    while (S->i_eval < P_->n_eval && P_->t_eval[S->i_eval] <= w->t) {
        dense(w, P_->t_eval[S->i_eval], P_->s_x + S->i_eval * w->nx);
        S->i_eval++;
    }
}

/* Run from the state (module doc): MGR_DONE, MGR_SLICE (call again to go on) or an error MGR_E_* */
int mgr_run(const mgr_problem *P_, mgr_state *S);
int mgr_run(const mgr_problem *P_, mgr_state *S)
{
    mgr_work *w;
    int rc;
    if (P_ == NULL || S == NULL || S->x == NULL || S->err_x == NULL || check_problem(P_))
        return MGR_E_INPUT;
    S->counted = 0;
    if (S->work == NULL && (rc = setup(P_, S)) != 0)
        return rc;
    w = (mgr_work *)S->work;
    while (w->t < P_->t_end) {
        if ((rc = radau_step(P_, S, w)) != 0)
            return rc;
        S->steps++;
        S->counted++;
        sample(P_, S, w);
        S->t = w->t;
        S->h_last = w->t - w->t_old;
        memcpy(S->x, w->y, (size_t)w->nx * sizeof(double));
        if (P_->budget_left >= 0 && S->counted > P_->budget_left)
            return MGR_E_BUDGET;
        if (P_->slice > 0 && S->counted >= P_->slice && w->t < P_->t_end)
            return MGR_SLICE;
    }
    return MGR_DONE;
}
