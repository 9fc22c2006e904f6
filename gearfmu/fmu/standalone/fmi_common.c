/*
 * fmi_common.c -- the generic FMI plumbing of the standalone gearfmu runtime,
 * shared by fmi2_gear.c (FMI 2.0) and fmi3_gear.c (FMI 3.0): the instance, the
 * state-machine check of every call, get/set dispatch over the variable table
 * and the FMU state box (fmi_common.h).  Nothing here knows gears: the model is
 * called through the contract of gf_model.h only.
 */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi_common.h"

/* ------------------------------------------------------------ instance */
gf_inst *gf_new(int fmi_version, const char *instance_name, int logging_on, gf_log_fn log, void *host_env,
                void (*host_logger)(void), const char *never_why)
{
    gf_inst *c = (gf_inst *)calloc(1, sizeof(gf_inst));
    if (c == NULL) return NULL;
    c->fmi_version = fmi_version;
    c->log = log;
    c->host_env = host_env;
    c->host_logger = host_logger;
    snprintf(c->instance_name, sizeof c->instance_name, "%s", instance_name ? instance_name : "gearfmu");
    c->logging_on = logging_on ? 1 : 0;
    c->never_why = never_why;
    return c;
}

void gf_free(gf_inst *c)
{
    if (c == NULL) return;
    gm_free(c);
    free(c);
}

gf_inst *gf_instantiate_error(gf_inst *c, const char *fn, const char *msg)
{
    gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: %s; refusing to instantiate", fn, msg);
    gf_free(c);
    return NULL;
}

static int hexval(int ch)
{
    if (ch >= '0' && ch <= '9') return ch - '0';
    if (ch >= 'a' && ch <= 'f') return ch - 'a' + 10;
    if (ch >= 'A' && ch <= 'F') return ch - 'A' + 10;
    return -1;
}

/* file:// URI of the resources folder (FMI 2.0 fmuResourceLocation, RFC 8089 / RFC 3986) -> local
 * folder path ending in '/', UTF-8 (the percent-escapes decoded: a URI carries a non-ASCII or
 * space character as %XX bytes of its UTF-8 encoding).  Accepts file:///path, file://localhost/path
 * and file:/path; on Windows also a drive letter (file:///C:/dir, file:///C%3A/dir, file:///C|/dir)
 * and a UNC host (file://server/share/dir -> //server/share/dir).  The path keeps its '/'; the model
 * opens it through the platform's wide-character API (gf_resources.c gfr_read_file).  0 if the URI is
 * not a file URI this platform can open, or the path does not fit. */
int gf_uri_to_dir(const char *uri, char *out, size_t cap)
{
    const char *p;
    size_t n = 0, skip = 0;
    int unc = 0;
    if (uri == NULL || cap < 3) return 0;
    if (strncmp(uri, "file://localhost/", 17) == 0) p = uri + 16;
    else if (strncmp(uri, "file:///", 8) == 0) p = uri + 7;
    else if (strncmp(uri, "file://", 7) == 0) { /* file://host/path */
#ifdef _WIN32
        p = uri + 5; /* //host/path: a UNC path */
        unc = 1;
#else
        return 0; /* no remote hosts here */
#endif
    } else if (strncmp(uri, "file:/", 6) == 0) p = uri + 5;
    else return 0;
    while (*p != '\0' && *p != '?' && *p != '#') {
        int ch = (unsigned char)*p;
        if (ch == '%' && hexval(p[1]) >= 0 && hexval(p[2]) >= 0) {
            ch = hexval(p[1]) * 16 + hexval(p[2]);
            p += 3;
        } else {
            p++;
        }
        if (ch == 0 || n + 2 >= cap) return 0;
        out[n++] = (char)ch;
    }
    out[n] = '\0';
#ifdef _WIN32
    /* /C:/dir (or /C|/dir) -> C:/dir */
    if (!unc && n >= 3 && out[0] == '/' && ((out[1] >= 'A' && out[1] <= 'Z') || (out[1] >= 'a' && out[1] <= 'z')) &&
        (out[2] == ':' || out[2] == '|')) {
        out[2] = ':';
        skip = 1;
    }
#endif
    (void)unc;
    if (skip) {
        memmove(out, out + skip, n - skip + 1);
        n -= skip;
    }
    if (n == 0) return 0;
    if (out[n - 1] != '/') {
        out[n++] = '/';
        out[n] = '\0';
    }
    return 1;
}

/* Initialization Mode (FMI 2.0 section 3.2.3 / 4.2.4, FMI 3.0 section 4.2.3): from here on every
 * output is the initial one computed from the values set so far -- the same initial state
 * gm_exit_init computes; a value set in this mode marks the outputs dirty and the next get of an
 * output recomputes them (gm_refresh_outputs). */
void gf_enter_init(gf_inst *c)
{
    c->mode = GF_INIT_MODE;
    c->dirty = 1;
}

/* ------------------------------------------------------ state machine */
static const char *state_name(const gf_inst *c, int mode)
{
    switch (mode) {
    case GF_INSTANTIATED: return c->fmi_version == 3 ? "Instantiated" : "instantiated";
    case GF_INIT_MODE: return c->fmi_version == 3 ? "InitializationMode" : "initializationMode";
    case GF_STEP_MODE: return c->fmi_version == 3 ? "StepMode" : "stepComplete";
    case GF_TERMINATED: return c->fmi_version == 3 ? "Terminated" : "terminated";
    case GF_ERROR: return c->fmi_version == 3 ? "error" : "error";
    case GF_EVENT_MODE: return c->fmi_version == 3 ? "EventMode" : "eventMode";
    case GF_CONT_MODE: return c->fmi_version == 3 ? "ContinuousTimeMode" : "continuousTimeMode";
    default: return "unknown";
    }
}

/* Which function may be called in which state: one table per FMI version (the
 * layer's), checked at the entry of every function, as in the Modelica
 * Reference-FMUs.  A call outside its states is refused with Error and a log
 * message naming the function and the state; the instance is left as it was. */
int gf_allowed(gf_inst *c, const gf_call *call)
{
    char states[240];
    int bit;
    size_t n = 0;
    if (c == NULL) return 0; /* no instance: nothing to log to */
    if (c->mode & call->allowed) return 1;
    states[0] = '\0';
    for (bit = GF_INSTANTIATED; bit <= GF_LAST_STATE; bit <<= 1)
        if (call->allowed & bit) n += (size_t)snprintf(states + n, sizeof states - n, "%s%s",
                                                       n ? ", " : "", state_name(c, bit));
    gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: illegal call sequence: not allowed in state %s (allowed in: %s)",
           call->name, state_name(c, c->mode), n ? states : c->never_why);
    return 0;
}

/* ------------------------------------------------------------ get / set */
/* a stored Integer value as int; a value no int holds (only from a foreign or
 * corrupted FMU state) becomes -1, which every integer parameter here rejects
 * (a plain cast would be undefined behaviour) */
static int as_int(double x)
{
    return (x >= -2147483647.0 && x <= 2147483647.0) ? (int)x : -1;
}

/* the current value of variable i (an output, or a local the model computes: the model's output vector) */
static inline double value_of(const gf_inst *c, int i)
{
    const gf_var *v = &c->vars[i];
    return v->out_index >= 0 ? c->out[v->out_index] : c->values[i];
}

/* 1 if variable i may be set now (inputs, tunable parameters, fixed parameters before the
 * initialization ends; in Model Exchange's continuous-time mode continuous inputs only and tunable
 * parameters in event mode, FMI 2.0 section 3.2.3, FMI 3.0 section 3.2.2), else logs why */
static int settable(gf_inst *c, const char *fn, int i)
{
    const gf_var *v = &c->vars[i];
    if (v->causality == GF_INPUT && (c->mode != GF_CONT_MODE || v->variability == GF_CONTINUOUS)) return 1;
    if (v->causality == GF_PARAMETER && v->variability == GF_TUNABLE && c->mode == GF_CONT_MODE) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: %s is a tunable parameter: it can be set in event mode, "
               "not in continuous-time mode", fn, v->name);
        return 0;
    }
    if (v->causality == GF_PARAMETER && v->variability == GF_TUNABLE) return 1;
    if (v->causality == GF_PARAMETER && v->variability == GF_FIXED &&
        (c->mode == GF_INSTANTIATED || c->mode == GF_INIT_MODE))
        return 1;
    gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: %s cannot be set now (causality/variability forbid it)", fn,
           v->name);
    return 0;
}

int gf_null_args(gf_inst *c, const char *fn, size_t nvr, const void *vr, const void *value)
{
    if (nvr > 0 && (vr == NULL || value == NULL)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: vr[] or value[] is NULL with nvr = %lu", fn,
               (unsigned long)nvr);
        return 1;
    }
    return 0;
}

/* the length of an array's name: element 1's name without its "[1]" (FMI 3 arrays, gear_model.c) */
static int array_name_len(const char *name)
{
    size_t n = strlen(name);
    return (int)(n > 3 && strcmp(name + n - 3, "[1]") == 0 ? n - 3 : n);
}

/* the number of values reference r brings (0: bad, logged) */
static size_t check_vr(gf_inst *c, const char *fn, unsigned int r, int want_integer, int arrays, long time_vr)
{
    const char *tname = c->fmi_version == 3 ? (want_integer ? "Int32" : "Float64") : (want_integer ? "Integer" : "Real");
    if (time_vr >= 0 && (long)r == time_vr) {
        if (want_integer) {
            gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: time is not of type %s", fn, tname);
            return 0;
        }
        return 1;
    }
    if ((long)r < (long)c->n_vars && arrays && c->vars[r].array_len == 0) {
        long first = (long)r;
        while (first > 0 && c->vars[first].array_len == 0) first--;
        gf_log(c, GF_WARNING, "logStatusWarning", "%s: value reference %u is element %ld of the array %.*s (value "
               "reference %ld, %d values), not a variable of its own: ask for the array by the reference of its "
               "first element, or use an FMU built with scalar outputs (gearfmu build --fmi3-outputs scalar)",
               fn, r, (long)r - first + 1, array_name_len(c->vars[first].name), c->vars[first].name, first,
               c->vars[first].array_len);
    }
    if ((long)r >= (long)c->n_vars || (arrays && c->vars[r].array_len == 0)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: no variable with value reference %u", fn, r);
        return 0;
    }
    if (c->vars[r].is_integer != want_integer) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: %s is not of type %s", fn, c->vars[r].name, tname);
        return 0;
    }
    return arrays ? (size_t)c->vars[r].array_len : 1;
}

/* the total number of values of vr[] (0 with a bad reference or a wrong n_values, logged); ok set to 1 if valid */
static int check_refs(gf_inst *c, const char *fn, const unsigned int vr[], size_t nvr, int want_integer, int arrays,
                      long time_vr, size_t n_values, int set)
{
    size_t i, total = 0, n;
    for (i = 0; i < nvr; ++i) {
        if ((n = check_vr(c, fn, vr[i], want_integer, arrays, time_vr)) == 0) return 0;
        if (set && (time_vr < 0 || (long)vr[i] != time_vr)) {
            size_t k;
            for (k = 0; k < n; ++k)
                if (!settable(c, fn, (int)vr[i] + (int)k)) return 0;
        } else if (set) {
            gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: time (the independent variable) cannot be set", fn);
            return 0;
        }
        total += n;
    }
    if (arrays && total != n_values) {
        /* a host that reads every reference as one value (no array support) lands here: say which
         * references are arrays, at warning level, which hosts show */
        for (i = 0; i < nvr; ++i) {
            long r = (long)vr[i];
            if (r < (long)c->n_vars && c->vars[r].array_len > 1)
                gf_log(c, GF_WARNING, "logStatusWarning", "%s: %.*s (value reference %ld) is an array of %d values; "
                       "nValues must count every element (a host without array support: use an FMU built with "
                       "scalar outputs, gearfmu build --fmi3-outputs scalar)", fn, array_name_len(c->vars[r].name),
                       c->vars[r].name, r,
                       c->vars[r].array_len);
        }
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: the value references have %lu values, nValues is %lu", fn,
               (unsigned long)total, (unsigned long)n_values);
        return 0;
    }
    return 1;
}

int gf_get_values(gf_inst *c, const char *fn, const unsigned int vr[], size_t nvr, int arrays, long time_vr,
                  double real[], int integer[], size_t n_values)
{
    size_t i, j = 0;
    int want_integer = integer != NULL;
    /* the common case first (a host reading scalar variables every step): every reference
     * names a variable of the type asked for and the outputs are up to date; anything else
     * takes the checks below, which say what is wrong */
    if (!arrays && time_vr < 0 && vr != NULL && (want_integer || real != NULL) &&
        !(c->dirty && (c->mode & (GF_INIT_MODE | GF_EVENT_MODE | GF_CONT_MODE)))) {
        for (i = 0; i < nvr && vr[i] < (unsigned int)c->n_vars && c->vars[vr[i]].is_integer == want_integer; ++i) {}
        if (i == nvr) {
            for (i = 0; i < nvr; ++i) {
                double x = value_of(c, (int)vr[i]);
                if (want_integer) integer[i] = as_int(x);
                else real[i] = x;
            }
            return GF_OK;
        }
    }
    if (gf_null_args(c, fn, nvr, vr, want_integer ? (const void *)integer : (const void *)real)) return GF_ERROR_STATUS;
    if (!check_refs(c, fn, vr, nvr, want_integer, arrays, time_vr, n_values, 0)) return GF_ERROR_STATUS;
    if (!gm_refresh_outputs(c, fn, vr, nvr)) return GF_ERROR_STATUS;
    for (i = 0; i < nvr; ++i) {
        size_t k, n = (time_vr >= 0 && (long)vr[i] == time_vr) ? 1 : (arrays ? (size_t)c->vars[vr[i]].array_len : 1);
        for (k = 0; k < n; ++k, ++j) {
            double x = (time_vr >= 0 && (long)vr[i] == time_vr) ? c->time : value_of(c, (int)(vr[i] + k));
            if (want_integer) integer[j] = as_int(x);
            else real[j] = x;
        }
    }
    return GF_OK;
}

int gf_set_values(gf_inst *c, const char *fn, const unsigned int vr[], size_t nvr, int arrays, long time_vr,
                  const double real[], const int integer[], size_t n_values)
{
    size_t i, j = 0;
    int want_integer = integer != NULL;
    if (gf_null_args(c, fn, nvr, vr, want_integer ? (const void *)integer : (const void *)real)) return GF_ERROR_STATUS;
    if (!check_refs(c, fn, vr, nvr, want_integer, arrays, time_vr, n_values, 1)) return GF_ERROR_STATUS;
    /* A parameter outside its min/max (NaN included) is discarded when set, and nothing of the call
     * is stored (FMI 2.0.5 section 2.2.7: "On a fixed or tunable parameter fmi2Status = fmi2Discard is
     * returned"; FMI 3.0 the same).  Inputs are stored as given (NaN included); doStep and the
     * initial state check them. */
    for (i = 0; i < nvr; ++i) {
        size_t k, n = arrays ? (size_t)c->vars[vr[i]].array_len : 1;
        for (k = 0; k < n; ++k, ++j) {
            const gf_var *v = &c->vars[vr[i] + k];
            double x = want_integer ? (double)integer[j] : real[j];
            if (v->causality == GF_PARAMETER && (x != x || (v->has_min && x < v->min) || (v->has_max && x > v->max))) {
                gf_log(c, GF_DISCARD, "logStatusDiscard", "%s: %s = %.17g is outside its range [%.17g, %.17g] (min/max of "
                       "the model description); not set, the call sets nothing", fn, v->name, x,
                       v->has_min ? v->min : -HUGE_VAL, v->has_max ? v->max : HUGE_VAL);
                return GF_DISCARD;
            }
        }
    }
    j = 0;
    for (i = 0; i < nvr; ++i) {
        size_t k, n = arrays ? (size_t)c->vars[vr[i]].array_len : 1;
        for (k = 0; k < n; ++k, ++j) c->values[vr[i] + k] = want_integer ? (double)integer[j] : real[j];
    }
    if (nvr > 0) c->dirty = 1;
    return GF_OK;
}

/* doStep's communication point must be the time the FMU has reached (the start time, the end of the
 * last step, or the time of a restored FMU state): FMI 2.0.5 section 4.2.2 and FMI 3.0 section 4.2.1
 * let a step start only there (tc_i+1 = tc_i + hc_i).  A master's arithmetic may differ from the
 * FMU's in the last bits (t = k*H against t + H), so 64 units in the last place of the time, and a
 * billionth of the step, are the same time.  Anything else (the 0.5 s, then 0.0 s) is an
 * Error: the instance goes to state error, from which fmiXSetFMUState or fmiXReset lead back. */
int gf_check_step_time(gf_inst *c, const char *fn, double t, double H)
{
    double tol = 64.0 * DBL_EPSILON * (fabs(t) > fabs(c->time) ? fabs(t) : fabs(c->time));
    if (H > 0.0 && H < HUGE_VAL) tol += 1e-9 * H;
    if (t == t && fabs(t - c->time) <= tol) {
        c->time = t;
        return 1;
    }
    c->mode = GF_ERROR;
    gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: currentCommunicationPoint = %.17g s is not the time this FMU has "
           "reached, %.17g s (the start time, the end of the last step, or the time of a restored FMU state); "
           "the instance is in state error (set an FMU state, reset or free it)", fn, t, c->time);
    return 0;
}

int gf_no_variables_of(gf_inst *c, const char *fn, const char *type, size_t nvr)
{
    if (nvr == 0) return GF_OK;
    gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: this FMU has no %s variables", fn, type);
    return GF_ERROR_STATUS;
}

/* ------------------------------------------------------- Model Exchange */
const char *gf_offered(gf_inst *c)
{
    int offers = c->offers ? c->offers : GF_COSIMULATION;
    if (c->fmu_type == GF_MODEL_EXCHANGE && (c->me == NULL || !(offers & GF_MODEL_EXCHANGE)))
        return c->me_refusal ? c->me_refusal : "this FMU offers Co-Simulation only (no ModelExchange element in its "
                                               "model description)";
    if (c->fmu_type == GF_COSIMULATION && !(offers & GF_COSIMULATION))
        return "this FMU offers Model Exchange only (no CoSimulation element in its model description)";
    return NULL;
}

/* n values in x, the model's count want (what: the array's name) */
static int me_array(gf_inst *c, const char *fn, const void *x, size_t n, size_t want, const char *what)
{
    if (c->me == NULL || c->fmu_type != GF_MODEL_EXCHANGE) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: this instance is not a Model Exchange instance", fn);
        return 0;
    }
    if (n != want) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: %lu %s, this FMU has %lu", fn, (unsigned long)n, what,
               (unsigned long)want);
        return 0;
    }
    if (n > 0 && x == NULL) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: the array of %s is NULL", fn, what);
        return 0;
    }
    return 1;
}

int gf_me_states(gf_inst *c, const char *fn, double x[], size_t nx)
{
    if (!me_array(c, fn, x, nx, c->n_states, "continuous states")) return GF_ERROR_STATUS;
    return nx ? c->me->states(c, fn, x) : GF_OK;
}

int gf_me_nominals(gf_inst *c, const char *fn, double x[], size_t nx)
{
    if (!me_array(c, fn, x, nx, c->n_states, "continuous states")) return GF_ERROR_STATUS;
    return nx ? c->me->nominals(c, fn, x) : GF_OK;
}

int gf_me_set_states(gf_inst *c, const char *fn, const double x[], size_t nx)
{
    if (!me_array(c, fn, x, nx, c->n_states, "continuous states")) return GF_ERROR_STATUS;
    return nx ? c->me->set_states(c, fn, x) : GF_OK;
}

int gf_me_derivatives(gf_inst *c, const char *fn, double dx[], size_t nx)
{
    if (!me_array(c, fn, dx, nx, c->n_states, "derivatives")) return GF_ERROR_STATUS;
    return nx ? c->me->derivatives(c, fn, dx) : GF_OK;
}

int gf_me_indicators(gf_inst *c, const char *fn, double z[], size_t nz)
{
    if (!me_array(c, fn, z, nz, c->n_indicators, "event indicators")) return GF_ERROR_STATUS;
    return nz ? c->me->indicators(c, fn, z) : GF_OK;
}

int gf_me_event_update(gf_inst *c, const char *fn, int *again, int *values_changed)
{
    *again = 0;
    *values_changed = 0;
    if (!me_array(c, fn, NULL, 0, 0, "values")) return GF_ERROR_STATUS;
    return c->me->event_update(c, fn, again, values_changed);
}

int gf_me_completed_step(gf_inst *c, const char *fn, int *enter_event)
{
    *enter_event = 0;
    if (!me_array(c, fn, NULL, 0, 0, "values")) return GF_ERROR_STATUS;
    return c->me->completed_step(c, fn, enter_event);
}

/* ------------------------------------------------------------ FMU state */
typedef struct {
    size_t size;
    /* followed by the bytes */
} gf_state_box;

int gf_get_state(gf_inst *c, const char *fn, void **state)
{
    gf_state_box *box;
    size_t n;
    if (state == NULL) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: FMUstate is NULL", fn);
        return GF_ERROR_STATUS;
    }
    n = gm_snap_size(c);
    box = (gf_state_box *)*state;
    if (box == NULL || box->size != n) {
        free(box);
        box = (gf_state_box *)malloc(sizeof(gf_state_box) + n);
        if (box == NULL) {
            *state = NULL;
            gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: out of memory", fn);
            return GF_ERROR_STATUS;
        }
        box->size = n;
    }
    gm_snap_write(c, (unsigned char *)(box + 1));
    *state = box;
    return GF_OK;
}

int gf_set_state(gf_inst *c, const char *fn, void *state)
{
    gf_state_box *box = (gf_state_box *)state;
    if (box == NULL) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: FMUstate is NULL", fn);
        return GF_ERROR_STATUS;
    }
    return gm_snap_read(c, (const unsigned char *)(box + 1), box->size, fn) ? GF_OK : GF_ERROR_STATUS;
}

void gf_free_state(void **state)
{
    if (state == NULL) return;
    free(*state);
    *state = NULL;
}

int gf_state_size(gf_inst *c, const char *fn, void *state, size_t *size)
{
    gf_state_box *box = (gf_state_box *)state;
    if (box == NULL || size == NULL) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: FMUstate or size is NULL", fn);
        return GF_ERROR_STATUS;
    }
    *size = box->size;
    return GF_OK;
}

int gf_serialize_state(gf_inst *c, const char *fn, void *state, unsigned char *buf, size_t size)
{
    gf_state_box *box = (gf_state_box *)state;
    if (box == NULL || buf == NULL) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: FMUstate or serializedState is NULL", fn);
        return GF_ERROR_STATUS;
    }
    if (size < box->size) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: buffer of %lu bytes, need %lu", fn, (unsigned long)size,
               (unsigned long)box->size);
        return GF_ERROR_STATUS;
    }
    memcpy(buf, box + 1, box->size);
    return GF_OK;
}

int gf_deserialize_state(gf_inst *c, const char *fn, const unsigned char *buf, size_t size, void **state)
{
    gf_state_box *box;
    if (buf == NULL || state == NULL) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: serializedState or FMUstate is NULL", fn);
        return GF_ERROR_STATUS;
    }
    if (size != gm_snap_size(c)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: %lu bytes, this FMU's state has %lu", fn,
               (unsigned long)size, (unsigned long)gm_snap_size(c));
        return GF_ERROR_STATUS;
    }
    if (!gm_snap_is_ours(c, buf, size)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: not a state of this FMU", fn);
        return GF_ERROR_STATUS;
    }
    box = (gf_state_box *)malloc(sizeof(gf_state_box) + size);
    if (box == NULL) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: out of memory", fn);
        return GF_ERROR_STATUS;
    }
    box->size = size;
    memcpy(box + 1, buf, size);
    free(*state);
    *state = box;
    return GF_OK;
}
