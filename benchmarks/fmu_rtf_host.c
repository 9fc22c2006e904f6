/*
 * fmu_rtf_host.c -- a minimal FMI 2.0 Co-Simulation host in plain C that times the
 * standalone gearfmu FMU with no Python in the loop (benchmarks/bench_fmu_rtf.py
 * compiles and runs it).  Calling sequence of the FMI 2.0 standard, section 4.2:
 * instantiate -> setupExperiment -> enter/exit initialization -> doStep... ->
 * terminate -> freeInstance.
 *
 * usage: fmu_rtf_host <unzipped FMU dir> <modelIdentifier> <guid> <stop_time_s> <comm_step_s>
 *                     <repeat> <output vrs, comma separated> <max_step vr> <max_step_s> <integrator vr> <integrator>
 *                     [vr=value ...]
 *
 * Runs <repeat> times: instantiate, set max_step, integrator and the given Real
 * parameters/inputs in initialization mode, then round(stop/step) calls of
 * fmi2DoStep followed by fmi2GetReal(outputs), timed (wall: CLOCK_MONOTONIC, CPU:
 * CLOCK_PROCESS_CPUTIME_ID) around the doStep/getReal loop only.
 * Prints one JSON line {"n_steps":..,"wall_s":[..],"cpu_s":[..]} and then the outputs
 * of the last run at every communication point (row 0 the initial one), one row of
 * comma-separated %.17g values per line.  Exit code 0 only if every FMI call returned fmi2OK.
 */
#define _POSIX_C_SOURCE 199309L
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"
#include "bench_host.h"

#if defined(__aarch64__)
#define FMU_BIN "aarch64-linux"
#else
#define FMU_BIN "linux64"
#endif

#define LOAD(T, name)                                                         \
    T name = (T)dlsym(lib, #name);                                            \
    if (name == NULL) {                                                       \
        fprintf(stderr, "missing symbol %s\n", #name);                        \
        return 2;                                                             \
    }


int main(int argc, char **argv)
{
    char path[4096], uri[4200];
    void *lib;
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2ValueReference outs[16], vr_hmax, vr_int;
    fmi2Real hmax;
    fmi2Integer integ;
    double stop, step, *rows, *walls, *cpus;
    int repeat, nsteps, r, k, nout = 0;

    if (argc < 12) {
        fprintf(stderr, "usage: %s dir id guid stop step repeat out_vrs hmax_vr hmax int_vr int [vr=value ...]\n",
                argv[0]);
        return 1;
    }
    snprintf(path, sizeof path, "%s/binaries/" FMU_BIN "/%s.so", argv[1], argv[2]);
    snprintf(uri, sizeof uri, "file://%s/resources", argv[1]);
    stop = atof(argv[4]);
    step = atof(argv[5]);
    repeat = atoi(argv[6]);
    nout = parse_vrs(argv[7], outs, 16);
    vr_hmax = (fmi2ValueReference)strtoul(argv[8], NULL, 10);
    hmax = atof(argv[9]);
    vr_int = (fmi2ValueReference)strtoul(argv[10], NULL, 10);
    integ = (fmi2Integer)atoi(argv[11]);
    if (repeat < 1 || step <= 0.0 || stop <= 0.0 || nout < 1) return 1;
    nsteps = (int)(stop / step + 0.5);
    rows = (double *)calloc(((size_t)nsteps + 1) * (size_t)nout, sizeof(double));
    walls = (double *)calloc((size_t)repeat, sizeof(double));
    cpus = (double *)calloc((size_t)repeat, sizeof(double));
    if (rows == NULL || walls == NULL || cpus == NULL) return 5;
    lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (lib == NULL) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        return 2;
    }
    {
        LOAD(fmi2InstantiateTYPE *, fmi2Instantiate)
        LOAD(fmi2FreeInstanceTYPE *, fmi2FreeInstance)
        LOAD(fmi2SetupExperimentTYPE *, fmi2SetupExperiment)
        LOAD(fmi2EnterInitializationModeTYPE *, fmi2EnterInitializationMode)
        LOAD(fmi2ExitInitializationModeTYPE *, fmi2ExitInitializationMode)
        LOAD(fmi2TerminateTYPE *, fmi2Terminate)
        LOAD(fmi2SetRealTYPE *, fmi2SetReal)
        LOAD(fmi2SetIntegerTYPE *, fmi2SetInteger)
        LOAD(fmi2GetRealTYPE *, fmi2GetReal)
        LOAD(fmi2DoStepTYPE *, fmi2DoStep)

        for (r = 0; r < repeat; ++r) {
            double w0, c0;
            fmi2Component c = fmi2Instantiate("rtf", fmi2CoSimulation, argv[3], uri, &cb, fmi2False, fmi2False);
            if (c == NULL) {
                fprintf(stderr, "fmi2Instantiate failed\n");
                return 4;
            }
            CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2True, stop));
            CHECK(fmi2EnterInitializationMode(c));
            CHECK(fmi2SetReal(c, &vr_hmax, 1, &hmax));
            CHECK(fmi2SetInteger(c, &vr_int, 1, &integ));
            {
                int bad = set_start_values(c, fmi2SetReal, 12, argc, argv);
                if (bad) return bad;
            }
            CHECK(fmi2ExitInitializationMode(c));
            CHECK(fmi2GetReal(c, outs, (size_t)nout, rows));
            w0 = clock_s(CLOCK_MONOTONIC);
            c0 = clock_s(CLOCK_PROCESS_CPUTIME_ID);
            for (k = 1; k <= nsteps; ++k) {
                CHECK(fmi2DoStep(c, (k - 1) * step, step, fmi2True));
                CHECK(fmi2GetReal(c, outs, (size_t)nout, rows + (size_t)k * nout));
            }
            cpus[r] = clock_s(CLOCK_PROCESS_CPUTIME_ID) - c0;
            walls[r] = clock_s(CLOCK_MONOTONIC) - w0;
            CHECK(fmi2Terminate(c));
            fmi2FreeInstance(c);
        }
    }
    printf("{\"n_steps\": %d, \"wall_s\": [", nsteps);
    for (r = 0; r < repeat; ++r) printf("%s%.9g", r ? ", " : "", walls[r]);
    printf("], \"cpu_s\": [");
    for (r = 0; r < repeat; ++r) printf("%s%.9g", r ? ", " : "", cpus[r]);
    printf("]}\n");
    for (k = 0; k <= nsteps; ++k) {
        int i;
        for (i = 0; i < nout; ++i) printf("%s%.17g", i ? "," : "", rows[(size_t)k * nout + i]);
        printf("\n");
    }
    free(rows);
    free(walls);
    free(cpus);
    dlclose(lib);
    return 0;
}
