/* A hand-written DOP853 loop (the peer of `mechgen bench simulate`): scipy.integrate.DOP853's method written
 * out in C - the Dormand-Prince 8(5,3) tableau (passed in by the caller from scipy's own arrays, so both sides
 * use the same numbers), scipy's error norm (|h| |e5|^2 / sqrt((|e5|^2 + 0.01 |e3|^2) n), errors scaled by
 * atol + max(|y|, |y_new|) rtol), step control (safety 0.9, factor in [0.2, 10], exponent -1/8, no growth right
 * after a rejection) and initial step (Hairer, Norsett & Wanner, Solving ODEs I, sec. II.4) - around a
 * right-hand side written by hand: the forced, damped Duffing oscillator
 *     x'' = (F cos(w t) - c x' - k x - k3 x^3) / m,   p = {m, c, k, k3, F, w}.
 * It integrates from 0 to t_end and returns the end state (no dense output): the number of accepted steps,
 * or -1 when the step size falls below the spacing of the numbers, -2 past max_steps. */
#include <math.h>

#define NS 12   /* stages of the 8th-order step */
#define NX 2    /* the state (x, x') */

static void duffing(double t, const double *y, double *f, const double *p)
{
    f[0] = y[1];
    f[1] = (p[4] * cos(p[5] * t) - p[1] * y[1] - p[2] * y[0] - p[3] * y[0] * y[0] * y[0]) / p[0];
}

static double rms(const double *v, const double *scale)
{
    double s = 0.0;
    for (int i = 0; i < NX; ++i) s += (v[i] / scale[i]) * (v[i] / scale[i]);
    return sqrt(s / NX);
}

static double initial_step(double t_end, const double *y, const double *f, const double *p, double rtol,
                           double atol)
{
    double scale[NX], y1[NX], f1[NX], df[NX];
    for (int i = 0; i < NX; ++i) scale[i] = atol + fabs(y[i]) * rtol;
    const double d0 = rms(y, scale), d1 = rms(f, scale);
    double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    if (h0 > t_end) h0 = t_end;
    for (int i = 0; i < NX; ++i) y1[i] = y[i] + h0 * f[i];
    duffing(h0, y1, f1, p);
    for (int i = 0; i < NX; ++i) df[i] = f1[i] - f[i];
    const double d2 = rms(df, scale) / h0;
    const double h1 = (d1 <= 1e-15 && d2 <= 1e-15) ? fmax(1e-6, h0 * 1e-3) : pow(0.01 / fmax(d1, d2), 1.0 / 8.0);
    return fmin(fmin(100.0 * h0, h1), t_end);
}

long hand_dop853(double t_end, double *y, const double *p, double rtol, double atol, const double *A,
                 const double *B, const double *C, const double *E3, const double *E5, long max_steps)
{
    double K[NS + 1][NX], ys[NX], y_new[NX], scale[NX], e3[NX], e5[NX];
    double t = 0.0;
    duffing(t, y, K[0], p);
    double h_abs = initial_step(t_end, y, K[0], p, rtol, atol);
    long steps = 0;
    while (t < t_end) {
        const double min_step = 10.0 * fabs(nextafter(t, INFINITY) - t);
        if (h_abs < min_step) h_abs = min_step;
        int rejected = 0;
        for (;;) {
            if (h_abs < min_step) return -1;
            double t_new = t + h_abs;
            if (t_new > t_end) t_new = t_end;
            const double h = t_new - t;
            for (int s = 1; s < NS; ++s) {
                for (int i = 0; i < NX; ++i) {
                    double dy = 0.0;
                    for (int j = 0; j < s; ++j) dy += K[j][i] * A[s * 16 + j];
                    ys[i] = y[i] + dy * h;
                }
                duffing(t + C[s] * h, ys, K[s], p);
            }
            for (int i = 0; i < NX; ++i) {
                double sum = 0.0;
                for (int j = 0; j < NS; ++j) sum += K[j][i] * B[j];
                y_new[i] = y[i] + h * sum;
            }
            duffing(t + h, y_new, K[NS], p);
            double n5 = 0.0, n3 = 0.0;
            for (int i = 0; i < NX; ++i) {
                scale[i] = atol + fmax(fabs(y[i]), fabs(y_new[i])) * rtol;
                e5[i] = 0.0;
                e3[i] = 0.0;
                for (int j = 0; j <= NS; ++j) {
                    e5[i] += K[j][i] * E5[j];
                    e3[i] += K[j][i] * E3[j];
                }
                n5 += (e5[i] / scale[i]) * (e5[i] / scale[i]);
                n3 += (e3[i] / scale[i]) * (e3[i] / scale[i]);
            }
            const double err = (n5 == 0.0 && n3 == 0.0) ? 0.0 : fabs(h) * n5 / sqrt((n5 + 0.01 * n3) * NX);
            if (err < 1.0) {
                double factor = err == 0.0 ? 10.0 : fmin(10.0, 0.9 * pow(err, -1.0 / 8.0));
                if (rejected && factor > 1.0) factor = 1.0;
                h_abs *= factor;
                t = t_new;
                for (int i = 0; i < NX; ++i) {
                    y[i] = y_new[i];
                    K[0][i] = K[NS][i];
                }
                break;
            }
            h_abs *= fmax(0.2, 0.9 * pow(err, -1.0 / 8.0));
            rejected = 1;
        }
        if (++steps > max_steps) return -2;
    }
    return steps;
}
