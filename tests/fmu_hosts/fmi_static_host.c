/*
 * fmi_static_host.c -- two gear FMUs compiled from their sources/ into one program, the way a
 * real-time or HIL target imports source-code FMUs (tests/fmu_hosts/test_source_fmus.py).
 *
 * Each FMU's one translation unit (sources/fmi2_all.c or fmi3_all.c) is compiled by the test
 * with FMIx_FUNCTION_PREFIX=<its modelIdentifier>_ and the standard's unmodified headers, which
 * turn fmi2DoStep into <id>_fmi2DoStep (FMI 2.0.5 section 2.1.1, FMI 3.0 section 2.2.2); this
 * host is compiled with FMU_A and FMU_B set to the two identifiers (and FMI_VERSION 2 or 3) and
 * linked with both objects.  A symbol defined by both objects would fail that link.
 *
 * usage: fmi_static_host <dir A> <token A> <dir B> <token B> <stop_time_s> <step_s>
 *                        <output vrs, comma separated>
 *
 * Runs both FMUs side by side (their steps interleaved) and prints, per FMU, "fmu <A|B>" then
 * "time,<vr>,..." and one CSV row per communication point (%.17g), the format of
 * tests/fmu_hosts/fmi_host.c.  Exit code 0 only if every call returned OK.
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PASTE_(a, b) a##b
#define PASTE(a, b) PASTE_(a, b)

#if FMI_VERSION == 3
#include "fmi3FunctionTypes.h"
#define DECLARE(P)                                                                                   \
    extern fmi3InstantiateCoSimulationTYPE PASTE(P, _fmi3InstantiateCoSimulation);                   \
    extern fmi3EnterInitializationModeTYPE PASTE(P, _fmi3EnterInitializationMode);                   \
    extern fmi3ExitInitializationModeTYPE PASTE(P, _fmi3ExitInitializationMode);                     \
    extern fmi3GetFloat64TYPE PASTE(P, _fmi3GetFloat64);                                             \
    extern fmi3DoStepTYPE PASTE(P, _fmi3DoStep);                                                     \
    extern fmi3TerminateTYPE PASTE(P, _fmi3Terminate);                                               \
    extern fmi3FreeInstanceTYPE PASTE(P, _fmi3FreeInstance);
typedef struct {
    fmi3InstantiateCoSimulationTYPE *instantiate;
    fmi3EnterInitializationModeTYPE *enter;
    fmi3ExitInitializationModeTYPE *exit_init;
    fmi3GetFloat64TYPE *get;
    fmi3DoStepTYPE *step;
    fmi3TerminateTYPE *terminate;
    fmi3FreeInstanceTYPE *free_instance;
    fmi3Instance c;
} fmu_t;
#define FUNCTIONS(P)                                                                                 \
    {PASTE(P, _fmi3InstantiateCoSimulation), PASTE(P, _fmi3EnterInitializationMode),                 \
     PASTE(P, _fmi3ExitInitializationMode), PASTE(P, _fmi3GetFloat64), PASTE(P, _fmi3DoStep),        \
     PASTE(P, _fmi3Terminate), PASTE(P, _fmi3FreeInstance), NULL}

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message)
{
    fprintf(stderr, "[%s %d %s] %s\n", (const char *)env, (int)status, category ? category : "?", message);
}
#else
#include "fmi2FunctionTypes.h"
#define DECLARE(P)                                                                                   \
    extern fmi2InstantiateTYPE PASTE(P, _fmi2Instantiate);                                           \
    extern fmi2SetupExperimentTYPE PASTE(P, _fmi2SetupExperiment);                                   \
    extern fmi2EnterInitializationModeTYPE PASTE(P, _fmi2EnterInitializationMode);                   \
    extern fmi2ExitInitializationModeTYPE PASTE(P, _fmi2ExitInitializationMode);                     \
    extern fmi2GetRealTYPE PASTE(P, _fmi2GetReal);                                                   \
    extern fmi2DoStepTYPE PASTE(P, _fmi2DoStep);                                                     \
    extern fmi2TerminateTYPE PASTE(P, _fmi2Terminate);                                               \
    extern fmi2FreeInstanceTYPE PASTE(P, _fmi2FreeInstance);
typedef struct {
    fmi2InstantiateTYPE *instantiate;
    fmi2SetupExperimentTYPE *setup;
    fmi2EnterInitializationModeTYPE *enter;
    fmi2ExitInitializationModeTYPE *exit_init;
    fmi2GetRealTYPE *get;
    fmi2DoStepTYPE *step;
    fmi2TerminateTYPE *terminate;
    fmi2FreeInstanceTYPE *free_instance;
    fmi2Component c;
} fmu_t;
#define FUNCTIONS(P)                                                                                 \
    {PASTE(P, _fmi2Instantiate), PASTE(P, _fmi2SetupExperiment), PASTE(P, _fmi2EnterInitializationMode), \
     PASTE(P, _fmi2ExitInitializationMode), PASTE(P, _fmi2GetReal), PASTE(P, _fmi2DoStep),          \
     PASTE(P, _fmi2Terminate), PASTE(P, _fmi2FreeInstance), NULL}

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...)
{
    va_list ap;
    (void)env;
    fprintf(stderr, "[%s %d %s] ", name ? name : "?", (int)status, category ? category : "?");
    va_start(ap, message);
    vfprintf(stderr, message, ap);
    va_end(ap);
    fputc('\n', stderr);
}
#endif

DECLARE(FMU_A)
DECLARE(FMU_B)

#define CHECK(call)                                                           \
    do {                                                                      \
        int st_ = (int)(call);                                                \
        if (st_ != 0) {                                                       \
            fprintf(stderr, "%s returned %d\n", #call, st_);                  \
            return 3;                                                         \
        }                                                                     \
    } while (0)

int main(int argc, char **argv)
{
    fmu_t fmu[2] = {FUNCTIONS(FMU_A), FUNCTIONS(FMU_B)};
    static const char *const names[2] = {"A", "B"};
    unsigned int outs[256];
    int nout = 0, i, j, k, nsteps;
    double stop, step, *rows[2];
    char *p;
    if (argc != 8) {
        fprintf(stderr, "usage: %s dirA tokenA dirB tokenB stop step vrs\n", argv[0]);
        return 1;
    }
    stop = atof(argv[5]);
    step = atof(argv[6]);
    for (p = argv[7]; *p != '\0' && nout < 256;) {
        outs[nout++] = (unsigned int)strtoul(p, &p, 10);
        if (*p == ',') p++;
    }
    nsteps = (int)(stop / step + 0.5);
    for (j = 0; j < 2; ++j) {
        const char *dir = argv[1 + 2 * j], *token = argv[2 + 2 * j];
        char res[4200];
        rows[j] = (double *)calloc((size_t)(nsteps + 1) * (size_t)nout, sizeof(double));
        if (rows[j] == NULL) return 5;
#if FMI_VERSION == 3
        snprintf(res, sizeof res, "%s/resources/", dir);
        fmu[j].c = fmu[j].instantiate(names[j], token, res, fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0,
                                      (void *)names[j], logger, NULL);
        if (fmu[j].c == NULL) return 4;
        CHECK(fmu[j].enter(fmu[j].c, fmi3False, 0.0, 0.0, fmi3True, stop));
        CHECK(fmu[j].exit_init(fmu[j].c));
        CHECK(fmu[j].get(fmu[j].c, outs, (size_t)nout, rows[j], (size_t)nout));
#else
        {
            fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
            snprintf(res, sizeof res, "file://%s/resources", dir);
            fmu[j].c = fmu[j].instantiate(names[j], fmi2CoSimulation, token, res, &cb, fmi2False, fmi2False);
        }
        if (fmu[j].c == NULL) return 4;
        CHECK(fmu[j].setup(fmu[j].c, fmi2False, 0.0, 0.0, fmi2True, stop));
        CHECK(fmu[j].enter(fmu[j].c));
        CHECK(fmu[j].exit_init(fmu[j].c));
        CHECK(fmu[j].get(fmu[j].c, outs, (size_t)nout, rows[j]));
#endif
    }
    for (k = 1; k <= nsteps; ++k) {
        for (j = 0; j < 2; ++j) {  /* interleaved: A's step k, then B's */
#if FMI_VERSION == 3
            fmi3Boolean event, terminate, early;
            fmi3Float64 last;
            CHECK(fmu[j].step(fmu[j].c, (k - 1) * step, step, fmi3True, &event, &terminate, &early, &last));
            CHECK(fmu[j].get(fmu[j].c, outs, (size_t)nout, rows[j] + (size_t)k * nout, (size_t)nout));
#else
            CHECK(fmu[j].step(fmu[j].c, (k - 1) * step, step, fmi2True));
            CHECK(fmu[j].get(fmu[j].c, outs, (size_t)nout, rows[j] + (size_t)k * nout));
#endif
        }
    }
    for (j = 0; j < 2; ++j) {
        CHECK(fmu[j].terminate(fmu[j].c));
        fmu[j].free_instance(fmu[j].c);
        printf("fmu %s\ntime", names[j]);
        for (i = 0; i < nout; ++i) printf(",%u", outs[i]);
        printf("\n");
        for (k = 0; k <= nsteps; ++k) {
            printf("%.17g", k * step);
            for (i = 0; i < nout; ++i) printf(",%.17g", rows[j][(size_t)k * nout + i]);
            printf("\n");
        }
        free(rows[j]);
    }
    return 0;
}
