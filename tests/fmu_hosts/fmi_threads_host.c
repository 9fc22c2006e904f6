/*
 * fmi_threads_host.c -- a plain C FMI 2.0 Co-Simulation master that runs
 * several FMUs at once, one thread each, used by tests/fmu_hosts/test_pyshim.py.
 * Every FMU's binary is loaded first; then all threads wait at a barrier and
 * call fmi2Instantiate at the same moment (the calling sequence of the FMI 2.0
 * standard, section 4.2: instantiate -> setupExperiment -> enter/exit
 * initialization -> doStep... -> terminate -> freeInstance).
 *
 * usage: fmi_threads_host <n_steps> <step_s> <output vr> <dir> <id> <guid> [<dir> <id> <guid> ...]
 *
 * Prints one line "<k> <output after the last step, %.17g>" per FMU; exit
 * code 0 only if every FMI call of every thread returned fmi2OK.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#define MAX_FMUS 8

typedef struct {
    const char *dir, *id, *guid;
    void *lib;
    int n_steps, rc;
    double step, result;
    fmi2ValueReference vr;
} job;

static pthread_barrier_t barrier;

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

#define SYM(T, name) T *name = (T *)dlsym(j->lib, #name)
#define CHECK(call)                                                            \
    if ((call) != fmi2OK) {                                                    \
        fprintf(stderr, "%s: %s failed\n", j->id, #call);                      \
        j->rc = 3;                                                             \
        return NULL;                                                           \
    }

static void *run(void *arg)
{
    job *j = (job *)arg;
    char uri[4200];
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2Component c;
    int k;
    SYM(fmi2InstantiateTYPE, fmi2Instantiate);
    SYM(fmi2FreeInstanceTYPE, fmi2FreeInstance);
    SYM(fmi2SetupExperimentTYPE, fmi2SetupExperiment);
    SYM(fmi2EnterInitializationModeTYPE, fmi2EnterInitializationMode);
    SYM(fmi2ExitInitializationModeTYPE, fmi2ExitInitializationMode);
    SYM(fmi2TerminateTYPE, fmi2Terminate);
    SYM(fmi2GetRealTYPE, fmi2GetReal);
    SYM(fmi2DoStepTYPE, fmi2DoStep);
    if (!fmi2Instantiate || !fmi2FreeInstance || !fmi2SetupExperiment || !fmi2EnterInitializationMode ||
        !fmi2ExitInitializationMode || !fmi2Terminate || !fmi2GetReal || !fmi2DoStep) {
        fprintf(stderr, "%s: missing fmi2 symbol\n", j->id);
        j->rc = 2;
        pthread_barrier_wait(&barrier);
        return NULL;
    }
    snprintf(uri, sizeof uri, "file://%s/resources", j->dir);
    pthread_barrier_wait(&barrier);
    c = fmi2Instantiate(j->id, fmi2CoSimulation, j->guid, uri, &cb, fmi2False, fmi2False);
    if (c == NULL) {
        fprintf(stderr, "%s: fmi2Instantiate failed\n", j->id);
        j->rc = 4;
        return NULL;
    }
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0))
    CHECK(fmi2EnterInitializationMode(c))
    CHECK(fmi2ExitInitializationMode(c))
    for (k = 0; k < j->n_steps; ++k) CHECK(fmi2DoStep(c, k * j->step, j->step, fmi2True))
    CHECK(fmi2GetReal(c, &j->vr, 1, &j->result))
    CHECK(fmi2Terminate(c))
    fmi2FreeInstance(c);
    j->rc = 0;
    return NULL;
}

int main(int argc, char **argv)
{
    job jobs[MAX_FMUS];
    pthread_t threads[MAX_FMUS];
    int n = (argc - 4) / 3, i, rc = 0;
    char path[4200];
    if (argc < 7 || (argc - 4) % 3 != 0 || n > MAX_FMUS) {
        fprintf(stderr, "usage: %s n_steps step vr dir id guid [dir id guid ...]\n", argv[0]);
        return 1;
    }
    for (i = 0; i < n; ++i) {
        job *j = &jobs[i];
        memset(j, 0, sizeof *j);
        j->n_steps = atoi(argv[1]);
        j->step = atof(argv[2]);
        j->vr = (fmi2ValueReference)strtoul(argv[3], NULL, 10);
        j->dir = argv[4 + 3 * i];
        j->id = argv[5 + 3 * i];
        j->guid = argv[6 + 3 * i];
        j->rc = 1;
        snprintf(path, sizeof path, "%s/binaries/linux64/%s.so", j->dir, j->id);
        j->lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
        if (j->lib == NULL) {
            fprintf(stderr, "dlopen: %s\n", dlerror());
            return 2;
        }
    }
    pthread_barrier_init(&barrier, NULL, (unsigned)n);
    for (i = 0; i < n; ++i) pthread_create(&threads[i], NULL, run, &jobs[i]);
    for (i = 0; i < n; ++i) pthread_join(threads[i], NULL);
    for (i = 0; i < n; ++i) {
        printf("%d %.17g\n", i, jobs[i].result);
        if (jobs[i].rc != 0) rc = jobs[i].rc;
    }
    return rc;
}
