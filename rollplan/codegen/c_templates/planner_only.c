/* planner_only.c -- firmware stub that links the planner and nothing else (no stdio), for
 * `make size`: one plan of the paper case, its status returned through semihosting. The
 * inputs are volatile so that nothing is folded at compile time. */
#include "@PREFIX@.h"

static volatile casadi_real s_in[5] = {0, 1, 0, 1, 2.5};

int main(int argc, char **argv) {
    @PREFIX@_plan_t plan;
    (void)argc;
    (void)argv;
    return @PREFIX@_plan(s_in[0], s_in[1], s_in[2], (int)s_in[3], s_in[4], &plan);
}
