/*
 * fmu_layers.c -- where one communication step of the standalone gearfmu FMU spends its
 * time, layer by layer, with no Python and no dynamic loading in the way
 * (benchmarks/bench_fmu.py compiles it together with the FMU's own sources/, at the
 * FMU's compile flags, and runs it).
 *
 * usage: fmu_layers <unzipped FMU dir> <guid> <comm_step_s> <n_steps> <repeat> <output vrs, comma separated>
 *                   <max_step vr> <max_step_s> <integrator vr> <integrator> [vr=value ...]
 *
 * One instance is initialised as fmu_rtf_host.c does (the values set in initialization
 * mode) and its FMU state saved (fmi2GetFMUstate).  Then, <repeat> times and in turn, each
 * of these loops runs <n_steps> communication steps from that saved state (fmi2SetFMUstate
 * first, outside the timing), so every loop integrates the same trajectory:
 *
 *   kernel      gk_do_step on the instance's model and state (the kernel alone: the
 *               internal steps and the outputs);
 *   shared      gkf_do_step (../gearfmu/fmu/kernel/gkfmu.c: the input and step checks,
 *               damping, temperature, the warnings, then gk_do_step);
 *   dostep      fmi2DoStep (the FMI state check, the values handed to gkfmu.c, the
 *               messages to the logger, then gkf_do_step);
 *   step_get    fmi2DoStep + fmi2GetReal(outputs): one communication step of a host;
 *   getreal     fmi2GetReal(outputs) alone, n_steps times without stepping.
 *
 * Prints one JSON line: nanoseconds per call of each loop (the best of <repeat>, on the CPU time
 * of the thread, CLOCK_THREAD_CPUTIME_ID: a wait for a core on a shared machine is not counted)
 * and whether the kernel and step_get loops ended on bitwise the same outputs.
 */
#define _POSIX_C_SOURCE 199309L
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"
#include "bench_host.h"
#include "gear_model.h"

enum { L_KERNEL, L_SHARED, L_DOSTEP, L_STEP_GET, L_GETREAL, L_N };
static const char *const LOOP_NAME[L_N] = {"kernel", "shared", "dostep", "step_get", "getreal"};


/* one timed loop of kind `loop`; 0 on success */
static int run_loop(fmi2Component comp, int loop, int n, double H, const fmi2ValueReference *outs, int nout,
                    double *vals, double *wall)
{
    gf_inst *g = (gf_inst *)comp;
    gm_data *d = g->data;
    double t = g->time, T1 = g->values[d->vr_T1], T2 = g->values[d->vr_T2], hmax = g->values[d->vr_hmax];
    double w0;
    int k;
    w0 = clock_s(CLOCK_THREAD_CPUTIME_ID);
    switch (loop) {
    case L_KERNEL:
        for (k = 0; k < n; ++k)
            if (gk_do_step(d->model, &d->state, T1, T2, H, hmax, g->out) != GK_OK) return 1;
        break;
    case L_SHARED:
        for (k = 0; k < n; ++k, t += H)
            if (!gkf_do_step(d->fmu, &d->state, t, H, g->out)) return 1;
        break;
    case L_DOSTEP:
        for (k = 0; k < n; ++k, t += H)
            if (fmi2DoStep(comp, t, H, fmi2True) != fmi2OK) return 1;
        break;
    case L_STEP_GET:
        for (k = 0; k < n; ++k, t += H)
            if (fmi2DoStep(comp, t, H, fmi2True) != fmi2OK || fmi2GetReal(comp, outs, (size_t)nout, vals) != fmi2OK)
                return 1;
        break;
    default:
        for (k = 0; k < n; ++k)
            if (fmi2GetReal(comp, outs, (size_t)nout, vals) != fmi2OK) return 1;
        break;
    }
    *wall = clock_s(CLOCK_THREAD_CPUTIME_ID) - w0;
    return 0;
}

int main(int argc, char **argv)
{
    char uri[4200];
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2ValueReference outs[16], vr_hmax, vr_int;
    fmi2Real hmax, H, vals[16], last[L_N][16];
    fmi2Integer integ;
    fmi2FMUstate s0 = NULL;
    fmi2Component c;
    double best[L_N];
    int n, repeat, r, loop, i, nout = 0;

    if (argc < 11) {
        fprintf(stderr, "usage: %s dir guid comm n_steps repeat out_vrs hmax_vr hmax int_vr int [vr=value ...]\n",
                argv[0]);
        return 1;
    }
    snprintf(uri, sizeof uri, "file://%s/resources", argv[1]);
    H = atof(argv[3]);
    n = atoi(argv[4]);
    repeat = atoi(argv[5]);
    nout = parse_vrs(argv[6], outs, 16);
    vr_hmax = (fmi2ValueReference)strtoul(argv[7], NULL, 10);
    hmax = atof(argv[8]);
    vr_int = (fmi2ValueReference)strtoul(argv[9], NULL, 10);
    integ = (fmi2Integer)atoi(argv[10]);
    if (n < 1 || repeat < 1 || !(H > 0.0) || nout < 1) return 1;
    c = fmi2Instantiate("layers", fmi2CoSimulation, argv[2], uri, &cb, fmi2False, fmi2False);
    if (c == NULL) return 4;
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    CHECK(fmi2SetReal(c, &vr_hmax, 1, &hmax));
    CHECK(fmi2SetInteger(c, &vr_int, 1, &integ));
    {
        int bad = set_start_values(c, fmi2SetReal, 11, argc, argv);
        if (bad) return bad;
    }
    CHECK(fmi2ExitInitializationMode(c));
    CHECK(fmi2GetFMUstate(c, &s0));
    for (loop = 0; loop < L_N; ++loop) best[loop] = 1e300;
    for (r = 0; r < repeat; ++r)
        for (loop = 0; loop < L_N; ++loop) {
            double w;
            CHECK(fmi2SetFMUstate(c, s0));
            if (run_loop(c, loop, n, H, outs, nout, vals, &w) != 0) {
                fprintf(stderr, "loop %s: a call failed\n", LOOP_NAME[loop]);
                return 3;
            }
            if (w < best[loop]) best[loop] = w;
            CHECK(fmi2GetReal(c, outs, (size_t)nout, last[loop]));
        }
    printf("{\"n_steps\": %d, \"repeat\": %d", n, repeat);
    for (loop = 0; loop < L_N; ++loop) printf(", \"%s_ns\": %.6g", LOOP_NAME[loop], 1e9 * best[loop] / n);
    for (i = 0; i < nout && memcmp(&last[L_KERNEL][i], &last[L_STEP_GET][i], sizeof(double)) == 0; ++i) {}
    printf(", \"same_outputs\": %s}\n", i == nout ? "true" : "false");
    fmi2FreeFMUstate(c, &s0);
    fmi2FreeInstance(c);
    return 0;
}
