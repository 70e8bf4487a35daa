/* mechgen field_flow.c: dx/dt of a discretised continuum, for the compiled DOP853 loop (C99).
 *
 * A fixed C source (not a template), built once into the compile cache as ``libmgfield`` and handed to the
 * event loop (hybrid_loop.c, mgh_problem.flow) as the provider of dx/dt in place of the lumped residual and
 * tangent kernels. For the reduced unknowns q (n of them) and x = (q, v):
 *
 *     dq/dt = v,   dv/dt = -M^-1 r(q, v, t),
 *     r = sum_b J_b^T (w_b .* rho_b(J_b q, J_b v, 0, z = [], t, s_b, p_b)) + P q,
 *
 * where each block b is a batch of points (the Gauss points of one segment, or one end term or placed part):
 * J_b (CSR, rows point-major then jet, columns the reduced unknowns) gives the jets at its points from the
 * reduced state (the jet tables composed with the reduction x_full = Z q), w_b the weight of each row (the
 * quadrature weight of its point; 1 at an end or part), rho_b the model's pointwise residual kernel called once
 * over the block's points by address (the mechgen kernel ABI), s_b the points' positions and p_b the block's
 * parameter vector (a segment's or a part's). P (CSR, n x n) is the penalty stiffness Z^T C^T diag(alpha) C Z
 * (absent without penalty rows). The sum over a block's rows is a gather through S_b = (diag(w_b) J_b)^T, also
 * CSR (n rows). M, the constant reduced mass matrix, comes as its Cholesky factor L of M permuted,
 * M[perm][:, perm] = L L^T, banded: lrow[j (band + 1) + i] = L[j, j - i] and lcol[j (band + 1) + i] = L[j + i, j]
 * for i = 1..band (zero outside L), so that both substitutions read memory in order, and entry i = 0 of both
 * the reciprocal 1 / L[j, j] (a product in the substitutions' dependency chain, not a division).
 * Everything that is linear in q is thus a sparse product; only rho is evaluated pointwise.
 *
 * With m > 0 the state carries m integrals after (q, v) (the energy balance's work and dissipated energy), whose
 * rates are quadratures of a pointwise kernel's output g (m entries a point) over the rate blocks (the same points,
 * jets and weights as the residual's, another kernel): dz_j/dt = sum_b sum_i w_b,i g_b,j(J_b q, J_b v, t, s_i, p_b).
 *
 * Entry point: mgf_rhs(flow, t, x, f): writes f[0 .. 2n + m) and returns 0, or the nonzero code a kernel returned
 * (flow->err_block names its block). Not reentrant: each run has its own workspace.
 */
#include <string.h>

typedef int (*mgf_fn)(const double *const *in, double *const *out, const long *sizes, long nbatch);

#define MGF_PORTS 8

/* what a kernel input is */
enum { MGF_IN_Q = 0, MGF_IN_V = 1, MGF_IN_A = 2, MGF_IN_Z = 3, MGF_IN_T = 4, MGF_IN_S = 5, MGF_IN_P = 6 };

typedef struct {
    mgf_fn fn;
    long nin, nout, pick;          /* pick: the output holding rho (na entries per point) */
    long ports[MGF_PORTS];         /* MGF_IN_* of each input, in the kernel's order */
    long out_len[MGF_PORTS];       /* entries of each output per point */
    long npts, na;                 /* points, jets per point */
    const double *s;               /* npts positions */
    const double *p;               /* the block's parameter vector */
    const long *indptr, *indices;  /* J_b: CSR, npts * na rows, n columns */
    const double *data;
    const double *w;               /* npts * na: each row's weight */
    const long *t_indptr, *t_indices;   /* S_b = (diag(w_b) J_b)^T: CSR, n rows, npts * na columns */
    const double *t_data;
} mgf_block;

typedef struct {
    long n, nblocks, m, nrates;
    const mgf_block *blocks;
    const mgf_block *rates;        /* nrates blocks whose kernel's output `pick` is g (m entries a point) */
    const long *p_indptr, *p_indices;   /* P: CSR n x n (p_indptr NULL: none) */
    const double *p_data;
    long band;
    const double *lrow, *lcol;     /* n x (band + 1) each: the rows and the columns of L within the band */
    const long *perm;              /* n */
    /* workspace, sized for the largest block: jets (rows each), times and positions (points), outputs */
    double *jq, *jv, *ja, *tt, *out[MGF_PORTS];
    double *r, *y;                 /* n each */
    long err_block, err_rc;
} mgf_flow;

/* the layout the Python side checks before its first call */
long mgf_layout(long which);
long mgf_layout(long which)
{
    switch (which) {
    case 0: return (long)sizeof(mgf_block);
    case 1: return (long)sizeof(mgf_flow);
    default: return -1;
    }
}

/* jq = J q and jv = J v for the rows of a block (one pass over J) */
static void jets(const mgf_block *b, const double *q, const double *v, double *jq, double *jv)
{
    long rows = b->npts * b->na, i, k, col;
    double sq, sv, a;
    for (i = 0; i < rows; ++i) {
        sq = 0.0;
        sv = 0.0;
        for (k = b->indptr[i]; k < b->indptr[i + 1]; ++k) {
            a = b->data[k];
            col = b->indices[k];
            sq += a * q[col];
            sv += a * v[col];
        }
        jq[i] = sq;
        jv[i] = sv;
    }
}

/* r += J^T (w .* rho) = S rho (a gather: each r[i] summed in a register) */
static void gather(const mgf_block *b, long n, const double *rho, double *r)
{
    long i, k;
    double s;
    for (i = 0; i < n; ++i) {
        s = 0.0;
        for (k = b->t_indptr[i]; k < b->t_indptr[i + 1]; ++k)
            s += b->t_data[k] * rho[b->t_indices[k]];
        r[i] += s;
    }
}

/* rho of a block at its points: one batched kernel call; 0 or the kernel's code */
static int pointwise(mgf_flow *F, const mgf_block *b, double t, const double *x)
{
    const double *in[MGF_PORTS];
    double *out[MGF_PORTS];
    long sizes = 0, i;
    jets(b, x, x + F->n, F->jq, F->jv);
    for (i = 0; i < b->npts; ++i)
        F->tt[i] = t;
    for (i = 0; i < b->nin; ++i) {
        switch (b->ports[i]) {
        case MGF_IN_Q: in[i] = F->jq; break;
        case MGF_IN_V: in[i] = F->jv; break;
        case MGF_IN_T: in[i] = F->tt; break;
        case MGF_IN_S: in[i] = b->s; break;
        case MGF_IN_P: in[i] = b->p != NULL ? b->p : F->ja; break;
        default: in[i] = F->ja; break;   /* a = 0, z = [] */
        }
    }
    for (i = 0; i < b->nout; ++i) {
        out[i] = F->out[i];
        memset(out[i], 0, (size_t)(b->npts * b->out_len[i]) * sizeof(double));
    }
    return b->fn(in, out, &sizes, b->npts);
}

/* y = M^-1 r by the banded Cholesky factor (forward and back substitution in the permuted order) */
static void mass_solve(const mgf_flow *F, const double *r, double *y)
{
    long n = F->n, w = F->band + 1, i, j;
    const double *row, *col;
    double s;
    for (j = 0; j < n; ++j) {
        row = F->lrow + j * w;
        s = r[F->perm[j]];
        for (i = 1; i < w && i <= j; ++i)
            s -= row[i] * y[j - i];
        y[j] = s * row[0];
    }
    for (j = n - 1; j >= 0; --j) {
        col = F->lcol + j * w;
        s = y[j];
        for (i = 1; i < w && j + i < n; ++i)
            s -= col[i] * y[j + i];
        y[j] = s * col[0];
    }
}

/* f[2n + j] = sum over the rate blocks and their points of w g_j (module doc); 0 or a kernel's code */
static int integrals(mgf_flow *F, double t, const double *x, double *f)
{
    long b, i, j, m = F->m;
    int rc;
    memset(f, 0, (size_t)m * sizeof(double));
    for (b = 0; b < F->nrates; ++b) {
        const mgf_block *blk = &F->rates[b];
        const double *g = F->out[blk->pick];
        if ((rc = pointwise(F, blk, t, x)) != 0) {
            F->err_block = F->nblocks + b;
            F->err_rc = rc;
            return rc;
        }
        for (i = 0; i < blk->npts; ++i)
            for (j = 0; j < m; ++j)
                f[j] += blk->w[i * blk->na] * g[i * m + j];
    }
    return 0;
}

/* f = (v, -M^-1 r(q, v, t), the integrals' rates) at (t, x = (q, v, z)): module doc */
int mgf_rhs(void *data, double t, const double *x, double *f);
int mgf_rhs(void *data, double t, const double *x, double *f)
{
    mgf_flow *F = (mgf_flow *)data;
    long n = F->n, b, i, k;
    int rc;
    memset(F->r, 0, (size_t)n * sizeof(double));
    for (b = 0; b < F->nblocks; ++b) {
        const mgf_block *blk = &F->blocks[b];
        if ((rc = pointwise(F, blk, t, x)) != 0) {
            F->err_block = b;
            F->err_rc = rc;
            return rc;
        }
        gather(blk, n, F->out[blk->pick], F->r);
    }
    if (F->p_indptr != NULL)
        for (i = 0; i < n; ++i)
            for (k = F->p_indptr[i]; k < F->p_indptr[i + 1]; ++k)
                F->r[i] += F->p_data[k] * x[F->p_indices[k]];
    mass_solve(F, F->r, F->y);
    memcpy(f, x + n, (size_t)n * sizeof(double));
    for (i = 0; i < n; ++i)
        f[n + F->perm[i]] = -F->y[i];
    return F->m > 0 ? integrals(F, t, x, f + 2 * n) : 0;
}
