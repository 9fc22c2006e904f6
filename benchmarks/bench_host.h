/*
 * bench_host.h -- what the two C hosts of the benchmarks (fmu_rtf_host.c, fmu_layers.c)
 * share: the FMI logger that prints to stderr, a clock reading in seconds, and the
 * parsing of a comma-separated list of value references.  Include after fmi2Functions.h.
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

#endif
