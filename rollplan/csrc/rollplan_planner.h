/*
 * rollplan_planner.h -- embedded geometric-phase planner for the spherical robot with two
 * internal rotors (Svinin, Morinaga, Yamamoto): the interface of rollplan_planner.c.
 *
 * Both files are static sources of the rollplan package (rollplan/csrc/); `rollplan codegen` copies them
 * unchanged next to what it generates: <prefix>_model.c and .h (the model functions, by CasADi's
 * CodeGenerator), rollplan_config.h (the prefix, the number type, sizes and constants of that generation) and
 * <prefix>.h (this interface under the prefix's names). RP_NAME(x) is <prefix>_x, so RP_NAME(plan) below
 * declares <prefix>_plan; every constant RP_X is also <PREFIX>_X.
 *
 * C99, no malloc, no globals visible outside the library. Lengths in units of the
 * sphere radius R, angles in rad. casadi_real is double or float (`rollplan codegen --real`, RP_REAL_NAME);
 * plans are certified to RP_CERT_TOL.
 *
 * Generated model functions (CasADi calling convention, see <prefix>_model.h):
 *   int f(const casadi_real **arg, casadi_real **res, casadi_int *iw, casadi_real *w, int mem);
 * arg[i] points to input i, res[i] to output i (matrices column-major); iw and w
 * are work arrays of at least the sizes reported by f_work(); mem = 0. They
 * return 0 on success.
 *
 *   <prefix>_omega_z(omega_xy[2], u_o, v_o, psi, k) -> omega_z
 *       spin that makes the realizability condition (13) hold for rolling rates
 *       (omega_x, omega_y) at contact coordinates (u_o, v_o, psi), inertia ratio k.
 *   <prefix>_rotor_rates(omega[3], u_o, v_o, psi, j_xx, j_zz, j_r) -> phi_dot[2]
 *       rotor rates from the momentum integral (11).
 *   <prefix>_montana(omega[3], u_o, v_o, psi) -> rates[5]
 *       rates of (u_a, v_a, u_o, v_o, psi), Montana's equations (6)-(10).
 *   <prefix>_step(ab[2], k) -> shift[2], eta, direction
 *       one trace of the spherical figure eight (31), (35) with leaf radii (a, b),
 *       gamma = 0, from zero state: displacement (u_a, v_a), holonomy eta (the
 *       change of psi) and atan2(v_a, u_a); Chebyshev spectral integration of
 *       (28)-(30) with RP_STEPS_PER_LEAF node intervals per leaf.
 *   <prefix>_step_jac(ab[2], k) -> shift[2], eta, direction, jac[4x2]
 *       the same and the Jacobian of (shift, eta, direction) by (a, b).
 *   <prefix>_rhs0(phi, x[3], p[2], k, gamma) -> xdot[3], <prefix>_rhs1(...)
 *       the curve ODE (28)-(30) along the first (+y) and the second (-y) leaf of the figure
 *       eight with radii p = (a, b) rotated by gamma, x = (u_a, v_a, psi).
 *   <prefix>_rk8_0(x[3], cos_t[12], sin_t[12], h, p[2], k, cos_gamma, sin_gamma) -> x_next[3], <prefix>_rk8_1(...)
 *       one step from phi = t to t + h of the eighth-order Runge-Kutta formula of Dormand and Prince of it,
 *       given cos phi and sin phi at its 12 stages t + c_j h (c_j the nodes of DOP853), and cos and sin of gamma.
 *   <prefix>_rates0(cos_phi, sin_phi, p[2], k, cos_gamma, sin_gamma) -> rates[2], <prefix>_rates1(...)
 *       the turn rate psi' of (30) along the leaf at inertia ratio 0 and k (independent of the state).
 *   <prefix>_piece0(phi, x[5], p[2], k, gamma, jxx, jzz, jr) -> xdot[5], uv[2], g[2], <prefix>_piece1(...)
 *       along a leaf, per unit phi: d/dphi of (u_a, v_a, psi, rotor angles), the contact coordinates (u_o, v_o)
 *       and the rotor rates (11) at psi = x[2]; <prefix>_rk8x_0(x[5], t, h, p[2], k, gamma, jxx, jzz, jr), _1:
 *       one RK8 step of it (for the time law <prefix>_sample).
 */
#ifndef ROLLPLAN_PLANNER_H
#define ROLLPLAN_PLANNER_H

#include "rollplan_config.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Status codes (equal to the exit codes of plan_demo and, for 0, 2, 3, of the `rollplan` command). */
#define RP_OK 0             /* a plan whose certificate holds: residual + bound <= CERT_TOL
                                   (or, with options.certify = 0, an uncertified root of the leaf map) */
#define RP_BAD_INPUT 2      /* non-finite input, |psi| > PSI_MAX, steps outside [1, MAX_STEPS],
                                   k outside [K_MIN, K_MAX] (the range this code was generated for), zero shift */
#define RP_NO_PLAN 3        /* no branch of (32)-(33) has a root with 0 < a, b <= A_MAX (a point the leaf
                                   map misses by more than enumerate.NOT_A_ROOT x CERT_TOL is none: the
                                   certificate could never accept it) */
#define RP_NO_CONVERGENCE 4 /* the search could not be completed (a branch needed more than
                                   its bounded number of cells, or the leaf table is not finite) */
#define RP_NOT_CERTIFIED 5  /* roots were found, but none passed the certificate */
#define RP_TOO_MANY 6       /* <prefix>_plan_all: more plans than the caller's capacity (the shortest
                                   `capacity` of them are returned, `count` says how many there are) */

/* The limits of this generation (defined in rollplan_config.h).
 * Largest admissible leaf radius [R] (the equator of the body frame is singular): RP_A_MAX. */
/* Smallest inertia ratio k accepted (k = 0 is pure rolling): RP_K_MIN. The enumeration runs on one graph per
 * branch over the smaller leaf radius for k >= 1/2, where the turn E(r, k) of a leaf is strictly decreasing in r,
 * and on graphs over the monotone pieces of E below. */
/* Largest inertia ratio k accepted (`rollplan codegen --k-max`): the leaf map's Gauss rule is accurate up to
 * rollplan's K_MAX, the step map <prefix>_step_jac to 1e-10 up to this k, and the rho table is sized for it: RP_K_MAX. */
/* Largest |psi| [rad] accepted: psi is reduced modulo 2 pi exactly up to it: RP_PSI_MAX. */
/* Largest number of figure-eight steps of a plan: RP_MAX_STEPS. */
/* Tolerance of the certificate: |final - target| + error bound <= CERT_TOL [R and rad]: RP_CERT_TOL. */

/* A plan: trace the figure eight (a, b) rotated by gamma about OZ, n times. */
typedef struct {
    casadi_real a;          /* first leaf radius [R], 0 < a <= A_MAX */
    casadi_real b;          /* second leaf radius [R], 0 < b <= A_MAX */
    casadi_real gamma;      /* rotation of the figure eight about OZ, eq. (31) [rad], in (-pi, pi] */
    casadi_real eta;        /* holonomy of one step [rad]: n eta = psi + 2 pi m */
    casadi_real h;          /* shift of one step [R] */
    long m;                 /* branch of (32): n eta = psi + 2 pi m, psi as given */
    casadi_real residual;   /* certificate: |final - target| (u_a, v_a in R, psi wrapped, in rad) of the whole
                          n-step motion integrated from rest by fixed-step RK8 (<prefix>_certify); NaN without it */
    casadi_real bound;      /* certificate: step-doubling estimate of the error of that integration, with a
                          margin (see <prefix>_certify); NaN without it */
    casadi_real predicted;  /* |final - target| predicted by the closed-form leaf map composed n times */
    int branches;      /* branches searched */
    long roots;        /* roots tried (polished, and certified unless options.certify = 0) */
} RP_NAME(plan_t);

/* Options of <prefix>_plan_with. */
typedef struct {
    int use_branch;    /* 1: search branch `branch` only (n eta = psi + 2 pi branch); 0: all branches, shortest */
    long branch;
    int certify;       /* 1: a plan is returned only if its certificate holds (the default); 0: the shortest
                          root of the leaf map, uncertified (residual and bound are NaN) */
} RP_NAME(options_t);

/*
 * Plan a motion from rest at the origin to (u_a, v_a, psi) = (u, v, psi) in `steps` traces of the figure
 * eight for inertia ratio k (eq. 14): the shortest certified plan over all branches m of (32)-(33),
 *   n eta = psi + 2 pi m,  h(a, b) = h_des |sin(eta/2) / sin(n eta/2)|  (h_des / n where sin(eta/2) = 0),
 * h_des = |(u, v)|, then gamma = atan2(v, u) - arg(sum_{j<n} exp(-i j eta) shift(a, b)); the same choice as
 * rollplan.planners.geometric (complete enumeration of the roots on each branch as one scalar equation in the
 * smaller leaf radius, where rollplan's numpy search uses other graphs of the same level set; the closed-form
 * leaf map; a bounded search over branches in the order of the smallest a + b they can hold). The shortest
 * root is certified by <prefix>_certify before it is returned (if it fails, the search runs again and
 * certifies every root before it is taken); a plan that fails is never returned as <PREFIX>_OK.
 * Time: the first plan for a new k builds the leaf map's table for k (kept for the last k); then
 * proportional to the branches searched. Deterministic; static memory only; not reentrant.
 * Returns one of the status codes above; `plan` is filled in on <PREFIX>_OK (on NOT_CERTIFIED it holds
 * the root with the smallest certified residual).
 */
int RP_NAME(plan)(casadi_real u, casadi_real v, casadi_real psi, int steps, casadi_real k, RP_NAME(plan_t) *plan);

/* The same with options (NULL: the defaults of <prefix>_plan): one branch, or no certificate. */
int RP_NAME(plan_with)(casadi_real u, casadi_real v, casadi_real psi, int steps, casadi_real k,
                       const RP_NAME(options_t) *options, RP_NAME(plan_t) *plan);

/*
 * Many plans in one call: for i < count, plans[i] and status[i] of <prefix>_plan_with for the target
 * targets[3 i .. 3 i + 2] = (u, v, psi), all with the same steps, k and options; finals (may be NULL; else 3 count
 * entries) receives the final state (u_a, v_a, psi) of the finest run of each returned plan's certificate
 * (<prefix>_certify; NaN where status[i] is not <PREFIX>_OK or options->certify = 0). Returns <PREFIX>_OK, or
 * <PREFIX>_BAD_INPUT for count < 0 or a NULL targets, plans or status with count > 0 (then nothing is planned).
 * Static memory only; not reentrant.
 */
int RP_NAME(plan_many)(int count, const casadi_real *targets, int steps, casadi_real k,
                       const RP_NAME(options_t) *options, RP_NAME(plan_t) *plans, casadi_real *finals, int *status);

/*
 * Every plan: every root of (32)-(33) on every branch (n eta = psi + 2 pi m for every m with |eta_m| at most the
 * range of E on (0, A_MAX]; or on options->branch only), each polished and certified by <prefix>_certify (with
 * options->certify = 0: every root of the leaf map, uncertified), as rollplan's `plan --all` lists them
 * (GeometricPhasePlanner.solve(all_solutions=True)). The plans go into plans[0 .. capacity - 1], shortest
 * (a + b) first; *count receives the number of certified plans found, which may exceed capacity (then the shortest
 * `capacity` are written and the status is <PREFIX>_TOO_MANY). No pruning: time proportional to every branch.
 * Returns <PREFIX>_OK (1 <= *count <= capacity), <PREFIX>_TOO_MANY, <PREFIX>_BAD_INPUT (also for
 * count = NULL, capacity < 0, or plans = NULL with capacity > 0), <PREFIX>_NO_PLAN (no root),
 * <PREFIX>_NOT_CERTIFIED (roots, none certified), <PREFIX>_NO_CONVERGENCE (a branch could not be
 * searched completely: the plans found are written, but the list may lack some). branches and roots of every plan
 * written count the whole search. Static memory only; not reentrant.
 */
int RP_NAME(plan_all)(casadi_real u, casadi_real v, casadi_real psi, int steps, casadi_real k,
                      const RP_NAME(options_t) *options, RP_NAME(plan_t) *plans, int capacity, int *count);

/*
 * Certificate of a plan: integrate the n-step motion (figure eight (a, b) rotated by gamma, traced
 * `steps` times from rest at the origin) with the generated RK8 steps, the right side (28)-(30) as
 * it is (independent of the planner's leaf map and its quadrature), every one of the `steps` traces from the
 * state the previous one left (not the first trace turned and shifted). Each panel of a leaf of width w
 * gets N = ceil(w (RP_CERT_BASE + max|psi'|) / RP_CERT_DELTA) equal steps (psi' sampled at 5 points; it does not
 * depend on the state); the motion is integrated with N and with 2N steps per panel, `bound` is
 * |x_2N - x_N| / RP_CERT_SAFETY (step doubling: the error of x_2N of an order-8 method is about
 * |x_2N - x_N| / 255; dividing by RP_CERT_SAFETY only leaves a margin) plus a rounding allowance
 * RP_CERT_ROUNDING eps (1 + max |psi|) sqrt(steps of the finer run) (the rounding errors, which the difference of
 * two runs does not show, add like a random walk and reach (u_a, v_a) through psi), and `residual` is
 * |x_2N - (u, v, psi)| (psi wrapped). While that is undecided (residual - bound <= CERT_TOL <
 * residual + bound), the steps are doubled again (x_2N becomes the coarse run), at most 3 times.
 * `final` (may be NULL) receives the finest run.
 * Returns <PREFIX>_OK if residual + bound <= CERT_TOL, <PREFIX>_NOT_CERTIFIED otherwise,
 * <PREFIX>_BAD_INPUT for arguments outside the ranges of <prefix>_plan.
 */
int RP_NAME(certify)(casadi_real a, casadi_real b, casadi_real gamma, int steps, casadi_real k, casadi_real u, casadi_real v, casadi_real psi,
                     casadi_real final[3], casadi_real *residual, casadi_real *bound);

/*
 * Time law: rotor-rate set points of a plan run by the min-jerk law of rollplan.execution.timing ("min-jerk":
 * each of the 2 n leaves in duration / (2 n), the leaf parameter phi = 2 pi (10 tau^3 - 15 tau^4 + 6 tau^5),
 * tau the fraction of the leaf's time; rest at every pole), for a robot with the inertias j_xx, j_zz (about the
 * contact point and the vertical, (14): k = j_xx / j_zz) and rotor inertia j_r [kg m^2, any consistent unit].
 * At time t in [0, duration] [s]: rates = the rotor rates phi_1_dot, phi_2_dot of (11) [rad/s]; angles (may be
 * NULL) = the rotor angles, zero at t = 0 [rad]; state (may be NULL) = (u_a, v_a [R], psi, u_o, v_o [rad]).
 * The rates are (11) per unit phi' (<prefix>_piece0/1) times phi'; angles and state integrate the motion from
 * rest up to t by the generated RK8 steps (<prefix>_rk8x_0/1) at the certificate's finer step count, so the
 * cost grows with t (at most the motion's full length). Returns <PREFIX>_OK, <PREFIX>_BAD_INPUT.
 */
int RP_NAME(sample)(const RP_NAME(plan_t) *plan, int steps, casadi_real k, casadi_real j_xx, casadi_real j_zz,
                    casadi_real j_r, casadi_real duration, casadi_real t, casadi_real rates[2], casadi_real angles[2],
                    casadi_real state[5]);

/* Drop the leaf map's table kept for the last k (the next plan recomputes it). */
void RP_NAME(forget_table)(void);

/*
 * The leaf map's rho table of k (built now unless it is the one kept): its rho and d rho / dr at the table's *n
 * radii into rho[] and drho[] (capacity entries each) and its largest error at the cells' midpoints into *err, so
 * that a later process can skip the build (<prefix>_table_load). Returns <PREFIX>_OK, <PREFIX>_BAD_INPUT (k outside
 * [K_MIN, K_MAX]), <PREFIX>_NO_CONVERGENCE or <PREFIX>_TOO_MANY (*n > capacity).
 */
int RP_NAME(table_save)(casadi_real k, int capacity, casadi_real *rho, casadi_real *drho, casadi_real *err, int *n);

/*
 * Give the planner the table <prefix>_table_save gave for k: the next plan at k takes it instead of building it
 * if it has as many radii as this build's table of k and its values at three radii evaluated again equal the given
 * ones exactly (otherwise the table is built as usual). Returns <PREFIX>_OK or <PREFIX>_BAD_INPUT.
 */
int RP_NAME(table_load)(casadi_real k, int n, const casadi_real *rho, const casadi_real *drho, casadi_real err);

/*
 * Convenience wrapper of <prefix>_step_jac with plain arguments (static work area).
 * jac may be NULL; otherwise it receives the 4x2 Jacobian, column-major.
 * Returns 0 on success.
 */
int RP_NAME(step_eval)(casadi_real a, casadi_real b, casadi_real k, casadi_real shift[2], casadi_real *eta, casadi_real *direction,
                       casadi_real jac[8]);

#ifdef __cplusplus
}
#endif

#endif /* ROLLPLAN_PLANNER_H */
