/* plan_demo U V PSI STEPS K [BRANCH] -- print one line "a b gamma residual bound m" of the embedded plan:
 * leaf radii [R], rotation [rad], its certificate (residual of the RK8 integration of the whole motion
 * and the integration's error bound, see @PREFIX@_certify) and its branch m (n eta = psi + 2 pi m).
 * The shortest certified plan over all branches, or on branch BRANCH (a whole number) if given.
 * plan_demo --all U V PSI STEPS K [BRANCH] -- every certified plan (@PREFIX@_plan_all), one such line each,
 * shortest first, then the line "N plans"; at most DEMO_PLANS lines (exit 6 if there are more).
 * Numbers are ASCII decimals as on rollplan's command line (2.5, -1e-3; no hex, inf, nan or spaces);
 * STEPS is a whole number in [1, @MAX_STEPS@], K lies in [@K_MIN@, @K_MAX@] (rollplan codegen --k-max),
 * |PSI| <= @PSI_MAX@.
 * Exit status: 0 certified plan, 2 bad input, 3 no root on any branch searched, 4 search incomplete,
 * 5 roots found but none passed the certificate, 6 (--all) more plans than DEMO_PLANS. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "@PREFIX@.h"

#define DEMO_PLANS 1024  /* plans --all lists at most */

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

static void print_plan(const @PREFIX@_plan_t *plan) {
    printf("%.17g %.17g %.17g %.3e %.3e %ld\n", (double)plan->a, (double)plan->b, (double)plan->gamma,
           (double)plan->residual, (double)plan->bound, plan->m);
}

int main(int argc, char **argv) {
    static @PREFIX@_plan_t plans[DEMO_PLANS];   /* static: keeps the stack small */
    double u, v, psi, steps_d, k, branch = 0.0;
    @PREFIX@_plan_t plan;
    @PREFIX@_options_t options = {0, 0, 1};
    int status, all = argc > 1 && strcmp(argv[1], "--all") == 0, count = 0, i;
    const char *self = argv[0];
    if (all) {   /* the same arguments after --all */
        argv[1] = argv[0];
        ++argv;
        --argc;
    }
    if ((argc != 6 && argc != 7) || !number(argv[1], &u) || !number(argv[2], &v) || !number(argv[3], &psi)
        || !number(argv[4], &steps_d) || !number(argv[5], &k) || (argc == 7 && !number(argv[6], &branch))) {
        fprintf(stderr, "usage: %s [--all] U V PSI STEPS K [BRANCH]   (decimal numbers such as 2.5 or -1e-3; STEPS a "
                "whole number in [1, @MAX_STEPS@], K in [@K_MIN@, @K_MAX@], BRANCH a whole number)\n", self);
        return @PREFIX_UPPER@_BAD_INPUT;
    }
    if (argc == 7) {
        if (branch != floor(branch) || fabs(branch) > 1e9) {
            fprintf(stderr, "%s: BRANCH = %s is not allowed: it must be a whole number in [-1e9, 1e9]\n", argv[0],
                    argv[6]);
            return @PREFIX_UPPER@_BAD_INPUT;
        }
        options.use_branch = 1;
        options.branch = (long)branch;
    }
    if (steps_d < 1 || steps_d > @PREFIX_UPPER@_MAX_STEPS || steps_d != floor(steps_d)) {
        fprintf(stderr, "%s: STEPS = %s is not allowed: it must be a whole number in [1, @MAX_STEPS@]\n", argv[0],
                argv[4]);
        return @PREFIX_UPPER@_BAD_INPUT;
    }
    if (!(k >= (double)@PREFIX_UPPER@_K_MIN && k <= (double)@PREFIX_UPPER@_K_MAX)) {
        fprintf(stderr, "%s: K = %s is not allowed: it must lie in [@K_MIN@, @K_MAX@] (the range this planner was "
                "generated for: rollplan codegen --k-max)\n", argv[0], argv[5]);
        return @PREFIX_UPPER@_BAD_INPUT;
    }
    if (!(fabs(psi) <= (double)@PREFIX_UPPER@_PSI_MAX)) {
        fprintf(stderr, "%s: PSI = %s is not allowed: |PSI| must be at most @PSI_MAX@\n", argv[0], argv[3]);
        return @PREFIX_UPPER@_BAD_INPUT;
    }
    /* ranges checked in double above, before the conversion to casadi_real (@REAL@ in this build) */
    if (all) {
        status = @PREFIX@_plan_all((casadi_real)u, (casadi_real)v, (casadi_real)psi, (int)steps_d, (casadi_real)k,
                                   &options, plans, DEMO_PLANS, &count);
        if (status == @PREFIX_UPPER@_OK || status == @PREFIX_UPPER@_TOO_MANY) {
            for (i = 0; i < count && i < DEMO_PLANS; ++i) print_plan(&plans[i]);
            printf("%d plans\n", count);
            if (status == @PREFIX_UPPER@_OK) return 0;
            fprintf(stderr, "%s: %d plans, more than the %d this demo lists (the shortest %d above)\n", argv[0],
                    count, DEMO_PLANS, DEMO_PLANS);
            return status;
        }
        if (status == @PREFIX_UPPER@_NO_CONVERGENCE) {
            fprintf(stderr, "%s: search incomplete: a branch needed more cells than the bound (the %d plans found "
                    "may not be all)\n", argv[0], count);
            return status;
        }
        if (status == @PREFIX_UPPER@_NOT_CERTIFIED) {
            fprintf(stderr, "%s: not certified: roots were found, but none passed the certificate (tolerance %g)\n",
                    argv[0], (double)@PREFIX_UPPER@_CERT_TOL);
            return status;
        }
    } else {
        status = @PREFIX@_plan_with((casadi_real)u, (casadi_real)v, (casadi_real)psi, (int)steps_d, (casadi_real)k,
                                    &options, &plan);
    }
    switch (status) {
    case @PREFIX_UPPER@_OK:
        print_plan(&plan);
        return 0;
    case @PREFIX_UPPER@_BAD_INPUT:
        fprintf(stderr, "%s: bad input: the target (U, V) must be away from the origin\n", argv[0]);
        break;
    case @PREFIX_UPPER@_NO_PLAN:
        fprintf(stderr, "%s: no plan: no branch of (32)-(33)%s has a root with 0 < a, b <= %g; try more steps\n",
                argv[0], options.use_branch ? " searched" : "", (double)@PREFIX_UPPER@_A_MAX);
        break;
    case @PREFIX_UPPER@_NOT_CERTIFIED:
        fprintf(stderr, "%s: not certified: the best root (a %.6g, b %.6g) misses by %.3e with an "
                "integration error bound %.3e (tolerance %g)\n", argv[0], (double)plan.a, (double)plan.b,
                (double)plan.residual, (double)plan.bound, (double)@PREFIX_UPPER@_CERT_TOL);
        break;
    default:
        fprintf(stderr, "%s: search incomplete: a branch needed more cells than the bound (%d branches "
                "searched)\n", argv[0], plan.branches);
        break;
    }
    return status;
}
