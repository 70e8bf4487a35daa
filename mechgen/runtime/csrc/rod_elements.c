/* Internal forces of the two-node SO(3) x R^3 Cosserat rod elements at the step's weighted configuration.
 *
 * The same operations as mechgen/runtime/rods/dynamics.py (Discrete.residual's configuration and
 * Discrete.internal; angle functions as mechgen/runtime/rods/liegroup.py: series below 1 rad, closed forms
 * above): for each of `batch` increments z (n nodes x 6: dx, theta)
 *
 *   xm_i = x_i + alpha dx_i,   Rm_i = R_i exp(alpha theta_i),
 *   Psi_e = log(Rm_i^T Rm_{i+1}),  Re = Rm_i exp(Psi_e/2),  nu = Re^T (xm_{i+1} - xm_i)/h,  kappa = Psi_e/h,
 *   sigma = K ((nu, kappa) - f0),  F_i += Re n,  F_{i+1} -= Re n,
 *   a = h n x nu,  c = m + J_r(Psi/2)^T a/2,
 *   Mb_i -= exp(Psi/2) a - J_l(Psi)^-T c,   Mb_{i+1} -= J_r(Psi)^-T c,
 *
 * writing xm (batch, n, 3), Rm (batch, n, 3, 3), F and Mb (batch, n, 3): spatial forces (N) and body moments
 * (N m), minus the exact gradient of V = sum_e h/2 (f_e - f0)^T K (f_e - f0). Row-major 3 x 3 matrices.
 *
 * mgr_residual: the whole step residual of Discrete.residual in one call (the element forces above, the lumped
 * loads and dead tip wrench, the inertial, gyroscopic, damping and fixed rows; the structure mgr_step is
 * mirrored by mechgen/runtime/rods/compiled.py). mgr_record: a saved state's elastic and kinetic energies and
 * turning angle. mgr_rotate: a step's new rotations R exp(theta). mgr_band_solve: a Newton correction from
 * LAPACK's band factors. numpy and scipy (dynamics.py) are their reference.
 */
#include <math.h>
#include <string.h>

/* exp_so3, jac_left_so3, jac_left_so3_inv and the angle functions of the squared angle (series below 1 rad,
 * closed forms above), generated from mechgen/symbolic/liegroup.py by `mechgen regen`
 * (mechgen/generated/liegroup/liegroup_maps.h, inlined by mechgen.runtime.csrc.source) */
#include "liegroup_maps.h"

static double norm3(const double *w) { return sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]); }

/* w with exp(hat w) = R, |w| <= pi (liegroup.log_so3: from the skew part, near pi from R + R^T) */
static void log3(const double *R, double *w) {
    double s[3] = {0.5 * (R[7] - R[5]), 0.5 * (R[2] - R[6]), 0.5 * (R[3] - R[1])};
    double c = 0.5 * (R[0] + R[4] + R[8] - 1.0);
    double t = atan2(norm3(s), c);
    if (c >= -0.9) {
        double k = 1.0 / mgl_sinc(t * t);
        for (int i = 0; i < 3; ++i) w[i] = s[i] * k;
        return;
    }
    double B[9];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) B[3 * i + j] = 0.5 * (R[3 * i + j] + R[3 * j + i]) - (i == j ? c : 0.0);
    int k = 0;
    if (B[4] > B[3 * k + k]) k = 1;
    if (B[8] > B[3 * k + k]) k = 2;
    double col[3] = {B[k], B[3 + k], B[6 + k]}, nc = norm3(col);
    double dot = (col[0] * s[0] + col[1] * s[1] + col[2] * s[2]) / nc;
    double sign = dot < 0.0 ? -1.0 : 1.0;
    for (int i = 0; i < 3; ++i) w[i] = sign * t * col[i] / nc;
}

static void matmul(const double *A, const double *B, double *C) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            C[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
}

static void matTmul(const double *A, const double *B, double *C) {   /* A^T B */
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) C[3 * i + j] = A[i] * B[j] + A[3 + i] * B[3 + j] + A[6 + i] * B[6 + j];
}

static void mv(const double *A, const double *b, double *y) {
    for (int i = 0; i < 3; ++i) y[i] = A[3 * i] * b[0] + A[3 * i + 1] * b[1] + A[3 * i + 2] * b[2];
}

static void mtv(const double *A, const double *b, double *y) {      /* A^T b */
    for (int i = 0; i < 3; ++i) y[i] = A[i] * b[0] + A[3 + i] * b[1] + A[6 + i] * b[2];
}

/* one rod's weighted configuration and internal forces (the header's equations) at increments zb (n x 6) */
static void internal_one(long n, double h, double alpha, const double *K, const double *f0, const double *x,
                         const double *R, const double *zb, double *xb, double *Rb, double *Fb, double *Mbb) {
    for (long i = 0; i < n; ++i) {
        double th[3] = {alpha * zb[6 * i + 3], alpha * zb[6 * i + 4], alpha * zb[6 * i + 5]}, E[9];
        for (int k = 0; k < 3; ++k) xb[3 * i + k] = x[3 * i + k] + alpha * zb[6 * i + k];
        mgl_exp_so3(th, E);
        matmul(R + 9 * i, E, Rb + 9 * i);
    }
    memset(Fb, 0, sizeof(double) * 3 * n);
    memset(Mbb, 0, sizeof(double) * 3 * n);
    for (long e = 0; e + 1 < n; ++e) {
        const double *Ri = Rb + 9 * e, *Rj = Rb + 9 * (e + 1);
        double Q[9], Psi[3], half[3], Rh[9], Re[9], d[3], nu[3], eps[6], sig[6];
        matTmul(Ri, Rj, Q);
        log3(Q, Psi);
        for (int k = 0; k < 3; ++k) half[k] = 0.5 * Psi[k];
        mgl_exp_so3(half, Rh);
        matmul(Ri, Rh, Re);
        for (int k = 0; k < 3; ++k) d[k] = xb[3 * (e + 1) + k] - xb[3 * e + k];
        mtv(Re, d, nu);
        for (int k = 0; k < 3; ++k) { nu[k] /= h; eps[k] = nu[k] - f0[k]; eps[3 + k] = Psi[k] / h - f0[3 + k]; }
        for (int r = 0; r < 6; ++r) {
            double acc = 0.0;
            for (int s = 0; s < 6; ++s) acc += eps[s] * K[6 * s + r];      /* (f - f0) @ K */
            sig[r] = acc;
        }
        double Fe[3];
        mv(Re, sig, Fe);
        for (int k = 0; k < 3; ++k) { Fb[3 * e + k] += Fe[k]; Fb[3 * (e + 1) + k] -= Fe[k]; }
        double a[3] = {h * (sig[1] * nu[2] - sig[2] * nu[1]), h * (sig[2] * nu[0] - sig[0] * nu[2]),
                       h * (sig[0] * nu[1] - sig[1] * nu[0])};
        /* J_r(Psi/2) = J_l(-Psi/2) */
        double Jr[9], ca[3], c[3], Jli[9], Jri[9];
        double mhalf[3] = {-half[0], -half[1], -half[2]};
        mgl_jac_left_so3(mhalf, Jr);
        mtv(Jr, a, ca);
        for (int k = 0; k < 3; ++k) c[k] = sig[3 + k] + 0.5 * ca[k];
        mgl_jac_left_so3_inv(Psi, Jli);           /* J_l(Psi)^-1 = I - hat/2 + b hat^2 */
        /* J_r(Psi)^-1 = J_l(-Psi)^-1 = J_l(Psi)^-1 + hat(Psi) (= I + hat/2 + b hat^2) */
        memcpy(Jri, Jli, sizeof Jri);
        Jri[1] -= Psi[2]; Jri[2] += Psi[1]; Jri[3] += Psi[2]; Jri[5] -= Psi[0]; Jri[6] -= Psi[1]; Jri[7] += Psi[0];
        double Rha[3], Jc[3], Jrc[3];
        mv(Rh, a, Rha);
        mtv(Jli, c, Jc);
        mtv(Jri, c, Jrc);
        for (int k = 0; k < 3; ++k) { Mbb[3 * e + k] -= Rha[k] - Jc[k]; Mbb[3 * (e + 1) + k] -= Jrc[k]; }
    }
}

int mgr_internal(long batch, long n, double h, double alpha, const double *K, const double *f0,
                 const double *x, const double *R, const double *z,
                 double *xm, double *Rm, double *F, double *Mb) {
    for (long b = 0; b < batch; ++b)
        internal_one(n, h, alpha, K, f0, x, R, z + b * n * 6, xm + b * n * 3, Rm + b * n * 9, F + b * n * 3,
                     Mb + b * n * 3);
    return 0;
}

/* The whole step residual of Discrete.residual (mechgen/runtime/rods/dynamics.py) for `batch` increments z.
 * Mirrored field for field by mechgen/runtime/rods/compiled.py's CStep (mgr_layout checks the size). */
typedef struct {
    long n, batch, load_stride;                 /* load_stride: 0 one lumped load for all, 6 n one per z */
    double h, alpha, dt, rhoA, damping;
    const double *K, *f0, *J;                   /* 6 x 6 (N, N m^2), 6, J_rho 3 x 3 (kg m) */
    const double *weights, *fixed_unit;         /* nodal lengths w_i (m); the fixed rows' scale times dt^2 (6) */
    const double *fixed;                        /* n x 6: 1 where the unknown is fixed, else 0 */
    const double *x, *R, *v, *w, *z;            /* the state at t_n; increments (batch, n, 6) */
    const double *load;                         /* lumped spatial load w_i q (n, 6) or NULL */
    const double *tip;                          /* the dead tip force and torque (6, spatial) */
    double *xm, *Rm, *F, *Mb;                   /* work: (batch, n, 3 | 9) */
    double *r, *Fx, *Mx;                        /* out: residual (batch, n, 6), external wrench (batch, n, 3) */
} mgr_step;

long mgr_layout(void) { return (long)sizeof(mgr_step); }

/* the external wrench at node i: Fx = w_i q_f (+ tip force), Mx = Rm^T w_i q_l (+ Rm^T tip torque) */
static void external_node(const mgr_step *s, const double *load, const double *Rmi, long i, double *fx,
                          double *mx) {
    double ql[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k < 3; ++k) { fx[k] = 0.0; mx[k] = 0.0; }
    if (load) for (int k = 0; k < 3; ++k) { fx[k] += load[6 * i + k]; ql[k] = load[6 * i + 3 + k]; }
    if (i == s->n - 1) for (int k = 0; k < 3; ++k) { fx[k] += s->tip[k]; ql[k] += s->tip[3 + k]; }
    mtv(Rmi, ql, mx);
}

/* r_t = m_i ((v_mid - v)/(alpha dt) + c v_mid) - F - Fx,
 * r_r = w_i (J ((w_mid - w)/(alpha dt) + c w_mid) + w_mid x J w_mid) - Mb - Mx,  r = z dt^-2 unit on fixed rows */
static void rows_one(const mgr_step *s, const double *zb, const double *load, const double *Rb, const double *Fb,
                     const double *Mbb, double *rb, double *Fxb, double *Mxb) {
    double dt = s->dt, adt = s->alpha * dt, c = s->damping, dt2 = dt * dt;
    for (long i = 0; i < s->n; ++i) {
        const double *zi = zb + 6 * i, *J = s->J;
        double vm[3], wm[3], acc[3], Ja[3], Jw[3], m = s->rhoA * s->weights[i];
        external_node(s, load, Rb + 9 * i, i, Fxb + 3 * i, Mxb + 3 * i);
        for (int k = 0; k < 3; ++k) {
            vm[k] = zi[k] / dt;
            wm[k] = zi[3 + k] / dt;
            rb[6 * i + k] = m * ((vm[k] - s->v[3 * i + k]) / adt + c * vm[k]) - Fb[3 * i + k] - Fxb[3 * i + k];
            acc[k] = (wm[k] - s->w[3 * i + k]) / adt + c * wm[k];
        }
        mv(J, acc, Ja);
        mv(J, wm, Jw);
        double cr[3] = {wm[1] * Jw[2] - wm[2] * Jw[1], wm[2] * Jw[0] - wm[0] * Jw[2], wm[0] * Jw[1] - wm[1] * Jw[0]};
        for (int k = 0; k < 3; ++k)
            rb[6 * i + 3 + k] = s->weights[i] * (Ja[k] + cr[k]) - Mbb[3 * i + k] - Mxb[3 * i + k];
        for (int k = 0; k < 6; ++k)
            if (s->fixed[6 * i + k] != 0.0) rb[6 * i + k] = zi[k] * (s->fixed_unit[k] / dt2);
    }
}

int mgr_residual(const mgr_step *s) {
    long n = s->n;
    for (long b = 0; b < s->batch; ++b) {
        const double *zb = s->z + b * n * 6, *load = s->load ? s->load + b * s->load_stride : 0;
        double *Rb = s->Rm + b * n * 9, *Fb = s->F + b * n * 3, *Mbb = s->Mb + b * n * 3;
        internal_one(n, s->h, s->alpha, s->K, s->f0, s->x, s->R, zb, s->xm + b * n * 3, Rb, Fb, Mbb);
        rows_one(s, zb, load, Rb, Fb, Mbb, s->r + b * n * 6, s->Fx + b * n * 3, s->Mx + b * n * 3);
    }
    return 0;
}

/* What a saved point needs (Discrete.elastic_energy, kinetic_energy, statics.turning_angle):
 * out[0] = V = sum_e h/2 (f_e - f0)^T K (f_e - f0), out[1] = T = sum_i w_i (rhoA |v_i|^2 + w_i^T J w_i)/2 (J),
 * out[2] = sum_e a . R_e0 Psi_e, the turning about the unit axis a (rad), Psi_e = log(R_i^T R_{i+1}). */
int mgr_record(long n, double h, double rhoA, const double *K, const double *f0, const double *J,
               const double *weights, const double *axis, const double *x, const double *R, const double *v,
               const double *w, double *out) {
    double V = 0.0, T = 0.0, turn = 0.0;
    for (long e = 0; e + 1 < n; ++e) {
        const double *Ri = R + 9 * e;
        double Q[9], Psi[3], half[3], Rh[9], Re[9], d[3], nu[3], eps[6], sp[3];
        matTmul(Ri, R + 9 * (e + 1), Q);
        log3(Q, Psi);
        for (int k = 0; k < 3; ++k) half[k] = 0.5 * Psi[k];
        mgl_exp_so3(half, Rh);
        matmul(Ri, Rh, Re);
        for (int k = 0; k < 3; ++k) d[k] = x[3 * (e + 1) + k] - x[3 * e + k];
        mtv(Re, d, nu);
        for (int k = 0; k < 3; ++k) { eps[k] = nu[k] / h - f0[k]; eps[3 + k] = Psi[k] / h - f0[3 + k]; }
        for (int r = 0; r < 6; ++r)
            for (int c = 0; c < 6; ++c) V += eps[r] * K[6 * r + c] * eps[c];
        mv(Ri, Psi, sp);
        turn += sp[0] * axis[0] + sp[1] * axis[1] + sp[2] * axis[2];
    }
    for (long i = 0; i < n; ++i) {
        double Jw[3];
        mv(J, w + 3 * i, Jw);
        const double *vi = v + 3 * i, *wi = w + 3 * i;
        T += weights[i] * (rhoA * (vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2])
                           + wi[0] * Jw[0] + wi[1] * Jw[1] + wi[2] * Jw[2]);
    }
    out[0] = 0.5 * h * V;
    out[1] = 0.5 * T;
    out[2] = turn;
    return 0;
}

/* out_i = R_i exp(hat theta_i), i < n: the rotations after a step's increments (dynamics.advance) */
int mgr_rotate(long n, const double *R, const double *theta, double *out) {
    for (long i = 0; i < n; ++i) {
        double E[9];
        mgl_exp_so3(theta + 3 * i, E);
        matmul(R + 9 * i, E, out + 9 * i);
    }
    return 0;
}

/* dz = -A^-1 r with LAPACK dgbtrf's band LU of A (column-major, ldab = 2 kl + ku + 1, 0-based pivots), the
 * operations of LAPACK's dgbtrs (no transpose: row swaps and L's columns, then U by columns as dtbsv); returns
 * max_i |dz_i| / scale_i (the Newton correction's size in units of L and rad). */
double mgr_band_solve(long n, long kl, long ku, const double *ab, const int *ipiv, const double *r,
                      const double *scale, double *dz) {
    long ld = 2 * kl + ku + 1, kd = kl + ku, k = kl + ku;
    for (long i = 0; i < n; ++i) dz[i] = -r[i];
    for (long j = 0; j + 1 < n; ++j) {
        long lm = kl < n - j - 1 ? kl : n - j - 1, l = ipiv[j];
        if (l != j) { double t = dz[l]; dz[l] = dz[j]; dz[j] = t; }
        for (long i = 1; i <= lm; ++i) dz[j + i] -= ab[ld * j + kd + i] * dz[j];
    }
    for (long j = n - 1; j >= 0; --j) {
        if (dz[j] == 0.0) continue;
        dz[j] /= ab[ld * j + k];
        double t = dz[j];
        long lo = j - k > 0 ? j - k : 0;
        for (long i = j - 1; i >= lo; --i) dz[i] -= t * ab[ld * j + k + i - j];
    }
    double size = 0.0;
    for (long i = 0; i < n; ++i) {
        double a = fabs(dz[i]) / scale[i];
        if (!(a <= size)) size = a;            /* a NaN propagates */
    }
    return size;
}

/* Simplified Newton's corrections within one step: dynamics._Solver.attempt's loop between two Jacobians, the same
 * operations in the same order (so the same iterates bit for bit). Each pass tries z + lam dz for lam = 1, 1/2, ...
 * (halved only while the factors were taken at z, down to 1/64) until the next correction dzt = -J^-1 r(z + lam dz)
 * passes |dzt| <= (1 - lam/4) |dz|; then z = z + lam dz, and the step has converged when lam = 1 and |dzt| is below
 * tol / 100 or its error estimate |dzt| rate / (1 - rate) below tol (z + dzt returned). The factors are to be taken
 * again at z (returned to the caller, which factors, solves and calls again) when no trial passes with factors of an
 * earlier iterate, or when the corrections contract slower than `refresh` or would still need more than
 * `jacobian_cost` corrections at the rate seen (dynamics.stale_corrections). */
typedef struct {
    long size, kl, ku;                          /* 6 n unknowns; LAPACK band widths */
    const double *ab;                           /* dgbtrf's band factors of the Jacobian held (column-major) */
    const int *ipiv;                            /* their pivots (0-based) */
    const double *scale;                        /* the correction's units (L and rad), size */
    double tol, refresh, jacobian_cost;         /* dynamics.py's tol, REFRESH and JACOBIAN_COST */
    long passes;                                /* in: passes left in the attempt; decremented */
    long here;                                  /* in/out: 1 when the factors were taken at z */
    double *z, *r, *Fx, *Mx;                    /* in/out: the iterate, its residual and external wrench */
    double *dz;                                 /* in/out: the correction at z */
    double dz_size;                             /* in/out: its size */
    double *zt, *dzt;                           /* work: a trial and its correction */
    long solves;                                /* out: band solves done (added to) */
} mgr_newton;

long mgr_newton_layout(void) { return (long)sizeof(mgr_newton); }

enum { MGR_CONVERGED = 0, MGR_NEED_JACOBIAN = 1, MGR_FAILED = 2 };

/* log(tol (1 - rate) / (size rate)) / log(rate), at least 0; infinite for rate >= 1 (dynamics.stale_corrections) */
static double stale_corrections(double rate, double size, double tol) {
    if (rate >= 1.0) return INFINITY;
    if (rate <= 0.0 || size <= 0.0) return 0.0;
    double k = log(tol * (1.0 - rate) / (size * rate)) / log(rate);
    return k > 0.0 ? k : 0.0;
}

int mgr_corrections(const mgr_step *s, mgr_newton *w) {
    long m = w->size, nn = 3 * s->n;
    mgr_step t = *s;                            /* the residual at the trials: batch 1, z = zt */
    t.z = w->zt;
    while (w->passes > 0) {
        --w->passes;
        double lam = 1.0, next = 0.0;
        int accepted = 0;
        for (;;) {
            for (long i = 0; i < m; ++i) w->zt[i] = w->z[i] + lam * w->dz[i];
            mgr_residual(&t);
            next = mgr_band_solve(m, w->kl, w->ku, w->ab, w->ipiv, t.r, w->scale, w->dzt);
            ++w->solves;
            if (isfinite(next) && next <= (1.0 - lam / 4.0) * w->dz_size) { accepted = 1; break; }
            lam *= 0.5;
            if (!w->here || lam < 1.0 / 64.0) break;
        }
        if (!accepted) return w->here ? MGR_FAILED : MGR_NEED_JACOBIAN;
        memcpy(w->z, w->zt, (size_t)m * sizeof(double));
        memcpy(w->r, t.r, (size_t)m * sizeof(double));
        memcpy(w->Fx, t.Fx, (size_t)nn * sizeof(double));
        memcpy(w->Mx, t.Mx, (size_t)nn * sizeof(double));
        w->here = 0;
        double rate = next / (w->dz_size > 1e-300 ? w->dz_size : 1e-300);
        if (lam == 1.0 && (next < 0.01 * w->tol || (rate < 1.0 && next * rate / (1.0 - rate) < w->tol))) {
            for (long i = 0; i < m; ++i) w->z[i] += w->dzt[i];
            return MGR_CONVERGED;
        }
        if (rate > w->refresh || stale_corrections(rate, next, w->tol) > w->jacobian_cost) return MGR_NEED_JACOBIAN;
        memcpy(w->dz, w->dzt, (size_t)m * sizeof(double));
        w->dz_size = next;
    }
    return MGR_FAILED;
}
