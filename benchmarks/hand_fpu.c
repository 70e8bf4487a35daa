/* Hand-written FPU chain kernels (reference for `mechgen bench`), same ABI as generated kernels:
 *   int fn(const double *const *in, double *const *out, const long *sizes, long nbatch)
 * in[0] = u (nbatch x N), in[1] = {gamma, alpha, beta}; sizes[0] = N.
 * force:  F_i = f(u_{i+1} - u_i) - f(u_i - u_{i-1}),  f(r) = gamma r + alpha r^2 + beta r^3, u_0 = u_{N+1} = 0
 * stiff:  CSR data (rows ascending, columns ascending) of K = -dF/du, tridiagonal, k(r) = f'(r). */
static double bond_force(double r, double g, double a, double b) { return r * (g + r * (a + r * b)); }
static double bond_stiff(double r, double g, double a, double b) { return g + r * (2.0 * a + 3.0 * b * r); }

int hand_force(const double *const *in, double *const *out, const long *sizes, long nbatch)
{
    const long n = sizes[0];
    const double g = in[1][0], a = in[1][1], b = in[1][2];
    for (long s = 0; s < nbatch; ++s) {
        const double *u = in[0] + s * n;
        double *F = out[0] + s * n;
        double left = bond_force(u[0], g, a, b);
        for (long i = 0; i < n; ++i) {
            const double right = bond_force((i + 1 < n ? u[i + 1] : 0.0) - u[i], g, a, b);
            F[i] = right - left;
            left = right;
        }
    }
    return 0;
}

int hand_stiffness(const double *const *in, double *const *out, const long *sizes, long nbatch)
{
    const long n = sizes[0];
    const long nnz = 3 * n - 2;
    const double g = in[1][0], a = in[1][1], b = in[1][2];
    for (long s = 0; s < nbatch; ++s) {
        const double *u = in[0] + s * n;
        double *K = out[0] + s * nnz;
        double left = bond_stiff(u[0], g, a, b);
        long p = 0;
        for (long i = 0; i < n; ++i) {
            const double right = bond_stiff((i + 1 < n ? u[i + 1] : 0.0) - u[i], g, a, b);
            if (i > 0) K[p++] = -left;
            K[p++] = left + right;
            if (i + 1 < n) K[p++] = -right;
            left = right;
        }
    }
    return 0;
}
