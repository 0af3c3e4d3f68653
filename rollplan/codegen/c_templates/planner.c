/* @PREFIX@_planner.c -- damped Newton planner on the generated step map (hand-written glue).
 * The model equations are all in @PREFIX@_model.c, generated from rollplan's symbolic model. */
#include <float.h>
#include <math.h>
#include <stddef.h>

#include "@PREFIX@.h"

#define SZ_ARG @SZ_ARG@
#define SZ_RES @SZ_RES@
#define SZ_IW @SZ_IW@
#define SZ_W @SZ_W@
#define NR @TABLE_RADII@        /* radii of the bracketing table (plus r = 0) */
#define A_MIN @A_MIN@
#define MAX_ITER @MAX_ITER@
#define MAX_CELLS @MAX_CELLS@
#define TOL @TOL@
#define REAL_TINY @REAL_TINY@          /* smallest normal casadi_real */
#define K_MAX @PREFIX_UPPER@_K_MAX
#define MAX_STEPS @PREFIX_UPPER@_MAX_STEPS
#define CERT_TOL @PREFIX_UPPER@_CERT_TOL
#define CERT_DELTA @CERT_DELTA@
#define CERT_BASE @CERT_BASE@
#define CERT_SAFETY @CERT_SAFETY@
#define NPANEL @NPANEL@                /* panels of each leaf (the spectral step map's) */
#define CERT_REFINE 3                  /* at most 3 more doublings when only the bound is too large */
#define CERT_MAX_PANEL_STEPS 2048      /* bounds the certificate's time; k <= K_MAX needs far fewer */
#define MIN_STEP (1.0 / 256.0)  /* smallest damping factor of the line search (9 trials) */
#define PI 3.14159265358979323846

/* Static work area shared by all calls (no malloc; not reentrant). */
static const casadi_real *s_arg[SZ_ARG];
static casadi_real *s_res[SZ_RES];
static casadi_int s_iw[SZ_IW];
static casadi_real s_w[SZ_W];
static casadi_real s_leaf0[3 * NR], s_leaf1[3 * NR];
/* Corner values eta, h of the (a, b) grid: only for bracketing, so single precision (half the RAM). */
static float s_eta[(NR + 1) * (NR + 1)], s_h[(NR + 1) * (NR + 1)];
/* Radii of the table rows/columns [R]: 0, then the generated function's grid. */
static const casadi_real s_radii[NR + 1] = {@RADII@};

/* Panel boundaries of each leaf in phi [rad]. */
static const casadi_real s_breaks[NPANEL + 1] = {@BREAKS@};
/* RK8 steps per panel of each leaf for the certificate (set per plan). */
static int s_counts[2][NPANEL];

/* Angle wrapped to (-pi, pi]. */
static casadi_real wrap(casadi_real x) {
    casadi_real m = fmod(PI - x, 2.0 * PI);
    if (m < 0.0) m += 2.0 * PI;
    return PI - m;
}

static casadi_real clamp(casadi_real x) { return x < A_MIN ? A_MIN : (x > @PREFIX_UPPER@_A_MAX ? @PREFIX_UPPER@_A_MAX : x); }

int @PREFIX@_step_eval(casadi_real a, casadi_real b, casadi_real k, casadi_real shift[2], casadi_real *eta, casadi_real *direction,
                       casadi_real jac[8]) {
    casadi_real ab[2];
    ab[0] = a;
    ab[1] = b;
    s_arg[0] = ab;
    s_arg[1] = &k;
    s_res[0] = shift;
    s_res[1] = eta;
    s_res[2] = direction;
    s_res[3] = jac;
    return @PREFIX@_step_jac(s_arg, s_res, s_iw, s_w, 0);
}

/* Residual of (32)-(33) and its Jacobian at (a, b). Returns 0 on success. */
static int residual(const casadi_real x[2], casadi_real k, casadi_real eta_m, casadi_real h_m, casadi_real r[2], casadi_real jr[4],
                    casadi_real shift[2], casadi_real *eta) {
    casadi_real jac[8], dir, h;
    if (@PREFIX@_step_eval(x[0], x[1], k, shift, eta, &dir, jac)) return 1;
    h = hypot(shift[0], shift[1]);
    r[0] = *eta - eta_m;
    r[1] = h - h_m;
    jr[0] = jac[2];                     /* d eta / d a */
    jr[1] = jac[6];                     /* d eta / d b */
    if (h < REAL_TINY) h = REAL_TINY;
    jr[2] = (shift[0] * jac[0] + shift[1] * jac[1]) / h;   /* d h / d a */
    jr[3] = (shift[0] * jac[4] + shift[1] * jac[5]) / h;   /* d h / d b */
    return !(isfinite(r[0]) && isfinite(r[1]));
}

/* Damped Newton from x (in place). Returns 1 if converged. */
static int newton(casadi_real x[2], casadi_real k, casadi_real eta_m, casadi_real h_m, casadi_real tol, casadi_real *res_norm, int *iters,
                  casadi_real shift[2], casadi_real *eta) {
    casadi_real r[2], jr[4], xt[2] = {0.0, 0.0}, rt[2] = {0.0, 0.0}, jt[4] = {0.0, 0.0, 0.0, 0.0};
    casadi_real st[2] = {0.0, 0.0}, et = 0.0, nr, nrt = INFINITY, det, dx0, dx1, alpha;
    int it;
    *iters = 0;
    if (residual(x, k, eta_m, h_m, r, jr, shift, eta)) return 0;
    nr = hypot(r[0], r[1]);
    for (it = 0; it < MAX_ITER; ++it) {
        *res_norm = nr;
        if (nr <= tol) return 1;
        det = jr[0] * jr[3] - jr[1] * jr[2];
        if (!(fabs(det) > 0.0) || !isfinite(det)) return 0;
        dx0 = -(jr[3] * r[0] - jr[1] * r[1]) / det;
        dx1 = -(-jr[2] * r[0] + jr[0] * r[1]) / det;
        for (alpha = 1.0; alpha >= MIN_STEP; alpha *= 0.5) {
            xt[0] = clamp(x[0] + alpha * dx0);
            xt[1] = clamp(x[1] + alpha * dx1);
            if (residual(xt, k, eta_m, h_m, rt, jt, st, &et)) continue;
            nrt = hypot(rt[0], rt[1]);
            if (nrt < (1.0 - 1e-4 * alpha) * nr || nrt <= tol) break;
        }
        *iters = it + 1;
        if (alpha < MIN_STEP) {
            /* no decrease: converged to rounding level, or stuck */
            return nr <= 1e3 * tol;
        }
        x[0] = xt[0];
        x[1] = xt[1];
        r[0] = rt[0];
        r[1] = rt[1];
        jr[0] = jt[0]; jr[1] = jt[1]; jr[2] = jt[2]; jr[3] = jt[3];
        shift[0] = st[0];
        shift[1] = st[1];
        *eta = et;
        nr = nrt;
    }
    *res_norm = nr;
    return nr <= tol;
}

/* The curve ODE (28)-(30) along leaf `leaf` at phi (generated). Returns 0 on success. */
static int curve_rhs(int leaf, casadi_real phi, const casadi_real x[3], const casadi_real ab[2], casadi_real k, casadi_real gamma,
                     casadi_real xdot[3]) {
    s_arg[0] = &phi;
    s_arg[1] = x;
    s_arg[2] = ab;
    s_arg[3] = &k;
    s_arg[4] = &gamma;
    s_res[0] = xdot;
    return leaf ? @PREFIX@_rhs1(s_arg, s_res, s_iw, s_w, 0) : @PREFIX@_rhs0(s_arg, s_res, s_iw, s_w, 0);
}

/* `n` equal RK8 steps (generated) over [t0, t0 + n h] along leaf `leaf`, x in place. */
static int rk8_steps(int leaf, casadi_real x[3], casadi_real t0, casadi_real h, int n, const casadi_real ab[2], casadi_real k, casadi_real gamma) {
    casadi_real t, xn[3];
    int q;
    for (q = 0; q < n; ++q) {
        t = t0 + q * h;
        s_arg[0] = x;
        s_arg[1] = &t;
        s_arg[2] = &h;
        s_arg[3] = ab;
        s_arg[4] = &k;
        s_arg[5] = &gamma;
        s_res[0] = xn;
        if (leaf ? @PREFIX@_rk8_1(s_arg, s_res, s_iw, s_w, 0) : @PREFIX@_rk8_0(s_arg, s_res, s_iw, s_w, 0)) return 1;
        x[0] = xn[0];
        x[1] = xn[1];
        x[2] = xn[2];
    }
    return 0;
}

/* The whole n-step motion from rest with mult x s_counts RK8 steps per panel; x in place. */
static int motion(casadi_real x[3], int mult, int steps, const casadi_real ab[2], casadi_real k, casadi_real gamma) {
    int s, leaf, j, nj;
    for (s = 0; s < steps; ++s) {
        for (leaf = 0; leaf < 2; ++leaf) {
            for (j = 0; j < NPANEL; ++j) {
                nj = mult * s_counts[leaf][j];
                if (rk8_steps(leaf, x, s_breaks[j], (s_breaks[j + 1] - s_breaks[j]) / nj, nj, ab, k, gamma)) return 1;
            }
        }
    }
    return 0;
}

int @PREFIX@_certify(casadi_real a, casadi_real b, casadi_real gamma, int steps, casadi_real k, casadi_real u, casadi_real v, casadi_real psi,
                     casadi_real final[3], casadi_real *residual, casadi_real *bound) {
    const casadi_real zero[3] = {0.0, 0.0, 0.0};
    casadi_real ab[2], xc[3] = {0.0, 0.0, 0.0}, xf[3] = {0.0, 0.0, 0.0}, xd[3], w, rate, n;
    int leaf, j, q, mult;
    if (residual) *residual = INFINITY;
    if (bound) *bound = INFINITY;
    if (!(isfinite(a) && isfinite(b) && isfinite(gamma) && isfinite(u) && isfinite(v) && isfinite(psi))
        || !(a > 0.0 && a <= @PREFIX_UPPER@_A_MAX && b > 0.0 && b <= @PREFIX_UPPER@_A_MAX)
        || !(k >= 0.0 && k <= K_MAX) || steps < 1 || steps > MAX_STEPS)
        return @PREFIX_UPPER@_BAD_INPUT;
    ab[0] = a;
    ab[1] = b;
    /* steps per panel from the turn rate psi', which does not depend on the state */
    for (leaf = 0; leaf < 2; ++leaf) {
        for (j = 0; j < NPANEL; ++j) {
            w = s_breaks[j + 1] - s_breaks[j];
            rate = 0.0;
            for (q = 0; q <= 4; ++q) {
                if (curve_rhs(leaf, s_breaks[j] + 0.25 * q * w, zero, ab, k, gamma, xd) || !isfinite(xd[2]))
                    return @PREFIX_UPPER@_NOT_CERTIFIED;
                rate = fmax(rate, fabs(xd[2]));
            }
            n = ceil(w * (CERT_BASE + rate) / CERT_DELTA);
            s_counts[leaf][j] = n > CERT_MAX_PANEL_STEPS ? CERT_MAX_PANEL_STEPS : (int)n;
        }
    }
    if (motion(xc, 1, steps, ab, k, gamma) || motion(xf, 2, steps, ab, k, gamma)) return @PREFIX_UPPER@_NOT_CERTIFIED;
    for (mult = 2;; mult *= 2) {
        /* step doubling: |x_2N - x_N| / (2^8 - 1) estimates the error of x_2N for an order-8 method; divided
         * by CERT_SAFETY only, a margin for steps not yet in the asymptotic regime */
        w = sqrt((xf[0] - xc[0]) * (xf[0] - xc[0]) + (xf[1] - xc[1]) * (xf[1] - xc[1])
                 + (xf[2] - xc[2]) * (xf[2] - xc[2])) / CERT_SAFETY;
        rate = wrap(xf[2] - psi);
        n = sqrt((xf[0] - u) * (xf[0] - u) + (xf[1] - v) * (xf[1] - v) + rate * rate);
        /* undecided (the miss may be within the integration error, the bound too large for the tolerance):
         * halve the steps again, the finer run becoming the coarse one, at most CERT_REFINE times */
        if (!(isfinite(n + w) && n - w <= CERT_TOL && n + w > CERT_TOL && mult < (2 << CERT_REFINE))) break;
        xc[0] = xf[0];
        xc[1] = xf[1];
        xc[2] = xf[2];
        xf[0] = xf[1] = xf[2] = 0.0;
        if (motion(xf, 2 * mult, steps, ab, k, gamma)) return @PREFIX_UPPER@_NOT_CERTIFIED;
    }
    if (final) {
        final[0] = xf[0];
        final[1] = xf[1];
        final[2] = xf[2];
    }
    if (residual) *residual = n;
    if (bound) *bound = w;
    return isfinite(n + w) && n + w <= CERT_TOL ? @PREFIX_UPPER@_OK : @PREFIX_UPPER@_NOT_CERTIFIED;
}

/* The table depends on k only; a robot has one k, so it is kept for the last k. */
static int s_have_table = 0;
static casadi_real s_table_k = 0.0;

void @PREFIX@_forget_table(void) { s_have_table = 0; }

/* Leaf tables and the corner values eta, h of the (a, b) grid (index 0 is r = 0). */
static int tabulate(casadi_real k) {
    int i, j;
    if (s_have_table && s_table_k == k) return 0;
    s_have_table = 0;
    s_arg[0] = &k;
    s_res[0] = s_leaf0;
    s_res[1] = s_leaf1;
    if (@PREFIX@_leaf_table(s_arg, s_res, s_iw, s_w, 0)) return 1;
    for (i = 0; i <= NR; ++i) {
        casadi_real u0 = i ? s_leaf0[3 * (i - 1)] : 0.0, v0 = i ? s_leaf0[3 * (i - 1) + 1] : 0.0;
        casadi_real p0 = i ? s_leaf0[3 * (i - 1) + 2] : 0.0;
        casadi_real c = cos(p0), s = sin(p0);
        for (j = 0; j <= NR; ++j) {
            casadi_real u1 = j ? s_leaf1[3 * (j - 1)] : 0.0, v1 = j ? s_leaf1[3 * (j - 1) + 1] : 0.0;
            casadi_real p1 = j ? s_leaf1[3 * (j - 1) + 2] : 0.0;
            /* second leaf starts at heading p0: its shift turns by -p0 */
            s_eta[i * (NR + 1) + j] = (float)(p0 + p1);
            s_h[i * (NR + 1) + j] = (float)hypot(u0 + c * u1 + s * v1, v0 - s * u1 + c * v1);
        }
    }
    s_have_table = 1;
    s_table_k = k;
    return 0;
}

static int brackets(int i, int j, casadi_real eta_m, casadi_real h_m) {
    int c[4], q;
    casadi_real emin, emax, hmin, hmax;
    c[0] = i * (NR + 1) + j;
    c[1] = c[0] + 1;
    c[2] = c[0] + NR + 1;
    c[3] = c[2] + 1;
    emin = emax = s_eta[c[0]];
    hmin = hmax = s_h[c[0]];
    for (q = 1; q < 4; ++q) {
        emin = fmin(emin, s_eta[c[q]]);
        emax = fmax(emax, s_eta[c[q]]);
        hmin = fmin(hmin, s_h[c[q]]);
        hmax = fmax(hmax, s_h[c[q]]);
    }
    return emin <= eta_m && eta_m <= emax && hmin <= h_m && h_m <= hmax;
}

/* Initial guess in cell (i, j): the targets interpolated linearly from the corner values
 * (kept inside the cell), or the cell centre where that is singular. */
static void start(int i, int j, casadi_real eta_m, casadi_real h_m, casadi_real x[2]) {
    const int c0 = i * (NR + 1) + j, c1 = c0 + NR + 1;   /* (i, j) and (i + 1, j) */
    casadi_real ec = 0.25 * (s_eta[c0] + s_eta[c0 + 1] + s_eta[c1] + s_eta[c1 + 1]);
    casadi_real hc = 0.25 * (s_h[c0] + s_h[c0 + 1] + s_h[c1] + s_h[c1 + 1]);
    casadi_real ea = 0.5 * (s_eta[c1] + s_eta[c1 + 1] - s_eta[c0] - s_eta[c0 + 1]);
    casadi_real eb = 0.5 * (s_eta[c0 + 1] + s_eta[c1 + 1] - s_eta[c0] - s_eta[c1]);
    casadi_real ha = 0.5 * (s_h[c1] + s_h[c1 + 1] - s_h[c0] - s_h[c0 + 1]);
    casadi_real hb = 0.5 * (s_h[c0 + 1] + s_h[c1 + 1] - s_h[c0] - s_h[c1]);
    casadi_real det = ea * hb - eb * ha, di = 0.0, dj = 0.0;
    if (fabs(det) > REAL_TINY && isfinite(det)) {
        di = (hb * (eta_m - ec) - eb * (h_m - hc)) / det;
        dj = (ea * (h_m - hc) - ha * (eta_m - ec)) / det;
        di = di < -0.5 ? -0.5 : (di > 0.5 ? 0.5 : di);
        dj = dj < -0.5 ? -0.5 : (dj > 0.5 ? 0.5 : dj);
    }
    x[0] = clamp(s_radii[i] + (0.5 + di) * (s_radii[i + 1] - s_radii[i]));
    x[1] = clamp(s_radii[j] + (0.5 + dj) * (s_radii[j + 1] - s_radii[j]));
}

/* gamma = arg(target) - arg(sum_{j<n} exp(-i j eta) shift), and the step map's prediction of the miss. */
static casadi_real rotation(casadi_real u, casadi_real v, casadi_real psi, int steps, const casadi_real shift[2], casadi_real eta,
                       casadi_real *predicted) {
    casadi_real sr = 0.0, si = 0.0, tr, ti, gamma, c, s, fu, fv, dr;
    int i;
    for (i = 0; i < steps; ++i) {
        sr += cos(i * eta);
        si -= sin(i * eta);
    }
    tr = sr * shift[0] - si * shift[1];
    ti = sr * shift[1] + si * shift[0];
    gamma = wrap(atan2(v, u) - atan2(ti, tr));
    /* n steps of the step map, the displacement turned by gamma */
    c = cos(gamma);
    s = sin(gamma);
    fu = c * tr - s * ti;
    fv = s * tr + c * ti;
    dr = wrap(steps * eta - psi);
    *predicted = sqrt((fu - u) * (fu - u) + (fv - v) * (fv - v) + dr * dr);
    return gamma;
}

int @PREFIX@_plan(casadi_real u, casadi_real v, casadi_real psi, int steps, casadi_real k, @PREFIX@_plan_t *plan) {
    casadi_real h_des, eta_m, h_m, num, den, tol, x[2], shift[2], eta = 0.0, res_norm = INFINITY;
    casadi_real cand_lower[MAX_CELLS];
    int cand[MAX_CELLS], ncand = 0, sum, i, j, iters, cells = 0, converged = 0, status;
    if (plan == NULL) return @PREFIX_UPPER@_BAD_INPUT;
    plan->a = plan->b = plan->gamma = plan->eta = plan->h = NAN;
    plan->residual = plan->bound = plan->predicted = INFINITY;
    plan->iterations = plan->cells = 0;
    if (!(isfinite(u) && isfinite(v) && isfinite(psi)) || !(k >= 0.0 && k <= K_MAX) || steps < 1
        || steps > MAX_STEPS)
        return @PREFIX_UPPER@_BAD_INPUT;
    h_des = hypot(u, v);
    if (!(h_des > 0.0)) return @PREFIX_UPPER@_BAD_INPUT;
    /* branch m = 0 of (32)-(33); the limit (34) where sin(n eta / 2) = sin(eta / 2) = 0 */
    eta_m = psi / steps;
    num = sin(eta_m / 2.0);
    den = sin(steps * eta_m / 2.0);
    if (fabs(den) < 1e-12) {
        if (fabs(num) >= 1e-12) return @PREFIX_UPPER@_NO_PLAN;
        h_m = h_des / steps;
    } else {
        h_m = h_des * fabs(num / den);
    }
    tol = TOL * (1.0 + fabs(eta_m) + h_m);
    if (tabulate(k)) return @PREFIX_UPPER@_NO_CONVERGENCE;
    /* the MAX_CELLS bracketing cells of smallest a + b (lower corner), by insertion */
    for (i = 0; i < NR; ++i) {
        for (j = 0; j < NR; ++j) {
            int q;
            casadi_real lower = s_radii[i] + s_radii[j];
            if ((ncand == MAX_CELLS && lower >= cand_lower[MAX_CELLS - 1]) || !brackets(i, j, eta_m, h_m)) continue;
            q = ncand < MAX_CELLS ? ncand++ : MAX_CELLS - 1;
            for (; q > 0 && cand_lower[q - 1] > lower; --q) {
                cand_lower[q] = cand_lower[q - 1];
                cand[q] = cand[q - 1];
            }
            cand_lower[q] = lower;
            cand[q] = i * NR + j;
        }
    }
    /* the first converged root whose certificate holds, in the order of the cells */
    for (sum = 0; sum < ncand; ++sum) {
        casadi_real gamma, predicted, residual, bound;
        ++cells;
        start(cand[sum] / NR, cand[sum] % NR, eta_m, h_m, x);
        if (!newton(x, k, eta_m, h_m, tol, &res_norm, &iters, shift, &eta)) {
            if (!converged) {
                plan->a = x[0];
                plan->b = x[1];
                plan->iterations = iters;
                plan->predicted = res_norm;
            }
            continue;
        }
        converged = 1;
        gamma = rotation(u, v, psi, steps, shift, eta, &predicted);
        status = @PREFIX@_certify(x[0], x[1], gamma, steps, k, u, v, psi, NULL, &residual, &bound);
        plan->a = x[0];
        plan->b = x[1];
        plan->gamma = gamma;
        plan->eta = eta;
        plan->h = hypot(shift[0], shift[1]);
        plan->iterations = iters;
        plan->predicted = predicted;
        plan->residual = residual;
        plan->bound = bound;
        plan->cells = cells;
        if (status == @PREFIX_UPPER@_OK) return @PREFIX_UPPER@_OK;
    }
    plan->cells = cells;
    if (!cells) return @PREFIX_UPPER@_NO_PLAN;
    return converged ? @PREFIX_UPPER@_NOT_CERTIFIED : @PREFIX_UPPER@_NO_CONVERGENCE;
}
