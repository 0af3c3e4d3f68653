/* plan_demo U V PSI STEPS K -- print one line "a b gamma residual bound" of the embedded plan: leaf
 * radii [R], rotation [rad], and its certificate (residual of the RK8 integration of the whole motion
 * and the integration's error bound, see @PREFIX@_certify).
 * Numbers are ASCII decimals as on rollplan's command line (2.5, -1e-3; no hex, inf, nan or spaces);
 * STEPS is a whole number in [1, @MAX_STEPS@], K lies in [0, @K_MAX@] (rollplan codegen --k-max).
 * Exit status: 0 certified plan, 2 bad input, 3 no bracket on branch m = 0, 4 no convergence,
 * 5 no converged plan passed the certificate. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "@PREFIX@.h"

/* 1 if text is [+-] digits [. digits] [(e|E) [+-] digits] with at least one digit before the exponent */
static int decimal(const char *s) {
    int digits = 0;
    if (*s == '+' || *s == '-') s++;
    for (; *s >= '0' && *s <= '9'; s++) digits++;
    if (*s == '.') {
        for (s++; *s >= '0' && *s <= '9'; s++) digits++;
    }
    if (!digits) return 0;
    if (*s == 'e' || *s == 'E') {
        s++;
        if (*s == '+' || *s == '-') s++;
        if (!(*s >= '0' && *s <= '9')) return 0;
        while (*s >= '0' && *s <= '9') s++;
    }
    return *s == '\0';
}

static int number(const char *text, double *x) {
    char *end;
    if (!decimal(text)) return 0;
    *x = strtod(text, &end);   /* underflow gives 0 (as in rollplan); overflow gives inf, refused */
    return end != text && *end == '\0' && isfinite(*x);
}

int main(int argc, char **argv) {
    double u, v, psi, steps_d, k;
    @PREFIX@_plan_t plan;
    int status;
    if (argc != 6 || !number(argv[1], &u) || !number(argv[2], &v) || !number(argv[3], &psi)
        || !number(argv[4], &steps_d) || !number(argv[5], &k)) {
        fprintf(stderr, "usage: %s U V PSI STEPS K   (decimal numbers such as 2.5 or -1e-3; STEPS a whole number "
                "in [1, @MAX_STEPS@], K in [0, @K_MAX@])\n", argv[0]);
        return @PREFIX_UPPER@_BAD_INPUT;
    }
    if (steps_d < 1 || steps_d > @PREFIX_UPPER@_MAX_STEPS || steps_d != floor(steps_d)) {
        fprintf(stderr, "%s: STEPS = %s is not allowed: it must be a whole number in [1, @MAX_STEPS@]\n", argv[0],
                argv[4]);
        return @PREFIX_UPPER@_BAD_INPUT;
    }
    if (!(k >= 0.0 && k <= (double)@PREFIX_UPPER@_K_MAX)) {
        fprintf(stderr, "%s: K = %s is not allowed: it must lie in [0, @K_MAX@] (the range this planner was "
                "generated for: rollplan codegen --k-max)\n", argv[0], argv[5]);
        return @PREFIX_UPPER@_BAD_INPUT;
    }
    /* ranges checked in double above, before the conversion to casadi_real (@REAL@ in this build) */
    status = @PREFIX@_plan((casadi_real)u, (casadi_real)v, (casadi_real)psi, (int)steps_d, (casadi_real)k, &plan);
    switch (status) {
    case @PREFIX_UPPER@_OK:
        printf("%.17g %.17g %.17g %.3e %.3e\n", (double)plan.a, (double)plan.b, (double)plan.gamma,
               (double)plan.residual, (double)plan.bound);
        return 0;
    case @PREFIX_UPPER@_BAD_INPUT:
        fprintf(stderr, "%s: bad input: the target (U, V) must be away from the origin\n", argv[0]);
        break;
    case @PREFIX_UPPER@_NO_PLAN:
        fprintf(stderr, "%s: no plan: no root of branch m = 0 with 0 < a, b <= %g; try more steps\n", argv[0],
                (double)@PREFIX_UPPER@_A_MAX);
        break;
    case @PREFIX_UPPER@_NOT_CERTIFIED:
        fprintf(stderr, "%s: not certified: the best converged plan (a %.6g, b %.6g) misses by %.3e with an "
                "integration error bound %.3e (tolerance %g)\n", argv[0], (double)plan.a, (double)plan.b,
                (double)plan.residual, (double)plan.bound, (double)@PREFIX_UPPER@_CERT_TOL);
        break;
    default:
        fprintf(stderr, "%s: no convergence after %d cells (last residual %.3e)\n", argv[0], plan.cells,
                (double)plan.predicted);
        break;
    }
    return status;
}
