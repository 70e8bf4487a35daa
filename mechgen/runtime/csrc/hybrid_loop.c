/* mechgen hybrid_loop.c: the compiled event-driven time loop of a hybrid lumped system (C99).
 *
 * Integrates x = (q, v, z) of mode i, dq/dt = v, dv/dt = a = -M^-1 r(q, v, 0, z, t) with M = dr/da,
 * dz/dt = rates(q, v, z, t), from the model's own compiled kernels (residual__i, tangent__i, rates__i,
 * guards__i, reset__j, called through their addresses with the mechgen ABI
 * int mg_NAME(const double *const *in, double *const *out, const long *sizes, long nbatch)),
 * by the explicit Dormand-Prince 8(5,3) method with its 7th-order dense output, step for step the
 * algorithm of scipy.integrate.DOP853 (scipy/integrate/_ivp/rk.py: Hairer's error estimate from the
 * 5th- and 3rd-order embedded pairs, step factor 0.9 err^(-1/8) within [0.2, 10], no growth after a
 * rejection; the initial step of scipy/integrate/_ivp/common.py select_initial_step). Events follow
 * the rules of mechgen/runtime/core/events.py (its module doc), with the same arithmetic: sign
 * tracking with the last nonzero sign, the rate-based splitting of suspicious intervals (depth 12),
 * Brent's method on the dense output (scipy/optimize/Zeros/brentq.c, C. Harris), the state at the
 * zero integrated afresh from the step's start, one Newton correction, the start-of-mode rule,
 * ties won in guard order, max_events and Zeno bounds.
 *
 * The coefficients below are those of scipy/integrate/_ivp/dop853_coefficients.py (scipy 1.17,
 * BSD-3-Clause; from Hairer's dop853.f), printed with 17 significant digits (exact doubles).
 *
 * Entry point: mgh_run(problem, state): runs from the state until t_end, a terminal event, a stop,
 * a full buffer, a slice of steps or an error, and returns a code (MGH_* below); the state is left
 * at a point the next call resumes from (the start of a mode, or the start of a step).
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef int (*mgh_fn)(const double *const *in, double *const *out, const long *sizes, long nbatch);

#define MGH_PORTS 8
#define MGH_MAX_DEPTH 12
#define MGH_DIP_DEPTH 4
#define MGH_STACK (MGH_MAX_DEPTH + MGH_DIP_DEPTH + 3)

/* what a kernel input is */
enum { MGH_IN_Q = 0, MGH_IN_V = 1, MGH_IN_A = 2, MGH_IN_Z = 3, MGH_IN_T = 4, MGH_IN_P = 5 };

/* return codes: >= 0 the run stopped at a clean point, < 0 an error (state->err_* say where) */
enum {
    MGH_DONE = 0,          /* t_end reached */
    MGH_TERMINATED = 1,    /* a terminal event, or the first event leaving stop_mode */
    MGH_PAUSED = 2,        /* after an event (pause set): the caller decides whether to go on */
    MGH_FULL_SAMPLES = 3,  /* the sample buffer cannot take another step: grow it and call again */
    MGH_FULL_EVENTS = 4,   /* the event buffer is full: grow it and call again */
    MGH_SLICE = 5,         /* slice budget steps done: the caller checks its clock and calls again */
    MGH_E_KERNEL = -1,     /* a kernel returned nonzero (err_kind, err_mode, err_rc) */
    MGH_E_RHS = -2,        /* dx/dt is NaN/Inf at (err_t, err_x) */
    MGH_E_STATE = -3,      /* the state after a step is NaN/Inf (err_t) */
    MGH_E_RESET = -4,      /* a reset gave NaN/Inf (err_guard) */
    MGH_E_SINGULAR = -5,   /* M is singular (err_t, err_x: the step's start) */
    MGH_E_SMALL = -6,      /* the step size fell below 10 ulp of t (err_t) */
    MGH_E_EVENTS = -7,     /* more than max_events events */
    MGH_E_ZENO = -8,       /* more than zeno_events events within zeno_span (err_span) */
    MGH_E_BUDGET = -9,     /* more than budget_left steps */
    MGH_E_GUARD = -10,     /* a guard value or rate is NaN/Inf */
    MGH_E_MEMORY = -11,
    MGH_E_INPUT = -12,
    MGH_E_LEFT = -13       /* a one-directional guard of unknown sign first seen past zero its own way: crossed
                              without an event (err_guard, err_span .. err_t: the interval) */
};

/* which kernel failed (err_kind) */
enum { MGH_K_RESIDUAL = 0, MGH_K_TANGENT = 1, MGH_K_RATES = 2, MGH_K_GUARDS = 3, MGH_K_RESET = 4 };

typedef struct {
    mgh_fn fn;                 /* NULL: the mode has no such kernel */
    long nin, nout;
    long ports[MGH_PORTS];     /* MGH_IN_* of each input, in the kernel's order */
    long out_len[MGH_PORTS];   /* entries of each output */
    long pick[2];              /* outputs used: residual r; tangent r_a; rates g; guards g, g_t; reset x */
} mgh_kernel;

typedef struct {
    mgh_kernel residual, tangent, rates, guards;
    long nguards;
    const long *direction;     /* +1 rising, -1 falling, 0 both */
    const long *terminal;      /* 1: ends the run */
    const long *target;        /* mode entered (-1: terminal) */
    const long *reset;         /* reset kernel index (-1: the state is kept) */
} mgh_mode;

typedef struct {
    long n, m, nmodes, nresets, max_guards;
    const mgh_mode *modes;
    const mgh_kernel *resets;
    const double *p;
    double rtol, atol, t_end;
    long max_events, zeno_events;
    double zeno_span;
    long stop_mode;            /* the run ends after the first event leaving this mode (-1: none) */
    long pause;                /* return MGH_PAUSED after every event that does not end the run */
    long budget_left;          /* steps allowed (-1: no limit); counted as events.py counts its budget */
    long slice;                /* return MGH_SLICE after this many counted steps in one call (0: never) */
    long n_eval;               /* samples at t_eval (sorted, in [0, t_end]); 0: at step ends and events;
                                  -1: no samples */
    const double *t_eval;
    long sample_cap, event_cap;
    double *s_t, *s_x;         /* samples: time, state (sample_cap x nx) */
    long *s_mode;
    double *e_t, *e_before, *e_after;   /* events: time, states (event_cap x nx) */
    long *e_source, *e_target, *e_guard;
    long carried;              /* the state's last `carried` entries (<= m) pass through resets unchanged: integrals
                                  carried across events; the reset kernels give the nx - carried before them */
    /* a provider of dx/dt = f[0 .. 2n + m) at (t, x) in place of the residual, tangent and rates kernels (a
       continuum: mechgen/runtime/csrc/field_flow.c), returning 0 or a kernel's nonzero code; NULL: none */
    int (*flow)(void *data, double t, const double *x, double *f);
    void *flow_data;
} mgh_problem;

typedef struct {
    long phase;                /* -1: not started; 0: start of a mode; 1: inside a mode (at a step start) */
    long mode;
    double t;
    double *x;                 /* nx: the state */
    double *f;                 /* nx: dx/dt at (t, x) inside a mode */
    double h_abs;              /* the next step size inside a mode */
    double *sign, *g_old, *d_old;   /* max_guards: tracked signs, g and dg/dt at (t, x) */
    double *recent;            /* max(2, zeno_events + 1): times of the latest events (a ring) */
    long n_recent;             /* events put in the ring */
    long i_eval, n_samples, n_events;
    long steps, nfev, nguard, counted;  /* counted: budget steps of this call */
    long err_kind, err_mode, err_rc, err_guard;
    double err_t, err_span;
    double *err_x;             /* nx */
    long nrate;                /* evaluations of dx/dt for guard rates only (interval midpoints, mode starts) */
    double t_start;            /* the time the current mode started */
} mgh_state;

/* the layout the Python side checks before its first call */
long mgh_layout(long which);
long mgh_layout(long which)
{
    switch (which) {
    case 0: return (long)sizeof(mgh_kernel);
    case 1: return (long)sizeof(mgh_mode);
    case 2: return (long)sizeof(mgh_problem);
    case 3: return (long)sizeof(mgh_state);
    default: return -1;
    }
}

/* ---- DOP853 coefficients (scipy/integrate/_ivp/dop853_coefficients.py) ---- */
extern const double mgh_C[16];
extern const double mgh_A[16][16];
extern const double mgh_B[12];
extern const double mgh_E3[13];
extern const double mgh_E5[13];
extern const double mgh_D[4][16];
const double mgh_C[16] = {
    0.0, 0.05260015195876773, 0.0789002279381516, 0.1183503419072274,
    0.2816496580927726, 0.3333333333333333, 0.25, 0.3076923076923077,
    0.6512820512820513, 0.6, 0.8571428571428571, 1.0,
    1.0, 0.1, 0.2, 0.7777777777777778};

const double mgh_A[16][16] = {
    {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {0.05260015195876773, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {0.0197250569845379, 0.0591751709536137, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {0.02958758547680685, 0.0, 0.08876275643042054, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {0.2413651341592667, 0.0, -0.8845494793282861, 0.924834003261792, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {0.037037037037037035, 0.0, 0.0, 0.17082860872947386, 0.12546768756682242, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {0.037109375, 0.0, 0.0, 0.17025221101954405, 0.06021653898045596, -0.017578125, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {0.03709200011850479, 0.0, 0.0, 0.17038392571223998, 0.10726203044637328, -0.015319437748624402, 0.008273789163814023, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {0.6241109587160757, 0.0, 0.0, -3.3608926294469414, -0.868219346841726, 27.59209969944671, 20.154067550477894, -43.48988418106996, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {0.47766253643826434, 0.0, 0.0, -2.4881146199716677, -0.590290826836843, 21.230051448181193, 15.279233632882423, -33.28821096898486, -0.020331201708508627, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {-0.9371424300859873, 0.0, 0.0, 5.186372428844064, 1.0914373489967295, -8.149787010746927, -18.52006565999696, 22.739487099350505, 2.4936055526796523, -3.0467644718982196, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {2.273310147516538, 0.0, 0.0, -10.53449546673725, -2.0008720582248625, -17.9589318631188, 27.94888452941996, -2.8589982771350235, -8.87285693353063, 12.360567175794303, 0.6433927460157636, 0.0, 0.0, 0.0, 0.0, 0.0},
    {0.054293734116568765, 0.0, 0.0, 0.0, 0.0, 4.450312892752409, 1.8915178993145003, -5.801203960010585, 0.3111643669578199, -0.1521609496625161, 0.20136540080403034, 0.04471061572777259, 0.0, 0.0, 0.0, 0.0},
    {0.056167502283047954, 0.0, 0.0, 0.0, 0.0, 0.0, 0.25350021021662483, -0.2462390374708025, -0.12419142326381637, 0.15329179827876568, 0.00820105229563469, 0.007567897660545699, -0.008298, 0.0, 0.0, 0.0},
    {0.03183464816350214, 0.0, 0.0, 0.0, 0.0, 0.028300909672366776, 0.053541988307438566, -0.05492374857139099, 0.0, 0.0, -0.00010834732869724932, 0.0003825710908356584, -0.00034046500868740456, 0.1413124436746325, 0.0, 0.0},
    {-0.42889630158379194, 0.0, 0.0, 0.0, 0.0, -4.697621415361164, 7.683421196062599, 4.06898981839711, 0.3567271874552811, 0.0, 0.0, 0.0, -0.0013990241651590145, 2.9475147891527724, -9.15095847217987, 0.0}};

const double mgh_B[12] = {
    0.054293734116568765, 0.0, 0.0, 0.0,
    0.0, 4.450312892752409, 1.8915178993145003, -5.801203960010585,
    0.3111643669578199, -0.1521609496625161, 0.20136540080403034, 0.04471061572777259};

const double mgh_E3[13] = {
    -0.18980075407240762, 0.0, 0.0, 0.0,
    0.0, 4.450312892752409, 1.8915178993145003, -5.801203960010585,
    -0.4226823213237919, -0.1521609496625161, 0.20136540080403034, 0.02265179219836082,
    0.0};

const double mgh_E5[13] = {
    0.01312004499419488, 0.0, 0.0, 0.0,
    0.0, -1.2251564463762044, -0.4957589496572502, 1.6643771824549864,
    -0.35032884874997366, 0.3341791187130175, 0.08192320648511571, -0.022355307863886294,
    0.0};

const double mgh_D[4][16] = {
    {-8.428938276109013, 0.0, 0.0, 0.0, 0.0, 0.5667149535193777, -3.0689499459498917, 2.38466765651207, 2.117034582445028, -0.871391583777973, 2.2404374302607883, 0.6315787787694688, -0.08899033645133331, 18.148505520854727, -9.194632392478356, -4.436036387594894},
    {10.427508642579134, 0.0, 0.0, 0.0, 0.0, 242.28349177525817, 165.20045171727028, -374.5467547226902, -22.113666853125306, 7.733432668472264, -30.674084731089398, -9.332130526430229, 15.697238121770845, -31.139403219565178, -9.35292435884448, 35.81684148639408},
    {19.985053242002433, 0.0, 0.0, 0.0, 0.0, -387.0373087493518, -189.17813819516758, 527.8081592054236, -11.57390253995963, 6.8812326946963, -1.0006050966910838, 0.7777137798053443, -2.778205752353508, -60.19669523126412, 84.32040550667716, 11.99229113618279},
    {-25.69393346270375, 0.0, 0.0, 0.0, 0.0, -154.18974869023643, -231.5293791760455, 357.6391179106141, 93.40532418362432, -37.45832313645163, 104.0996495089623, 29.8402934266605, -43.53345659001114, 96.32455395918828, -39.17726167561544, -149.72683625798564}};

/* ---- the run's workspace ---- */
/* The state's sizes: the fields of the context, or constants when the library is built for one size
 * (-DMGH_FIXED_N=n -DMGH_FIXED_M=m: the compiler then unrolls the loops over the state; mgh_run refuses any
 * other size with MGH_E_INPUT) */
#ifdef MGH_FIXED_N
#define MGH_N(c) ((long)(MGH_FIXED_N))
#define MGH_M(c) ((long)(MGH_FIXED_M))
#else
#define MGH_N(c) ((c)->n)
#define MGH_M(c) ((c)->m)
#endif
#define MGH_NX(c) (2 * MGH_N(c) + MGH_M(c))

#define MGH_CONTINUE 100
#define MGH_EPS DBL_EPSILON

typedef struct {
    const mgh_problem *P;
    mgh_state *S;
    long n, m, nx, ng, ring;
    long *flags;               /* 2 * max_guards: crossed, crossing just after (a tie) */
    double *mem;
    double *zeros, *M, *b, *K, *F;
    double **kout;             /* (4 nmodes + nresets) x MGH_PORTS: each kernel's own outputs (kout_of) */
    const double **kin;        /* the same slots: each kernel's inputs as last set (kcall) */
    const double **kin_x, **kin_a;  /* per slot: the state and acceleration those inputs point into */
    double t_in;               /* the time input every kernel reads */
    double *y_old, *f_old, *y_new, *f_new, *ytmp, *xm, *fm, *xd, *fd, *xa, *xs, *fy, *ff, *fy2, *ff2;
    double *g_new, *d_new, *gm, *dm, *gt, *gtt, *ca, *cda, *cb, *cdb, *roots, *t_his;
    double *st_g;              /* MGH_STACK entries of 4 * max_guards: ga, da, gb, db */
    double st_ta[MGH_STACK], st_tb[MGH_STACK];
    long st_depth[MGH_STACK];
    double dense_t0, dense_h;  /* the dense output's step */
} mgh_ctx;

static double sgn(double x) { return (double)((x > 0) - (x < 0)); }

/* max(1e-12 |t_end|, 64 eps |t|): events.py time_tolerance */
static double time_tolerance(double t, double t_end)
{
    return fmax(1e-12 * fabs(t_end), 64 * MGH_EPS * fabs(t));
}

/* the outputs of the kernel `kind` (MGH_K_*) of mode `where`, or of reset `where`: its own buffers, zeroed once at
 * setup. A lumped kernel sets its structurally nonzero entries at every call and never accumulates (only lattice
 * kernels do, and the loop does not run lattices), so its structural zeros stay zero without a memset per call. */
static double *const *kout_of(const mgh_ctx *c, long kind, long where)
{
    long slot = kind == MGH_K_RESET ? 4 * c->P->nmodes + where : 4 * where + kind;
    return c->kout + slot * MGH_PORTS;
}

static int kcall(mgh_ctx *c, const mgh_kernel *k, long kind, long where, const double *x, const double *a, double t)
{
    long slot = kind == MGH_K_RESET ? 4 * c->P->nmodes + where : 4 * where + kind;
    const double **in = c->kin + slot * MGH_PORTS;
    double *const *out = c->kout + slot * MGH_PORTS;
    long sizes = 0, i;
    int rc;
    /* the inputs point into x and a: set again only when the caller's buffers change (most calls of a step
     * pass the same stage buffer); the time is read from c->t_in */
    if (x != c->kin_x[slot] || a != c->kin_a[slot]) {
        for (i = 0; i < k->nin; ++i) {
            switch (k->ports[i]) {
            case MGH_IN_Q: in[i] = x; break;
            case MGH_IN_V: in[i] = x + MGH_N(c); break;
            case MGH_IN_A: in[i] = a != NULL ? a : c->zeros; break;
            case MGH_IN_Z: in[i] = MGH_M(c) ? x + 2 * MGH_N(c) : c->zeros; break;
            case MGH_IN_T: in[i] = &c->t_in; break;
            default: in[i] = c->P->p != NULL ? c->P->p : c->zeros; break;
            }
        }
        c->kin_x[slot] = x;
        c->kin_a[slot] = a;
    }
    c->t_in = t;
    rc = k->fn(in, out, &sizes, 1);
    if (rc != 0) {
        c->S->err_kind = kind;
        c->S->err_guard = where;   /* the kernel's index: its mode, or the reset's number */
        c->S->err_mode = c->S->mode;
        c->S->err_rc = rc;
        c->S->err_t = t;
        return MGH_E_KERNEL;
    }
    return 0;
}

/* a = M^-1 b in place (Gaussian elimination with partial pivoting, M row-major n x n, destroyed); 1 if singular */
static int solve(long n, double *M, double *b)
{
    long i, j, k, p;
    double big, l, s;
    for (k = 0; k < n; ++k) {
        p = k;
        big = fabs(M[k * n + k]);
        for (i = k + 1; i < n; ++i) {
            if (fabs(M[i * n + k]) > big) {
                big = fabs(M[i * n + k]);
                p = i;
            }
        }
        if (big == 0.0)
            return 1;
        if (p != k) {
            for (j = 0; j < n; ++j) {
                s = M[k * n + j];
                M[k * n + j] = M[p * n + j];
                M[p * n + j] = s;
            }
            s = b[k];
            b[k] = b[p];
            b[p] = s;
        }
        for (i = k + 1; i < n; ++i) {
            l = M[i * n + k] / M[k * n + k];
            if (l != 0.0) {
                for (j = k + 1; j < n; ++j)
                    M[i * n + j] -= l * M[k * n + j];
                b[i] -= l * b[k];
            }
        }
    }
    for (k = n - 1; k >= 0; --k) {
        s = b[k];
        for (j = k + 1; j < n; ++j)
            s -= M[k * n + j] * b[j];
        b[k] = s / M[k * n + k];
    }
    return 0;
}

static void fail_at(mgh_ctx *c, double t, const double *x)
{
    c->S->err_t = t;
    if (x != c->S->err_x)
        memcpy(c->S->err_x, x, (size_t)MGH_NX(c) * sizeof(double));
}

/* f[0 .. 2n + m) from the problem's flow provider; its nonzero code is a kernel error of the residual */
static int flow_rhs(mgh_ctx *c, long mode, double t, const double *x, double *f)
{
    int rc = c->P->flow(c->P->flow_data, t, x, f);
    if (rc != 0) {
        c->S->err_kind = MGH_K_RESIDUAL;
        c->S->err_guard = mode;
        c->S->err_mode = mode;
        c->S->err_rc = rc;
        c->S->err_t = t;
        return MGH_E_KERNEL;
    }
    return 0;
}

/* f = dx/dt of mode `mode` at (t, x): (v, -M^-1 r(q, v, 0, z, t), rates); only the rates when n = 0.
 * Not checked for NaN/Inf: rhs() checks; the step's stages are checked at once through their error norm. */
static int rhs_unchecked(mgh_ctx *c, long mode, double t, const double *x, double *f)
{
    const mgh_mode *md = &c->P->modes[mode];
    long n = MGH_N(c), i;
    double *const *r_out = kout_of(c, MGH_K_RESIDUAL, mode), *const *M_out = r_out;
    int rc;
    if (n == 0)
        goto rates;
    if (c->P->flow != NULL) {
        if ((rc = flow_rhs(c, mode, t, x, f)) != 0)
            return rc;
        goto rates;
    }
    if ((rc = kcall(c, &md->residual, MGH_K_RESIDUAL, mode, x, NULL, t)) != 0)
        return rc;
    for (i = 0; i < n; ++i)
        c->b[i] = -r_out[md->residual.pick[0]][i];
    /* one kernel may give both r and M (the fused `flow` kernel): then M is among the residual call's outputs */
    if (md->tangent.fn != md->residual.fn) {
        if ((rc = kcall(c, &md->tangent, MGH_K_TANGENT, mode, x, NULL, t)) != 0)
            return rc;
        M_out = kout_of(c, MGH_K_TANGENT, mode);
    }
    if (n == 1) {  /* a scalar M: no elimination */
        if (M_out[md->tangent.pick[0]][0] == 0.0) {
            fail_at(c, t, x);
            c->S->err_mode = mode;  /* the mode whose M it is (a mode entered at an event: not the one left) */
            return MGH_E_SINGULAR;
        }
        c->b[0] /= M_out[md->tangent.pick[0]][0];
        goto solved;
    }
    memcpy(c->M, M_out[md->tangent.pick[0]], (size_t)(n * n) * sizeof(double));
    if (solve(n, c->M, c->b)) {
        fail_at(c, t, x);
        c->S->err_mode = mode;
        return MGH_E_SINGULAR;
    }
solved:
    memcpy(f, x + n, (size_t)n * sizeof(double));
    memcpy(f + n, c->b, (size_t)n * sizeof(double));
rates:
    if (MGH_M(c) && c->P->flow == NULL) {   /* a flow provider gives dz/dt as well */
        if ((rc = kcall(c, &md->rates, MGH_K_RATES, mode, x, NULL, t)) != 0)
            return rc;
        memcpy(f + 2 * n, kout_of(c, MGH_K_RATES, mode)[md->rates.pick[0]], (size_t)MGH_M(c) * sizeof(double));
    }
    c->S->nfev++;
    return 0;
}

/* rhs_unchecked, MGH_E_RHS (at t, x) when dx/dt is NaN/Inf */
static int rhs(mgh_ctx *c, long mode, double t, const double *x, double *f)
{
    long i;
    int rc = rhs_unchecked(c, mode, t, x, f);
    if (rc != 0)
        return rc;
    for (i = 0; i < MGH_NX(c); ++i) {
        if (!isfinite(f[i])) {
            fail_at(c, t, x);
            c->S->err_mode = mode;
            return MGH_E_RHS;
        }
    }
    return 0;
}

/* g and (with f = dx/dt there) g_t of the guards of `mode` at (t, x); without f, a = 0 and g_t = 0 */
static int guards(mgh_ctx *c, long mode, double t, const double *x, const double *f, double *g, double *gt)
{
    const mgh_mode *md = &c->P->modes[mode];
    double *const *out = kout_of(c, MGH_K_GUARDS, mode);
    long k, ng = md->nguards;
    int rc;
    if (ng == 0)
        return 0;
    if ((rc = kcall(c, &md->guards, MGH_K_GUARDS, mode, x, f != NULL ? f + MGH_N(c) : NULL, t)) != 0)
        return rc;
    c->S->nguard++;
    for (k = 0; k < ng; ++k) {
        g[k] = out[md->guards.pick[0]][k];
        gt[k] = f != NULL ? out[md->guards.pick[1]][k] : 0.0;
        if (!isfinite(g[k]) || !isfinite(gt[k])) {
            fail_at(c, t, x);
            c->S->err_guard = k;
            return MGH_E_GUARD;
        }
    }
    return 0;
}

/* ---- DOP853 (scipy.integrate._ivp.rk: rk_step, DOP853._estimate_error_norm, RungeKutta._step_impl) ---- */
static int rk_stages(mgh_ctx *c, long mode, double t, const double *y, const double *f, double h,
                     double *y_new, double *f_new)
{
    long nx = MGH_NX(c), s, j, i;
    double *K = c->K, dy;
    int rc;
    memcpy(K, f, (size_t)nx * sizeof(double));
    for (s = 1; s < 12; ++s) {
        for (i = 0; i < nx; ++i) {
            dy = 0.0;
            for (j = 0; j < s; ++j)
                dy += K[j * nx + i] * mgh_A[s][j];
            c->ytmp[i] = y[i] + dy * h;
        }
        if ((rc = rhs_unchecked(c, mode, t + mgh_C[s] * h, c->ytmp, K + s * nx)) != 0)
            return rc;
    }
    for (i = 0; i < nx; ++i) {
        dy = 0.0;
        for (j = 0; j < 12; ++j)
            dy += K[j * nx + i] * mgh_B[j];
        y_new[i] = y[i] + h * dy;
    }
    if ((rc = rhs_unchecked(c, mode, t + h, y_new, f_new)) != 0)
        return rc;
    memcpy(K + 12 * nx, f_new, (size_t)nx * sizeof(double));
    return 0;
}

/* After a step whose error norm is NaN/Inf: MGH_E_RHS at the first stage whose dx/dt is NaN/Inf (its state
 * rebuilt exactly as rk_stages made it), 0 when every stage is finite. A NaN/Inf entry of any stage makes the
 * norm NaN/Inf (it enters the E5 sum multiplied by a coefficient, and 0 * Inf is NaN), so a finite norm
 * vouches for all 13 stages: the same failures rhs() reports, checked once per step. */
static int stage_failure(mgh_ctx *c, long mode, double t, const double *y, double h, const double *y_new)
{
    long nx = MGH_NX(c), s, j, i;
    double dy;
    for (s = 1; s < 13; ++s) {  /* K[0] = f was checked where it was made */
        for (i = 0; i < nx && isfinite(c->K[s * nx + i]); ++i)
            ;
        if (i == nx)
            continue;
        if (s == 12) {
            fail_at(c, t + h, y_new);
        } else {
            for (i = 0; i < nx; ++i) {
                dy = 0.0;
                for (j = 0; j < s; ++j)
                    dy += c->K[j * nx + i] * mgh_A[s][j];
                c->ytmp[i] = y[i] + dy * h;
            }
            fail_at(c, t + mgh_C[s] * h, c->ytmp);
        }
        c->S->err_mode = mode;
        return MGH_E_RHS;
    }
    return 0;
}

static double error_norm(mgh_ctx *c, double h, const double *y, const double *y_new)
{
    long nx = MGH_NX(c), i, j;
    const mgh_problem *P = c->P;
    double e5 = 0.0, e3 = 0.0, s5, s3, scale;
    for (i = 0; i < nx; ++i) {
        scale = P->atol + fmax(fabs(y[i]), fabs(y_new[i])) * P->rtol;
        s5 = 0.0;
        s3 = 0.0;
        for (j = 0; j < 13; ++j) {
            s5 += c->K[j * nx + i] * mgh_E5[j];
            s3 += c->K[j * nx + i] * mgh_E3[j];
        }
        s5 /= scale;
        s3 /= scale;
        e5 += s5 * s5;
        e3 += s3 * s3;
    }
    if (e5 == 0.0 && e3 == 0.0)
        return 0.0;
    return fabs(h) * e5 / sqrt((e5 + 0.01 * e3) * (double)nx);
}

/* one accepted step from (t, y, f) towards t_bound; *h_abs: the proposed size in, the next one out */
static int dop_step(mgh_ctx *c, long mode, double t, const double *y, const double *f, double *h_abs_io,
                    double t_bound, double *t_new_out, double *h_out, double *y_new, double *f_new)
{
    double min_step = 10 * fabs(nextafter(t, INFINITY) - t);
    double h_abs = *h_abs_io, h, t_new, err, factor;
    int rejected = 0, rc;
    if (h_abs < min_step)
        h_abs = min_step;
    for (;;) {
        if (h_abs < min_step)
            return MGH_E_SMALL;
        t_new = t + h_abs;
        if (t_new - t_bound > 0)
            t_new = t_bound;
        h = t_new - t;
        h_abs = fabs(h);
        if ((rc = rk_stages(c, mode, t, y, f, h, y_new, f_new)) != 0)
            return rc;
        err = error_norm(c, h, y, y_new);
        if (!isfinite(err) && (rc = stage_failure(c, mode, t, y, h, y_new)) != 0)
            return rc;
        if (err < 1) {
            factor = err == 0 ? 10.0 : fmin(10.0, 0.9 * pow(err, -0.125));
            if (rejected)
                factor = fmin(1.0, factor);
            h_abs *= factor;
            break;
        }
        h_abs *= fmax(0.2, 0.9 * pow(err, -0.125));
        rejected = 1;
    }
    *h_abs_io = h_abs;
    *t_new_out = t_new;
    *h_out = h;
    return 0;
}

/* the dense output of the last step (t_old, y_old, f_old) -> (t_old + h, y_new, f_new): F (7 x nx) */
static int dense_prepare(mgh_ctx *c, long mode, double t_old, double h)
{
    long nx = MGH_NX(c), s, j, i, r;
    double *K = c->K, dy;
    int rc;
    for (s = 13; s < 16; ++s) {
        for (i = 0; i < nx; ++i) {
            dy = 0.0;
            for (j = 0; j < s; ++j)
                dy += K[j * nx + i] * mgh_A[s][j];
            c->ytmp[i] = c->y_old[i] + dy * h;
        }
        if ((rc = rhs(c, mode, t_old + mgh_C[s] * h, c->ytmp, K + s * nx)) != 0)
            return rc;
    }
    for (i = 0; i < nx; ++i) {
        dy = c->y_new[i] - c->y_old[i];
        c->F[i] = dy;
        c->F[nx + i] = h * c->f_old[i] - dy;
        c->F[2 * nx + i] = 2 * dy - h * (c->f_new[i] + c->f_old[i]);
        for (r = 0; r < 4; ++r) {
            dy = 0.0;
            for (j = 0; j < 16; ++j)
                dy += mgh_D[r][j] * K[j * nx + i];
            c->F[(3 + r) * nx + i] = h * dy;
        }
    }
    c->dense_t0 = t_old;
    c->dense_h = h;
    return 0;
}

/* the dense output at tt (scipy Dop853DenseOutput._call_impl) */
static void dense_eval(mgh_ctx *c, double tt, double *out)
{
    long nx = MGH_NX(c), i, k;
    double x = (tt - c->dense_t0) / c->dense_h;
    for (i = 0; i < nx; ++i) {
        double y = 0.0;
        for (k = 0; k < 7; ++k) {
            y += c->F[(6 - k) * nx + i];
            y *= (k % 2 == 0) ? x : 1 - x;
        }
        out[i] = y + c->y_old[i];
    }
}

static double rms(const double *a, const double *scale, long nx)
{
    double s = 0.0;
    long i;
    for (i = 0; i < nx; ++i)
        s += (a[i] / scale[i]) * (a[i] / scale[i]);
    return sqrt(s) / sqrt((double)nx);
}

/* scipy.integrate._ivp.common.select_initial_step (order 7, forward, no max_step) */
static int initial_step(mgh_ctx *c, long mode, double t0, const double *y0, const double *f0, double *h_out)
{
    const mgh_problem *P = c->P;
    long nx = MGH_NX(c), i;
    double interval = fabs(P->t_end - t0), d0, d1, d2, h0, h1;
    double *scale = c->xd, *y1 = c->ytmp, *f1 = c->fd;
    int rc;
    if (interval == 0.0) {
        *h_out = 0.0;
        return 0;
    }
    for (i = 0; i < nx; ++i)
        scale[i] = P->atol + fabs(y0[i]) * P->rtol;
    d0 = rms(y0, scale, nx);
    d1 = rms(f0, scale, nx);
    h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    h0 = fmin(h0, interval);
    for (i = 0; i < nx; ++i)
        y1[i] = y0[i] + h0 * f0[i];
    if ((rc = rhs(c, mode, t0 + h0, y1, f1)) != 0)
        return rc;
    for (i = 0; i < nx; ++i)
        f1[i] -= f0[i];
    d2 = rms(f1, scale, nx) / h0;
    if (d1 <= 1e-15 && d2 <= 1e-15)
        h1 = fmax(1e-6, h0 * 1e-3);
    else
        h1 = pow(0.01 / fmax(d1, d2), 1.0 / 8.0);
    *h_out = fmin(fmin(100 * h0, h1), interval);
    return 0;
}

/* ---- samples and events ---- */
static void record(mgh_ctx *c, double t, const double *x, long mode)
{
    const mgh_problem *P = c->P;
    mgh_state *S = c->S;
    if (P->n_eval != 0 || S->n_samples >= P->sample_cap)
        return;
    P->s_t[S->n_samples] = t;
    memcpy(P->s_x + S->n_samples * MGH_NX(c), x, (size_t)MGH_NX(c) * sizeof(double));
    P->s_mode[S->n_samples] = mode;
    S->n_samples++;
}

/* samples at the t_eval <= t_hi not yet taken, from the dense output */
static void sample_until(mgh_ctx *c, double t_hi, long mode)
{
    const mgh_problem *P = c->P;
    mgh_state *S = c->S;
    if (P->n_eval <= 0)
        return;
    while (S->i_eval < P->n_eval && P->t_eval[S->i_eval] <= t_hi) {
        P->s_t[S->i_eval] = P->t_eval[S->i_eval];
        dense_eval(c, P->t_eval[S->i_eval], P->s_x + S->i_eval * MGH_NX(c));
        P->s_mode[S->i_eval] = mode;
        S->i_eval++;
    }
    S->n_samples = S->i_eval;
}

/* guard k of the current mode fires at (t, x): the state after it in c->xa, the mode entered in *target */
static int fire(mgh_ctx *c, long k, double t, const double *x, long *target)
{
    const mgh_problem *P = c->P;
    mgh_state *S = c->S;
    const mgh_mode *md = &P->modes[S->mode];
    long nx = MGH_NX(c), r = md->reset[k], e, i;
    int rc;
    if (r >= 0) {
        if ((rc = kcall(c, &P->resets[r], MGH_K_RESET, r, x, NULL, t)) != 0)
            return rc;
        memcpy(c->xa, kout_of(c, MGH_K_RESET, r)[P->resets[r].pick[0]], (size_t)(nx - P->carried) * sizeof(double));
        memcpy(c->xa + nx - P->carried, x + nx - P->carried, (size_t)P->carried * sizeof(double));
    } else {
        memcpy(c->xa, x, (size_t)nx * sizeof(double));
    }
    for (i = 0; i < nx; ++i) {
        if (!isfinite(c->xa[i])) {
            fail_at(c, t, x);
            S->err_mode = S->mode;
            S->err_guard = k;
            return MGH_E_RESET;
        }
    }
    *target = md->terminal[k] ? -1 : md->target[k];
    e = S->n_events;
    if (e >= P->event_cap)
        return MGH_E_INPUT;
    P->e_t[e] = t;
    P->e_source[e] = S->mode;
    P->e_target[e] = *target;
    P->e_guard[e] = k;
    memcpy(P->e_before + e * nx, x, (size_t)nx * sizeof(double));
    memcpy(P->e_after + e * nx, c->xa, (size_t)nx * sizeof(double));
    S->n_events++;
    S->recent[S->n_recent % c->ring] = t;
    S->n_recent++;
    S->err_t = t;
    S->err_mode = S->mode;
    S->err_guard = k;
    if (S->n_events > P->max_events)
        return MGH_E_EVENTS;
    if (S->n_recent >= c->ring) {
        double span = t - S->recent[S->n_recent % c->ring];
        if (span <= P->zeno_span) {
            S->err_span = span;
            return MGH_E_ZENO;
        }
    }
    return 0;
}

/* after an event: the run ends (terminal, stop_mode), pauses, or goes on in the mode entered */
static int after_event(mgh_ctx *c, long target)
{
    mgh_state *S = c->S;
    long source = S->mode;
    memcpy(S->x, c->xa, (size_t)MGH_NX(c) * sizeof(double));
    S->phase = 0;
    if (target < 0)
        return MGH_TERMINATED;
    S->mode = target;
    if (c->P->stop_mode == source)
        return MGH_TERMINATED;
    if (c->P->pause)
        return MGH_PAUSED;
    return MGH_CONTINUE;
}

/* ---- guard checks on a step (events.py _crossed, _possible_crossing, _many_roots, _scan, _root) ---- */
static long quad_roots(double A, double B, double C, double *u)
{
    double disc, sq, q;
    if (A == 0.0) {
        if (B == 0.0)
            return 0;
        u[0] = -C / B;
        return 1;
    }
    disc = B * B - 4 * A * C;
    if (disc < 0)
        return 0;
    sq = sqrt(disc);
    q = -0.5 * (B + (B >= 0 ? sq : -sq));
    if (q == 0.0) {
        u[0] = 0.0;
        return 1;
    }
    u[0] = q / A;
    u[1] = C / q;
    return 2;
}

/* the interior extrema u in (0, 1) of the cubic Hermite through (ga, da), (gb, db) on an interval h */
static long hermite_extrema(double ga, double da, double gb, double db, double h, double *u, double *cs)
{
    double c1 = h * da, c2 = 3 * (gb - ga) - h * (2 * da + db), c3 = 2 * (ga - gb) + h * (da + db);
    double r[2];
    long nr, i, out = 0;
    cs[0] = c1;
    cs[1] = c2;
    cs[2] = c3;
    if (c3 == 0.0 && c2 == 0.0)
        return 0;
    nr = quad_roots(3 * c3, 2 * c2, c1, r);
    for (i = 0; i < nr; ++i)
        if (0 < r[i] && r[i] < 1)
            u[out++] = r[i];
    return out;
}

static int crossed_rule(double sign, double g, long direction)
{
    double s = sgn(g);
    return sign != 0 && s != 0 && s == -sign && (direction == 0 || (double)direction == s);
}

/* events.py _hermite: the sign changes of the cubic Hermite through (ga, h da), (gb, h db) counted from the
 * tracked sign s along its interior extrema (in order) and its end; *inside: whether it has an interior extremum */
static long hermite_changes(double s, double ga, double da, double gb, double db, double h, int *inside)
{
    double u[2], cs[3], values[3], last = s, swap;
    long nu = hermite_extrema(ga, da, gb, db, h, u, cs), i, n = 0, changes = 0;
    if (nu == 2 && u[1] < u[0]) {
        swap = u[0];
        u[0] = u[1];
        u[1] = swap;
    }
    for (i = 0; i < nu; ++i)
        values[n++] = ga + u[i] * (cs[0] + u[i] * (cs[1] + u[i] * cs[2]));
    values[n++] = gb;
    for (i = 0; i < n; ++i) {
        if (values[i] != 0.0 && sgn(values[i]) != last) {
            changes++;
            last = -last;
        }
    }
    *inside = nu > 0;
    return changes;
}

/* events.py _dip: u of the first interior extremum of the cubic Hermite past zero (sign -s) while both ends
 * keep the sign s; -1 when there is none */
static double hermite_dip(double s, double ga, double da, double gb, double db, double h)
{
    double u[2], cs[3], swap, value;
    long nu, i;
    if (ga == 0.0 || gb == 0.0 || sgn(ga) != s || sgn(gb) != s)
        return -1.0;
    nu = hermite_extrema(ga, da, gb, db, h, u, cs);
    if (nu == 2 && u[1] < u[0]) {
        swap = u[0];
        u[0] = u[1];
        u[1] = swap;
    }
    for (i = 0; i < nu; ++i) {
        value = ga + u[i] * (cs[0] + u[i] * (cs[1] + u[i] * cs[2]));
        if (value != 0.0 && sgn(value) != s)
            return u[i];
    }
    return -1.0;
}

/* events.py split_point: the midpoint above MGH_MAX_DEPTH; below it, for MGH_DIP_DEPTH more levels, the
 * extremum of the first guard whose cubic dips through zero between two ends of its tracked sign, within
 * [1/16, 15/16] of the interval; else -INFINITY (not split) */
static double split_point(const double *sign, const double *ga, const double *da, const double *gb,
                          const double *db, long ng, double ta, double tb, long depth)
{
    long k;
    double h = tb - ta, u;
    if (depth < MGH_MAX_DEPTH)
        return 0.5 * (ta + tb);
    if (depth >= MGH_MAX_DEPTH + MGH_DIP_DEPTH)
        return -INFINITY;
    for (k = 0; k < ng; ++k) {
        if (sign[k] == 0)
            continue;
        u = hermite_dip(sign[k], ga[k], da[k], gb[k], db[k], h);
        if (u >= 0.0)
            return ta + fmin(fmax(u, 1.0 / 16), 15.0 / 16) * h;
    }
    return -INFINITY;
}

/* events.py _suspicious: whether the interval of length h with ends (ga, da), (gb, db) must be halved ("Missed
 * events"): a guard of unchanged sign whose zero is within reach of either end at its rate, whose end rates
 * depart from the chord by as much as its distance from zero, or whose cubic dips through zero; a guard whose
 * sign flipped and whose cubic turns inside; a guard of unknown sign on the interval that starts the mode */
static int suspicious(const double *sign, const double *ga, const double *da, const double *gb, const double *db,
                      long ng, double h, int at_start)
{
    long k;
    int inside;
    for (k = 0; k < ng; ++k) {
        double s = sign[k], a = ga[k], ra = da[k], b = gb[k], rb = db[k], toward_a, toward_b, chord;
        if (s == 0) {
            if (at_start)
                return 1;
            continue;
        }
        if (b != 0.0 && sgn(b) != s) {
            hermite_changes(s, a, ra, b, rb, h, &inside);
            if (inside)
                return 1;
            continue;
        }
        toward_a = -s * ra;
        toward_b = s * rb;
        if ((toward_a > 0 && s * a <= h * toward_a) || (toward_b > 0 && s * b <= h * toward_b))
            return 1;
        chord = b - a;
        if (fmax(fabs(h * ra - chord), fabs(h * rb - chord)) >= fmax(s * a, s * b))
            return 1;
        if (hermite_changes(s, a, ra, b, rb, h, &inside) > 0)
            return 1;
    }
    return 0;
}

static int gvalue(mgh_ctx *c, long mode, long k, double t, double *value)
{
    int rc;
    dense_eval(c, t, c->xm);
    if ((rc = guards(c, mode, t, c->xm, NULL, c->gt, c->gtt)) != 0)
        return rc;
    *value = c->gt[k];
    return 0;
}

/* the zero of guard k on [ta, tb] along the dense output: scipy's brentq (xtol 4 eps max|t|, rtol 4 eps) */
static int root(mgh_ctx *c, long mode, long k, double ta, double tb, double *out)
{
    double xpre = ta, xcur = tb, xblk = 0.0, fpre, fcur, fblk = 0.0, spre = 0.0, scur = 0.0, sbis;
    double delta, stry, dpre, dblk;
    double xtol = 4 * MGH_EPS * fmax(fmax(fabs(ta), fabs(tb)), 1e-300), rtol = 4 * MGH_EPS;
    int rc, i;
    if ((rc = gvalue(c, mode, k, ta, &fpre)) != 0 || (rc = gvalue(c, mode, k, tb, &fcur)) != 0)
        return rc;
    if (fpre == 0) {
        *out = ta;
        return 0;
    }
    if (fcur == 0 || sgn(fpre) == sgn(fcur)) {
        *out = tb;
        return 0;
    }
    for (i = 0; i < 200; ++i) {
        if (fpre != 0 && fcur != 0 && (signbit(fpre) != signbit(fcur))) {
            xblk = xpre;
            fblk = fpre;
            spre = scur = xcur - xpre;
        }
        if (fabs(fblk) < fabs(fcur)) {
            xpre = xcur;
            xcur = xblk;
            xblk = xpre;
            fpre = fcur;
            fcur = fblk;
            fblk = fpre;
        }
        delta = (xtol + rtol * fabs(xcur)) / 2;
        sbis = (xblk - xcur) / 2;
        if (fcur == 0 || fabs(sbis) < delta)
            break;
        if (fabs(spre) > delta && fabs(fcur) < fabs(fpre)) {
            if (xpre == xblk) {
                stry = -fcur * (xcur - xpre) / (fcur - fpre);     /* interpolate */
            } else {
                dpre = (fpre - fcur) / (xpre - xcur);             /* extrapolate */
                dblk = (fblk - fcur) / (xblk - xcur);
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre));
            }
            if (2 * fabs(stry) < fmin(fabs(spre), 3 * fabs(sbis) - delta)) {
                spre = scur;                                      /* good short step */
                scur = stry;
            } else {
                spre = sbis;                                      /* bisect */
                scur = sbis;
            }
        } else {
            spre = sbis;
            scur = sbis;
        }
        xpre = xcur;
        fpre = fcur;
        if (fabs(scur) > delta)
            xcur += scur;
        else
            xcur += (sbis > 0 ? delta : -delta);
        if ((rc = gvalue(c, mode, k, xcur, &fcur)) != 0)
            return rc;
    }
    *out = xcur;
    return 0;
}

static void push(mgh_ctx *c, long *sp, double ta, const double *ga, const double *da, double tb,
                 const double *gb, const double *db, long depth)
{
    long ng = c->ng;
    size_t nb = (size_t)ng * sizeof(double);
    double *slot = c->st_g + *sp * 4 * ng;
    c->st_ta[*sp] = ta;
    c->st_tb[*sp] = tb;
    c->st_depth[*sp] = depth;
    if (ng) {
        memcpy(slot, ga, nb);
        memcpy(slot + ng, da, nb);
        memcpy(slot + 2 * ng, gb, nb);
        memcpy(slot + 3 * ng, db, nb);
    }
    (*sp)++;
}

/* the earliest interval of the step in which a guard crosses: 1 (and *k, *t_lo, *t_hi, *t_root), 0 none */
static int scan(mgh_ctx *c, long mode, double *sign, double t0, double t1, long *k_out, double *t_lo,
                double *t_hi, double *t_root)
{
    const mgh_mode *md = &c->P->modes[mode];
    long ng = md->nguards, sp = 0, k, depth, best;
    long *crossed = c->flags, *tie = c->flags + c->ng;
    double *t_his = c->t_his;
    double ta, tb, tm, h, t_first, t_tie;
    int rc, any_crossed, others;
    push(c, &sp, t0, c->S->g_old, c->S->d_old, t1, c->g_new, c->d_new, 0);
    while (sp > 0) {
        double *slot;
        sp--;
        slot = c->st_g + sp * 4 * c->ng;
        ta = c->st_ta[sp];
        tb = c->st_tb[sp];
        depth = c->st_depth[sp];
        memcpy(c->ca, slot, (size_t)ng * sizeof(double));
        memcpy(c->cda, slot + c->ng, (size_t)ng * sizeof(double));
        memcpy(c->cb, slot + 2 * c->ng, (size_t)ng * sizeof(double));
        memcpy(c->cdb, slot + 3 * c->ng, (size_t)ng * sizeof(double));
        h = tb - ta;
        tm = -INFINITY;
        if (depth < MGH_MAX_DEPTH + MGH_DIP_DEPTH
            && suspicious(sign, c->ca, c->cda, c->cb, c->cdb, ng, h, ta == c->S->t_start))
            tm = split_point(sign, c->ca, c->cda, c->cb, c->cdb, ng, ta, tb, depth);
        if (tm > -INFINITY) {
            dense_eval(c, tm, c->xm);
            if ((rc = rhs(c, mode, tm, c->xm, c->fm)) != 0)
                return rc;
            c->S->nrate++;
            if ((rc = guards(c, mode, tm, c->xm, c->fm, c->gm, c->dm)) != 0)
                return rc;
            push(c, &sp, tm, c->gm, c->dm, tb, c->cb, c->cdb, depth + 1);
            push(c, &sp, ta, c->ca, c->cda, tm, c->gm, c->dm, depth + 1);
            continue;
        }
        any_crossed = 0;
        for (k = 0; k < ng; ++k) {
            crossed[k] = crossed_rule(sign[k], c->cb[k], md->direction[k]);
            any_crossed |= (int)crossed[k];
        }
        if (any_crossed) {  /* events.py _first: the earliest zero, ties within the location tolerance */
            t_first = INFINITY;
            for (k = 0; k < ng; ++k) {
                tie[k] = 0;
                t_his[k] = tb;
                if (crossed[k]) {
                    if ((rc = root(c, mode, k, ta, tb, &c->roots[k])) != 0)
                        return rc;
                    if (c->roots[k] < t_first)
                        t_first = c->roots[k];
                }
            }
            t_tie = t_first + time_tolerance(t_first, c->P->t_end);
            others = 0;
            for (k = 0; k < ng; ++k)
                others |= !crossed[k] && sign[k] != 0;
            if (t_tie > tb && others) {  /* a guard crossing just after the interval is a tie */
                dense_eval(c, t_tie, c->xm);
                if ((rc = guards(c, mode, t_tie, c->xm, NULL, c->gm, c->dm)) != 0)
                    return rc;
                for (k = 0; k < ng; ++k)
                    tie[k] = !crossed[k] && sign[k] != 0 && crossed_rule(sign[k], c->gm[k], md->direction[k]);
                for (k = 0; k < ng; ++k) {
                    if (tie[k]) {
                        if ((rc = root(c, mode, k, ta, t_tie, &c->roots[k])) != 0)
                            return rc;
                        t_his[k] = t_tie;
                    }
                }
            }
            best = -1;
            for (k = 0; k < ng && best < 0; ++k)
                if ((crossed[k] || tie[k]) && c->roots[k] <= t_tie)
                    best = k;
            *k_out = best;
            *t_lo = ta;
            *t_hi = t_his[best];
            *t_root = c->roots[best];
            return 1;
        }
        for (k = 0; k < ng; ++k) {  /* events.py "Unnoticed crossings" */
            if (sign[k] == 0 && md->direction[k] != 0 && sgn(c->cb[k]) == (double)md->direction[k]) {
                c->S->err_guard = k;
                c->S->err_span = ta;
                c->S->err_t = tb;
                return MGH_E_LEFT;
            }
        }
        for (k = 0; k < ng; ++k)
            if (sgn(c->cb[k]) != 0)
                sign[k] = sgn(c->cb[k]);
    }
    return 0;
}

/* (t*, x*) of guard k's zero t_d in [t_lo, t_hi] (events.py _locate): the state integrated afresh from the
 * step's start to t_d, and one Newton correction t* = t_d - g/g_t, x* = x_d + (t* - t_d) f */
static int locate(mgh_ctx *c, long mode, long k, double t_lo, double t_hi, double t_old, double t_d,
                  double *t_star)
{
    const mgh_problem *P = c->P;
    long nx = MGH_NX(c), i;
    double t = t_old, h_abs = t_d - t_old, t_new, h, dt;
    int rc;
    if (t_d > t_old) {
        int failed = 0;
        memcpy(c->fy, c->y_old, (size_t)nx * sizeof(double));
        memcpy(c->ff, c->f_old, (size_t)nx * sizeof(double));
        while (t < t_d) {
            rc = dop_step(c, mode, t, c->fy, c->ff, &h_abs, t_d, &t_new, &h, c->fy2, c->ff2);
            if (rc == MGH_E_SMALL) {
                failed = 1;
                break;
            }
            if (rc != 0)
                return rc;
            memcpy(c->fy, c->fy2, (size_t)nx * sizeof(double));
            memcpy(c->ff, c->ff2, (size_t)nx * sizeof(double));
            t = t_new;
        }
        if (failed)
            dense_eval(c, t_d, c->xs);
        else
            memcpy(c->xs, c->fy, (size_t)nx * sizeof(double));
    } else {
        memcpy(c->xs, c->y_old, (size_t)nx * sizeof(double));
    }
    if ((rc = rhs(c, mode, t_d, c->xs, c->fd)) != 0)
        return rc;
    if ((rc = guards(c, mode, t_d, c->xs, c->fd, c->gt, c->gtt)) != 0)
        return rc;
    *t_star = t_d;
    if (c->gtt[k] != 0 && fabs(c->gt[k] / c->gtt[k]) <= fmax(t_hi - t_lo, time_tolerance(t_d, P->t_end))) {
        dt = -c->gt[k] / c->gtt[k];
        *t_star = t_d + dt;
        for (i = 0; i < nx; ++i)
            c->xs[i] += dt * c->fd[i];
    }
    return 0;
}

/* the start of a mode (events.py "Start of a mode"): a guard on its surface takes the sign of its rate and
 * fires at once when that is its direction; else the mode's integration starts */
static int start_mode(mgh_ctx *c)
{
    const mgh_problem *P = c->P;
    mgh_state *S = c->S;
    const mgh_mode *md = &P->modes[S->mode];
    long ng = md->nguards, k, at_once = -1, target;
    double tol;
    int rc;
    if (P->n_eval == 0 && S->n_samples + 1 > P->sample_cap)
        return MGH_FULL_SAMPLES;
    if (ng > 0 && S->n_events + 1 > P->event_cap)
        return MGH_FULL_EVENTS;
    if ((rc = rhs(c, S->mode, S->t, S->x, S->f)) != 0)
        return rc;
    S->t_start = S->t;
    if (ng > 0)
        S->nrate++;
    if ((rc = guards(c, S->mode, S->t, S->x, S->f, S->g_old, S->d_old)) != 0)
        return rc;
    tol = time_tolerance(S->t, P->t_end);
    for (k = 0; k < ng; ++k) {
        int surface = S->g_old[k] == 0 || fabs(S->g_old[k]) <= fabs(S->d_old[k]) * tol;
        S->sign[k] = surface ? sgn(S->d_old[k]) : sgn(S->g_old[k]);
        if (at_once < 0 && surface && S->sign[k] != 0
            && (md->direction[k] == 0 || (double)md->direction[k] == S->sign[k]))
            at_once = k;
    }
    if (at_once >= 0) {
        if ((rc = fire(c, at_once, S->t, S->x, &target)) != 0)
            return rc;
        record(c, S->t, c->xa, target < 0 ? S->mode : target);
        return after_event(c, target);
    }
    if (S->t >= P->t_end)
        return MGH_DONE;
    if ((rc = initial_step(c, S->mode, S->t, S->x, S->f, &S->h_abs)) != 0)
        return rc;
    S->phase = 1;
    return MGH_CONTINUE;
}

/* one accepted step of the current mode, its guards checked (events.py _integrate_segment) */
static int step(mgh_ctx *c)
{
    const mgh_problem *P = c->P;
    mgh_state *S = c->S;
    const mgh_mode *md = &P->modes[S->mode];
    long nx = MGH_NX(c), ng = md->nguards, mode = S->mode, k = 0, i, target;
    double t_old = S->t, t_new, h, t_lo = 0.0, t_hi = 0.0, t_root = 0.0, t_star;
    int rc, found;
    if (P->n_eval == 0 && S->n_samples + 3 > P->sample_cap)
        return MGH_FULL_SAMPLES;
    if (ng > 0 && S->n_events + 1 > P->event_cap)
        return MGH_FULL_EVENTS;
    memcpy(c->y_old, S->x, (size_t)nx * sizeof(double));
    memcpy(c->f_old, S->f, (size_t)nx * sizeof(double));
    rc = dop_step(c, mode, t_old, c->y_old, c->f_old, &S->h_abs, P->t_end, &t_new, &h, c->y_new, c->f_new);
    if (rc == MGH_E_SMALL || rc == MGH_E_SINGULAR) {
        fail_at(c, t_old, c->y_old);
        S->err_mode = mode;
    }
    if (rc != 0)
        return rc;
    S->steps++;
    for (i = 0; i < nx; ++i) {
        if (!isfinite(c->y_new[i])) {
            fail_at(c, t_new, c->y_new);
            S->err_mode = mode;
            return MGH_E_STATE;
        }
    }
    /* the dense output (3 more evaluations) only where it is read: guards to scan, or a sample inside the step
     * (scipy's solve_ivp builds it on the same condition) */
    if (ng > 0 || (P->n_eval > 0 && S->i_eval < P->n_eval && P->t_eval[S->i_eval] <= t_new))
        if ((rc = dense_prepare(c, mode, t_old, h)) != 0)
            goto failed;
    if ((rc = guards(c, mode, t_new, c->y_new, c->f_new, c->g_new, c->d_new)) != 0)
        goto failed;
    found = ng > 0 ? scan(c, mode, S->sign, t_old, t_new, &k, &t_lo, &t_hi, &t_root) : 0;
    if (found < 0) {
        rc = found;
        goto failed;
    }
    if (found) {
        if ((rc = locate(c, mode, k, t_lo, t_hi, t_old, t_root, &t_star)) != 0)
            goto failed;
        sample_until(c, t_star, mode);
        S->t = t_star;
        if ((rc = fire(c, k, t_star, c->xs, &target)) != 0)
            return rc;
        record(c, t_star, c->xs, mode);
        record(c, t_star, c->xa, target < 0 ? mode : target);
        return after_event(c, target);
    }
    for (k = 0; k < ng; ++k)
        if (sgn(c->g_new[k]) != 0)
            S->sign[k] = sgn(c->g_new[k]);
    sample_until(c, t_new, mode);
    record(c, t_new, c->y_new, mode);
    S->t = t_new;
    memcpy(S->x, c->y_new, (size_t)nx * sizeof(double));
    memcpy(S->f, c->f_new, (size_t)nx * sizeof(double));
    if (ng) {
        memcpy(S->g_old, c->g_new, (size_t)ng * sizeof(double));
        memcpy(S->d_old, c->d_new, (size_t)ng * sizeof(double));
    }
    S->counted++;
    if (P->budget_left >= 0 && S->counted > P->budget_left) {
        S->err_t = t_new;
        S->err_mode = mode;
        return MGH_E_BUDGET;
    }
    if (t_new >= P->t_end)
        return MGH_DONE;
    if (P->slice > 0 && S->counted >= P->slice)
        return MGH_SLICE;
    return MGH_CONTINUE;
failed:
    if (rc == MGH_E_SINGULAR)
        fail_at(c, t_old, c->y_old);
    S->err_mode = mode;
    return rc;
}

static long kernel_outputs(const mgh_kernel *k, long j)
{
    return (k->fn != NULL && j < k->nout) ? k->out_len[j] : 0;
}

static int check_kernel(const mgh_kernel *k, int needed)
{
    long i;
    if (k->fn == NULL)
        return needed ? 1 : 0;
    if (k->nin < 0 || k->nin > MGH_PORTS || k->nout < 1 || k->nout > MGH_PORTS)
        return 1;
    for (i = 0; i < k->nin; ++i)
        if (k->ports[i] < MGH_IN_Q || k->ports[i] > MGH_IN_P)
            return 1;
    for (i = 0; i < 2; ++i)
        if (k->pick[i] < 0 || k->pick[i] >= k->nout)
            return 1;
    return 0;
}

/* kernel slot i of kout_of: 4 per mode (residual, tangent, rates, guards), then the resets */
static const mgh_kernel *loop_kernel(const mgh_problem *P, long i)
{
    const mgh_mode *md;
    if (i >= 4 * P->nmodes)
        return &P->resets[i - 4 * P->nmodes];
    md = &P->modes[i / 4];
    switch (i % 4) {
    case MGH_K_RESIDUAL: return &md->residual;
    case MGH_K_TANGENT: return &md->tangent;
    case MGH_K_RATES: return &md->rates;
    default: return &md->guards;
    }
}

static void release(mgh_ctx *c)
{
    free(c->mem);
    free(c->flags);
    free(c->kout);
    free((void *)c->kin);
    c->mem = NULL;
    c->flags = NULL;
    c->kout = NULL;
    c->kin = NULL;
}

static int setup(mgh_ctx *c, const mgh_problem *P, mgh_state *S)
{
    long n = P->n, m = P->m, nx = 2 * P->n + P->m, ng = P->max_guards > 0 ? P->max_guards : 1;
    long i, j, total, nk = 4 * P->nmodes + P->nresets;
    long lumped = P->flow == NULL ? n : 0;   /* unknowns whose dx/dt the residual and tangent kernels give */
    double *p;
    memset(c, 0, sizeof(*c));
    c->P = P;
    c->S = S;
#ifdef MGH_FIXED_N
    if (n != MGH_FIXED_N || m != MGH_FIXED_M)
        return MGH_E_INPUT;
#endif
    if (n < 0 || m < 0 || n + m < 1 || P->nmodes < 1 || P->modes == NULL || S->mode < 0 || S->mode >= P->nmodes
        || P->max_guards < 0 || (P->nresets > 0 && P->resets == NULL) || P->zeno_events < 0
        || P->carried < 0 || P->carried > m)
        return MGH_E_INPUT;
    for (i = 0; i < P->nmodes; ++i) {
        const mgh_mode *md = &P->modes[i];
        if (check_kernel(&md->residual, lumped > 0) || check_kernel(&md->tangent, lumped > 0)
            || check_kernel(&md->rates, m > 0 && P->flow == NULL) || check_kernel(&md->guards, md->nguards > 0) || md->nguards > P->max_guards || md->nguards < 0)
            return MGH_E_INPUT;
        for (j = 0; j < md->nguards; ++j)
            if (md->target[j] >= P->nmodes || md->reset[j] >= P->nresets || (!md->terminal[j] && md->target[j] < 0))
                return MGH_E_INPUT;
        if (lumped > 0 && (md->tangent.out_len[md->tangent.pick[0]] != n * n
                      || md->residual.out_len[md->residual.pick[0]] != n))
            return MGH_E_INPUT;
    }
    for (i = 0; i < P->nresets; ++i)
        if (check_kernel(&P->resets[i], 1) || P->resets[i].out_len[P->resets[i].pick[0]] != nx - P->carried)
            return MGH_E_INPUT;
    c->n = n;
    c->m = m;
    c->nx = nx;
    c->ng = ng;
    c->ring = P->zeno_events + 1 > 2 ? P->zeno_events + 1 : 2;  /* more than zeno_events within zeno_span */
    total = nx + lumped * lumped + n + 16 * nx + 7 * nx + 15 * nx + 12 * ng + MGH_STACK * 4 * ng;
    for (i = 0; i < nk; ++i)
        for (j = 0; j < MGH_PORTS; ++j)
            total += kernel_outputs(loop_kernel(P, i), j);
    c->mem = (double *)calloc((size_t)total, sizeof(double));
    c->flags = (long *)calloc((size_t)(2 * ng), sizeof(long));
    c->kout = (double **)calloc((size_t)(nk * MGH_PORTS), sizeof(double *));
    c->kin = (const double **)calloc((size_t)(nk * MGH_PORTS + 2 * nk), sizeof(double *));
    if (c->mem == NULL || c->flags == NULL || c->kout == NULL || c->kin == NULL) {
        release(c);
        return MGH_E_MEMORY;
    }
    c->kin_x = c->kin + nk * MGH_PORTS;   /* all NULL: the first call of each kernel sets its inputs */
    c->kin_a = c->kin_x + nk;
    p = c->mem;
#define MGH_TAKE(name, count) do { c->name = p; p += (count); } while (0)
    MGH_TAKE(zeros, nx);
    MGH_TAKE(M, lumped * lumped);
    MGH_TAKE(b, n);
    MGH_TAKE(K, 16 * nx);
    MGH_TAKE(F, 7 * nx);
    MGH_TAKE(y_old, nx); MGH_TAKE(f_old, nx); MGH_TAKE(y_new, nx); MGH_TAKE(f_new, nx); MGH_TAKE(ytmp, nx);
    MGH_TAKE(xm, nx); MGH_TAKE(fm, nx); MGH_TAKE(xd, nx); MGH_TAKE(fd, nx); MGH_TAKE(xa, nx);
    MGH_TAKE(xs, nx); MGH_TAKE(fy, nx); MGH_TAKE(ff, nx); MGH_TAKE(fy2, nx); MGH_TAKE(ff2, nx);
    MGH_TAKE(g_new, ng); MGH_TAKE(d_new, ng); MGH_TAKE(gm, ng); MGH_TAKE(dm, ng); MGH_TAKE(gt, ng);
    MGH_TAKE(gtt, ng); MGH_TAKE(ca, ng); MGH_TAKE(cda, ng); MGH_TAKE(cb, ng); MGH_TAKE(cdb, ng);
    MGH_TAKE(roots, ng); MGH_TAKE(t_his, ng);
    MGH_TAKE(st_g, MGH_STACK * 4 * ng);
    for (i = 0; i < nk; ++i)
        for (j = 0; j < MGH_PORTS; ++j)
            MGH_TAKE(kout[i * MGH_PORTS + j], kernel_outputs(loop_kernel(P, i), j));
#undef MGH_TAKE
    return 0;
}

/* Run from the state (see the module doc): returns MGH_DONE, MGH_TERMINATED, MGH_PAUSED, MGH_FULL_*,
 * MGH_SLICE (the state is then a point to resume from) or an error MGH_E_* (state->err_* say where). */
int mgh_run(const mgh_problem *P, mgh_state *S);
int mgh_run(const mgh_problem *P, mgh_state *S)
{
    mgh_ctx c;
    int rc;
    if (P == NULL || S == NULL)
        return MGH_E_INPUT;
    rc = setup(&c, P, S);
    if (rc != 0)
        return rc;
    S->counted = 0;
    for (;;) {
        if (S->phase < 0) {
            if (P->n_eval == 0 && S->n_samples + 1 > P->sample_cap) {
                rc = MGH_FULL_SAMPLES;
                break;
            }
            record(&c, S->t, S->x, S->mode);
            S->phase = 0;
        }
        rc = S->phase == 0 ? start_mode(&c) : step(&c);
        if (rc != MGH_CONTINUE)
            break;
    }
    release(&c);
    return rc;
}
