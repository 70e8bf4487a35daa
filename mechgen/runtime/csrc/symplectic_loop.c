/* mechgen symplectic_loop.c: the whole time loop of a separable H = T(p) + V(q) in C (C99).
 *
 * One step of length h is the splitting (mechgen/runtime/core/splitting.py)
 *
 *     v += b_0 h a(q); q += a_1 h v; v += b_1 h a(q); ... ; q += a_s h v; v += b_s h a(q),
 *
 * a(q) = minv * f(q), f = -dV/dq from the model's own compiled ``force`` kernel, called through its
 * address with the mechgen ABI int mg_NAME(const double *const *in, double *const *out,
 * const long *sizes, long nbatch); its inputs are (q, v, p), its output f. The kick at the end of a
 * step and the first kick of the next share one force evaluation (no drift between them).
 * Every ``stride`` steps the total energy from the model's ``outputs`` kernel (inputs (q, v, p),
 * output number ``energy_port``) is written to energies[k] (k = 1, 2, ...; energies[0] at the start).
 *
 * Entry point: mgs_run(...) returns 0, a kernel's nonzero return code (> 0), or -1 when the state
 * became NaN/Inf (checked at every output point and at the end; *done holds the steps taken).
 */
#include <math.h>
#include <stddef.h>

typedef int (*mgs_fn)(const double *const *in, double *const *out, const long *sizes, long nbatch);

#define MGS_MAX_OUT 8

static int mgs_energy(mgs_fn fn, long nout, long port, const double *q, const double *v, const double *p,
                      const long *sizes, double *value)
{
    double slots[MGS_MAX_OUT];
    double *out[MGS_MAX_OUT];
    const double *in[3];
    long j;
    int rc;
    if (nout > MGS_MAX_OUT) return 1;
    for (j = 0; j < nout; ++j) {
        slots[j] = 0.0;
        out[j] = &slots[j];
    }
    in[0] = q;
    in[1] = v;
    in[2] = p;
    rc = fn(in, (double *const *)out, sizes, 1);
    *value = slots[port];
    return rc;
}

static int mgs_finite(const double *x, long n)
{
    long i;
    for (i = 0; i < n; ++i)
        if (!isfinite(x[i])) return 0;
    return 1;
}

int mgs_run(mgs_fn force, mgs_fn energy, long energy_nout, long energy_port, const long *sizes,
            const double *p, long n, double *q, double *v, const double *minv, double h, long steps,
            long stride, long ns, const double *a, const double *b, double *f, double *energies, long *done)
{
    const double *in[3];
    double *out[1];
    long step, s, i, k = 1;
    int valid = 0, rc;
    in[0] = q;
    in[1] = v;
    in[2] = p;
    out[0] = f;
    *done = 0;
    if (energy && stride > 0) {
        rc = mgs_energy(energy, energy_nout, energy_port, q, v, p, sizes, &energies[0]);
        if (rc) return rc;
    }
    for (step = 1; step <= steps; ++step) {
        for (s = 0; s <= ns; ++s) {
            if (b[s] != 0.0) {
                const double bh = b[s] * h;
                if (!valid) {
                    for (i = 0; i < n; ++i) f[i] = 0.0;
                    rc = force((const double *const *)in, (double *const *)out, sizes, 1);
                    if (rc) return rc;
                    valid = 1;
                }
                if (minv)
                    for (i = 0; i < n; ++i) v[i] += bh * minv[i] * f[i];
                else
                    for (i = 0; i < n; ++i) v[i] += bh * f[i];
            }
            if (s < ns) {
                const double ah = a[s] * h;
                for (i = 0; i < n; ++i) q[i] += ah * v[i];
                valid = 0;
            }
        }
        *done = step;
        if (stride > 0 && step % stride == 0) {
            if (!mgs_finite(q, n) || !mgs_finite(v, n)) return -1;
            if (energy) {
                rc = mgs_energy(energy, energy_nout, energy_port, q, v, p, sizes, &energies[k]);
                if (rc) return rc;
            }
            ++k;
        }
    }
    if (!mgs_finite(q, n) || !mgs_finite(v, n)) return -1;
    return 0;
}
