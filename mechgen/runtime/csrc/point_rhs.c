/* mechgen point_rhs.c: dx/dt at one state of a smooth lumped model, in one call (C99).
 *
 * For x = (q, v) of a model without internal variables, dx/dt = (v, a) with M a = -r(q, v, 0, t), r and
 * M = dr/da from the model's fused `flow` kernel (called through its address with the mechgen ABI
 * int mg_flow(const double *const *in, double *const *out, const long *sizes, long nbatch)). M = d2T/dv2 is
 * symmetric: Cholesky M = L L^T (the same arithmetic as LAPACK's unblocked dpotf2 + dpotrs on the lower
 * triangle), and Gaussian elimination with partial pivoting where M is not positive definite (an indefinite or
 * singular M: code 1 when singular). The Python side (mechgen/runtime/core/point_rhs.py) calls mgp_rhs with one
 * pointer, the state and the parameters already in the buffers the struct points to.
 *
 * A non-finite r or M is code 2 before any solve (an overflowed entry would factor into finite nonsense).
 * mgp_jacobian gives d(dx/dt)/dx in the same call: the tangent kernel at the acceleration just found, and
 * da/dx = -M^-1 (r_q r_v) with the same factor of M (for the implicit integrators).
 *
 * Codes: 0 done; 1 M singular; 2 a non-finite dx/dt (mgp_rhs only); 3 the kernel's own nonzero code (in kernel_rc).
 */
#include <math.h>
#include <string.h>

#include "dense_lu.h"

typedef int (*mgp_fn)(const double *const *in, double *const *out, const long *sizes, long nbatch);

#define MGP_PORTS 8

/* what a kernel input is */
enum { MGP_IN_Q = 0, MGP_IN_V = 1, MGP_IN_A = 2, MGP_IN_Z = 3, MGP_IN_T = 4, MGP_IN_P = 5 };

typedef struct {
    mgp_fn flow;
    long n, nin, r_index, M_index, kernel_rc;
    long ports[MGP_PORTS];     /* MGP_IN_* of each input, in the kernel's order */
    const double *p;           /* the parameters */
    double t;
    const double *x;           /* 2n: the state (q, v) */
    double *f;                 /* 2n: dx/dt */
    double *out[MGP_PORTS];    /* the kernel's outputs (r: n, M: n x n row-major) */
    double *zeros;             /* 2n: a = 0 and z (n zeros), then a column of mgp_jacobian's solve (n) */
    double *work;              /* n x n: the factor of M */
    long *piv;                 /* n: LU's row swaps */
    long lu;                   /* 1 when work holds LU (M not positive definite), 0 Cholesky */
    mgp_fn tangent;            /* the tangent kernel (NULL: no mgp_jacobian) */
    long tin, rq_index, rv_index;
    long tports[MGP_PORTS];    /* MGP_IN_* of each tangent input */
    double *tout[MGP_PORTS];   /* the tangent's outputs (r_q, r_v, r_a: n x n row-major; r_z) */
    double *J;                 /* 2n x 2n: mgp_jacobian's result */
} mgp_point;

long mgp_layout(void);
long mgp_layout(void) { return (long)sizeof(mgp_point); }

/* L L^T = M (the lower triangle of M, into L); 1 when M is not positive definite */
static int cholesky_factor(long n, const double *M, double *L)
{
    long i, j, k;
    double s;
    for (j = 0; j < n; ++j) {
        s = M[j * n + j];
        for (k = 0; k < j; ++k)
            s -= L[j * n + k] * L[j * n + k];
        if (!(s > 0.0))
            return 1;
        L[j * n + j] = sqrt(s);
        for (i = j + 1; i < n; ++i) {
            s = M[i * n + j];
            for (k = 0; k < j; ++k)
                s -= L[i * n + k] * L[j * n + k];
            L[i * n + j] = s / L[j * n + j];
        }
    }
    return 0;
}

/* b = (L L^T)^-1 b */
static void cholesky_apply(long n, const double *L, double *b)
{
    long i, k;
    double s;
    for (i = 0; i < n; ++i) {   /* L y = b */
        s = b[i];
        for (k = 0; k < i; ++k)
            s -= L[i * n + k] * b[k];
        b[i] = s / L[i * n + i];
    }
    for (i = n - 1; i >= 0; --i) {   /* L^T a = y */
        s = b[i];
        for (k = i + 1; k < n; ++k)
            s -= L[k * n + i] * b[k];
        b[i] = s / L[i * n + i];
    }
}

/* factor M into P->work (Cholesky, else LU: P->lu set); 1 if M is singular */
static int factor(mgp_point *P, const double *M)
{
    P->lu = cholesky_factor(P->n, M, P->work);
    if (!P->lu)
        return 0;
    memcpy(P->work, M, (size_t)(P->n * P->n) * sizeof(double));   /* LU of a copy of M (dense_lu.h) */
    return mg_lu_factor(P->n, P->work, P->piv);
}

/* b = M^-1 b with the factor of the last factor() */
static void apply(const mgp_point *P, double *b)
{
    if (P->lu)
        mg_lu_apply(P->n, P->work, P->piv, b);
    else
        cholesky_apply(P->n, P->work, b);
}

/* the kernel inputs of the state: q, v and t from the struct, a = accel (NULL: zeros), z = zeros */
static void inputs(const mgp_point *P, const long *ports, long nin, const double *accel, const double **in)
{
    long i, n = P->n;
    for (i = 0; i < nin; ++i) {
        switch (ports[i]) {
        case MGP_IN_Q: in[i] = P->x; break;
        case MGP_IN_V: in[i] = P->x + n; break;
        case MGP_IN_T: in[i] = &P->t; break;
        case MGP_IN_P: in[i] = P->p; break;
        case MGP_IN_A: in[i] = accel ? accel : P->zeros; break;
        default: in[i] = P->zeros; break;
        }
    }
}

int mgp_rhs(mgp_point *P);
int mgp_rhs(mgp_point *P)
{
    const double *in[MGP_PORTS];
    long n = P->n, i, sizes = 0;
    double *a = P->f + n;
    int rc;
    inputs(P, P->ports, P->nin, NULL, in);
    rc = P->flow(in, P->out, &sizes, 1);
    if (rc != 0) {
        P->kernel_rc = rc;
        return 3;
    }
    for (i = 0; i < n * n; ++i)   /* an overflowed M (a Cholesky of inf entries would give finite nonsense) */
        if (!isfinite(P->out[P->M_index][i]) || (i < n && !isfinite(P->out[P->r_index][i])))
            return 2;
    if (factor(P, P->out[P->M_index]))
        return 1;
    for (i = 0; i < n; ++i)
        a[i] = -P->out[P->r_index][i];
    apply(P, a);
    memcpy(P->f, P->x + n, (size_t)n * sizeof(double));
    for (i = 0; i < 2 * n; ++i)
        if (!isfinite(P->f[i]))
            return 2;
    return 0;
}

/* J = d(dx/dt)/dx (2n x 2n, row-major) at the state: rows 0..n-1 (0 I); rows n..2n-1 da/dx = -M^-1 (r_q r_v), the
 * tangent kernel evaluated at the acceleration of mgp_rhs (which also leaves dx/dt in f and M's factor in work) */
int mgp_jacobian(mgp_point *P);
int mgp_jacobian(mgp_point *P)
{
    const double *in[MGP_PORTS];
    long n = P->n, i, j, sizes = 0;
    const double *rq, *rv;
    double *J = P->J, *col = P->zeros + n;
    int rc = mgp_rhs(P);
    if (rc == 1 || rc == 3)
        return rc;
    if (rc == 2) {   /* a non-finite M, r or dx/dt: no finite J (the Python path's NaN, no error) */
        for (i = 0; i < 4 * n * n; ++i)
            J[i] = i < 2 * n * n ? (i % (2 * n) == n + i / (2 * n)) : NAN;
        return 0;
    }
    inputs(P, P->tports, P->tin, P->f + n, in);
    rc = P->tangent(in, P->tout, &sizes, 1);
    if (rc != 0) {
        P->kernel_rc = rc;
        return 3;
    }
    rq = P->tout[P->rq_index];
    rv = P->tout[P->rv_index];
    memset(J, 0, (size_t)(4 * n * n) * sizeof(double));
    for (i = 0; i < n; ++i)
        J[i * 2 * n + n + i] = 1.0;
    for (j = 0; j < 2 * n; ++j) {
        for (i = 0; i < n; ++i)
            col[i] = -(j < n ? rq[i * n + j] : rv[i * n + j - n]);
        apply(P, col);
        for (i = 0; i < n; ++i)
            J[(n + i) * 2 * n + j] = col[i];
    }
    return 0;
}
