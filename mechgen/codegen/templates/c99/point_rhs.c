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
 * Codes: 0 done; 1 M singular; 2 a non-finite dx/dt; 3 the kernel's own nonzero code (in kernel_rc).
 */
#include <math.h>
#include <string.h>

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
    double *zeros;             /* n: a = 0 and z */
    double *work;              /* n x n: the factor */
} mgp_point;

long mgp_layout(void);
long mgp_layout(void) { return (long)sizeof(mgp_point); }

/* b = M^-1 b by Cholesky of the lower triangle of M (copied into L); 1 when M is not positive definite */
static int cholesky_solve(long n, const double *M, double *L, double *b)
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
    return 0;
}

/* b = M^-1 b, Gaussian elimination with partial pivoting on a copy A of M; 1 if singular */
static int lu_solve(long n, const double *M, double *A, double *b)
{
    long i, j, k, p;
    double big, l, s;
    memcpy(A, M, (size_t)(n * n) * sizeof(double));
    for (k = 0; k < n; ++k) {
        p = k;
        big = fabs(A[k * n + k]);
        for (i = k + 1; i < n; ++i)
            if (fabs(A[i * n + k]) > big) {
                big = fabs(A[i * n + k]);
                p = i;
            }
        if (big == 0.0)
            return 1;
        if (p != k) {
            for (j = 0; j < n; ++j) {
                s = A[k * n + j];
                A[k * n + j] = A[p * n + j];
                A[p * n + j] = s;
            }
            s = b[k];
            b[k] = b[p];
            b[p] = s;
        }
        for (i = k + 1; i < n; ++i) {
            l = A[i * n + k] / A[k * n + k];
            for (j = k + 1; j < n; ++j)
                A[i * n + j] -= l * A[k * n + j];
            b[i] -= l * b[k];
        }
    }
    for (k = n - 1; k >= 0; --k) {
        s = b[k];
        for (j = k + 1; j < n; ++j)
            s -= A[k * n + j] * b[j];
        b[k] = s / A[k * n + k];
    }
    return 0;
}

int mgp_rhs(mgp_point *P);
int mgp_rhs(mgp_point *P)
{
    const double *in[MGP_PORTS];
    long n = P->n, i, sizes = 0;
    double *a = P->f + n;
    int rc;
    for (i = 0; i < P->nin; ++i) {
        switch (P->ports[i]) {
        case MGP_IN_Q: in[i] = P->x; break;
        case MGP_IN_V: in[i] = P->x + n; break;
        case MGP_IN_T: in[i] = &P->t; break;
        case MGP_IN_P: in[i] = P->p; break;
        default: in[i] = P->zeros; break;
        }
    }
    rc = P->flow(in, P->out, &sizes, 1);
    if (rc != 0) {
        P->kernel_rc = rc;
        return 3;
    }
    for (i = 0; i < n; ++i)
        a[i] = -P->out[P->r_index][i];
    if (cholesky_solve(n, P->out[P->M_index], P->work, a)) {
        for (i = 0; i < n; ++i)
            a[i] = -P->out[P->r_index][i];
        if (lu_solve(n, P->out[P->M_index], P->work, a))
            return 1;
    }
    memcpy(P->f, P->x + n, (size_t)n * sizeof(double));
    for (i = 0; i < 2 * n; ++i)
        if (!isfinite(P->f[i]))
            return 2;
    return 0;
}
