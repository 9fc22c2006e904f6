/*
 * fmi2_noop.c -- fmi2DoStep and fmi2GetReal that do nothing but return fmi2OK (fmi2GetReal
 * writes zeros).  benchmarks/bench_fmu.py (python_floor) compiles this file and calls these two
 * functions from the same Python loops that drive the FMU, with fmpy's argument types: what
 * the loop costs when the FMU costs nothing, the most any FMU can reach through that loop.
 */
#include <stddef.h>

int fmi2DoStep(void *c, double t, double h, int no_set_state_prior)
{
    (void)c; (void)t; (void)h; (void)no_set_state_prior;
    return 0;
}

int fmi2GetReal(void *c, const unsigned int *vr, size_t nvr, double *value)
{
    (void)c; (void)vr;
    for (size_t i = 0; i < nvr; i++)
        value[i] = 0.0;
    return 0;
}
