/* plan_demo U V PSI STEPS K -- print one line "a b gamma residual bound" of the embedded plan: leaf
 * radii [R], rotation [rad], and its certificate (residual of the RK8 integration of the whole motion
 * and the integration's error bound, see @PREFIX@_certify).
 * Exit status: 0 certified plan, 2 bad input, 3 no bracket on branch m = 0, 4 no convergence,
 * 5 no converged plan passed the certificate. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "@PREFIX@.h"

static int number(const char *text, double *x) {
    char *end;
    errno = 0;
    *x = strtod(text, &end);
    return end != text && *end == '\0' && errno == 0 && isfinite(*x);
}

int main(int argc, char **argv) {
    double u, v, psi, steps_d, k;
    @PREFIX@_plan_t plan;
    int status;
    if (argc != 6 || !number(argv[1], &u) || !number(argv[2], &v) || !number(argv[3], &psi)
        || !number(argv[4], &steps_d) || !number(argv[5], &k)) {
        fprintf(stderr, "usage: %s U V PSI STEPS K   (finite numbers; STEPS a whole number in [1, %d], "
                "0 <= K <= %g)\n", argv[0], @PREFIX_UPPER@_MAX_STEPS, (double)@PREFIX_UPPER@_K_MAX);
        return @PREFIX_UPPER@_BAD_INPUT;
    }
    if (steps_d < 1 || steps_d > @PREFIX_UPPER@_MAX_STEPS || steps_d != floor(steps_d)) {
        fprintf(stderr, "%s: STEPS = %s is not allowed: it must be a whole number in [1, %d]\n", argv[0], argv[4],
                @PREFIX_UPPER@_MAX_STEPS);
        return @PREFIX_UPPER@_BAD_INPUT;
    }
    if (!(k >= 0.0 && k <= (double)@PREFIX_UPPER@_K_MAX)) {
        fprintf(stderr, "%s: K = %s is not allowed: this planner was generated for 0 <= K <= %g "
                "(rollplan codegen --k-max)\n", argv[0], argv[5], (double)@PREFIX_UPPER@_K_MAX);
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
