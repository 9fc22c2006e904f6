/*
 * fmi3_host.c -- a minimal FMI 3.0 Co-Simulation master in plain C (no Python
 * in the process), used by tests/fmu_hosts/test_fmi3.py for the standalone gearfmu FMU:
 *
 *   fmi3_host run <unzipped FMU dir> <modelIdentifier> <token> <stop_time_s> <step_s>
 *                 <output vrs, comma separated> <number of values> [--state-check]
 *       The FMI 3.0 calling sequence (standard section 4.2: instantiate ->
 *       enter/exit initialization mode -> doStep... -> terminate -> free).
 *       Prints "time,<n values>" then one CSV row per communication point
 *       (%.17g; the outputs of one fmi3GetFloat64 call over all vrs, arrays
 *       included).  --state-check: at the middle of the run get the FMU state,
 *       serialize and deserialize it, run to the end, restore the deserialized
 *       state, run the second half again and print "state-check ok" if both
 *       halves agree bit for bit.  Exit code 0 only if every call returned fmi3OK.
 *
 *   fmi3_host fuzz <unzipped FMU dir> <modelIdentifier> <token> <first_seed> <sequences>
 *       Random call orders: per sequence fmi3InstantiateCoSimulation
 *       (sometimes with a wrong token), a call the Instantiated state forbids,
 *       then 5..60 calls drawn from the Co-Simulation functions (a third of
 *       them in the legal order, so that deep states are reached) with valid
 *       and invalid value references, NaN/inf values, bad step sizes, NULL
 *       arrays, FMU states got/set/serialized/deserialized (also truncated),
 *       then the held states and the instance are freed.  Checked per call:
 *       the status is one of fmi3OK..fmi3Fatal, and a status other than
 *       fmi3OK/fmi3Warning logged a message.  Prints one line
 *       "sequences=.. calls=.. refused=.. illegal_first=.. unlogged=.. bad_status=..
 *       steps_ok=..".
 *       Exit code 0 when the run finished (whatever it counted).
 *
 * The binary loaded is binaries/<FMI 3 platform tuple>/<id>.<ext> for the
 * platform this host is compiled for: x86_64-linux, aarch64-linux,
 * x86_64-windows (.dll, LoadLibrary; the FMU dir is a Windows path under
 * Wine), x86_64-darwin / aarch64-darwin (.dylib).
 */
#ifdef _WIN32
#define __USE_MINGW_ANSI_STDIO 1 /* correctly rounded %.17g with any C runtime */
#include <windows.h>
#define FMU_BIN "x86_64-windows"
#define FMU_EXT ".dll"
#define SEP "\\"
typedef HMODULE lib_t;
#define LIB_SYM(lib, name) ((void *)GetProcAddress((lib), (name)))
#else
#include <dlfcn.h>
#define SEP "/"
#if defined(__APPLE__) && defined(__aarch64__)
#define FMU_BIN "aarch64-darwin"
#define FMU_EXT ".dylib"
#elif defined(__APPLE__)
#define FMU_BIN "x86_64-darwin"
#define FMU_EXT ".dylib"
#elif defined(__aarch64__)
#define FMU_BIN "aarch64-linux"
#define FMU_EXT ".so"
#else
#define FMU_BIN "x86_64-linux"
#define FMU_EXT ".so"
#endif
typedef void *lib_t;
#define LIB_SYM(lib, name) dlsym((lib), (name))
#endif
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"

static long n_logged;
static int quiet;

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message)
{
    (void)env;
    n_logged++;
    if (!quiet) fprintf(stderr, "[%d %s] %s\n", (int)status, category ? category : "?", message ? message : "");
}

#define FN(name) static name##TYPE *name##_
FN(fmi3InstantiateCoSimulation); FN(fmi3FreeInstance); FN(fmi3EnterInitializationMode);
FN(fmi3ExitInitializationMode); FN(fmi3DoStep); FN(fmi3Terminate); FN(fmi3Reset); FN(fmi3GetFloat64);
FN(fmi3SetFloat64); FN(fmi3GetInt32); FN(fmi3SetInt32); FN(fmi3GetFMUState); FN(fmi3SetFMUState);
FN(fmi3FreeFMUState); FN(fmi3SerializedFMUStateSize); FN(fmi3SerializeFMUState); FN(fmi3DeserializeFMUState);
FN(fmi3EnterEventMode); FN(fmi3EnterStepMode); FN(fmi3GetBoolean); FN(fmi3SetDebugLogging);
FN(fmi3EnterConfigurationMode); FN(fmi3UpdateDiscreteStates); FN(fmi3GetOutputDerivatives);

static int load(const char *dir, const char *id)
{
    char path[4096];
    lib_t lib;
    snprintf(path, sizeof path, "%s" SEP "binaries" SEP FMU_BIN SEP "%s" FMU_EXT, dir, id);
#ifdef _WIN32
    lib = LoadLibraryA(path);
#else
    lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
#endif
    if (lib == NULL) {
        fprintf(stderr, "cannot load %s\n", path);
        return 0;
    }
#define L(name) if ((name##_ = (name##TYPE *)LIB_SYM(lib, #name)) == NULL) { fprintf(stderr, "no %s\n", #name); return 0; }
    L(fmi3InstantiateCoSimulation) L(fmi3FreeInstance) L(fmi3EnterInitializationMode) L(fmi3ExitInitializationMode)
    L(fmi3DoStep) L(fmi3Terminate) L(fmi3Reset) L(fmi3GetFloat64) L(fmi3SetFloat64) L(fmi3GetInt32) L(fmi3SetInt32)
    L(fmi3GetFMUState) L(fmi3SetFMUState) L(fmi3FreeFMUState) L(fmi3SerializedFMUStateSize) L(fmi3SerializeFMUState)
    L(fmi3DeserializeFMUState) L(fmi3EnterEventMode) L(fmi3EnterStepMode) L(fmi3GetBoolean) L(fmi3SetDebugLogging)
    L(fmi3EnterConfigurationMode) L(fmi3UpdateDiscreteStates) L(fmi3GetOutputDerivatives)
#undef L
    return 1;
}

static fmi3Instance instantiate(const char *dir, const char *token)
{
    char res[4096];
    snprintf(res, sizeof res, "%s" SEP "resources" SEP, dir);
    return fmi3InstantiateCoSimulation_("gear", token, res, fmi3False, fmi3True, fmi3False, fmi3False, NULL, 0,
                                        NULL, logger, NULL);
}

/* ------------------------------------------------------------------ run */
static int step(fmi3Instance c, double t, double h)
{
    fmi3Boolean ev, term, early;
    fmi3Float64 last;
    return fmi3DoStep_(c, t, h, fmi3False, &ev, &term, &early, &last) == fmi3OK && last == t + h;
}

static int run(int argc, char **argv)
{
    const char *dir = argv[2], *id = argv[3], *token = argv[4];
    double stop = atof(argv[5]), h = atof(argv[6]);
    fmi3ValueReference vrs[64];
    size_t nvr = 0, nval = (size_t)atol(argv[8]), i, k;
    long n = (long)floor(stop / h + 0.5), s, mid;
    int check = argc > 9 && strcmp(argv[9], "--state-check") == 0;
    double *rows, *again;
    char *p = argv[7];
    fmi3Instance c;
    while (*p && nvr < 64) {
        vrs[nvr++] = (fmi3ValueReference)strtoul(p, &p, 10);
        if (*p == ',') p++;
    }
    if (!load(dir, id)) return 2;
    c = instantiate(dir, token);
    if (c == NULL) return 3;
    rows = (double *)calloc((size_t)(n + 1) * nval, sizeof(double));
    again = (double *)calloc((size_t)(n + 1) * nval, sizeof(double));
    if (fmi3EnterInitializationMode_(c, fmi3False, 0.0, 0.0, fmi3True, stop) != fmi3OK) return 4;
    if (fmi3ExitInitializationMode_(c) != fmi3OK) return 5;
    if (fmi3GetFloat64_(c, vrs, nvr, rows, nval) != fmi3OK) return 6;
    mid = n / 2;
    {
        fmi3FMUState st = NULL, st2 = NULL;
        size_t sz = 0;
        fmi3Byte *buf = NULL;
        for (s = 0; s < n; ++s) {
            if (check && s == mid) {
                if (fmi3GetFMUState_(c, &st) != fmi3OK || fmi3SerializedFMUStateSize_(c, st, &sz) != fmi3OK) return 7;
                buf = (fmi3Byte *)malloc(sz);
                if (fmi3SerializeFMUState_(c, st, buf, sz) != fmi3OK) return 7;
                if (fmi3FreeFMUState_(c, &st) != fmi3OK || fmi3DeserializeFMUState_(c, buf, sz, &st2) != fmi3OK)
                    return 7;
            }
            if (!step(c, s * h, h)) return 8;
            if (fmi3GetFloat64_(c, vrs, nvr, rows + (size_t)(s + 1) * nval, nval) != fmi3OK) return 6;
        }
        if (check) {
            if (fmi3SetFMUState_(c, st2) != fmi3OK) return 9;
            for (s = mid; s < n; ++s) {
                if (!step(c, s * h, h)) return 8;
                if (fmi3GetFloat64_(c, vrs, nvr, again + (size_t)(s + 1) * nval, nval) != fmi3OK) return 6;
            }
            if (memcmp(rows + (size_t)(mid + 1) * nval, again + (size_t)(mid + 1) * nval,
                       sizeof(double) * (size_t)(n - mid) * nval) != 0) {
                fprintf(stderr, "state-check: the second half differs after restoring the state\n");
                return 10;
            }
            fmi3FreeFMUState_(c, &st2);
            free(buf);
        }
    }
    printf("time,%lu\n", (unsigned long)nval);
    for (s = 0; s <= n; ++s) {
        printf("%.17g", s * h);
        for (k = 0; k < nval; ++k) printf(",%.17g", rows[(size_t)s * nval + k]);
        printf("\n");
    }
    if (check) printf("state-check ok\n");
    if (fmi3Terminate_(c) != fmi3OK) return 11;
    fmi3FreeInstance_(c);
    free(rows);
    free(again);
    (void)i;
    return 0;
}

/* ----------------------------------------------------------------- fuzz */
static uint64_t rng_state;
static uint64_t rnd(void)
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return rng_state * 2685821657736338717ull;
}
static int rint_(int n) { return (int)(rnd() % (uint64_t)n); }

static double nasty(void)
{
    static const double v[] = {0.0, -1.0, 1e6, -1e6, 1e308, 1e-308, 100.0, 0.05, 200.0, 50.0, 1e-5};
    int k = rint_(14);
    if (k == 11) return NAN;
    if (k == 12) return INFINITY;
    if (k == 13) return -INFINITY;
    return v[k];
}

static long calls, refused, unlogged, bad_status, steps_ok;

static void check(int st, long before)
{
    calls++;
    if (st < (int)fmi3OK || st > (int)fmi3Fatal) bad_status++;
    if (st != fmi3OK && st != fmi3Warning) {
        refused++;
        if (n_logged == before) unlogged++;
    }
}

#define CALL(expr) do { long b_ = n_logged; check((int)(expr), b_); } while (0)

static int fuzz(char **argv)
{
    const char *dir = argv[2], *id = argv[3], *token = argv[4];
    long seed = atol(argv[5]), nseq = atol(argv[6]), q, sequences = 0, illegal_first = 0;
    quiet = 1;
    if (!load(dir, id)) return 2;
    for (q = 0; q < nseq; ++q) {
        fmi3Instance c;
        fmi3FMUState held[4] = {NULL, NULL, NULL, NULL};
        fmi3Byte buf[8192];
        size_t bufn = 0;
        double t = 0.0;
        int i, n, h;
        rng_state = (uint64_t)(seed + q) * 0x9E3779B97F4A7C15ull + 1;
        sequences++;
        c = instantiate(dir, rint_(10) == 0 ? "{wrong-token}" : token);
        if (c == NULL) continue;
        {   /* a call the Instantiated state forbids */
            long b = n_logged;
            fmi3Boolean ev, term, early;
            fmi3Float64 last;
            int st = rint_(2) ? fmi3DoStep_(c, 0.0, 1e-4, fmi3False, &ev, &term, &early, &last)
                              : fmi3ExitInitializationMode_(c);
            check(st, b);
            if (st == fmi3Error) illegal_first++;
        }
        n = 5 + rint_(56);
        for (i = 0; i < n; ++i) {
            int k = rint_(3) == 0 ? i % 5 : rint_(22);
            fmi3ValueReference vr[4];
            double v[64];
            fmi3Int32 iv[4];
            fmi3Boolean ev, term, early;
            fmi3Float64 last;
            for (h = 0; h < 4; ++h) vr[h] = (fmi3ValueReference)(rint_(5) == 0 ? rint_(100000) : rint_(24));
            for (h = 0; h < 64; ++h) v[h] = nasty();
            for (h = 0; h < 4; ++h) iv[h] = rint_(4) - 1;
            switch (k) {
            case 0: CALL(fmi3EnterInitializationMode_(c, fmi3False, 0.0, rint_(8) ? 0.0 : nasty(), fmi3False, 0.0)); break;
            case 1: CALL(fmi3ExitInitializationMode_(c)); break;
            case 2: case 3: {
                /* bad step sizes, but none of many substeps (a legal long step is work, not a fault) */
                static const double bad_h[] = {0.0, -1e-4, 1e-200, 5e-324, NAN, INFINITY, -INFINITY, 2e-5};
                double hh = rint_(5) ? 1e-4 : bad_h[rint_(8)];
                long b = n_logged;
                int st = fmi3DoStep_(c, t, hh, fmi3False, &ev, &term, &early, &last);
                check(st, b);
                if (st == fmi3OK) steps_ok++;
                t += 1e-4;
                break;
            }
            case 4: CALL(fmi3GetFloat64_(c, vr, (size_t)(1 + rint_(4)), v, (size_t)rint_(64))); break;
            case 5: CALL(fmi3SetFloat64_(c, vr, (size_t)(1 + rint_(2)), v, (size_t)rint_(4))); break;
            case 6: CALL(fmi3GetInt32_(c, vr, 1, iv, 1)); break;
            case 7: CALL(fmi3SetInt32_(c, vr, 1, iv, 1)); break;
            case 8: CALL(fmi3GetFloat64_(c, rint_(2) ? NULL : vr, 2, rint_(2) ? NULL : v, 2)); break;
            case 9: CALL(fmi3GetFMUState_(c, &held[rint_(4)])); break;
            case 10: { fmi3FMUState s = held[rint_(4)]; if (s != NULL || rint_(2)) CALL(fmi3SetFMUState_(c, s)); break; }
            case 11: { int j = rint_(4); CALL(fmi3FreeFMUState_(c, &held[j])); break; }
            case 12: {
                fmi3FMUState s = held[rint_(4)];
                size_t sz = 0;
                if (s != NULL) {
                    CALL(fmi3SerializedFMUStateSize_(c, s, &sz));
                    if (sz <= sizeof buf) { CALL(fmi3SerializeFMUState_(c, s, buf, sz)); bufn = sz; }
                }
                break;
            }
            case 13: {
                int j = rint_(4);
                size_t sz = bufn;
                if (rint_(3) == 0 && sz > 0) sz = (size_t)rint_((int)sz);     /* truncated */
                if (rint_(4) == 0 && bufn > 16) buf[rint_((int)bufn)] ^= 0x5a; /* corrupted */
                CALL(fmi3DeserializeFMUState_(c, buf, sz, &held[j]));
                break;
            }
            case 14: CALL(fmi3Terminate_(c)); break;
            case 15: CALL(fmi3Reset_(c)); t = 0.0; break;
            case 16: CALL(fmi3EnterEventMode_(c)); break;
            case 17: CALL(fmi3EnterStepMode_(c)); break;
            case 18: { fmi3Boolean b[2]; CALL(fmi3GetBoolean_(c, vr, 1, b, 1)); break; }
            case 19: CALL(fmi3SetDebugLogging_(c, (fmi3Boolean)rint_(2), 0, NULL)); break;
            case 20: CALL(fmi3EnterConfigurationMode_(c)); break;
            default: {
                fmi3Int32 ord[1] = {1};
                CALL(fmi3GetOutputDerivatives_(c, vr, 1, ord, v, 1));
                break;
            }
            }
        }
        for (h = 0; h < 4; ++h)
            if (held[h] != NULL) fmi3FreeFMUState_(c, &held[h]);
        fmi3FreeInstance_(c);
    }
    printf("sequences=%ld calls=%ld refused=%ld illegal_first=%ld unlogged=%ld bad_status=%ld steps_ok=%ld\n",
           sequences, calls, refused, illegal_first, unlogged, bad_status, steps_ok);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc >= 9 && strcmp(argv[1], "run") == 0) return run(argc, argv);
    if (argc >= 7 && strcmp(argv[1], "fuzz") == 0) return fuzz(argv);
    fprintf(stderr, "usage: fmi3_host run DIR ID TOKEN STOP STEP VRS NVALUES [--state-check] | "
                    "fmi3_host fuzz DIR ID TOKEN FIRST_SEED SEQUENCES\n");
    return 1;
}
