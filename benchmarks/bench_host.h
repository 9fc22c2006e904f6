/*
 * bench_host.h -- what the two C hosts of the benchmarks (fmu_rtf_host.c, fmu_layers.c)
 * share: the FMI logger that prints to stderr, the status check of an FMI call, a clock
 * reading in seconds, the parsing of a comma-separated list of value references, and the
 * setting of the `vr=value` start values.  Include after fmi2Functions.h.
 */
#ifndef GEARFMU_BENCH_HOST_H
#define GEARFMU_BENCH_HOST_H

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

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

/* an FMI call that does not return fmi2OK ends the host (exit code 3) */
#define CHECK(call)                                                           \
    do {                                                                      \
        fmi2Status st_ = (call);                                              \
        if (st_ != fmi2OK) {                                                  \
            fprintf(stderr, "%s returned %d\n", #call, (int)st_);             \
            return 3;                                                         \
        }                                                                     \
    } while (0)

/* the clock `clk` in seconds */
static double clock_s(clockid_t clk)
{
    struct timespec ts;
    clock_gettime(clk, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* value references of a comma-separated list into outs (at most max); their number */
static int parse_vrs(const char *list, fmi2ValueReference *outs, int max)
{
    char *p = (char *)list;
    int n = 0;
    while (*p != '\0' && n < max) {
        outs[n++] = (fmi2ValueReference)strtoul(p, &p, 10);
        if (*p == ',') p++;
    }
    return n;
}

/* the start values argv[first..argc-1], each `vr=value`, set with set_real on c; 0, 1 for an
 * argument that is not `vr=value`, 3 for a call that did not return fmi2OK */
static int set_start_values(fmi2Component c, fmi2SetRealTYPE *set_real, int first, int argc, char **argv)
{
    int argi;
    for (argi = first; argi < argc; ++argi) {
        char *p;
        fmi2ValueReference vr = (fmi2ValueReference)strtoul(argv[argi], &p, 10);
        fmi2Real v;
        if (*p != '=') return 1;
        v = atof(p + 1);
        CHECK(set_real(c, &vr, 1, &v));
    }
    return 0;
}

#endif
