/* rollplan_planner.c -- the planner of rollplan.planners.geometric in C (a static source of the package,
 * rollplan/csrc/; what varies by generation comes from rollplan_config.h, see rollplan_planner.h).
 *
 * The ODE of the certificate is in <prefix>_model.c, generated from rollplan's symbolic model. The planner
 * solves the problem of rollplan.planners.geometric and makes the same choice (the shortest certified plan) for
 * every k in [K_MIN, K_MAX]: the roots are enumerated on one graph per branch over the smaller leaf radius x for
 * k >= 1/2 (E decreasing), and on the sigma graphs of enumerate.py (one per branch and rectangle of monotone
 * pieces of E) below, with the rho table interpolated in r (docs/design/c-planner.md,
 * docs/design/enumeration.md). Each formula is written once, here, with the Python function it ports where
 * there is one (enumerate = tests/reference_enumerate.py, the tests' numpy reference; its constants and
 * table_radii are in rollplan/planners/geometric/search_constants.py):
 *   leafmap.turn / turn_dr / turn_inverse   closed-form turn E(r, k) of a leaf and its inverse
 *   leafmap.displacement / signed_length    the leaf's displacement d(r, k) by the Gauss rule in chi (the
 *                                           nodes chi < pi; the others by the symmetry chi -> 2 pi - chi),
 *                                           and rho = Re(exp(i E / 2) d)
 *   enumerate.branches                      branches m of (32) (make_branch)
 *   (no Python counterpart)                 the graph over x: y(x) = E^-1(E(x) - e) (other) and the scalar
 *                                           equation g(x) of (33) on it (branch_values)
 *   enumerate._SigmaGraphs, leafmap.turn_pieces
 *                                           the sigma graphs (sigma_graphs, sigma_radii, sigma_values)
 *   enumerate.rho_table / rho_lookup        rho tabulated once per k (cubic Hermite in r)
 *   enumerate.roots (_cells, _critical, _examine, _bracketed, _tangencies, _outward, _polish)
 *                                           every root on a branch (search_branch, search_sigma, sweep and the
 *                                           functions they call)
 *   enumerate.ReferencePlanner._solve_enumerated
 *                                           the bounded search for the shortest certified plan
 *   planner._certified                      gamma from the geometry
 * Static memory only; not reentrant (one static work area and the table of the last k). */
#include <float.h>
#include <math.h>
#include <stddef.h>

#include "rollplan_planner.h"

#define SZ_ARG RP_SZ_ARG
#define SZ_RES RP_SZ_RES
#define SZ_IW RP_SZ_IW
#define SZ_W RP_SZ_W
#define REAL_TINY RP_REAL_TINY          /* smallest normal casadi_real */
#define REAL_EPS RP_REAL_EPS            /* machine epsilon of casadi_real */
#define REAL_MAX RP_REAL_MAX            /* largest finite casadi_real */
#define A_MAX RP_A_MAX
#define K_MIN RP_K_MIN
#define K_MONOTONE RP_K_MONOTONE          /* E strictly decreasing for k >= K_MONOTONE: the graph over x; sigma graphs below */
#define K_MAX RP_K_MAX
#define PSI_MAX RP_PSI_MAX
#define MAX_STEPS RP_MAX_STEPS
#define CERT_TOL RP_CERT_TOL
#define CERT_DELTA RP_CERT_DELTA
#define CERT_BASE RP_CERT_BASE
#define CERT_SAFETY RP_CERT_SAFETY
#define CERT_ROUNDING RP_CERT_ROUNDING  /* safety factor of the rounding allowance (certify.ROUNDING_FACTOR) */
#define NPANEL RP_NPANEL                /* panels of each leaf (the curve's) */
#define FAMILY RP_FAMILY                /* leaf family of this generation (c_sources.C_FAMILIES): 0 circles (35),
                                           1 the Viviani lobes, 2 the geodesic triangles, 3 the geodesic squares */
#define FAMILY_CIRCLES 0
#define FAMILY_VIVIANI 1
#define FAMILY_TRIANGLE 2
#define FAMILY_SQUARE 3
#define PHASE RP_PHASE                  /* the certificate's right sides take cos and sin of PHASE phi */
#define FAMILY_MULT RP_FAMILY_MULT      /* a family's leaf map integrates the leaf with this many times the
                                           certificate's RK8 steps */
#define NOT_A_ROOT (RP_NOT_A_ROOT * CERT_TOL)  /* a polished root the leaf map misses by more is none (enumerate.NOT_A_ROOT) */
#define CERT_REFINE 3                  /* at most 3 more doublings when only the bound is too large */
#define CERT_MAX_PANEL_STEPS 2048      /* bounds the certificate's time; k <= K_MAX needs far fewer */
#define PI RP_R(3.14159265358979323846)
#define TWO_PI RP_R(6.28318530717958647692)
/* 2 pi = TWO_PI_1 + TWO_PI_2 + TWO_PI_3, the first two with 32 significant bits (Cody and Waite) */
#define TWO_PI_1 RP_TWO_PI_1
#define TWO_PI_2 RP_TWO_PI_2
#define TWO_PI_3 RP_TWO_PI_3

/* enumerate.py and leafmap.py constants */
#define ORDER RP_ORDER                  /* Gauss-Legendre nodes per panel (leafmap.ORDER) */
#define MAX_PANELS RP_MAX_PANELS        /* panels of the rule at K_MAX (leafmap.BUCKETS) */
#define NBUCKET RP_NBUCKET
#define PHASE_STEP RP_PHASE_STEP
#define X_STEP RP_X_STEP
#define SIGMA_STEP RP_SIGMA_STEP        /* initial sampling step of the sigma graphs (enumerate.SIGMA_STEP) */
#define HERMITE_REL RP_HERMITE_REL
#define POLISH_BRACKET RP_POLISH_BRACKET  /* a polish step across the root at most this long brackets it */
#define POLISH_STEP RP_POLISH_STEP        /* Newton steps of the polish below this are taken without a new evaluation */
#define SAFETY RP_SAFETY
#define MIN_WIDTH RP_MIN_WIDTH
#define TABLE_PHASE RP_TABLE_PHASE
#define TABLE_STEP RP_TABLE_STEP
#define TABLE_INV_S RP_TABLE_INV_S
#define NTABLE RP_NTABLE                /* most radii of the rho table (at K_MAX) */
#define STACK_CELLS 96                 /* pending cells of a branch's splitting (depth <= log2(X_STEP / MIN_WIDTH)) */
#define MAX_CELLS_PER_BRANCH 1000000L  /* bounds the time of one branch; beyond it the search is incomplete */
#define MAX_CELL_ROOTS 32              /* 3 sign changes, 3 zeros, 4 tangencies of 4 roots at most */

/* Static work area shared by all calls (no malloc; not reentrant). */
static const casadi_real *s_arg[SZ_ARG];
static casadi_real *s_res[SZ_RES];
static casadi_int s_iw[SZ_IW];
static casadi_real s_w[SZ_W];

/* Panel boundaries of each leaf in phi [rad]. */
static const casadi_real s_breaks[NPANEL + 1] = {RP_BREAKS};
/* RK8 steps per panel of each leaf for the certificate (set per plan). */
static int s_counts[2][NPANEL];

/* Angle wrapped to (-pi, pi] (rollplan.core.plane.wrap). */
static casadi_real wrap(casadi_real x) {
    casadi_real m = RP_FMOD(PI - x, RP_R(2.0) * PI);
    if (m < RP_R(0.0)) m += RP_R(2.0) * PI;
    return PI - m;
}

int RP_NAME(step_eval)(casadi_real a, casadi_real b, casadi_real k, casadi_real shift[2], casadi_real *eta, casadi_real *direction,
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
    return RP_NAME(step_jac)(s_arg, s_res, s_iw, s_w, 0);
}

/* RK8 steps per panel of each leaf into s_counts: ceil(w (CERT_BASE + rate) / CERT_DELTA) for a panel of
 * width w, rate = max |psi'_0| + |psi'_k - psi'_0| over 5 points of the panel: psi' of (30) at k = 0 (the
 * rolling part) and at k (plus the spin part k w); psi' does not depend on the state (generated rates<i>). Both
 * parts count separately: near A_MAX they are large and cancel in part for k near 1/2, while the path is still
 * steep. */
static int counts(const casadi_real ab[2], casadi_real k, casadi_real gamma) {
    casadi_real w, rate[2], n, r[2], phi, cp[2], cg[2];
    int leaf, j, q;
    cg[0] = RP_COS(gamma);
    cg[1] = RP_SIN(gamma);
    for (j = 0; j < NPANEL; ++j) {
        w = s_breaks[j + 1] - s_breaks[j];
        rate[0] = rate[1] = RP_R(0.0);
        for (q = 0; q <= 4; ++q) {
            phi = PHASE * (s_breaks[j] + RP_R(0.25) * q * w);
            cp[0] = RP_COS(phi);
            cp[1] = RP_SIN(phi);
            for (leaf = 0; leaf < 2; ++leaf) {
                s_arg[0] = cp;
                s_arg[1] = cp + 1;
                s_arg[2] = ab;
                s_arg[3] = &k;
                s_arg[4] = cg;
                s_arg[5] = cg + 1;
                s_res[0] = r;
                if ((leaf ? RP_NAME(rates1)(s_arg, s_res, s_iw, s_w, 0) : RP_NAME(rates0)(s_arg, s_res, s_iw, s_w, 0))
                    || !isfinite(r[0]) || !isfinite(r[1]))
                    return 1;
                rate[leaf] = RP_FMAX(rate[leaf], RP_FABS(r[0]) + RP_FABS(r[1] - r[0]));
            }
        }
        for (leaf = 0; leaf < 2; ++leaf) {
            n = RP_CEIL(w * (CERT_BASE + rate[leaf]) / CERT_DELTA);
            s_counts[leaf][j] = n > CERT_MAX_PANEL_STEPS ? CERT_MAX_PANEL_STEPS : (int)n;
        }
    }
    return 0;
}

/* `n` equal RK8 steps (generated) of the time law's ODE over [t0, t0 + n h] along leaf `leaf`, x = (u_a, v_a, psi,
 * rotor angles) in place, jj = the inertias. */
static int rk8x_steps(int leaf, casadi_real x[5], casadi_real t0, casadi_real h, int n, const casadi_real ab[2],
                      casadi_real k, casadi_real gamma, const casadi_real jj[3]) {
    casadi_real t, xn[5];
    int q, i;
    for (q = 0; q < n; ++q) {
        t = t0 + q * h;
        s_arg[0] = x;
        s_arg[1] = &t;
        s_arg[2] = &h;
        s_arg[3] = ab;
        s_arg[4] = &k;
        s_arg[5] = &gamma;
        s_arg[6] = jj;
        s_arg[7] = jj + 1;
        s_arg[8] = jj + 2;
        s_res[0] = xn;
        if (leaf ? RP_NAME(rk8x_1)(s_arg, s_res, s_iw, s_w, 0) : RP_NAME(rk8x_0)(s_arg, s_res, s_iw, s_w, 0)) return 1;
        for (i = 0; i < 5; ++i) x[i] = xn[i];
    }
    return 0;
}

/* Stages of the RK8 formula and their nodes c (rollplan.core.integrate.DOP853_C): stage j of a step from phi = t
 * is at t + c[j] h. */
#define NSTAGE RP_RK8_STAGES
static const casadi_real s_rk8_c[NSTAGE] = {RP_RK8_C};

/* cos(c[j] h) (rot[j]) and sin(c[j] h) (rot[NSTAGE + j]) of the stages of a step h. */
static void stage_rotations(casadi_real h, casadi_real rot[2 * NSTAGE]) {
    int j;
    for (j = 0; j < NSTAGE; ++j) {
        rot[j] = RP_COS(PHASE * s_rk8_c[j] * h);
        rot[NSTAGE + j] = RP_SIN(PHASE * s_rk8_c[j] * h);
    }
}

/* `n` equal RK8 steps (generated) of the curve ODE over [t0, t0 + n h] along leaf `leaf`, x = (u_a, v_a, psi) in
 * place. The right side depends on phi through cos phi and sin phi only; at the stages they are
 * cos(t + c h) = cos t cos(c h) - sin t sin(c h) and sin(t + c h) = sin t cos(c h) + cos t sin(c h) with the
 * stage table rot of h (stage_rotations): one cos and sin per step instead of one per stage. */
static int rk8_steps(int leaf, casadi_real x[3], casadi_real t0, casadi_real h, int n, const casadi_real rot[2 * NSTAGE],
                     const casadi_real ab[2], casadi_real k, const casadi_real cg[2]) {
    casadi_real t, ct, st, cs[NSTAGE], sn[NSTAGE], xn[3];
    int q, j;
    for (q = 0; q < n; ++q) {
        t = t0 + q * h;
        ct = RP_COS(PHASE * t);
        st = RP_SIN(PHASE * t);
        for (j = 0; j < NSTAGE; ++j) {
            cs[j] = ct * rot[j] - st * rot[NSTAGE + j];
            sn[j] = st * rot[j] + ct * rot[NSTAGE + j];
        }
        s_arg[0] = x;
        s_arg[1] = cs;
        s_arg[2] = sn;
        s_arg[3] = &h;
        s_arg[4] = ab;
        s_arg[5] = &k;
        s_arg[6] = cg;
        s_arg[7] = cg + 1;
        s_res[0] = xn;
        if (leaf ? RP_NAME(rk8_1)(s_arg, s_res, s_iw, s_w, 0) : RP_NAME(rk8_0)(s_arg, s_res, s_iw, s_w, 0)) return 1;
        x[0] = xn[0];
        x[1] = xn[1];
        x[2] = xn[2];
    }
    return 0;
}

/* The whole n-step motion from rest with mult x s_counts RK8 steps per panel; x in place; *psi_scale grows to the
 * largest |psi| at the end of a leaf. Every step of the motion is integrated (from the state the previous one
 * left); only the stage tables of the panels, which depend on the panel's step h alone, are computed once, in the
 * first step. */
static int motion(casadi_real x[3], int mult, int steps, const casadi_real ab[2], casadi_real k, casadi_real gamma,
                  casadi_real *psi_scale) {
    static casadi_real rot[2][NPANEL][2 * NSTAGE];   /* static: not reentrant anyway; keeps the stack small */
    casadi_real h, cg[2];
    int s, leaf, j, nj;
    cg[0] = RP_COS(gamma);
    cg[1] = RP_SIN(gamma);
    for (s = 0; s < steps; ++s) {
        for (leaf = 0; leaf < 2; ++leaf) {
            for (j = 0; j < NPANEL; ++j) {
                nj = mult * s_counts[leaf][j];
                h = (s_breaks[j + 1] - s_breaks[j]) / nj;
                if (s == 0) stage_rotations(h, rot[leaf][j]);
                if (rk8_steps(leaf, x, s_breaks[j], h, nj, rot[leaf][j], ab, k, cg)) return 1;
            }
            *psi_scale = RP_FMAX(*psi_scale, RP_FABS(x[2]));
        }
    }
    return 0;
}

int RP_NAME(certify)(casadi_real a, casadi_real b, casadi_real gamma, int steps, casadi_real k, casadi_real u, casadi_real v, casadi_real psi,
                     casadi_real final[3], casadi_real *residual, casadi_real *bound) {
    casadi_real ab[2], xc[3] = {RP_R(0.0), RP_R(0.0), RP_R(0.0)}, xf[3] = {RP_R(0.0), RP_R(0.0), RP_R(0.0)}, w, rate, n;
    casadi_real scale = RP_R(0.0), per = RP_R(0.0);
    int mult, leaf, j;
    if (residual) *residual = INFINITY;
    if (bound) *bound = INFINITY;
    if (!(isfinite(a) && isfinite(b) && isfinite(gamma) && isfinite(u) && isfinite(v) && isfinite(psi))
        || !(a > RP_R(0.0) && a <= RP_A_MAX && b > RP_R(0.0) && b <= RP_A_MAX)
        || !(k >= RP_R(0.0) && k <= K_MAX) || steps < 1 || steps > MAX_STEPS)
        return RP_BAD_INPUT;
    ab[0] = a;
    ab[1] = b;
    if (counts(ab, k, gamma)) return RP_NOT_CERTIFIED;
    for (leaf = 0; leaf < 2; ++leaf)
        for (j = 0; j < NPANEL; ++j) per += s_counts[leaf][j];   /* RK8 steps of one figure eight, coarse run */
    if (motion(xc, 1, steps, ab, k, gamma, &scale) || motion(xf, 2, steps, ab, k, gamma, &scale))
        return RP_NOT_CERTIFIED;
    for (mult = 2;; mult *= 2) {
        /* step doubling: |x_2N - x_N| / (2^8 - 1) estimates the error of x_2N for an order-8 method; divided
         * by CERT_SAFETY only, a margin for steps not yet in the asymptotic regime; plus the rounding errors of
         * the finer run, which the difference of two runs does not show: a random walk over its steps, reaching
         * (u_a, v_a) through psi (certify.rounding_allowance) */
        w = RP_SQRT((xf[0] - xc[0]) * (xf[0] - xc[0]) + (xf[1] - xc[1]) * (xf[1] - xc[1])
                 + (xf[2] - xc[2]) * (xf[2] - xc[2])) / CERT_SAFETY
            + CERT_ROUNDING * REAL_EPS * (RP_R(1.0) + scale) * RP_SQRT(mult * per * steps);
        rate = wrap(xf[2] - psi);
        n = RP_SQRT((xf[0] - u) * (xf[0] - u) + (xf[1] - v) * (xf[1] - v) + rate * rate);
        /* undecided (the miss may be within the integration error, the bound too large for the tolerance):
         * halve the steps again, the finer run becoming the coarse one, at most CERT_REFINE times */
        if (!(isfinite(n + w) && n - w <= CERT_TOL && n + w > CERT_TOL && mult < (2 << CERT_REFINE))) break;
        xc[0] = xf[0];
        xc[1] = xf[1];
        xc[2] = xf[2];
        xf[0] = xf[1] = xf[2] = RP_R(0.0);
        if (motion(xf, 2 * mult, steps, ab, k, gamma, &scale)) return RP_NOT_CERTIFIED;
    }
    if (final) {
        final[0] = xf[0];
        final[1] = xf[1];
        final[2] = xf[2];
    }
    if (residual) *residual = n;
    if (bound) *bound = w;
    return isfinite(n + w) && n + w <= CERT_TOL ? RP_OK : RP_NOT_CERTIFIED;
}

/* ------------------------------------------------------------------ leaf map (leafmap.py) */

/* Gauss-Legendre nodes and weights on [-1, 1] (numpy's leggauss, written at generation). */
static const casadi_real s_gx[ORDER] = {RP_GAUSS_X};
static const casadi_real s_gw[ORDER] = {RP_GAUSS_W};
/* leafmap.BUCKETS: for k <= s_bucket_k[i] (and above the previous bucket) the rule has s_bucket_p[i] panels */
static const casadi_real s_bucket_k[NBUCKET] = {RP_BUCKET_K};
static const int s_bucket_p[NBUCKET] = {RP_BUCKET_P};

/* State kept for the last k: the rule's nodes, E(A_MAX) and the rho table. */
static int s_ready = 0;
static casadi_real s_k = RP_R(0.0);
static int s_nodes;                                       /* ORDER x panels / 2: the nodes chi < pi */
static casadi_real s_chi[ORDER * MAX_PANELS / 2], s_cchi[ORDER * MAX_PANELS / 2], s_schi[ORDER * MAX_PANELS / 2],
    s_wchi[ORDER * MAX_PANELS / 2];
static casadi_real s_e_min;                               /* E(A_MAX, k) < 0 */
static int s_nt;                                          /* radii of the table */
static casadi_real s_tr[NTABLE], s_te[NTABLE], s_trho[NTABLE], s_tdrho[NTABLE];
static casadi_real s_tdu[NTABLE];                         /* du/dE at the radii, u = r^2 (inf where dE/du = 0) */
/* Buckets of the table: radius bucket j (r >= A_MAX j / NTABLE) starts at the last radius s_tr[i] <= A_MAX j / NTABLE,
 * s_rb[j] = i; turn bucket j (E <= e_min j / NTABLE) starts at the last radius with s_te[i] >= e_min j / NTABLE. */
static unsigned short s_rb[NTABLE + 1], s_eb[NTABLE + 1];
static casadi_real s_rscale, s_escale;                    /* bucket of r: r s_rscale; of a turn E: E s_escale */
static casadi_real s_eps, s_eps_g;                        /* table error bound; its effect on g */
static casadi_real s_err_mid;                             /* the table's largest error at the cells' midpoints */
/* A table given by table_load (rho and d rho / dr already in s_trho, s_tdrho) for s_loaded_k, s_loaded_n radii
 * (0: none), its midpoint error s_loaded_err: the next prepare() of that k takes it instead of evaluating. */
static casadi_real s_loaded_k, s_loaded_err;
static int s_loaded_n = 0;
/* Bounds of the table's rho on its cells (cell_range) and, for range queries (rho_range), on blocks of RHO_BLOCK
 * cells: level j of the sparse table bounds the 2^j blocks from each block. */
#define RHO_BLOCK 16
#define NBLOCK (NTABLE / RHO_BLOCK + 1)
#define NLEVEL (NBLOCK < 2 ? 1 : NBLOCK < 4 ? 2 : NBLOCK < 8 ? 3 : NBLOCK < 16 ? 4 : NBLOCK < 32 ? 5 : NBLOCK < 64 ? 6 \
                : NBLOCK < 128 ? 7 : NBLOCK < 256 ? 8 : NBLOCK < 512 ? 9 : NBLOCK < 1024 ? 10 : 11)
static casadi_real s_rlo[NTABLE], s_rhi[NTABLE], s_blo[NLEVEL][NBLOCK], s_bhi[NLEVEL][NBLOCK];
static int s_nblock;                                      /* full blocks of the table */
#define MIN(x, y) ((x) < (y) ? (x) : (y))
#define MAX(x, y) ((x) > (y) ? (x) : (y))

/* (c, s, rho) of radius r: c = sqrt(1 - r^2), s = sqrt(1 - 2 r^2), rho = r^2 / (c^2 + s) (leafmap._consts). */
static void consts(casadi_real r, casadi_real *c, casadi_real *s, casadi_real *rho) {
    *c = RP_SQRT(RP_R(1.0) - r * r);
    *s = RP_SQRT(RP_R(1.0) - RP_R(2.0) * r * r);
    *rho = r * r / (*c * *c + *s);
}

/* Turn E(r, k) of the Viviani lobe of size r and dE/dr (families.turn, docs/design/curve-families.md):
 *   E = 4 asin r - 4 r c - k B,  B = (2 sqrt 2 c / s) atan(sqrt 2 r / s) - 4 r c,
 *   dE/dr = 8 r^2 / c - k (2 sqrt 2 r atan(sqrt 2 r / s) / (c s^3) + 4 c / s^2 - 4 (c^2 - r^2) / c). */
static casadi_real viviani_turn(casadi_real r, casadi_real k, casadi_real *dr) {
    const casadi_real sq2 = RP_R(1.41421356237309504880);
    casadi_real c = RP_SQRT(RP_R(1.0) - r * r), s = RP_SQRT(RP_R(1.0) - RP_R(2.0) * r * r), at = RP_ATAN(sq2 * r / s);
    if (dr)
        *dr = RP_R(8.0) * r * r / c
              - k * (RP_R(2.0) * sq2 * r * at / (c * s * s * s) + RP_R(4.0) * c / (s * s) - RP_R(4.0) * (c * c - r * r) / c);
    return RP_R(4.0) * RP_ASIN(r) - RP_R(4.0) * r * c - k * (RP_R(2.0) * sq2 * c / s * at - RP_R(4.0) * r * c);
}

/* Unit vector at polar distance sigma from the south pole in the direction beta from +y towards +x. */
static void polar(casadi_real sigma, casadi_real beta, casadi_real p[3]) {
    p[0] = RP_SIN(sigma) * RP_SIN(beta);
    p[1] = RP_SIN(sigma) * RP_COS(beta);
    p[2] = -RP_COS(sigma);
}

/* One edge's part of the turn of a polygon leaf (families._edge_terms): on the great circle whose nearest point to
 * the pole is at distance p in direction theta_n, [x - asin(cos p sin x) - k tan p asinh(sin p tan x)] between the
 * edge's end directions x (from theta_n). */
static casadi_real edge_term(const casadi_real a[3], const casadi_real b[3], casadi_real k) {
    casadi_real n[3], nh, tp, sp, cp, th, x, y, q, out = RP_R(0.0);
    int i;
    n[0] = a[1] * b[2] - a[2] * b[1];
    n[1] = a[2] * b[0] - a[0] * b[2];
    n[2] = a[0] * b[1] - a[1] * b[0];
    if (n[2] < RP_R(0.0)) for (i = 0; i < 3; ++i) n[i] = -n[i];
    nh = RP_HYPOT(n[0], n[1]);
    tp = n[2] / nh;
    cp = RP_R(1.0) / RP_SQRT(RP_R(1.0) + tp * tp);
    sp = tp * cp;
    th = RP_ATAN2(n[1], n[0]);
    for (i = 0; i < 2; ++i) {
        x = wrap(RP_ATAN2(i ? b[1] : a[1], i ? b[0] : a[0]) - th);
        y = sp * RP_TAN(x);
        q = RP_LOG(RP_FABS(y) + RP_SQRT(RP_R(1.0) + y * y));          /* asinh |y| */
        q = x - RP_ASIN(cp * RP_SIN(x)) - k * tp * (y < RP_R(0.0) ? -q : q);
        out += i ? q : -q;
    }
    return out;
}

/* Turn E(r, k) of the polygon leaf of size r (families.turn): the triangle with apex 60 degrees and legs 2 asin r, or
 * the rhombus with 90 degrees at the pole, its far corner at 2 asin r and its side corners at atan(sqrt 2 tan(D/2));
 * the radial edges add nothing. */
static casadi_real polygon_turn(casadi_real r, casadi_real k) {
    casadi_real d = RP_R(2.0) * RP_ASIN(r), v1[3], v2[3], v3[3], l;
    if (!(r > RP_R(0.0))) return RP_R(0.0);                     /* the leaf of size 0 is the pole */
    if (FAMILY == FAMILY_TRIANGLE) {
        polar(d, PI / RP_R(6.0), v1);
        polar(d, -PI / RP_R(6.0), v2);
        return edge_term(v1, v2, k);
    }
    l = RP_ATAN(RP_R(1.41421356237309504880) * r / RP_SQRT(RP_R(1.0) - r * r));
    polar(l, PI / RP_R(4.0), v1);
    polar(d, RP_R(0.0), v2);
    polar(l, -PI / RP_R(4.0), v3);
    return edge_term(v1, v2, k) + edge_term(v2, v3, k);
}

/* dE/dr of a polygon leaf: the fourth-order central difference of polygon_turn with step min(1e-3, r / 4)
 * (E is smooth in r on (0, A_MAX], even at 0). */
static casadi_real polygon_turn_dr(casadi_real r, casadi_real k) {
    casadi_real h = r / RP_R(4.0) < RP_R(1e-3) ? r / RP_R(4.0) : RP_R(1e-3);
    if (!(r > RP_R(0.0))) return RP_R(0.0);
    return (RP_R(8.0) * (polygon_turn(r + h, k) - polygon_turn(r - h, k))
            - (polygon_turn(r + RP_R(2.0) * h, k) - polygon_turn(r - RP_R(2.0) * h, k))) / (RP_R(12.0) * h);
}

/* Turn of psi over the +y leaf, E(r, k) = 2 pi r^2 / (1 + c) - 4 pi k c r^2 / (s (1 + s)) (leafmap.turn); another
 * family's closed form (viviani_turn, polygon_turn). */
static casadi_real turn(casadi_real r, casadi_real k) {
    casadi_real c, s, rho;
    if (FAMILY == FAMILY_VIVIANI) return viviani_turn(r, k, NULL);
    if (FAMILY >= FAMILY_TRIANGLE) return polygon_turn(r, k);
    consts(r, &c, &s, &rho);
    return TWO_PI * r * r / (RP_R(1.0) + c) - RP_R(2.0) * TWO_PI * k * c * r * r / (s * (RP_R(1.0) + s));
}

/* dE/dr = (2 pi r / c) (1 - k (1 + s^-3)) (leafmap.turn_dr). */
static casadi_real turn_dr(casadi_real r, casadi_real k) {
    casadi_real c, s, rho;
    if (FAMILY == FAMILY_VIVIANI) {
        viviani_turn(r, k, &c);
        return c;
    }
    if (FAMILY >= FAMILY_TRIANGLE) return polygon_turn_dr(r, k);
    consts(r, &c, &s, &rho);
    return TWO_PI * r / c * (RP_R(1.0) - k * (RP_R(1.0) + RP_R(1.0) / (s * s * s)));
}

/* E(r, k) and dE/dr (turn and turn_dr from one evaluation of c and s). */
static casadi_real turn_and_dr(casadi_real r, casadi_real k, casadi_real *dr) {
    casadi_real c, s, rho;
    if (FAMILY == FAMILY_VIVIANI) return viviani_turn(r, k, dr);
    if (FAMILY >= FAMILY_TRIANGLE) {
        *dr = polygon_turn_dr(r, k);
        return polygon_turn(r, k);
    }
    consts(r, &c, &s, &rho);
    *dr = TWO_PI * r / c * (RP_R(1.0) - k * (RP_R(1.0) + RP_R(1.0) / (s * s * s)));
    return TWO_PI * r * r / (RP_R(1.0) + c) - RP_R(2.0) * TWO_PI * k * c * r * r / (s * (RP_R(1.0) + s));
}

/* Table radii i0 < i1 = i0 + 1 around x (s_tr[i0] <= x < s_tr[i1], i1 = s_nt - 1 at the end) if turn = 0, or around
 * the turn x (s_te[i0] >= x > s_te[i1]) if turn = 1: bisection started in x's bucket (the whole table if the bucket's
 * bounds do not hold x, which rounding at a bucket's edge may cause). */
static void bracket(casadi_real x, int turn, int *lo, int *hi) {
    const casadi_real *tab = turn ? s_te : s_tr;
    const unsigned short *bucket = turn ? s_eb : s_rb;
    casadi_real pos = x * (turn ? s_escale : s_rscale);
    int j = pos >= RP_R(0.0) ? (pos < NTABLE ? (int)pos : NTABLE - 1) : 0, i0 = bucket[j], i1 = bucket[j + 1] + 1, im;
    if (i1 > s_nt - 1) i1 = s_nt - 1;
    if (i0 >= i1) i0 = i1 - 1;
    if (turn ? !(tab[i0] >= x) : !(tab[i0] <= x)) i0 = 0;
    if (i1 < s_nt - 1 && (turn ? !(tab[i1] < x) : !(tab[i1] > x))) i1 = s_nt - 1;
    while (i1 - i0 > 1) {
        im = (i0 + i1) / 2;
        if (turn ? tab[im] >= x : tab[im] <= x) i0 = im; else i1 = im;
    }
    *lo = i0;
    *hi = i1;
}

/* Radius r in [0, A_MAX] with E(r, k) = e (k >= 1/2: E strictly decreasing), NaN for e outside
 * [E(A_MAX), 0] (leafmap.turn_inverse): safeguarded Newton in u = r^2 (E is smooth in u, with
 * dE/du = (pi / c) (1 - k (1 + s^-3))) from a start interpolated in the table of the last k (cubic Hermite in E
 * with the tabulated du/dE, linear where that is not finite or leaves the cell), bisecting whenever a step leaves
 * the bracket. */
static casadi_real family_inverse(casadi_real e, casadi_real k);

/* The root x in [lo, hi] of g(x, k) = e for g decreasing in x (a leaf's turn), by Newton's method from x with its
 * derivative, bisecting whenever a step leaves the bracket; it stops at the rounding level of g (leafmap.turn_inverse)
 * or when the step or the bracket is below xtol relative. */
static casadi_real decreasing_root(casadi_real (*g)(casadi_real, casadi_real, casadi_real *), casadi_real e,
                                   casadi_real k, casadi_real x, casadi_real lo, casadi_real hi, casadi_real xtol) {
    casadi_real f, df, nxt;
    int it;
    for (it = 0; it < 200; ++it) {
        f = g(x, k, &df) - e;
        if (RP_FABS(f) <= RP_R(4e-16) * (RP_R(1.0) + RP_FABS(e)) * (RP_R(1.0) + k)) break;
        if (f > RP_R(0.0)) lo = x; else hi = x;                   /* g decreasing: the root is to the right of x if f > 0 */
        nxt = x - f / df;
        if (!isfinite(nxt) || nxt <= lo || nxt >= hi) nxt = RP_R(0.5) * (lo + hi);
        if (RP_FABS(nxt - x) <= xtol * nxt || hi - lo <= xtol * hi) return nxt;
        x = nxt;
    }
    return x;
}

/* The circle's turn E as a function of u = r^2 (the closed form of turn()), and dE/du. */
static casadi_real turn_of_u(casadi_real u, casadi_real k, casadi_real *du) {
    casadi_real c = RP_SQRT(RP_R(1.0) - u), s = RP_SQRT(RP_R(1.0) - RP_R(2.0) * u);
    *du = PI / c * (RP_R(1.0) - k * (RP_R(1.0) + RP_R(1.0) / (s * s * s)));
    return TWO_PI * u / (RP_R(1.0) + c) - RP_R(2.0) * TWO_PI * k * c * u / (s * (RP_R(1.0) + s));
}

static casadi_real turn_inverse(casadi_real e, casadi_real k) {
    const casadi_real umax = A_MAX * A_MAX;
    casadi_real lo = RP_R(0.0), hi = umax, u, w, t;
    int i0, i1;
    if (!(e <= RP_R(0.0) && e >= s_e_min)) return NAN;
    if (e >= RP_R(0.0)) return RP_R(0.0);
    if (e <= s_e_min) return A_MAX;
    if (FAMILY != FAMILY_CIRCLES) return family_inverse(e, k);
    if (s_nt > 1) {
        bracket(e, 1, &i0, &i1);
        lo = s_tr[i0] * s_tr[i0];
        hi = s_tr[i1] * s_tr[i1];
        w = s_te[i1] - s_te[i0];
        t = (e - s_te[i0]) / w;
        u = (2 * t * t * t - 3 * t * t + 1) * lo + (t * t * t - 2 * t * t + t) * w * s_tdu[i0]
            + (-2 * t * t * t + 3 * t * t) * hi + (t * t * t - t * t) * w * s_tdu[i1];
        if (!(u >= lo && u <= hi)) u = lo + (hi - lo) * t;
        if (!(u >= lo && u <= hi)) u = RP_R(0.5) * (lo + hi);
    } else {
        u = umax * e / s_e_min;
    }
    return RP_SQRT(decreasing_root(turn_of_u, e, k, u, lo, hi, RP_R(1e-15)));
}

/* Another family's turn inverse (k >= K_MONOTONE, E decreasing, e inside (E(A_MAX), 0)): safeguarded Newton in r on
 * the closed form from the table's linear interpolation in E, bisecting whenever a step leaves the bracket. */
static casadi_real family_inverse(casadi_real e, casadi_real k) {
    casadi_real lo = RP_R(0.0), hi = A_MAX, r;
    int i0, i1;
    if (s_nt > 1) {
        bracket(e, 1, &i0, &i1);
        lo = s_tr[i0];
        hi = s_tr[i1];
        r = lo + (hi - lo) * (e - s_te[i0]) / (s_te[i1] - s_te[i0]);
        if (!(r >= lo && r <= hi)) r = RP_R(0.5) * (lo + hi);
    } else {
        r = RP_R(0.5) * A_MAX;
    }
    return decreasing_root(turn_and_dr, e, k, r, lo, hi, RP_R(1e-16));
}

/* Displacement d = u_a + i v_a of the +y leaf of radius r from zero (leafmap.displacement):
 *   d = r int_0^{2 pi} phi'(chi) exp(i [(1 - k) c phi(chi) + (k c / s) chi]) d chi,
 *   phi(chi) = chi + 2 atan(rho sin chi / (1 - rho cos chi)), phi'(chi) = (1 - rho^2) / (1 - 2 rho cos chi + rho^2),
 * by the composite Gauss rule of the last k; with dd (not NULL) also dd/dr, the rule applied to the
 * r-derivative of the integrand. */
/* The last MEMO evaluations of displacement (a plan evaluates the same radii several times: the polished
 * root, its gamma, and both leaves when a = b). */
#define MEMO 4
static struct {
    casadi_real r, k, d[2], dd[2];
    int has_dd;
} s_memo[MEMO];
static int s_memo_next = 0, s_memo_used = 0;

/* Another family's displacement: the +y leaf of size r integrated from zero by the generated RK8 steps of its curve
 * ODE (28)-(30) with FAMILY_MULT times the certificate's steps per panel (counts() at r, kept for the neighbours);
 * with dd (not NULL) also dd/dr by the difference quotient of r + dr and max(r - dr, 0). Returns 0 on success. */
static int family_displacement(casadi_real r, casadi_real k, casadi_real d[2], casadi_real dd[2]) {
    static casadi_real rot[2 * NSTAGE];
    const casadi_real cg[2] = {RP_R(1.0), RP_R(0.0)};
    casadi_real ab[2], x[3], h, step = RP_R(1e-5), lo[2] = {RP_R(0.0), RP_R(0.0)}, at[3];
    int j, n, q, pass;
    at[0] = r;
    at[1] = r + step;
    at[2] = r > step ? r - step : RP_R(0.0);
    ab[0] = ab[1] = r > step ? r : step;
    if (counts(ab, k, RP_R(0.0))) return 1;
    for (pass = 0; pass < (dd ? 3 : 1); ++pass) {
        ab[0] = ab[1] = at[pass];
        x[0] = x[1] = x[2] = RP_R(0.0);
        for (j = 0; j < NPANEL && at[pass] > RP_R(0.0); ++j) {   /* (the leaf of size 0 stays at the pole) */
            n = FAMILY_MULT * s_counts[0][j];
            h = (s_breaks[j + 1] - s_breaks[j]) / n;
            stage_rotations(h, rot);
            if (rk8_steps(0, x, s_breaks[j], h, n, rot, ab, k, cg)) return 1;
        }
        if (pass == 0) {
            d[0] = x[0];
            d[1] = x[1];
        } else if (pass == 1) {
            lo[0] = x[0];
            lo[1] = x[1];
        } else {
            for (q = 0; q < 2; ++q) dd[q] = (lo[q] - x[q]) / (at[1] - at[2]);
        }
    }
    return 0;
}

static void displacement(casadi_real r, casadi_real k, casadi_real d[2], casadi_real dd[2]) {
    casadi_real c, s, rho, br = RP_R(0.0), bi = RP_R(0.0), tr = RP_R(0.0), ti = RP_R(0.0), c_r = RP_R(0.0), s_r = RP_R(0.0), g, rho_r = RP_R(0.0);
    casadi_real cx, sx, den, q, phi, jac, theta, ec, es, w, phi_rho, jac_rho, theta_r, p1, p2, tt, ct, st, fr, fi, qr,
        qi, tt_r;
    int j;
    for (j = 0; j < s_memo_used; ++j) {
        if (s_memo[j].r == r && s_memo[j].k == k && (s_memo[j].has_dd || !dd)) {
            d[0] = s_memo[j].d[0];
            d[1] = s_memo[j].d[1];
            if (dd) {
                dd[0] = s_memo[j].dd[0];
                dd[1] = s_memo[j].dd[1];
            }
            return;
        }
    }
    if (FAMILY != FAMILY_CIRCLES) {
        if (family_displacement(r, k, d, dd)) {
            d[0] = d[1] = NAN;
            if (dd) dd[0] = dd[1] = NAN;
        }
        goto keep;
    }
    consts(r, &c, &s, &rho);
    if (dd) {
        c_r = -r / c;
        s_r = -RP_R(2.0) * r / s;
        g = c * c + s;
        rho_r = (RP_R(2.0) * r * g - r * r * (-RP_R(2.0) * r + s_r)) / (g * g);
    }
    for (j = 0; j < s_nodes; ++j) {
        cx = s_cchi[j];
        sx = s_schi[j];
        w = s_wchi[j];
        den = RP_R(1.0) - rho * cx;
        q = den * den + (rho * sx) * (rho * sx);
        phi = s_chi[j] + RP_R(2.0) * RP_ATAN2(rho * sx, den);
        jac = (RP_R(1.0) - rho * rho) / q;
        theta = (RP_R(1.0) - k) * c * phi + (k * c / s) * s_chi[j];
        ec = RP_COS(theta);
        es = RP_SIN(theta);
        br += w * jac * ec;
        bi += w * jac * es;
        if (dd) {
            phi_rho = RP_R(2.0) * sx / q;
            jac_rho = (-RP_R(2.0) * rho * q - (RP_R(1.0) - rho * rho) * (RP_R(2.0) * rho - RP_R(2.0) * cx)) / (q * q);
            theta_r = (RP_R(1.0) - k) * (c_r * phi + c * phi_rho * rho_r) + k * s_chi[j] * (c_r * s - c * s_r) / (s * s);
            p1 = jac_rho * rho_r;
            p2 = theta_r * jac;
            tr += w * (p1 * ec - p2 * es);
            ti += w * (p1 * es + p2 * ec);
        }
    }
    /* the nodes chi > pi: phi(2 pi - chi) = 2 pi - phi(chi), phi' and the weights are symmetric, so
     * theta(2 pi - chi) = T - theta(chi) with T = 2 pi ((1 - k) c + k c / s), and that half of the rule is
     * exp(i T) conj(I) for I = br + i bi the half summed above; of the r-derivative, exp(i T) (conj(J) + i T_r conj(I))
     * for J = tr + i ti */
    tt = TWO_PI * ((RP_R(1.0) - k) * c + k * c / s);
    ct = RP_COS(tt);
    st = RP_SIN(tt);
    fr = br + ct * br + st * bi;
    fi = bi + st * br - ct * bi;
    d[0] = r * fr;
    d[1] = r * fi;
    if (dd) {
        tt_r = TWO_PI * ((RP_R(1.0) - k) * c_r + k * (c_r * s - c * s_r) / (s * s));
        qr = tr + tt_r * bi;
        qi = -ti + tt_r * br;
        dd[0] = fr + r * (tr + ct * qr - st * qi);
        dd[1] = fi + r * (ti + st * qr + ct * qi);
    }
keep:
    j = s_memo_next;
    s_memo_next = (s_memo_next + 1) % MEMO;
    if (s_memo_used < MEMO) ++s_memo_used;
    s_memo[j].r = r;
    s_memo[j].k = k;
    s_memo[j].d[0] = d[0];
    s_memo[j].d[1] = d[1];
    s_memo[j].has_dd = dd != NULL;
    if (dd) {
        s_memo[j].dd[0] = dd[0];
        s_memo[j].dd[1] = dd[1];
    }
}

/* rho(r, k) = Re(exp(i E / 2) d) and d rho / dr (leafmap.signed_length): d = rho exp(-i E / 2). */
static void signed_length(casadi_real r, casadi_real k, casadi_real *rho, casadi_real *drho) {
    casadi_real d[2], dd[2], e = turn(r, k), ch = RP_COS(RP_R(0.5) * e), sh = RP_SIN(RP_R(0.5) * e), zr, zi, de;
    displacement(r, k, d, drho ? dd : NULL);
    *rho = d[0] * ch - d[1] * sh;
    if (drho) {
        de = turn_dr(r, k);
        zr = dd[0] - RP_R(0.5) * de * d[1];
        zi = dd[1] + RP_R(0.5) * de * d[0];
        *drho = zr * ch - zi * sh;
    }
}

/* ------------------------------------------------------------------ rho table (enumerate.rho_table) */

/* Cubic Hermite lookup of (rho, d rho / dr) at r in the table (enumerate.rho_lookup). */
static void rho_lookup(casadi_real r, casadi_real *rho, casadi_real *drho) {
    int i0, i1;
    casadi_real w, t, t2, t3, g0, g1, p0, p1;
    bracket(r, 0, &i0, &i1);
    w = s_tr[i1] - s_tr[i0];
    t = (r - s_tr[i0]) / w;
    t2 = t * t;
    t3 = t2 * t;
    g0 = s_trho[i0];
    g1 = s_trho[i1];
    p0 = s_tdrho[i0];
    p1 = s_tdrho[i1];
    *rho = (2 * t3 - 3 * t2 + 1) * g0 + (t3 - 2 * t2 + t) * w * p0 + (-2 * t3 + 3 * t2) * g1 + (t3 - t2) * w * p1;
    if (drho)
        *drho = ((6 * t2 - 6 * t) * g0 + (-6 * t2 + 6 * t) * g1) / w + (3 * t2 - 4 * t + 1) * p0 + (3 * t2 - 2 * t) * p1;
}

/* Bounds [lo, hi] of the table's rho (the cubic Hermite rho_lookup evaluates) on the radii [r0, r1] (0 <= r0 <= r1):
 * on a table cell of width w the cubic is a convex combination of its end values plus w (h10 p0 + h11 p1) with
 * 0 <= h10 <= 4/27 and -4/27 <= h11 <= 0, so it lies within 4/27 w (|p0| + |p1|) of the range of its end values
 * (cell_range). The cells are bounded a block of RHO_BLOCK at a time through the sparse table (s_blo, s_bhi). */
static void cell_range(int i, casadi_real *lo, casadi_real *hi) {
    casadi_real m = (RP_R(4.0) / RP_R(27.0)) * (s_tr[i + 1] - s_tr[i]) * (RP_FABS(s_tdrho[i]) + RP_FABS(s_tdrho[i + 1]));
    *lo = MIN(s_trho[i], s_trho[i + 1]) - m;
    *hi = MAX(s_trho[i], s_trho[i + 1]) + m;
}

static void rho_range(casadi_real r0, casadi_real r1, casadi_real *lo, casadi_real *hi) {
    int i0, i1, j, i, b0, b1, lev;
    casadi_real l = INFINITY, h = -INFINITY;
    bracket(r0 < r1 ? r0 : r1, 0, &i0, &j);             /* (the ends in either order) */
    bracket(r0 < r1 ? r1 : r0, 0, &i1, &j);
    b0 = (i0 + RHO_BLOCK - 1) / RHO_BLOCK;             /* the full blocks inside the cells i0 .. i1 */
    b1 = (i1 + 1) / RHO_BLOCK - 1;
    if (b1 >= s_nblock) b1 = s_nblock - 1;
    if (b0 > b1) {
        b0 = b1 + 1;
        j = i1 + 1;
    } else {
        j = b0 * RHO_BLOCK;
        for (lev = 0; (2 << lev) <= b1 - b0 + 1; ++lev) {}
        l = MIN(s_blo[lev][b0], s_blo[lev][b1 - (1 << lev) + 1]);
        h = MAX(s_bhi[lev][b0], s_bhi[lev][b1 - (1 << lev) + 1]);
    }
    for (i = i0; i < j; ++i) {
        l = MIN(l, s_rlo[i]);
        h = MAX(h, s_rhi[i]);
    }
    for (i = (b1 + 1) * RHO_BLOCK > j ? (b1 + 1) * RHO_BLOCK : j; i <= i1; ++i) {
        l = MIN(l, s_rlo[i]);
        h = MAX(h, s_rhi[i]);
    }
    *lo = l;
    *hi = h;
}

/* Rule, E(A_MAX) and the rho table for k (kept for the last k). The radii are those of enumerate.table_radii; eps
 * is SAFETY times the largest error at the midpoints against the accurate map, plus rounding
 * (enumerate._build_rho_table). Returns 0 on success. */
static void prepare_pieces(casadi_real k);

/* A loaded table (table_load) matches this build and k: rho and d rho / dr evaluated again at three of its n radii
 * equal the loaded ones exactly. */
static int loaded_intact(int n, casadi_real k) {
    const int at[3] = {n / 3, (2 * n) / 3, n - 1};
    casadi_real rho, drho;
    int q;
    for (q = 0; q < 3; ++q) {
        signed_length(s_tr[at[q]], k, &rho, &drho);
        if (!(rho == s_trho[at[q]] && drho == s_tdrho[at[q]])) return 0;
    }
    return 1;
}

static int prepare(casadi_real k) {
    int panels = s_bucket_p[NBUCKET - 1], i, j, parts, nr, n, loaded;
    casadi_real h, re, rr, x, rho, err, big, e0, e1, is0, is1;
    if (s_ready && s_k == k) return 0;
    s_ready = 0;
    for (i = 0; i < NBUCKET; ++i) {
        if (k <= s_bucket_k[i]) {
            panels = s_bucket_p[i];
            break;
        }
    }
    h = PI / panels;
    /* the rule's nodes chi < pi only (displacement() gets the others by symmetry): the panels' centres are
     * symmetric about pi, the Gauss nodes about the centres, ORDER is even */
    s_nodes = 0;
    for (i = 0; i < panels; ++i) {
        for (j = 0; j < ORDER; ++j) {
            x = (RP_R(2.0) * i + RP_R(1.0)) * h + h * s_gx[j];
            if (!(x < PI) || s_nodes >= ORDER * MAX_PANELS / 2) continue;
            s_chi[s_nodes] = x;
            s_cchi[s_nodes] = RP_COS(x);
            s_schi[s_nodes] = RP_SIN(x);
            s_wchi[s_nodes] = h * s_gw[j];
            ++s_nodes;
        }
    }
    if (2 * s_nodes != ORDER * panels) return 1;
    s_e_min = turn(A_MAX, k);
    prepare_pieces(k);
    s_nt = 0;
    /* radii uniform in r with TABLE_STEP, each cell split evenly so that E changes by at most TABLE_PHASE and
     * 1 / s = (1 - 2 r^2)^(-1/2) by at most TABLE_INV_S (enumerate.table_radii: the same radii) */
    nr = (int)RP_CEIL(A_MAX / TABLE_STEP) + 1;
    h = A_MAX / (nr - 1);
    n = 0;
    e0 = RP_R(0.0);                                              /* E and 1 / s at the cell's left end */
    is0 = RP_R(1.0);
    for (j = 0; j + 1 < nr; ++j) {
        x = j + 2 == nr ? A_MAX : (j + 1) * h;             /* the cell's right end */
        e1 = turn(x, k);
        is1 = RP_R(1.0) / RP_SQRT(RP_R(1.0) - RP_R(2.0) * x * x);
        big = RP_FMAX(RP_CEIL(RP_FABS(e1 - e0) / TABLE_PHASE), RP_CEIL((is1 - is0) / TABLE_INV_S));
        parts = big > RP_R(1.0) ? (int)big : 1;
        if (n + parts + 1 > NTABLE) return 1;
        for (i = 0; i < parts; ++i) s_tr[n++] = j * h + (casadi_real)i / parts * (x - j * h);
        e0 = e1;
        is0 = is1;
    }
    s_tr[n++] = A_MAX;
    loaded = s_loaded_n == n && s_loaded_k == k && loaded_intact(n, k);
    s_loaded_n = 0;
    for (i = 0; i < n; ++i) {
        if (!loaded) signed_length(s_tr[i], k, &s_trho[i], &s_tdrho[i]);
        s_te[i] = turn(s_tr[i], k);
        re = RP_SQRT(RP_R(1.0) - s_tr[i] * s_tr[i]);                 /* c and s of consts(); du/dE = 1 / (dE/du) */
        rr = RP_SQRT(RP_R(1.0) - RP_R(2.0) * s_tr[i] * s_tr[i]);
        s_tdu[i] = re / (PI * (RP_R(1.0) - k * (RP_R(1.0) + RP_R(1.0) / (rr * rr * rr))));
        if (FAMILY != FAMILY_CIRCLES) s_tdu[i] = RP_R(2.0) * s_tr[i] / turn_dr(s_tr[i], k);   /* (not used) */
        if (!(isfinite(s_trho[i]) && isfinite(s_tdrho[i]))) return 1;
    }
    s_rscale = NTABLE / A_MAX;
    s_escale = s_e_min < RP_R(0.0) ? NTABLE / s_e_min : RP_R(0.0);   /* (turn buckets serve turn_inverse, k >= K_MONOTONE) */
    for (i = 0, j = 0; j <= NTABLE; ++j) {   /* buckets (both sequences increase along the table) */
        while (i + 1 < n && s_tr[i + 1] <= A_MAX * j / NTABLE) ++i;
        s_rb[j] = (unsigned short)i;
    }
    for (i = 0, j = 0; j <= NTABLE; ++j) {
        while (i + 1 < n && s_te[i + 1] >= s_e_min * j / NTABLE) ++i;
        s_eb[j] = (unsigned short)i;
    }
    s_nt = n;
    for (i = 0; i + 1 < n; ++i) cell_range(i, &s_rlo[i], &s_rhi[i]);
    s_nblock = (n - 1) / RHO_BLOCK;                        /* block b: the cells b RHO_BLOCK .. (b + 1) RHO_BLOCK - 1 */
    for (i = 0; i < s_nblock; ++i) {
        s_blo[0][i] = INFINITY;
        s_bhi[0][i] = -INFINITY;
        for (j = i * RHO_BLOCK; j < (i + 1) * RHO_BLOCK; ++j) {
            s_blo[0][i] = MIN(s_blo[0][i], s_rlo[j]);
            s_bhi[0][i] = MAX(s_bhi[0][i], s_rhi[j]);
        }
    }
    for (j = 1; j < NLEVEL; ++j) {
        for (i = 0; i + (1 << j) <= s_nblock; ++i) {
            s_blo[j][i] = MIN(s_blo[j - 1][i], s_blo[j - 1][i + (1 << (j - 1))]);
            s_bhi[j][i] = MAX(s_bhi[j - 1][i], s_bhi[j - 1][i + (1 << (j - 1))]);
        }
    }
    err = loaded ? s_loaded_err : RP_R(0.0);
    big = RP_R(0.0);
    for (i = 0; i + 1 < n && !loaded; ++i) {
        x = RP_R(0.5) * (s_tr[i] + s_tr[i + 1]);
        signed_length(x, k, &rho, NULL);
        rho_lookup(x, &re, NULL);
        err = RP_FMAX(err, RP_FABS(re - rho));
    }
    s_err_mid = err;
    for (i = 0; i < n; ++i) big = RP_FMAX(big, RP_FABS(s_trho[i]));
    s_eps = SAFETY * err + RP_R(1e-13);
    s_eps_g = RP_R(8.0) * big * s_eps + s_eps * s_eps;    /* the table's error carried into g (enumerate.roots) */
    s_k = k;
    s_ready = 1;
    return 0;
}

void RP_NAME(forget_table)(void) {
    s_ready = 0;
    s_memo_used = 0;
}

int RP_NAME(table_save)(casadi_real k, int capacity, casadi_real *rho, casadi_real *drho, casadi_real *err, int *n) {
    int i;
    *n = 0;
    if (!(k >= K_MIN && k <= K_MAX)) return RP_BAD_INPUT;
    if (prepare(k)) return RP_NO_CONVERGENCE;
    *n = s_nt;
    if (s_nt > capacity) return RP_TOO_MANY;
    for (i = 0; i < s_nt; ++i) {
        rho[i] = s_trho[i];
        drho[i] = s_tdrho[i];
    }
    *err = s_err_mid;
    return RP_OK;
}

int RP_NAME(table_load)(casadi_real k, int n, const casadi_real *rho, const casadi_real *drho, casadi_real err) {
    int i;
    if (s_ready && s_k == k) return RP_OK;   /* that table is already kept */
    if (!(k >= K_MIN && k <= K_MAX) || n < 2 || n > NTABLE || !(err >= RP_R(0.0))) return RP_BAD_INPUT;
    for (i = 0; i < n; ++i)
        if (!(isfinite(rho[i]) && isfinite(drho[i]))) return RP_BAD_INPUT;
    s_ready = 0;
    for (i = 0; i < n; ++i) {
        s_trho[i] = rho[i];
        s_tdrho[i] = drho[i];
    }
    s_loaded_k = k;
    s_loaded_n = n;
    s_loaded_err = err;
    return RP_OK;
}

/* ------------------------------------------------------------------ branches (enumerate.py) */

typedef struct {
    long m;              /* branch of n eta = psi_w + 2 pi m (psi_w the wrapped target heading) */
    casadi_real eta;     /* turn per step eta_m */
    casadi_real e;       /* |eta_m| */
    casadi_real h;       /* shift per step h_m (33)-(34) */
    casadi_real x_end;   /* range [0, x_end] of the smaller radius */
    casadi_real y0;      /* smallest a + b on the branch (a lower bound of it on a sigma graph) */
    casadi_real c_half;  /* cos(eta / 2) */
    /* the graph: over x (kap = 0, k >= K_MONOTONE) or over sigma = a + kap b on a rectangle of monotone pieces of E
     * (kap = +-1, k < K_MONOTONE: sigma_graphs); the parameter runs over [p_lo, p_hi] */
    int kap, sa;         /* kap = s_a s_b; s_a the sign of E' on a's piece */
    casadi_real p_lo, p_hi, a_lo, a_hi, b_lo, b_hi;   /* a at p_lo and p_hi; b's piece [b_lo, b_hi] */
} branch_t;

/* ------------------------------------------------------------------ sigma graphs (k < K_MONOTONE; enumerate._SigmaGraphs)
 *
 * Below K_MONOTONE E is not monotone on (0, A_MAX]: (0, A_MAX] splits into the monotone pieces of E (s_piece_*,
 * leafmap.turn_pieces: one, or two around the maximum at r* for 1/Q < k < 1/2). On the rectangle of pieces (i, j)
 * (a on piece i, b on piece j, signs s_i, s_j of E') the level set E(a) - E(b) = eta_m is one curve along which
 * sigma = a + kap b, kap = s_i s_j, strictly increases, with da/dsigma = E'(b) / (E'(b) + kap E'(a)) in [0, 1] and
 * db/dsigma = E'(a) / (E'(b) + kap E'(a)); a(sigma) solves E(a) - E(kap (sigma - a)) = eta_m (bracketed Newton on
 * the closed form, sigma_radii). The cells, their examination and the polish are those of the graph over x with
 * the parameter sigma (docs/design/enumeration.md). */

/* The monotone pieces of E for the last k (leafmap.turn_pieces) and the range [s_e_lo, s_e_hi] of E on [0, A_MAX]. */
static int s_npiece, s_piece_sign[2];
static casadi_real s_piece_lo[2], s_piece_hi[2], s_e_lo, s_e_hi;

static void prepare_pieces(casadi_real k) {
    casadi_real q = RP_R(1.0) + RP_POW(RP_R(1.0) - RP_R(2.0) * A_MAX * A_MAX, -RP_R(1.5)), s, r_star, e;
    int i;
    s_npiece = 1;
    s_piece_lo[0] = RP_R(0.0);
    s_piece_hi[0] = A_MAX;
    if (k >= K_MONOTONE) {
        s_piece_sign[0] = -1;
    } else if (k * q <= RP_R(1.0)) {
        s_piece_sign[0] = 1;
    } else {
        s = RP_POW(RP_R(1.0) / k - RP_R(1.0), -RP_R(1.0) / RP_R(3.0));
        r_star = RP_SQRT(RP_R(0.5) * (RP_R(1.0) - s * s));
        s_npiece = 2;
        s_piece_hi[0] = s_piece_lo[1] = r_star;
        s_piece_hi[1] = A_MAX;
        s_piece_sign[0] = 1;
        s_piece_sign[1] = -1;
    }
    s_e_lo = s_e_hi = RP_R(0.0);   /* E(0) = 0; the extremes lie at the ends of the pieces */
    for (i = 0; i < s_npiece; ++i) {
        e = turn(s_piece_hi[i], k);
        s_e_lo = MIN(s_e_lo, e);
        s_e_hi = MAX(s_e_hi, e);
    }
}

/* Radius on the piece [lo, hi] (sign of E' there) with E = t (t clipped to the piece's range), by bisection on the
 * closed form (enumerate._inverse_on). */
static casadi_real inverse_on(casadi_real t, casadi_real k, casadi_real lo, casadi_real hi, int sign) {
    casadi_real mid;
    int it;
    for (it = 0; it < 60; ++it) {
        mid = RP_R(0.5) * (lo + hi);
        if ((turn(mid, k) - t) * sign < RP_R(0.0)) lo = mid; else hi = mid;
    }
    return RP_R(0.5) * (lo + hi);
}

static casadi_real clip(casadi_real x, casadi_real lo, casadi_real hi) { return x < lo ? lo : (x > hi ? hi : x); }

/* (a, b) on the sigma graph br at sigma = p: bracketed Newton on E(a) - E(kap (p - a)) = eta (_SigmaGraphs.radii). */
static void sigma_radii(casadi_real p, const branch_t *br, casadi_real k, casadi_real *a_out, casadi_real *b_out) {
    casadi_real lo, hi, span, a, b, f, df, ea, eb, nxt;
    int it, done;
    lo = MAX(br->a_lo, br->kap > 0 ? p - br->b_hi : p + br->b_lo);
    hi = MIN(br->a_hi, br->kap > 0 ? p - br->b_lo : p + br->b_hi);
    hi = MAX(hi, lo);
    span = br->p_hi - br->p_lo;
    a = clip(br->a_lo + (span > RP_R(0.0) ? (p - br->p_lo) / span : RP_R(0.5)) * (br->a_hi - br->a_lo), lo, hi);
    for (it = 0; it < 80; ++it) {
        b = clip(br->kap * (p - a), br->b_lo, br->b_hi);
        ea = turn_and_dr(a, k, &df);
        eb = turn_and_dr(b, k, &f);
        df += br->kap * f;
        f = ea - eb - br->eta;
        if (f * br->sa < RP_R(0.0)) lo = a; else hi = a;   /* E(a) - E(b) increases along s_a: the root is to the right */
        nxt = a - f / df;
        if (!isfinite(nxt) || nxt <= lo || nxt >= hi) nxt = RP_R(0.5) * (lo + hi);
        done = RP_FABS(nxt - a) <= RP_R(1e-16) + RP_R(2e-16) * a || hi - lo <= RP_R(4e-16) * (RP_R(1.0) + hi) || f == RP_R(0.0);
        if (f != RP_R(0.0)) a = nxt;
        if (done) break;
    }
    *a_out = a;
    *b_out = clip(br->kap * (p - a), br->b_lo, br->b_hi);
}

/* g = rho(a)^2 + rho(b)^2 + 2 rho(a) rho(b) cos(eta / 2) - h^2 of the branch br at the radii (a, b), and its
 * derivative along the graph whose radii move as (da, db); rho from the table (accurate = 0) or from the accurate
 * map (accurate = 1). With dg NULL the accurate map gives rho alone (a family's d rho / dr costs two more leaf
 * integrations); g is the same. */
static void level_values(casadi_real a, casadi_real b, casadi_real da, casadi_real db, const branch_t *br,
                         casadi_real k, int accurate, casadi_real *g, casadi_real *dg) {
    casadi_real ra, rb, pa = RP_R(0.0), pb = RP_R(0.0), c = br->c_half;
    if (accurate) {
        signed_length(a, k, &ra, dg ? &pa : NULL);
        signed_length(b, k, &rb, dg ? &pb : NULL);
    } else {
        rho_lookup(a, &ra, &pa);
        rho_lookup(b, &rb, &pb);
    }
    *g = ra * ra + rb * rb + RP_R(2.0) * c * ra * rb - br->h * br->h;
    if (dg) *dg = RP_R(2.0) * (ra + c * rb) * pa * da + RP_R(2.0) * (rb + c * ra) * pb * db;
}

/* (g, g', a, b) at sigma = p on the sigma graph br (_SigmaGraphs._values): rho of the table (accurate = 0) or of the
 * accurate map (1); g as in branch_values, g' with da/dsigma and db/dsigma (not computed on the accurate map when dg
 * is NULL). */
static void sigma_values(casadi_real p, const branch_t *br, casadi_real k, int accurate, casadi_real *g,
                         casadi_real *dg, casadi_real *a, casadi_real *b) {
    casadi_real ea, eb, den;
    sigma_radii(p, br, k, a, b);
    ea = turn_dr(*a, k);
    eb = turn_dr(*b, k);
    den = eb + br->kap * ea;
    level_values(*a, *b, den != RP_R(0.0) ? eb / den : RP_R(0.5), den != RP_R(0.0) ? ea / den : RP_R(0.5) * br->kap,
                 br, k, accurate, g, dg);
}

/* The sigma graphs of the branch br (eta, h and c_half set) into gr, one per rectangle of pieces whose curve is
 * not empty (_SigmaGraphs.__init__); br->y0 becomes the smallest lower bound a(p_lo) + min b of a + b on them.
 * Returns their number (0: the level set is empty). */
static int sigma_graphs(branch_t *br, casadi_real k, branch_t gr[4]) {
    casadi_real ti[2], tj[2], t_lo, t_hi, a0, a1, b0, b1, v, s0, s1, low;
    int i, j, n = 0;
    br->y0 = INFINITY;
    for (i = 0; i < s_npiece; ++i) {
        ti[0] = turn(s_piece_lo[i], k);
        ti[1] = turn(s_piece_hi[i], k);
        if (ti[0] > ti[1]) { v = ti[0]; ti[0] = ti[1]; ti[1] = v; }
        for (j = 0; j < s_npiece; ++j) {
            tj[0] = turn(s_piece_lo[j], k);
            tj[1] = turn(s_piece_hi[j], k);
            if (tj[0] > tj[1]) { v = tj[0]; tj[0] = tj[1]; tj[1] = v; }
            t_lo = MAX(ti[0], tj[0] + br->eta);   /* E(a) in E(piece i) and E(a) - eta in E(piece j) */
            t_hi = MIN(ti[1], tj[1] + br->eta);
            if (!(t_hi > t_lo)) continue;
            a0 = inverse_on(t_lo, k, s_piece_lo[i], s_piece_hi[i], s_piece_sign[i]);
            a1 = inverse_on(t_hi, k, s_piece_lo[i], s_piece_hi[i], s_piece_sign[i]);
            b0 = inverse_on(t_lo - br->eta, k, s_piece_lo[j], s_piece_hi[j], s_piece_sign[j]);
            b1 = inverse_on(t_hi - br->eta, k, s_piece_lo[j], s_piece_hi[j], s_piece_sign[j]);
            if (s_piece_sign[i] < 0) {   /* a decreasing in E(a): the end of larger E has the smaller a */
                v = a0; a0 = a1; a1 = v;
                v = b0; b0 = b1; b1 = v;
            }
            s0 = a0 + s_piece_sign[i] * s_piece_sign[j] * b0;
            s1 = a1 + s_piece_sign[i] * s_piece_sign[j] * b1;
            if (!(s1 > s0)) continue;
            gr[n] = *br;
            gr[n].kap = s_piece_sign[i] * s_piece_sign[j];
            gr[n].sa = s_piece_sign[i];
            gr[n].p_lo = s0;
            gr[n].p_hi = s1;
            gr[n].a_lo = a0;
            gr[n].a_hi = a1;
            gr[n].b_lo = s_piece_lo[j];
            gr[n].b_hi = s_piece_hi[j];
            low = a0 + MIN(b0, b1);
            gr[n].y0 = low;
            gr[n].x_end = MIN(MAX(a0, a1), MAX(b0, b1));
            br->y0 = MIN(br->y0, low);
            ++n;
        }
    }
    return n;
}

/* Larger radius y(x) = E^-1(E(x) - e) of the branch at the smaller radius x (the graph over x; no Python
 * counterpart since enumerate.py moved to w and sigma graphs). */
static casadi_real other(casadi_real x, casadi_real e, casadi_real k) {
    casadi_real y;
    if (e == RP_R(0.0)) return x;
    y = turn_inverse(turn(x, k) - e, k);
    return isnan(y) ? A_MAX : y;
}

/* (g, g', a, b) at x on branch br (the graph over x; the w and sigma graphs of enumerate.py compute the same g
 * in their own parameter): with (a, b) = (x, y) if eta >= 0 else (y, x),
 *   g = rho(a)^2 + rho(b)^2 + 2 rho(a) rho(b) cos(eta / 2) - h^2,  dy/dx = E'(x) / E'(y);
 * rho from the table (accurate = 0) or from the accurate map (accurate = 1; dg may be NULL there: g alone). */
static void branch_values(casadi_real x, const branch_t *br, casadi_real k, int accurate, casadi_real *g,
                          casadi_real *dg, casadi_real *a, casadi_real *b) {
    casadi_real y = x, dy = RP_R(1.0), ex, dex, da, db;
    if (br->kap) {
        sigma_values(x, br, k, accurate, g, dg, a, b);
        return;
    }
    if (br->e != RP_R(0.0)) {   /* y = other(x) and dy/dx = E'(x) / E'(y) */
        ex = turn_and_dr(x, k, &dex);
        y = turn_inverse(ex - br->e, k);
        if (isnan(y)) y = A_MAX;
        dy = dex / turn_dr(y, k);
    }
    if (!isfinite(dy)) dy = isnan(dy) ? RP_R(0.0) : (dy > RP_R(0.0) ? REAL_MAX : -REAL_MAX);   /* numpy's nan_to_num */
    if (br->eta >= RP_R(0.0)) {
        *a = x;
        *b = y;
        da = RP_R(1.0);
        db = dy;
    } else {
        *a = y;
        *b = x;
        da = dy;
        db = RP_R(1.0);
    }
    level_values(*a, *b, da, db, br, k, accurate, g, dg);
}

static casadi_real gval(casadi_real x, const branch_t *br, casadi_real k, casadi_real *dg) {
    casadi_real g, d, a, b;
    branch_values(x, br, k, 0, &g, &d, &a, &b);
    if (dg) *dg = d;
    return g;
}

/* 1 if no root of the tabulated g of branch br can lie where the two radii are in [x0, x1] and [y0, y1]:
 * g + h^2 = q(rho_a, rho_b) = rho_a^2 + rho_b^2 + 2 c rho_a rho_b (c = cos(eta / 2), symmetric in a and b) is
 * convex (|c| <= 1), so on the box of the rho ranges (rho_range) its maximum is at a corner, and it is at least
 * dist(0, range of rho_a + c rho_b)^2 + (1 - c^2) dist(0, range of rho_b)^2 (and the same with a and b swapped).
 * Excluded when g < -margin or g > margin everywhere on the box, margin = floor (the table's error carried into
 * g and rounding, as in search_branch) plus a generous multiple of the rounding of g and of the bound (4096 REAL_EPS
 * of their size): the search would find no root there (its roots need a sign change of the computed g, or |g|
 * within the floor at a double root). */
static int excluded(const branch_t *br, casadi_real x0, casadi_real x1, casadi_real y0, casadi_real y1,
                    casadi_real floor_g) {
    casadi_real la, ha, lb, hb, c = br->c_half, h2 = br->h * br->h, qmax, qmin, s0, s1, d, e, t, margin;
    rho_range(x0, x1, &la, &ha);
    rho_range(y0, y1, &lb, &hb);
    qmax = MAX(MAX(la * la + lb * lb + RP_R(2.0) * c * la * lb, la * la + hb * hb + RP_R(2.0) * c * la * hb),
                MAX(ha * ha + lb * lb + RP_R(2.0) * c * ha * lb, ha * ha + hb * hb + RP_R(2.0) * c * ha * hb));
    margin = floor_g + RP_R(4096.0) * REAL_EPS * (RP_R(1.0) + h2 + qmax);
    if (qmax - h2 < -margin) return 1;
    s0 = la + MIN(c * lb, c * hb);                 /* rho_a + c rho_b in [s0, s1] */
    s1 = ha + MAX(c * lb, c * hb);
    d = s0 > RP_R(0.0) ? s0 : (s1 < RP_R(0.0) ? -s1 : RP_R(0.0));
    e = lb > RP_R(0.0) ? lb : (hb < RP_R(0.0) ? -hb : RP_R(0.0));
    qmin = d * d + (RP_R(1.0) - c * c) * e * e;
    s0 = lb + MIN(c * la, c * ha);
    s1 = hb + MAX(c * la, c * ha);
    d = s0 > RP_R(0.0) ? s0 : (s1 < RP_R(0.0) ? -s1 : RP_R(0.0));
    e = la > RP_R(0.0) ? la : (ha < RP_R(0.0) ? -ha : RP_R(0.0));
    t = d * d + (RP_R(1.0) - c * c) * e * e;
    qmin = MAX(qmin, t);
    return qmin - h2 > margin;
}

static int sgn(casadi_real x) { return (x > RP_R(0.0)) - (x < RP_R(0.0)); }

/* Branch m (enumerate.branches): eta_m = (psi_w + 2 pi m) / n, h_m = h_des / |sin(n eta / 2) / sin(eta / 2)|
 * (h_des / n where |sin(eta / 2)| < 1e-12; core.plane.target_shift and n_step_gain). Returns 0 if the
 * branch cannot hold a root (|eta_m| > |E(A_MAX)| or h_m unreachable). */
static int make_branch(long m, casadi_real psi_w, int steps, casadi_real h_des, casadi_real k, branch_t *br) {
    casadi_real eta = (psi_w + TWO_PI * (casadi_real)m) / steps, num, den, gain;
    num = RP_SIN(steps * eta / RP_R(2.0));
    den = RP_SIN(eta / RP_R(2.0));
    gain = RP_FABS(den) < RP_R(1e-12) ? (casadi_real)steps : RP_FABS(num / den);
    if (gain < RP_R(1e-12) || !(RP_FABS(eta) <= s_e_hi - s_e_lo)) return 0;
    br->m = m;
    br->eta = eta;
    br->e = RP_FABS(eta);
    br->h = h_des / gain;
    br->c_half = RP_COS(RP_R(0.5) * eta);
    if (k < K_MONOTONE) return isfinite(br->h);   /* y0 and the graphs: sigma_graphs() */
    br->y0 = turn_inverse(-br->e, k);
    br->x_end = turn_inverse(s_e_min + br->e, k);
    br->kap = br->sa = 0;
    br->p_lo = RP_R(0.0);
    br->p_hi = br->x_end;
    br->a_lo = br->a_hi = br->b_lo = br->b_hi = RP_R(0.0);
    return isfinite(br->h) && isfinite(br->y0) && isfinite(br->x_end);
}

/* Local coordinates in (0, 1) of the critical points of the Hermite cubic of a cell, sorted, NaN if none
 * (enumerate._critical). */
static void critical(casadi_real g0, casadi_real p0, casadi_real g1, casadi_real p1, casadi_real w, casadi_real out[2]) {
    casadi_real A = RP_R(3.0) * (2 * g0 + w * p0 - 2 * g1 + w * p1) / w, B = RP_R(2.0) * (-3 * g0 - 2 * w * p0 + 3 * g1 - w * p1) / w;
    casadi_real C = p0, disc = B * B - 4 * A * C, sq = RP_SQRT(disc > RP_R(0.0) ? disc : RP_R(0.0)), r[2], t;
    int j, quad = RP_FABS(A) > REAL_TINY;
    r[0] = quad ? (-B - sq) / (2 * A) : -C / B;
    r[1] = quad ? (-B + sq) / (2 * A) : NAN;
    for (j = 0; j < 2; ++j) out[j] = (disc >= 0 && isfinite(r[j]) && r[j] > 0 && r[j] < 1) ? r[j] : NAN;
    if (isnan(out[0]) || (!isnan(out[1]) && out[1] < out[0])) {
        t = out[0];
        out[0] = out[1];
        out[1] = t;
    }
}

static casadi_real hermite(casadi_real g0, casadi_real p0, casadi_real g1, casadi_real p1, casadi_real w, casadi_real s) {
    return (2 * s * s * s - 3 * s * s + 1) * g0 + (s * s * s - 2 * s * s + s) * w * p0 + (-2 * s * s * s + 3 * s * s) * g1
           + (s * s * s - s * s) * w * p1;
}

/* A root in [lo, hi] of g (which = 0) or g' (1) with a sign change there: Newton on g (the secant on g')
 * kept inside the shrinking bracket, bisection otherwise (enumerate._bracketed); g of the table (accurate = 0)
 * or of the accurate map (1). */
static casadi_real bracketed(casadi_real lo, casadi_real hi, casadi_real glo, const branch_t *br, casadi_real k, int which,
                             int accurate) {
    int slo = sgn(glo), it;
    casadi_real x = RP_R(0.5) * (lo + hi), prev_x = lo, prev_f = glo, f, dg, nxt, a, b;
    for (it = 0; it < 100; ++it) {
        branch_values(x, br, k, accurate, &f, &dg, &a, &b);
        if (which) f = dg;
        if (sgn(f) == slo) lo = x; else hi = x;
        nxt = which ? x - f * (x - prev_x) / (f - prev_f) : x - f / dg;
        prev_x = x;
        prev_f = f;
        if (!isfinite(nxt) || nxt <= lo || nxt >= hi) nxt = RP_R(0.5) * (lo + hi);
        if (!(f != RP_R(0.0) && RP_FABS(nxt - x) > RP_R(2e-16) * (RP_R(1.0) + RP_FABS(x)) && hi - lo > RP_R(4e-16) * (RP_R(1.0) + RP_FABS(x)))) {
            x = nxt;
            break;
        }
        x = nxt;
    }
    return x;
}

/* Outward from x (dir = +1: to the right, -1: to the left) on the accurate map, where g (gx at x) has the sign
 * opposite to ref, the table's: steps doubling from w until g has ref's sign (a root between the last two points,
 * bracketed) or the end of the branch. Each step checks that g still moves toward ref's sign (dir g' of ref's sign:
 * g monotone that way, so one root at most between two points); if not, it stops (enumerate._outward). Returns the
 * roots written to xs (0 or 1). */
static int outward(casadi_real x, casadi_real gx, casadi_real w, int dir, int ref, const branch_t *br, casadi_real k,
                   casadi_real *xs) {
    casadi_real lim = dir > 0 ? br->p_hi : br->p_lo, nxt, gn, dg, a, b;
    int it;
    for (it = 0; it < 64; ++it) {
        nxt = x + dir * w;
        if (dir > 0 ? !(nxt < lim) : !(nxt > lim)) nxt = lim;
        if (!(nxt != x)) return 0;
        branch_values(nxt, br, k, 1, &gn, &dg, &a, &b);
        if (sgn(gn) == ref || gn == RP_R(0.0)) {
            xs[0] = dir > 0 ? bracketed(x, nxt, gx, br, k, 0, 1) : bracketed(nxt, x, gn, br, k, 0, 1);
            return 1;
        }
        if (sgn(dg) * dir != ref) return 0;
        x = nxt;
        gx = gn;
        w *= RP_R(2.0);
    }
    return 0;
}

/* A tangency of the tabulated g at xc (|g| within the floor there, of sign ref on [sl, sh]), decided on the accurate
 * map (enumerate._tangencies): a sign change of the accurate g between sl and xc or between xc and sh is a root there
 * (a close pair the table's error hid), bracketed on the accurate map; where the accurate g at sl (sh) has the sign
 * opposite to the table's, the root is beyond it, found outward(). With none, xc is a double root (polished, and no
 * root if the accurate map misses there by more than NOT_A_ROOT: candidate()). Returns the roots written to xs. */
static int tangency(casadi_real sl, casadi_real xc, casadi_real sh, int ref, const branch_t *br, casadi_real k,
                    casadi_real *xs) {
    casadi_real gl, gc, gh, a, b, w = sh - sl;
    int n = 0;
    branch_values(sl, br, k, 1, &gl, NULL, &a, &b);
    branch_values(xc, br, k, 1, &gc, NULL, &a, &b);
    branch_values(sh, br, k, 1, &gh, NULL, &a, &b);
    if (sgn(gl) == -ref) n += outward(sl, gl, w, -1, ref, br, k, xs + n);
    if (gl * gc < 0) xs[n++] = bracketed(sl, xc, gl, br, k, 0, 1);
    if (gc * gh < 0) xs[n++] = bracketed(xc, sh, gc, br, k, 0, 1);
    if (sgn(gh) == -ref) n += outward(sh, gh, w, 1, ref, br, k, xs + n);
    if (!n) xs[n++] = xc;
    return n;
}

/* Roots in one resolved cell [x0, x1] (enumerate._examine): sign changes of g between the ends and the
 * critical points of the Hermite cubic H (simple roots; between points where |g| is within the floor floor_g, the
 * signs of the accurate map), and where g keeps its sign around a point where g' changes sign, the critical point
 * of g: two roots if g changes sign there, a tangency if |g| is within the floor (decided on the accurate map:
 * tangency()). Returns the number of roots written to xs (unsorted). */
static int examine(casadi_real x0, casadi_real x1, casadi_real g0, casadi_real p0, casadi_real g1, casadi_real p1,
                   const casadi_real crit[2], const branch_t *br, casadi_real k, casadi_real floor_g, casadi_real *xs) {
    casadi_real w = x1 - x0, pts[4], vals[4], dv[4], lo, mid, hi, sl, sh, dl, dh, xc, gc, gl, ga, gb, a, b;
    int n = 0, j, half;
    pts[0] = x0;
    pts[3] = x1;
    vals[0] = g0;
    vals[3] = g1;
    dv[0] = p0;
    dv[3] = p1;
    for (j = 0; j < 2; ++j) {
        pts[j + 1] = isnan(crit[j]) ? x1 : x0 + w * crit[j];
        vals[j + 1] = gval(pts[j + 1], br, k, &dv[j + 1]);
    }
    for (j = 0; j < 3; ++j) {
        if (pts[j + 1] > pts[j] && vals[j] * vals[j + 1] < 0) {
            xs[n++] = bracketed(pts[j], pts[j + 1], vals[j], br, k, 0, 0);
        } else if (pts[j + 1] > pts[j] && (RP_FABS(vals[j]) <= floor_g || RP_FABS(vals[j + 1]) <= floor_g)) {
            /* an end whose sign the table cannot tell (|g| within its floor): the accurate map's signs decide
             * (H is monotone between the points, so one root at most) */
            ga = vals[j];
            gb = vals[j + 1];
            if (RP_FABS(ga) <= floor_g) branch_values(pts[j], br, k, 1, &ga, NULL, &a, &b);
            if (RP_FABS(gb) <= floor_g) branch_values(pts[j + 1], br, k, 1, &gb, NULL, &a, &b);
            if (ga * gb < 0) xs[n++] = bracketed(pts[j], pts[j + 1], ga, br, k, 0, 1);
        }
        if (vals[j + 1] == RP_R(0.0) && pts[j + 1] > br->p_lo) xs[n++] = pts[j + 1];
    }
    for (j = 1; j <= 2; ++j) {
        lo = pts[j - 1];
        mid = pts[j];
        hi = pts[j + 1];
        if (!(vals[j] * vals[j - 1] > 0 && vals[j] * vals[j + 1] > 0 && hi > lo)) continue;
        for (half = 0; half < 2; ++half) {
            sl = half ? mid : lo;
            sh = half ? hi : mid;
            dl = dv[j - 1 + half];
            dh = dv[j + half];
            if (!(sh > sl && dl * dh < 0)) continue;
            xc = bracketed(sl, sh, dl, br, k, 1, 0);
            gc = gval(xc, br, k, NULL);
            if (gc * vals[j] < 0) {
                gl = gval(sl, br, k, NULL);
                xs[n++] = bracketed(sl, xc, gl, br, k, 0, 0);
                xs[n++] = bracketed(xc, sh, gc, br, k, 0, 0);
            } else if (RP_FABS(gc) <= floor_g) {
                n += tangency(sl, xc, sh, sgn(vals[j]), br, k, xs + n);
            }
        }
    }
    return n;
}

/* Newton step for g at x (g and dg = g' there) taken on f = sqrt(q) - h instead, q = g + h^2 = |S|^2 (the step's
 * shift |S| = |rho_a + exp(i eta / 2) rho_b|): f = g / (sqrt(q) + h), f' = g' / (2 sqrt(q)). g = f (|S| + h) is as
 * smooth as f but its curvature relative to g' grows like 1 / h (g'' ~ 2 |S|'^2 where g' ~ 2 h |S|'), so for a small
 * shift Newton on g leaves a root error ~ step^2 / h while on f it is ~ step^2 |S|'' / |S|' (enumerate.newton_step).
 * Returns the step (x - step is the next point) and |f| in *miss. */
static casadi_real newton_step(casadi_real g, casadi_real dg, casadi_real h, casadi_real *miss) {
    casadi_real q = g + h * h, sq = q > RP_R(0.0) ? RP_SQRT(q) : RP_R(0.0), f = sq + h > RP_R(0.0) ? g / (sq + h) : RP_R(0.0);
    *miss = RP_FABS(f);
    return sq > RP_R(0.0) ? RP_R(2.0) * sq * f / dg : g / dg;
}

/* Newton (newton_step) on the accurate map from a root of the table (a step that would leave [0, x_end] is
 * clipped; one that does not decrease |f| is not taken, but if g changed sign over it and it is at most
 * POLISH_BRACKET, the root is bracketed there on the accurate map; at most 6 evaluations after the first); with
 * quick = 1, once a step is at most POLISH_STEP (the quadratic regime) it is taken without a new evaluation
 * (enumerate._polish);
 * with quick = 0 the steps go on until one is at the rounding level of x: the fallback of a root whose quick polish
 * failed the certificate. */
static casadi_real polish(casadi_real x, const branch_t *br, casadi_real k, int quick) {
    casadi_real gx, g, dg, f, f2, a, b, nxt, after;
    int it;
    branch_values(x, br, k, 1, &gx, &dg, &a, &b);
    nxt = x - newton_step(gx, dg, br->h, &f);
    for (it = 0; it < (quick ? 6 : 12); ++it) {
        nxt = nxt < br->p_lo ? br->p_lo : (nxt > br->p_hi ? br->p_hi : nxt);
        if (!isfinite(nxt)) break;
        if (quick ? RP_FABS(nxt - x) <= POLISH_STEP : RP_FABS(nxt - x) <= RP_R(4.0) * REAL_EPS * x) return nxt;
        if (!(nxt != x)) break;
        branch_values(nxt, br, k, 1, &g, &dg, &a, &b);
        after = nxt - newton_step(g, dg, br->h, &f2);
        if (!(f2 < f)) {   /* no better: a step across the root brackets it (on the accurate map) */
            if (gx * g < RP_R(0.0) && RP_FABS(nxt - x) <= POLISH_BRACKET)
                return nxt > x ? bracketed(x, nxt, gx, br, k, 0, 1) : bracketed(nxt, x, g, br, k, 0, 1);
            break;
        }
        x = nxt;
        gx = g;
        f = f2;
        nxt = after;
    }
    return x;
}

/* gamma = arg(target) - arg(sum_{j<n} exp(-i j eta) S) with S = d(a) + exp(-i E(a)) conj(d(b)), eta = E(a) - E(b)
 * (planner._certified, leafmap.step_values); also eta, h = |S| and the miss predicted by the leaf map. */
static casadi_real rotation(casadi_real u, casadi_real v, casadi_real psi, int steps, casadi_real a, casadi_real b,
                            casadi_real k, casadi_real *eta, casadi_real *h, casadi_real *predicted) {
    casadi_real da[2], db[2], ea = turn(a, k), eb = turn(b, k), sr, si, cr = RP_R(0.0), ci = RP_R(0.0), tr, ti, gamma, c, s, fu, fv, dr;
    int i;
    displacement(a, k, da, NULL);
    displacement(b, k, db, NULL);
    c = RP_COS(ea);
    s = RP_SIN(ea);
    sr = da[0] + c * db[0] - s * db[1];            /* d(a) + exp(-i E(a)) conj(d(b)) */
    si = da[1] - s * db[0] - c * db[1];
    *eta = ea - eb;
    *h = RP_HYPOT(sr, si);
    for (i = 0; i < steps; ++i) {
        cr += RP_COS(i * *eta);
        ci -= RP_SIN(i * *eta);
    }
    tr = cr * sr - ci * si;
    ti = cr * si + ci * sr;
    gamma = wrap(RP_ATAN2(v, u) - RP_ATAN2(ti, tr));
    c = RP_COS(gamma);
    s = RP_SIN(gamma);
    fu = c * tr - s * ti;
    fv = s * tr + c * ti;
    dr = wrap(steps * *eta - psi);
    *predicted = RP_SQRT((fu - u) * (fu - u) + (fv - v) * (fv - v) + dr * dr);
    return gamma;
}

/* ------------------------------------------------------------------ search (planner._solve_enumerated) */

#define SEEN 16                        /* recent roots of a branch compared for duplicates (plan_all) */

typedef struct {
    casadi_real u, v, psi_w, k, best;   /* target (psi wrapped), inertia ratio, shortest certified a + b so far */
    int steps, certify, defer, rejected, incomplete;
    long turns, roots;
    casadi_real rej[5];                 /* a, b, gamma, residual, bound of the best rejected root */
    RP_NAME(plan_t) *plan;              /* filled in by an accepted root only */
    /* plan_all: every accepted root goes into list (capacity entries, sorted by a + b, the shortest kept);
     * count counts them all; the last SEEN polished roots (a, b) of branch last_m (nseen of them, a ring), for
     * duplicates */
    int all, capacity, count;
    RP_NAME(plan_t) *list;
    long last_m;
    int nseen;
    casadi_real seen[SEEN][2];
} search_t;

/* The certificate as the search applies it (<prefix>_certify). A test build may define
 * <PREFIX>_TEST_REJECT_BELOW = L: then every plan with a + b < L is rejected (after its certificate ran), which
 * makes the shortest root fail and exercises the search's fallback (tests/test_codegen.py); no other build defines it. */
static casadi_real s_cert_final[3];   /* the finest run of the last certificate of the search */
static casadi_real s_plan_final[3];   /* that of the plan plan_with returned (for plan_many) */
static int search_certify(casadi_real a, casadi_real b, casadi_real gamma, int steps, casadi_real k, casadi_real u,
                          casadi_real v, casadi_real psi, casadi_real *residual, casadi_real *bound) {
    int status = RP_NAME(certify)(a, b, gamma, steps, k, u, v, psi, s_cert_final, residual, bound);
#ifdef RP_TEST_REJECT_BELOW
    if (a + b < RP_TEST_REJECT_BELOW) status = RP_NOT_CERTIFIED;
#endif
    return status;
}

/* plan_all: the plan (a, b, gamma, ...) of branch br into S->list, sorted by a + b (after the plans of equal length
 * found before it); when the list is full, the longest plan drops out. Counts it in S->count. */
static void keep(search_t *S, const branch_t *br, casadi_real a, casadi_real b, casadi_real gamma, casadi_real eta,
                 casadi_real h, casadi_real predicted, casadi_real residual, casadi_real bound) {
    RP_NAME(plan_t) *p;
    int pos = S->count < S->capacity ? S->count : S->capacity, j;
    S->count++;
    while (pos > 0 && S->list[pos - 1].a + S->list[pos - 1].b > a + b) --pos;
    if (pos >= S->capacity) return;
    for (j = (S->count <= S->capacity ? S->count : S->capacity) - 1; j > pos; --j) S->list[j] = S->list[j - 1];
    p = &S->list[pos];
    p->a = a;
    p->b = b;
    p->gamma = gamma;
    p->eta = eta;
    p->h = h;
    p->m = br->m - S->turns;
    p->residual = residual;
    p->bound = bound;
    p->predicted = predicted;
    p->branches = 0;
    p->roots = 0;
}

/* 1 if (a, b) is within 1e-12 of one of the last SEEN roots of branch br (polished, counted), else 0 and (a, b)
 * joins them. */
static int seen(search_t *S, const branch_t *br, casadi_real a, casadi_real b) {
    int i;
    if (br->m != S->last_m) S->nseen = 0;
    S->last_m = br->m;
    for (i = 0; i < S->nseen && i < SEEN; ++i)
        if (RP_FABS(a - S->seen[i][0]) <= RP_R(1e-12) && RP_FABS(b - S->seen[i][1]) <= RP_R(1e-12)) return 1;
    S->seen[S->nseen % SEEN][0] = a;
    S->seen[S->nseen % SEEN][1] = b;
    S->nseen++;
    return 0;
}

/* A root x of branch br (from the table): polish, and accept it as the best plan if a + b < best and
 * (with the certificate) it certifies. Returns 1 if accepted, -1 if a + b >= best (on the graph over x the branch is
 * done), 0 if
 * rejected by the certificate or if the leaf map misses the target there by more than NOT_A_ROOT (then it is no root
 * of the accurate map, only a tangency of the table within its error, and is not counted). */
static int candidate(search_t *S, const branch_t *br, casadi_real x) {
    casadi_real g, dg, a, b, gamma, eta, h, predicted, residual = NAN, bound = NAN;
    int status = RP_OK;
    x = polish(x, br, S->k, S->defer || !S->certify);
    branch_values(x, br, S->k, 0, &g, &dg, &a, &b);   /* a and b (which do not depend on the table) */
    if (!(a + b < S->best)) return -1;
    if (!(a > RP_R(0.0) && b > RP_R(0.0))) return 0;
    if (S->all) {   /* the same root twice (a close pair merged by the polish, a corner shared by two sigma graphs):
                     * once (enumerate.roots) */
        if (seen(S, br, a, b)) return 0;
    }
    gamma = rotation(S->u, S->v, S->psi_w, S->steps, a, b, S->k, &eta, &h, &predicted);
    if (!(predicted <= NOT_A_ROOT)) return 0;   /* no root of the accurate map: a tangency of the table only */
    S->roots++;
    if (S->certify && !S->defer)
        status = search_certify(a, b, gamma, S->steps, S->k, S->u, S->v, S->psi_w, &residual, &bound);
    if (status != RP_OK) {
        if (!S->rejected || residual < S->rej[3]) {   /* the best rejected root, reported if no plan is found */
            S->rej[0] = a;
            S->rej[1] = b;
            S->rej[2] = gamma;
            S->rej[3] = residual;
            S->rej[4] = bound;
        }
        S->rejected++;
        return 0;
    }
    if (S->all) {
        keep(S, br, a, b, gamma, eta, h, predicted, residual, bound);
        return 0;
    }
    S->best = a + b;
    s_plan_final[0] = s_cert_final[0];
    s_plan_final[1] = s_cert_final[1];
    s_plan_final[2] = s_cert_final[2];
    S->plan->a = a;
    S->plan->b = b;
    S->plan->gamma = gamma;
    S->plan->eta = eta;
    S->plan->h = h;
    S->plan->m = br->m - S->turns;
    S->plan->predicted = predicted;
    S->plan->residual = residual;
    S->plan->bound = bound;
    return 1;
}

typedef struct {
    casadi_real x0, x1, g0, p0, g1, p1;
} cell_t;

/* Phase point i (0 < i < nt) of a branch's grid: the x with E(x) = t1 i / (nt - 1), x_end at i = nt - 1. */
static casadi_real phase_point(int i, int nt, casadi_real t1, casadi_real x_end, casadi_real k) {
    casadi_real x = i == nt - 1 ? x_end : turn_inverse(t1 * i / (nt - 1), k);
    return isnan(x) ? x_end : x;
}

/* The cells of branch br from stack[0] on, in increasing parameter (docs/design/enumeration.md): each split at its
 * midpoint while the Hermite interpolant of (g, g') at its ends misses g there by more than HERMITE_REL of the
 * cell's largest |g| and more than rounding (down to MIN_WIDTH); a resolved cell is examined unless
 * min |H| > SAFETY |g(mid) - H(mid)| + floor_g, and its roots go to candidate() in increasing parameter (a root
 * within 1e-13 of the last one, *last_root, once). Returns 1 when the branch is done: on the graph over x a root
 * accepted or a + b reaching S->best; on any graph more than MAX_CELLS_PER_BRANCH cells (*cells counts them;
 * S->incomplete). */
static int sweep(search_t *S, const branch_t *br, cell_t *stack, casadi_real floor_g, long *cells,
                 casadi_real *last_root) {
    const casadi_real k = S->k;
    int top = 1, nroot, i, j, crosses, status;
    casadi_real crit[2], hc, low, gm, pm, err, big, xm, hv, xs[MAX_CELL_ROOTS];
    cell_t c;
    while (top) {
        c = stack[--top];
        if (++*cells > MAX_CELLS_PER_BRANCH) {
            S->incomplete = 1;
            return 1;
        }
        xm = RP_R(0.5) * (c.x0 + c.x1);
        gm = gval(xm, br, k, &pm);
        hv = hermite(c.g0, c.p0, c.g1, c.p1, c.x1 - c.x0, RP_R(0.5));
        err = RP_FABS(gm - hv);
        big = RP_FMAX(RP_FMAX(RP_FABS(c.g0), RP_FABS(c.g1)), RP_FABS(gm));
        if (err > HERMITE_REL * big && err > RP_R(1e-15) * (RP_R(1.0) + br->h * br->h) && c.x1 - c.x0 > MIN_WIDTH
            && top + 2 <= STACK_CELLS) {
            /* split: the right half below the left one, so the cells come in increasing x */
            stack[top].x0 = xm;
            stack[top].x1 = c.x1;
            stack[top].g0 = gm;
            stack[top].p0 = pm;
            stack[top].g1 = c.g1;
            stack[top].p1 = c.p1;
            ++top;
            stack[top].x0 = c.x0;
            stack[top].x1 = xm;
            stack[top].g0 = c.g0;
            stack[top].p0 = c.p0;
            stack[top].g1 = gm;
            stack[top].p1 = pm;
            ++top;
            continue;
        }
        if (err > HERMITE_REL * big && err > RP_R(1e-15) * (RP_R(1.0) + br->h * br->h) && c.x1 - c.x0 > MIN_WIDTH)
            S->incomplete = 1;   /* cannot happen: the stack holds the deepest split */
        critical(c.g0, c.p0, c.g1, c.p1, c.x1 - c.x0, crit);
        crosses = 0;
        low = RP_FMIN(RP_FABS(c.g0), RP_FABS(c.g1));
        for (j = 0; j < 2; ++j) {
            if (isnan(crit[j])) continue;
            hc = hermite(c.g0, c.p0, c.g1, c.p1, c.x1 - c.x0, crit[j]);
            if (hc * c.g0 <= 0) crosses = 1;
            low = RP_FMIN(low, RP_FABS(hc));
        }
        if (!(sgn(c.g0) != sgn(c.g1) || sgn(c.g0) != sgn(gm) || crosses || low <= SAFETY * err + floor_g))
            continue;
        nroot = examine(c.x0, c.x1, c.g0, c.p0, c.g1, c.p1, crit, br, k, floor_g, xs);
        for (i = 1; i < nroot; ++i) {           /* sort (few) */
            for (j = i; j > 0 && xs[j - 1] > xs[j]; --j) {
                hv = xs[j];
                xs[j] = xs[j - 1];
                xs[j - 1] = hv;
            }
        }
        for (i = 0; i < nroot; ++i) {
            if (!(xs[i] > br->p_lo) || RP_FABS(xs[i] - *last_root) <= RP_R(1e-13)) continue;
            *last_root = xs[i];
            status = candidate(S, br, xs[i]);
            if (status && !br->kap) return 1;   /* the graph over x: a + b grows with x, the branch is done */
        }
    }
    return 0;
}

/* The roots of branch br in increasing x until one is accepted or a + b reaches S->best (enumerate.roots
 * with first_only, then the next roots of the branch if the first is rejected). The branch is sampled on a
 * grid uniform in the phase E(x) (PHASE_STEP) and in x (X_STEP); each cell is split at its midpoint while
 * the Hermite interpolant of (g, g') at its ends misses g there by more than HERMITE_REL of the cell's
 * largest |g| and more than rounding (down to MIN_WIDTH); a resolved cell is examined unless
 * min |H| > SAFETY |g(mid) - H(mid)| + floor (docs/design/enumeration.md: the completeness argument, which
 * holds on this graph with the parameter x).
 * Before that, intervals of x where the tabulated g provably has no root (excluded(): a bound of g from the
 * bounds of the table's rho over the radii of the interval) are skipped: first the whole branch below the best
 * plan, then intervals from the last point reached, their width doubled after a success and halved after a
 * failure down to the next cell of the grid, which is then tested alone and sampled if that fails too. After a
 * skip to x the grid resumes at its first point beyond x (so a cell may start at a skip's end: it is smaller than
 * a cell of the grid, which the argument allows). Skipping removes no root of the tabulated g (nor a point where
 * |g| is within the floor), so the roots found, and the plan, are those of the search without it (up to the
 * rounding of roots located from other cell ends). */
static void search_branch(search_t *S, const branch_t *br) {
    const casadi_real k = S->k, floor_g = RP_R(1e-13) * (RP_R(1.0) + br->h * br->h) + s_eps_g;
    casadi_real t1 = turn(br->x_end, k), xp, xl, prev, g = RP_R(0.0), p = RP_R(0.0), last_root = -RP_R(1.0), hv, t, y_prev, y_t, x_lim,
        xj, wide;
    static cell_t stack[STACK_CELLS];   /* static: the planner is not reentrant anyway, and the stack stays small */
    int nt, nx, ip = 1, ix = 1, have_g = 0;
    long cells = 0;
    nt = (int)RP_CEIL(RP_FABS(t1) / PHASE_STEP) + 1;
    nx = (int)RP_CEIL(br->x_end / X_STEP) + 1;
    if (nt < 2) nt = 2;
    if (nx < 2) nx = 2;
    if (!(br->x_end > RP_R(0.0))) return;
    prev = RP_R(0.0);
    y_prev = other(prev, br->e, k);
    /* a root with a + b < best has x <= y (E decreasing, e >= 0), so x < best / 2 and x < best - y0; y grows with x:
     * if the table's g has no root on the box [0, x_lim] x [y0, y(x_lim)], the branch has none below the best plan.
     * A skip never goes beyond x_lim, where x + y(x) >= best ends the branch. */
    x_lim = br->x_end;
    if (S->best < INFINITY) x_lim = RP_FMIN(x_lim, RP_FMIN(RP_R(0.5) * S->best, S->best - br->y0));
    if (!(x_lim > RP_R(0.0)) || excluded(br, RP_R(0.0), x_lim, y_prev, other(x_lim, br->e, k), floor_g)) return;
    wide = RP_R(0.0);                         /* width of the next skip tried (0: one cell of the grid) */
    xp = -RP_R(1.0);                          /* the next phase point, computed when ip moves on */
    while (prev < br->x_end) {
        /* nothing on or after this cell can be shorter than the best plan: a + b = x + y(x) grows with x */
        if (prev + y_prev >= S->best) return;
        /* next grid point: the smaller of the next phase point and the next uniform point */
        if (xp < RP_R(0.0)) xp = ip < nt ? phase_point(ip, nt, t1, br->x_end, k) : INFINITY;
        xl = ix < nx ? (ix == nx - 1 ? br->x_end : br->x_end * ix / (nx - 1)) : INFINITY;
        t = xp <= xl ? xp : xl;
        if (!(t > prev)) {              /* a grid point at or before prev (after a skip): the next one */
            if (xp <= xl) {
                ++ip;
                xp = -RP_R(1.0);
            } else {
                ++ix;
            }
            continue;
        }
        if (t > br->x_end) t = br->x_end;
        if (wide > t - prev) {          /* try to skip [prev, prev + wide] */
            xj = prev + wide < x_lim ? prev + wide : x_lim;
            y_t = other(xj, br->e, k);
            if (xj > prev && excluded(br, prev, xj, y_prev, y_t, floor_g)) {
                prev = xj;
                y_prev = y_t;
                have_g = 0;
                wide *= RP_R(2.0);
                /* the grid's first points beyond xj: phase index i > E(xj) (nt - 1) / t1, uniform index
                 * j > xj (nx - 1) / x_end (a point equal to xj up to rounding is passed over above) */
                hv = RP_FLOOR(turn(xj, k) / t1 * (nt - 1)) + RP_R(1.0);
                if (hv > (casadi_real)ip) {
                    ip = hv < (casadi_real)nt ? (int)hv : nt;
                    xp = -RP_R(1.0);
                }
                hv = RP_FLOOR(xj / br->x_end * (nx - 1)) + RP_R(1.0);
                if (hv > (casadi_real)ix) ix = hv < (casadi_real)nx ? (int)hv : nx;
            } else {
                wide *= RP_R(0.5);
            }
            continue;
        }
        if (xp <= xl) {
            ++ip;
            xp = -RP_R(1.0);
        } else {
            ++ix;
        }
        y_t = other(t, br->e, k);
        if (excluded(br, prev, t, y_prev, y_t, floor_g)) {
            wide = RP_R(2.0) * (t - prev);
            prev = t;
            y_prev = y_t;
            have_g = 0;
            continue;
        }
        wide = RP_R(0.0);
        if (!have_g) g = gval(prev, br, k, &p);
        have_g = 1;
        stack[0].x0 = prev;
        stack[0].x1 = t;
        stack[0].g0 = g;
        stack[0].p0 = p;
        stack[0].g1 = g = gval(t, br, k, &p);
        stack[0].p1 = p;
        prev = t;
        y_prev = y_t;
        if (sweep(S, br, stack, floor_g, &cells, &last_root)) return;
    }
    return;
}

/* The roots of the sigma graphs gr[0 .. n - 1] of one branch (k < K_MONOTONE) with a + b < S->best: a + b is not
 * monotone along a sigma graph, so every root is found and each goes to candidate() (enumerate.roots keeps the
 * shortest of each branch). Each graph is sampled uniformly in sigma with steps of at most SIGMA_STEP
 * (_SigmaGraphs.grid) and its cells go through sweep(); a cell where a + b >= S->best throughout (a increases along
 * the graph and b is monotone, so a + b >= a(p0) + min(b(p0), b(p1)) on [p0, p1]) holds no shorter root and is
 * skipped. */
static void search_sigma(search_t *S, const branch_t *gr, int n) {
    static cell_t stack[STACK_CELLS];   /* static: the planner is not reentrant anyway, and the stack stays small */
    const casadi_real k = S->k;
    casadi_real floor_g, x0, g0, p0, a0, b0, x1, g1, p1, a1, b1, last_root;
    long cells = 0;
    int q, i, cnt;
    for (q = 0; q < n; ++q) {
        floor_g = RP_R(1e-13) * (RP_R(1.0) + gr[q].h * gr[q].h) + s_eps_g;
        cnt = (int)RP_CEIL((gr[q].p_hi - gr[q].p_lo) / SIGMA_STEP) + 1;
        last_root = -INFINITY;
        x0 = gr[q].p_lo;
        branch_values(x0, gr + q, k, 0, &g0, &p0, &a0, &b0);
        for (i = 1; i < cnt; ++i) {
            x1 = gr[q].p_lo + (casadi_real)i / (cnt - 1) * (gr[q].p_hi - gr[q].p_lo);
            branch_values(x1, gr + q, k, 0, &g1, &p1, &a1, &b1);
            if (x1 > x0 && a0 + MIN(b0, b1) < S->best) {
                stack[0].x0 = x0;
                stack[0].x1 = x1;
                stack[0].g0 = g0;
                stack[0].p0 = p0;
                stack[0].g1 = g1;
                stack[0].p1 = p1;
                if (sweep(S, gr + q, stack, floor_g, &cells, &last_root)) return;
            }
            x0 = x1;
            g0 = g1;
            p0 = p1;
            a0 = a1;
            b0 = b1;
        }
    }
}

/* psi = psi_w + 2 pi turns with psi_w in [-pi, pi] (core.plane.wrap_exact, exact for |psi| <= PSI_MAX). */
static casadi_real wrap_turns(casadi_real psi, long *turns) {
    casadi_real m = RP_FLOOR(psi / TWO_PI + RP_R(0.5)), w = ((psi - m * TWO_PI_1) - m * TWO_PI_2) - m * TWO_PI_3;
    if (w > PI) {
        w = ((psi - (m + 1) * TWO_PI_1) - (m + 1) * TWO_PI_2) - (m + 1) * TWO_PI_3;
        m += 1;
    } else if (w < -PI) {
        w = ((psi - (m - 1) * TWO_PI_1) - (m - 1) * TWO_PI_2) - (m - 1) * TWO_PI_3;
        m -= 1;
    }
    *turns = (long)m;
    return w;
}

/* The search of plan_with over the branches (all, in the order of their smallest a + b, or options->branch only). */
/* Branch m searched: the graph over x (search_branch) or its sigma graphs (search_sigma). Returns 0 if the branch
 * holds no root (nothing searched), 1 if searched, -1 if it cannot hold a plan shorter than S->best (on the graph
 * over x then no branch after it in the order of search() can either: y0 = E^-1(-|eta_m|) grows with |eta_m|;
 * the bound y0 of sigma_graphs need not grow, and a sigma branch is passed over). */
static int search_m(search_t *S, long m, casadi_real h_des) {
    branch_t br, gr[4];
    int n = 1;
    if (!make_branch(m, S->psi_w, S->steps, h_des, S->k, &br)) return 0;
    if (S->k < K_MONOTONE && !(n = sigma_graphs(&br, S->k, gr))) return 0;
    if (!(br.y0 < S->best)) return S->k < K_MONOTONE ? 0 : -1;
    S->plan->branches++;
    if (S->k < K_MONOTONE) search_sigma(S, gr, n); else search_branch(S, &br);
    return 1;
}

static void search(search_t *S, const RP_NAME(options_t) *options, casadi_real h_des) {
    casadi_real lam = s_e_hi - s_e_lo, dm;
    long lo, hi, mp, mn, m;
    int steps = S->steps;
    S->best = INFINITY;
    S->rejected = S->incomplete = 0;
    S->roots = 0;
    S->plan->branches = 0;
    /* branches with |eta_m| <= lam (the range of E), in increasing |psi_w + 2 pi m| (the order of their smallest
     * a + b, y0; ties: smaller m first) */
    dm = RP_FLOOR((steps * lam - S->psi_w) / TWO_PI);
    hi = (long)dm;
    lo = (long)RP_CEIL((-steps * lam - S->psi_w) / TWO_PI);
    if (options && options->use_branch) {
        m = options->branch + S->turns;
        if (m >= lo && m <= hi) search_m(S, m, h_des);
    } else {
        /* two runs from the centre c = -psi_w / (2 pi) in [-1/2, 1/2]: mn = floor(c) down, mp = mn + 1 up */
        mn = (long)RP_FLOOR(-S->psi_w / TWO_PI);
        for (mp = mn + 1; mn >= lo || mp <= hi;) {
            int use_neg = mp > hi || (mn >= lo && RP_FABS(S->psi_w + TWO_PI * mn) <= RP_FABS(S->psi_w + TWO_PI * mp));
            m = use_neg ? mn-- : mp++;
            if (m >= lo && m <= hi && search_m(S, m, h_des) < 0) break;   /* nothing left can be shorter */
        }
    }
    S->plan->roots = S->roots;
}

/* The checks of a target shared by plan_with and plan_all: OK with the shift h_des = |(u, v)| and the rho
 * table of k prepared, BAD_INPUT or NO_CONVERGENCE otherwise. */
static int start_search(casadi_real u, casadi_real v, casadi_real psi, int steps, casadi_real k, casadi_real *h_des) {
    if (!(isfinite(u) && isfinite(v) && isfinite(psi)) || !(RP_FABS(psi) <= PSI_MAX) || !(k >= K_MIN && k <= K_MAX)
        || steps < 1 || steps > MAX_STEPS || (FAMILY != FAMILY_CIRCLES && !(k >= K_MONOTONE)))
        return RP_BAD_INPUT;
    *h_des = RP_HYPOT(u, v);
    if (!(*h_des > RP_R(0.0))) return RP_BAD_INPUT;
    if (prepare(k)) return RP_NO_CONVERGENCE;
    return RP_OK;
}

int RP_NAME(plan_with)(casadi_real u, casadi_real v, casadi_real psi, int steps, casadi_real k,
                       const RP_NAME(options_t) *options, RP_NAME(plan_t) *plan) {
    search_t S;
    casadi_real h_des, residual, bound;
    int status;
    if (plan == NULL) return RP_BAD_INPUT;
    plan->a = plan->b = plan->gamma = plan->eta = plan->h = NAN;
    plan->residual = plan->bound = plan->predicted = INFINITY;
    plan->m = 0;
    plan->branches = 0;
    plan->roots = 0;
    status = start_search(u, v, psi, steps, k, &h_des);
    if (status != RP_OK) return status;
    s_memo_used = 0;   /* the memo serves one plan (timings of repeated plans stay honest) */
    S.u = u;
    S.v = v;
    S.k = k;
    S.steps = steps;
    S.certify = !options || options->certify;
    S.plan = plan;
    S.all = 0;
    S.psi_w = wrap_turns(psi, &S.turns);
    /* First the shortest root of all (no certificate during the search), then its certificate: if it holds, that
     * root is the shortest certified plan (every certified plan is a root). If it fails, search again certifying
     * every root on the way (the pruning then uses certified plans only). */
    S.defer = S.certify;
    search(&S, options, h_des);
    if (S.defer && S.best < INFINITY) {
        if (search_certify(plan->a, plan->b, plan->gamma, steps, k, u, v, S.psi_w, &residual, &bound)
            == RP_OK) {
            s_plan_final[0] = s_cert_final[0];
            s_plan_final[1] = s_cert_final[1];
            s_plan_final[2] = s_cert_final[2];
            plan->residual = residual;
            plan->bound = bound;
            return RP_OK;
        }
        S.defer = 0;
        plan->a = plan->b = plan->gamma = plan->eta = plan->h = NAN;
        plan->residual = plan->bound = plan->predicted = INFINITY;
        search(&S, options, h_des);
    }
    if (S.best < INFINITY) return RP_OK;
    if (S.rejected) {
        plan->a = S.rej[0];
        plan->b = S.rej[1];
        plan->gamma = S.rej[2];
        plan->residual = S.rej[3];
        plan->bound = S.rej[4];
    }
    if (S.incomplete) return RP_NO_CONVERGENCE;
    return S.rejected ? RP_NOT_CERTIFIED : RP_NO_PLAN;
}

int RP_NAME(plan_all)(casadi_real u, casadi_real v, casadi_real psi, int steps, casadi_real k,
                      const RP_NAME(options_t) *options, RP_NAME(plan_t) *plans, int capacity, int *count) {
    search_t S;
    RP_NAME(plan_t) scratch;   /* counts the branches searched */
    casadi_real h_des;
    int i, status;
    if (count == NULL || capacity < 0 || (plans == NULL && capacity > 0)) return RP_BAD_INPUT;
    *count = 0;
    status = start_search(u, v, psi, steps, k, &h_des);
    if (status != RP_OK) return status;
    s_memo_used = 0;
    S.u = u;
    S.v = v;
    S.k = k;
    S.steps = steps;
    S.certify = !options || options->certify;
    S.defer = 0;                /* every root is certified as it is found (no pruning: best stays infinite) */
    S.plan = &scratch;
    S.all = 1;
    S.list = plans;
    S.capacity = capacity;
    S.count = 0;
    S.last_m = 0;
    S.nseen = 0;
    S.psi_w = wrap_turns(psi, &S.turns);
    search(&S, options, h_des);
    *count = S.count;
    for (i = 0; i < S.count && i < capacity; ++i) {
        plans[i].branches = scratch.branches;
        plans[i].roots = scratch.roots;
    }
    if (S.incomplete) return RP_NO_CONVERGENCE;
    if (S.count > capacity) return RP_TOO_MANY;
    if (S.count > 0) return RP_OK;
    return S.rejected ? RP_NOT_CERTIFIED : RP_NO_PLAN;
}

int RP_NAME(plan)(casadi_real u, casadi_real v, casadi_real psi, int steps, casadi_real k, RP_NAME(plan_t) *plan) {
    return RP_NAME(plan_with)(u, v, psi, steps, k, NULL, plan);
}

int RP_NAME(plan_many)(int count, const casadi_real *targets, int steps, casadi_real k,
                       const RP_NAME(options_t) *options, RP_NAME(plan_t) *plans, casadi_real *finals, int *status) {
    int i, j, certified = !options || options->certify;
    if (count < 0 || (count > 0 && (targets == NULL || plans == NULL || status == NULL))) return RP_BAD_INPUT;
    for (i = 0; i < count; ++i) {
        status[i] = RP_NAME(plan_with)(targets[3 * i], targets[3 * i + 1], targets[3 * i + 2], steps, k, options,
                                       &plans[i]);
        if (finals)
            for (j = 0; j < 3; ++j) finals[3 * i + j] = status[i] == RP_OK && certified ? s_plan_final[j] : NAN;
    }
    return RP_OK;
}

/* ------------------------------------------------------------------ time law (rollplan.execution.timing) */

/* Leaf `leaf` from phi = 0 to phi_end <= 2 pi by the generated RK8 steps of (u_a, v_a, psi, rotor angles)'
 * (x in place), 2 s_counts steps per panel (the certificate's finer run). */
static int leaf_to(int leaf, casadi_real x[5], casadi_real phi_end, const casadi_real ab[2], casadi_real k,
                   casadi_real gamma, const casadi_real jj[3]) {
    casadi_real b1;
    int j, n;
    for (j = 0; j < NPANEL && s_breaks[j] < phi_end; ++j) {
        b1 = s_breaks[j + 1] < phi_end ? s_breaks[j + 1] : phi_end;
        n = 2 * s_counts[leaf][j];
        if (rk8x_steps(leaf, x, s_breaks[j], (b1 - s_breaks[j]) / n, n, ab, k, gamma, jj)) return 1;
    }
    return 0;
}

int RP_NAME(sample)(const RP_NAME(plan_t) *plan, int steps, casadi_real k, casadi_real j_xx, casadi_real j_zz,
                    casadi_real j_r, casadi_real duration, casadi_real t, casadi_real rates[2], casadi_real angles[2],
                    casadi_real state[5]) {
    casadi_real ab[2], jj[3], x[5] = {RP_R(0.0), RP_R(0.0), RP_R(0.0), RP_R(0.0), RP_R(0.0)}, piece_t, tau, f, df, phi, xdot[5], uv[2], g[2];
    int pieces, j, q;
    if (plan == NULL || rates == NULL) return RP_BAD_INPUT;
    if (!(plan->a > RP_R(0.0) && plan->a <= A_MAX && plan->b > RP_R(0.0) && plan->b <= A_MAX) || !isfinite(plan->gamma)
        || steps < 1 || steps > MAX_STEPS || !(k >= RP_R(0.0) && k <= K_MAX) || !(j_xx > RP_R(0.0) && isfinite(j_xx))
        || !(j_zz > RP_R(0.0) && isfinite(j_zz)) || !(j_r > RP_R(0.0) && isfinite(j_r)) || !(duration > RP_R(0.0) && isfinite(duration))
        || !(t >= RP_R(0.0) && t <= duration))
        return RP_BAD_INPUT;
    ab[0] = plan->a;
    ab[1] = plan->b;
    jj[0] = j_xx;
    jj[1] = j_zz;
    jj[2] = j_r;
    /* min-jerk: each of the 2 n leaves in duration / (2 n), phi = 2 pi (10 tau^3 - 15 tau^4 + 6 tau^5) */
    pieces = 2 * steps;
    piece_t = duration / pieces;
    j = (int)RP_FLOOR(t / piece_t);
    if (j >= pieces) j = pieces - 1;
    if (j < 0) j = 0;
    tau = (t - j * piece_t) / piece_t;
    tau = tau < RP_R(0.0) ? RP_R(0.0) : (tau > RP_R(1.0) ? RP_R(1.0) : tau);
    f = tau * tau * tau * (RP_R(10.0) + tau * (-RP_R(15.0) + RP_R(6.0) * tau));
    df = RP_R(30.0) * tau * tau * (RP_R(1.0) - tau) * (RP_R(1.0) - tau);
    phi = TWO_PI * f;
    if (counts(ab, k, plan->gamma)) return RP_NOT_CERTIFIED;
    for (q = 0; q < j; ++q)
        if (leaf_to(q % 2, x, TWO_PI, ab, k, plan->gamma, jj)) return RP_NOT_CERTIFIED;
    if (leaf_to(j % 2, x, phi, ab, k, plan->gamma, jj)) return RP_NOT_CERTIFIED;
    s_arg[0] = &phi;
    s_arg[1] = x;
    s_arg[2] = ab;
    s_arg[3] = &k;
    s_arg[4] = &plan->gamma;
    s_arg[5] = jj;
    s_arg[6] = jj + 1;
    s_arg[7] = jj + 2;
    s_res[0] = xdot;
    s_res[1] = uv;
    s_res[2] = g;
    if ((j % 2 ? RP_NAME(piece1)(s_arg, s_res, s_iw, s_w, 0) : RP_NAME(piece0)(s_arg, s_res, s_iw, s_w, 0)))
        return RP_NOT_CERTIFIED;
    rates[0] = g[0] * TWO_PI * df / piece_t;
    rates[1] = g[1] * TWO_PI * df / piece_t;
    if (angles) {
        angles[0] = x[3];
        angles[1] = x[4];
    }
    if (state) {
        state[0] = x[0];
        state[1] = x[1];
        state[2] = x[2];
        state[3] = uv[0];
        state[4] = uv[1];
    }
    return isfinite(rates[0]) && isfinite(rates[1]) ? RP_OK : RP_NOT_CERTIFIED;
}
