/*
 * fmi_fuzz.c -- a C host that throws random FMI 2.0 call sequences at an FMU
 * binary, many sequences in one process (tests/fmu_hosts/fuzz_fmu.py runs it in a child
 * process, so that a crash is counted as a crash).
 *
 * usage: fmi_fuzz <unzipped FMU dir> <modelIdentifier> <guid> <n_vars> <first_seed> <sequences> [<n_states>]
 * (n_states: the Model Exchange state count the state vectors have, 4 when not given, at most FZ_MAX_STATES)
 *
 * Every sequence: fmi2Instantiate (sometimes with a wrong GUID; a quarter of them for Model
 * Exchange), then 5..60 calls drawn from all fmi2 functions of Co-Simulation and Model
 * Exchange, in any order: the
 * first one is always a call the instantiated state forbids, then about a
 * third of the draws follow the legal order of the instance's interface (so that deep states
 * are reached; Model Exchange: event and continuous-time mode, states set, derivatives and
 * event indicators read with right and wrong array lengths and NULL arrays),
 * with valid and invalid value references, NaN/inf/huge/negative values, bad
 * step sizes, NULL arrays, FMU states got/set/freed/serialized, serialized
 * states truncated or corrupted, then fmi2FreeFMUstate of what is held and
 * fmi2FreeInstance.  Calls that the standard leaves undefined for the host
 * (a freed or NULL component) are not made.
 *
 * Checked per call: the status is one of fmi2OK..fmi2Fatal, and a status other
 * than fmi2OK/fmi2Warning logged at least one message during the call.  Prints
 * "done <seed>" after every sequence, then one JSON line: sequences, calls,
 * refused, unlogged, ...
 * Exit code 0 when the run finished (whatever it counted).
 */
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

static long n_logged;           /* messages logged so far */
static long n_illegal_logged;   /* of which "illegal call sequence" */
static char last_msg[1200];

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...)
{
    va_list ap;
    (void)env; (void)name; (void)status; (void)category;
    va_start(ap, message);
    vsnprintf(last_msg, sizeof last_msg, message, ap); /* formats the FMU's printf-style message */
    va_end(ap);
    n_logged++;
    if (strstr(last_msg, "illegal call sequence") != NULL) n_illegal_logged++;
}

/* xorshift64*: reproducible from the seed */
static uint64_t rng_state;
static uint64_t rnd(void)
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return rng_state * 2685821657736338717ull;
}
static int rint_(int n) { return (int)(rnd() % (uint64_t)n); }

static double nasty_real(void)
{
    static const double v[] = {0.0, -0.0, -1.0, 1e6, -1e6, 1e308, -1e308, 1e-308, 5e-324, 100.0, 0.05, 200.0, 50.0};
    int k = rint_(16);
    if (k == 13) return NAN;
    if (k == 14) return INFINITY;
    if (k == 15) return -INFINITY;
    return v[k];
}

static double step_size(void)
{
    /* no step that is exactly GK_MAX_SUBSTEPS = 1e8 times a nasty max_step (1e-300 with 1e-308): that
     * is a legal step of 1e8 substeps, minutes of work, not a fault */
    static const double v[] = {1e-4, 1e-4, 1e-4, 2e-5, 1e-3, 0.0, -1e-4, 1e6, 1e-200, 5e-324, 1e308};
    int k = rint_(14);
    if (k == 11) return NAN;
    if (k == 12) return INFINITY;
    if (k == 13) return -INFINITY;
    return v[k];
}

typedef struct {
    fmi2InstantiateTYPE *Instantiate;
    fmi2FreeInstanceTYPE *FreeInstance;
    fmi2SetDebugLoggingTYPE *SetDebugLogging;
    fmi2SetupExperimentTYPE *SetupExperiment;
    fmi2EnterInitializationModeTYPE *EnterInitializationMode;
    fmi2ExitInitializationModeTYPE *ExitInitializationMode;
    fmi2TerminateTYPE *Terminate;
    fmi2ResetTYPE *Reset;
    fmi2GetRealTYPE *GetReal;
    fmi2GetIntegerTYPE *GetInteger;
    fmi2GetBooleanTYPE *GetBoolean;
    fmi2GetStringTYPE *GetString;
    fmi2SetRealTYPE *SetReal;
    fmi2SetIntegerTYPE *SetInteger;
    fmi2SetBooleanTYPE *SetBoolean;
    fmi2SetStringTYPE *SetString;
    fmi2GetFMUstateTYPE *GetFMUstate;
    fmi2SetFMUstateTYPE *SetFMUstate;
    fmi2FreeFMUstateTYPE *FreeFMUstate;
    fmi2SerializedFMUstateSizeTYPE *SerializedFMUstateSize;
    fmi2SerializeFMUstateTYPE *SerializeFMUstate;
    fmi2DeSerializeFMUstateTYPE *DeSerializeFMUstate;
    fmi2GetDirectionalDerivativeTYPE *GetDirectionalDerivative;
    fmi2SetRealInputDerivativesTYPE *SetRealInputDerivatives;
    fmi2GetRealOutputDerivativesTYPE *GetRealOutputDerivatives;
    fmi2DoStepTYPE *DoStep;
    fmi2CancelStepTYPE *CancelStep;
    fmi2GetStatusTYPE *GetStatus;
    fmi2GetRealStatusTYPE *GetRealStatus;
    fmi2GetIntegerStatusTYPE *GetIntegerStatus;
    fmi2GetBooleanStatusTYPE *GetBooleanStatus;
    fmi2GetStringStatusTYPE *GetStringStatus;
    fmi2EnterEventModeTYPE *EnterEventMode;
    fmi2NewDiscreteStatesTYPE *NewDiscreteStates;
    fmi2EnterContinuousTimeModeTYPE *EnterContinuousTimeMode;
    fmi2CompletedIntegratorStepTYPE *CompletedIntegratorStep;
    fmi2SetTimeTYPE *SetTime;
    fmi2SetContinuousStatesTYPE *SetContinuousStates;
    fmi2GetDerivativesTYPE *GetDerivatives;
    fmi2GetEventIndicatorsTYPE *GetEventIndicators;
    fmi2GetContinuousStatesTYPE *GetContinuousStates;
    fmi2GetNominalsOfContinuousStatesTYPE *GetNominalsOfContinuousStates;
} api;

static long calls, refused, unlogged, bad_status, discards, errors, fatals, warnings;
static char unlogged_example[200];

/* account for one call: status sanity, and a refusal must have logged */
static void account(const char *fn, int st, long logged_before)
{
    calls++;
    if (st < fmi2OK || st > fmi2Fatal) {
        bad_status++;
        return;
    }
    if (st == fmi2Warning) warnings++;
    if (st == fmi2Discard) discards++;
    if (st == fmi2Error) errors++;
    if (st == fmi2Fatal) fatals++;
    if (st >= fmi2Discard) {
        refused++;
        if (n_logged == logged_before) {
            unlogged++;
            if (unlogged_example[0] == '\0') snprintf(unlogged_example, sizeof unlogged_example, "%s -> %d", fn, st);
        }
    }
}

#define CALL(fn, ...)                                                          \
    do {                                                                       \
        long before_ = n_logged;                                               \
        int st_ = (int)f->fn(__VA_ARGS__);                                     \
        account(#fn, st_, before_);                                            \
    } while (0)

#define FZ_MAX_STATES 256

int main(int argc, char **argv)
{
    char path[4096], uri[4200];
    void *lib;
    api A, *f = &A;
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    int n_vars;
    long first_seed, n_seq, seq, inst_null = 0, seq_breaking = 0;
    int nx = 4;
    if (argc != 7 && argc != 8) {
        fprintf(stderr, "usage: fmi_fuzz <dir> <modelIdentifier> <guid> <n_vars> <first_seed> <sequences> [<n_states>]\n");
        return 2;
    }
    n_vars = atoi(argv[4]);
    first_seed = atol(argv[5]);
    n_seq = atol(argv[6]);
    if (argc == 8) nx = atoi(argv[7]);
    if (nx < 1 || nx > FZ_MAX_STATES) {
        fprintf(stderr, "n_states: %d not in 1..%d\n", nx, FZ_MAX_STATES);
        return 2;
    }
    snprintf(path, sizeof path, "%s/binaries/linux64/%s.so", argv[1], argv[2]);
    lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (lib == NULL) {
        fprintf(stderr, "dlopen %s: %s\n", path, dlerror());
        return 2;
    }
#define LOAD(name)                                                             \
    *(void **)(&A.name) = dlsym(lib, "fmi2" #name);                            \
    if (A.name == NULL) {                                                      \
        fprintf(stderr, "missing fmi2%s\n", #name);                            \
        return 2;                                                              \
    }
    LOAD(Instantiate) LOAD(FreeInstance) LOAD(SetDebugLogging) LOAD(SetupExperiment)
    LOAD(EnterInitializationMode) LOAD(ExitInitializationMode) LOAD(Terminate) LOAD(Reset)
    LOAD(GetReal) LOAD(GetInteger) LOAD(GetBoolean) LOAD(GetString)
    LOAD(SetReal) LOAD(SetInteger) LOAD(SetBoolean) LOAD(SetString)
    LOAD(GetFMUstate) LOAD(SetFMUstate) LOAD(FreeFMUstate) LOAD(SerializedFMUstateSize)
    LOAD(SerializeFMUstate) LOAD(DeSerializeFMUstate) LOAD(GetDirectionalDerivative)
    LOAD(SetRealInputDerivatives) LOAD(GetRealOutputDerivatives) LOAD(DoStep) LOAD(CancelStep)
    LOAD(GetStatus) LOAD(GetRealStatus) LOAD(GetIntegerStatus) LOAD(GetBooleanStatus) LOAD(GetStringStatus)
    LOAD(EnterEventMode) LOAD(NewDiscreteStates) LOAD(EnterContinuousTimeMode) LOAD(CompletedIntegratorStep)
    LOAD(SetTime) LOAD(SetContinuousStates) LOAD(GetDerivatives) LOAD(GetEventIndicators) LOAD(GetContinuousStates)
    LOAD(GetNominalsOfContinuousStates)
    snprintf(uri, sizeof uri, "file://%s/resources", argv[1]);

    for (seq = 0; seq < n_seq; ++seq) {
        fmi2Component c;
        fmi2FMUstate states[2] = {NULL, NULL};
        unsigned char *ser = NULL;
        size_t ser_size = 0;
        double t = 0.0;
        int len, k, legal = 0, me;
        double x[FZ_MAX_STATES];
        long illegal_before = n_illegal_logged, before = n_logged;
        rng_state = 0x9E3779B97F4A7C15ull ^ ((uint64_t)(first_seed + seq) * 0xD1B54A32D192ED03ull);
        if (rng_state == 0) rng_state = 1;
        rnd();
        /* the motor angle and speed, then small deviations and rates */
        for (k = 0; k < nx; ++k) x[k] = k == 1 ? 100.0 : (k % 2 == 0 && k > 0 ? 1e-5 : 0.0);
        me = rint_(4) == 0;
        c = f->Instantiate("fuzz", me ? fmi2ModelExchange : fmi2CoSimulation, rint_(50) == 0 ? "{wrong-guid}" : argv[3],
                           uri, &cb, fmi2False, rint_(2) ? fmi2True : fmi2False);
        if (c == NULL) {
            inst_null++;
            calls++;
            refused++;
            if (n_logged == before) unlogged++;
            continue;
        }
        len = 5 + rint_(56);
        for (k = 0; k < len; ++k) {
            int op;
            if (k == 0) { /* every sequence breaks the order at once: a call instantiated forbids */
                static const int first[] = {2, 3, 4, 8, 20, 21};
                op = first[rint_(6)];
            } else if (rint_(3) == 0) { /* about a third of the draws: the next call of the legal order */
                static const int order[] = {0, 1, 6, 2, 3, 8, 3, 8, 4};
                /* Model Exchange: initialization, event mode, continuous time (time, states, derivatives,
                 * indicators, completed step), back to event mode and on, read, terminate */
                static const int order_me[] = {0, 1, 6, 2, 28, 29, 30, 31, 32, 33, 34, 30, 31, 32, 35, 27, 28, 29, 8, 4};
                op = me ? order_me[legal % 20] : order[legal % 9];
                legal++;
            } else {
                op = rint_(38);
            }
            switch (op) {
            case 0: CALL(SetupExperiment, c, fmi2False, 0.0, rint_(4) ? 0.0 : nasty_real(), fmi2False, 0.0); break;
            case 1: CALL(EnterInitializationMode, c); break;
            case 2: CALL(ExitInitializationMode, c); break;
            case 3: {
                double H = step_size();
                CALL(DoStep, c, t, H, fmi2True);
                if (isfinite(H) && H > 0 && H < 1.0) t += H;
                break;
            }
            case 4: CALL(Terminate, c); break;
            case 5: if (rint_(3) == 0) CALL(Reset, c); break;
            case 6: case 7: {
                fmi2ValueReference vr[3];
                fmi2Real v[3];
                int i, n = 1 + rint_(3);
                for (i = 0; i < n; ++i) {
                    vr[i] = (fmi2ValueReference)(rint_(10) == 0 ? (unsigned)rnd() : (unsigned)rint_(n_vars + 2));
                    v[i] = nasty_real();
                }
                CALL(SetReal, c, vr, (size_t)n, v);
                break;
            }
            case 8: case 9: {
                fmi2ValueReference vr[4];
                fmi2Real v[4];
                int i, n = rint_(5);
                for (i = 0; i < n; ++i) vr[i] = (fmi2ValueReference)rint_(n_vars + 2);
                CALL(GetReal, c, vr, (size_t)n, v);
                break;
            }
            case 10: {
                fmi2ValueReference vr = (fmi2ValueReference)rint_(n_vars + 2);
                fmi2Integer v = rint_(4) - 1, out = 0;
                if (rint_(2)) CALL(SetInteger, c, &vr, 1, &v);
                else CALL(GetInteger, c, &vr, 1, &out);
                break;
            }
            case 11: {
                fmi2ValueReference vr = 0;
                fmi2Boolean b = fmi2False;
                fmi2String s = "x";
                size_t n = (size_t)rint_(2);
                switch (rint_(4)) {
                case 0: CALL(GetBoolean, c, &vr, n, &b); break;
                case 1: CALL(SetBoolean, c, &vr, n, &b); break;
                case 2: CALL(GetString, c, &vr, n, &s); break;
                default: CALL(SetString, c, &vr, n, &s); break;
                }
                break;
            }
            case 12: case 13: CALL(GetFMUstate, c, &states[rint_(2)]); break;
            case 14: {
                int i = rint_(2);
                if (states[i] != NULL) CALL(SetFMUstate, c, states[i]);
                break;
            }
            case 15: CALL(FreeFMUstate, c, &states[rint_(2)]); break;
            case 16: {
                int i = rint_(2);
                size_t n = 0;
                if (states[i] == NULL) break;
                CALL(SerializedFMUstateSize, c, states[i], &n);
                if (n > 0 && n < (1u << 24)) {
                    unsigned char *buf = (unsigned char *)malloc(n);
                    size_t give = rint_(5) == 0 ? n / 2 : n; /* sometimes too small */
                    if (buf == NULL) break;
                    CALL(SerializeFMUstate, c, states[i], (fmi2Byte *)buf, give);
                    if (give == n) {
                        free(ser);
                        ser = buf;
                        ser_size = n;
                    } else {
                        free(buf);
                    }
                }
                break;
            }
            case 17: {
                int i = rint_(2), how = rint_(4);
                size_t n = ser_size;
                if (ser == NULL) break;
                if (how == 1 && n > 0) ser[rint_((int)n)] ^= (unsigned char)(1 + rint_(255)); /* corrupt a byte */
                if (how == 2 && n > 0) n = (size_t)rint_((int)n);                           /* truncated */
                CALL(DeSerializeFMUstate, c, (const fmi2Byte *)ser, n, &states[i]);
                break;
            }
            case 18: {
                fmi2ValueReference u = 3, kn = 0;
                fmi2Real dv = 1.0, out = 0.0;
                CALL(GetDirectionalDerivative, c, &u, 1, &kn, 1, &dv, &out);
                break;
            }
            case 19: {
                fmi2ValueReference vr = 0;
                fmi2Integer order = 1;
                fmi2Real v = 0.0;
                size_t n = (size_t)rint_(2);
                if (rint_(2)) CALL(SetRealInputDerivatives, c, &vr, n, &order, &v);
                else CALL(GetRealOutputDerivatives, c, &vr, n, &order, &v);
                break;
            }
            case 20: CALL(CancelStep, c); break;
            case 21: {
                fmi2StatusKind kind = (fmi2StatusKind)rint_(4);
                fmi2Status s1;
                fmi2Real r;
                fmi2Integer iv;
                fmi2Boolean b;
                fmi2String str;
                switch (rint_(5)) {
                case 0: CALL(GetStatus, c, kind, &s1); break;
                case 1: CALL(GetRealStatus, c, kind, &r); break;
                case 2: CALL(GetIntegerStatus, c, kind, &iv); break;
                case 3: CALL(GetBooleanStatus, c, kind, &b); break;
                default: CALL(GetStringStatus, c, kind, &str); break;
                }
                break;
            }
            case 22: CALL(SetDebugLogging, c, rint_(2) ? fmi2True : fmi2False, 0, NULL); break;
            case 23: { /* NULL arrays with nvr > 0 */
                fmi2ValueReference vr = 0;
                if (rint_(2)) CALL(GetReal, c, NULL, 1, NULL);
                else CALL(SetReal, c, &vr, 1, NULL);
                break;
            }
            case 27: CALL(EnterEventMode, c); break;
            case 28: {
                fmi2EventInfo info;
                if (rint_(20) == 0) CALL(NewDiscreteStates, c, NULL);
                else CALL(NewDiscreteStates, c, &info);
                break;
            }
            case 29: CALL(EnterContinuousTimeMode, c); break;
            case 30: {
                double tt = rint_(8) == 0 ? nasty_real() : t + 1e-5;
                CALL(SetTime, c, tt);
                if (isfinite(tt)) t = tt;
                break;
            }
            case 31: { /* states near the last ones, sometimes nasty, a wrong count or NULL */
                size_t n = rint_(10) == 0 ? (size_t)rint_(nx + 3) : (size_t)nx;
                int i = rint_(nx);
                x[0] += 1e-3;
                if (rint_(6) == 0) x[i] = nasty_real();
                if (rint_(20) == 0) CALL(SetContinuousStates, c, NULL, n);
                else CALL(SetContinuousStates, c, x, n);
                break;
            }
            case 32: {
                double dx[FZ_MAX_STATES + 3];
                size_t n = rint_(10) == 0 ? (size_t)rint_(nx + 3) : (size_t)nx;
                if (rint_(20) == 0) CALL(GetDerivatives, c, NULL, n);
                else CALL(GetDerivatives, c, dx, n);
                break;
            }
            case 33: {
                double z[64];
                size_t n = (size_t)rint_(64);
                if (rint_(20) == 0) CALL(GetEventIndicators, c, NULL, n);
                else CALL(GetEventIndicators, c, z, n);
                break;
            }
            case 34: {
                fmi2Boolean ev = fmi2False, term = fmi2False;
                if (rint_(20) == 0) CALL(CompletedIntegratorStep, c, fmi2True, NULL, &term);
                else CALL(CompletedIntegratorStep, c, fmi2True, &ev, &term);
                break;
            }
            case 35: {
                double xs[FZ_MAX_STATES + 3];
                size_t n = rint_(10) == 0 ? (size_t)rint_(nx + 3) : (size_t)nx;
                if (rint_(2)) CALL(GetContinuousStates, c, xs, n);
                else CALL(GetNominalsOfContinuousStates, c, xs, n);
                break;
            }
            default: { /* a pinion torque in range, to get past the input checks */
                fmi2ValueReference vr = 0;
                fmi2Real v = 60.0 + rint_(80);
                CALL(SetReal, c, &vr, 1, &v);
                break;
            }
            }
        }
        CALL(FreeFMUstate, c, &states[0]);
        CALL(FreeFMUstate, c, &states[1]);
        free(ser);
        f->FreeInstance(c);
        if (n_illegal_logged > illegal_before) seq_breaking++;
        printf("done %ld\n", first_seed + seq);
        fflush(stdout); /* the parent learns where a crash happened */
    }
    printf("{\"sequences\": %ld, \"sequences_breaking_order\": %ld, \"calls\": %ld, \"refused\": %ld, "
           "\"unlogged\": %ld, \"illegal_sequence_refusals\": %ld, \"bad_status\": %ld, \"discards\": %ld, "
           "\"errors\": %ld, \"fatals\": %ld, \"warnings\": %ld, \"instantiate_refused\": %ld, "
           "\"unlogged_example\": \"%s\"}\n",
           n_seq, seq_breaking, calls, refused, unlogged, n_illegal_logged, bad_status, discards, errors, fatals,
           warnings, inst_null, unlogged_example);
    return 0;
}
