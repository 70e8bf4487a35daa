/* mechgen dense_lu.h: LU with partial pivoting of a small dense row-major matrix, and the solve with its factors
 * (C99). Included textually by the runtime's C sources that need it (mechgen.runtime.csrc.source inlines the
 * quoted include), so each library is still built from one text. static inline: a source that uses one of the two
 * does not warn about the other. */

/* P A = L U in place (unit L below the diagonal; piv[k]: the row swapped with row k at step k); 1 if singular */
static inline int mg_lu_factor(long n, double *A, long *piv)
{
    long i, j, k, p;
    double big, l, s;
    for (k = 0; k < n; ++k) {
        p = k;
        big = fabs(A[k * n + k]);
        for (i = k + 1; i < n; ++i)
            if (fabs(A[i * n + k]) > big) {
                big = fabs(A[i * n + k]);
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

/* b = A^-1 b from mg_lu_factor's factors */
static inline void mg_lu_apply(long n, const double *A, const long *piv, double *b)
{
    long i, j;
    double s;
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
