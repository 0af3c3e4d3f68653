/* plan_demo U V PSI STEPS K -- print one line "a b gamma residual" of the embedded plan.
 * Numbers are ASCII decimals as on rollplan's command line (2.5, -1e-3; no hex, inf, nan or spaces);
 * STEPS is a whole number in [1, @MAX_STEPS@], K lies in [0, @K_MAX@].
 * Exit status: 0 converged, 2 bad input, 3 no bracket on branch m = 0, 4 no convergence. */
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
    if (steps_d < 1 || steps_d > @MAX_STEPS@ || steps_d != floor(steps_d)) {
        fprintf(stderr, "%s: STEPS = %s is not allowed: it must be a whole number in [1, @MAX_STEPS@]\n", argv[0],
                argv[4]);
        return @PREFIX_UPPER@_BAD_INPUT;
    }
    if (k < 0 || k > @K_MAX@) {
        fprintf(stderr, "%s: K = %s is not allowed: it must lie in [0, @K_MAX@]\n", argv[0], argv[5]);
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
