/* plan_demo U V PSI STEPS K -- print one line "a b gamma residual" of the embedded plan.
 * Exit status: 0 converged, 2 bad input, 3 no bracket on branch m = 0, 4 no convergence. */
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
        fprintf(stderr, "usage: %s U V PSI STEPS K   (finite numbers; STEPS a whole number >= 1, K >= 0)\n",
                argv[0]);
        return @PREFIX_UPPER@_BAD_INPUT;
    }
    if (steps_d < 1 || steps_d > 1e6 || steps_d != floor(steps_d)) {
        fprintf(stderr, "%s: STEPS = %s is not allowed: it must be a whole number >= 1\n", argv[0], argv[4]);
        return @PREFIX_UPPER@_BAD_INPUT;
    }
    status = @PREFIX@_plan(u, v, psi, (int)steps_d, k, &plan);
    switch (status) {
    case @PREFIX_UPPER@_OK:
        printf("%.17g %.17g %.17g %.3e\n", plan.a, plan.b, plan.gamma, plan.residual);
        return 0;
    case @PREFIX_UPPER@_BAD_INPUT:
        fprintf(stderr, "%s: bad input: need K >= 0 and a target (U, V) away from the origin\n", argv[0]);
        break;
    case @PREFIX_UPPER@_NO_PLAN:
        fprintf(stderr, "%s: no plan: no root of branch m = 0 with 0 < a, b <= %g; try more steps\n", argv[0],
                @PREFIX_UPPER@_A_MAX);
        break;
    default:
        fprintf(stderr, "%s: no convergence after %d cells (last residual %.3e)\n", argv[0], plan.cells,
                plan.residual);
        break;
    }
    return status;
}
