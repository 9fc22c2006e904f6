/*
 * gkfmu.c -- the FMU behaviour both gearfmu runtimes share (gkfmu.h says what and who).
 *
 * Policy (docs/fmu.md): a parameter that is non-finite or outside its min/max, or
 * max_step <= 0, damping_model not 0/1, integrator not 0/1/2/3 -> no initial state (Error);
 * a non-finite or out-of-range input, a temperature outside the table's axis (no
 * clamping) or a communication step that is not finite and > 0 -> the step is discarded
 * with the state unchanged; a pinion torque outside the tables' torque axis -> one
 * warning (the tables are used at the nearest end); the verified envelope -> the
 * kernel's gk_envelope_check warnings.
 *
 * Numbers in messages: as Python's repr writes a float (the shortest form that reads back to
 * the same double, e.g. 170.0, 0.0001, 1e-05, nan).
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gkfmu.h"

#define NUM_LEN 40

/* a damping_model or integrator value as the kernel's code; -1 (refused by the kernel) if not one */
static int code_of(double x, int n_codes)
{
    int i;
    for (i = 0; i < n_codes; ++i)
        if (x == (double)i) return i;
    return -1;
}

int gkf_abi_version(void) { return GKF_ABI_VERSION; }
int gkf_sizeof(void) { return (int)sizeof(gkf_fmu); }

const char *gkf_kernel_error(int st)
{
    switch (st) {
    case GK_ERR_MODEL: return "bad table dimensions or scalars";
    case GK_ERR_INPUT: return "non-finite input";
    case GK_ERR_STEP: return "communication step or max_step not finite and > 0 (or more than 1e8 substeps)";
    case GK_ERR_NONFINITE: return "the state became non-finite (step too large for the stiffness? lower max_step)";
    case GK_ERR_NOCONTACT: return "no tooth pair in contact at the initial angle (tables have k = 0 there)";
    case GK_ERR_PARAM: return "damping_ratio, damping_model or integrator out of range";
    default: return "kernel error";
    }
}

/* x as Python's repr writes a float: the shortest form that reads back exactly, an exponent
 * only below 1e-4 or from 1e16 on, ".0" after a whole number (nan, inf, -inf as such) */
static const char *num(double x, char buf[NUM_LEN])
{
    int p, e;
    const char *ep;
    if (isnan(x)) return "nan";
    if (isinf(x)) return x > 0 ? "inf" : "-inf";
    for (p = 1; p < 17; ++p) {
        snprintf(buf, NUM_LEN, "%.*g", p, x);
        if (strtod(buf, NULL) == x) break;
    }
    snprintf(buf, NUM_LEN, "%.*e", p - 1, x);
    ep = strchr(buf, 'e');
    e = ep != NULL ? atoi(ep + 1) : 0;
    if (e >= 0 && e < 16 && p < e + 1) p = e + 1;
    snprintf(buf, NUM_LEN, "%.*g", p, x);
    if (strpbrk(buf, ".e") == NULL) strcat(buf, ".0");
    return buf;
}

static void say(gkf_fmu *f, int level, const char *fmt, ...)
{
    va_list ap;
    if (f->n_messages >= GKF_MAX_MESSAGES) return;
    va_start(ap, fmt);
    vsnprintf(f->message[f->n_messages], GKF_MESSAGE_LEN, fmt, ap);
    va_end(ap);
    f->level[f->n_messages++] = level;
}

int gkf_init(gkf_fmu *f, gk_model *m, gk_envelope *env)
{
    if (f == NULL || m == NULL) return GK_ERR_MODEL;
    memset(f, 0, sizeof *f);
    f->model = m;
    f->envelope = env;
    return GK_OK;
}

int gkf_declare(gkf_fmu *f, int slot, const char *name, int has_min, double min, int has_max, double max)
{
    if (f == NULL || slot < 0 || slot >= GKF_N || name == NULL || strlen(name) >= GKF_NAME_LEN) return GK_ERR_PARAM;
    strcpy(f->name[slot], name);
    f->has_min[slot] = has_min != 0;
    f->min[slot] = min;
    f->has_max[slot] = has_max != 0;
    f->max[slot] = max;
    f->present[slot] = 1;
    return GK_OK;
}

int gkf_set_values(gkf_fmu *f, const double *values)
{
    int i;
    if (f == NULL || values == NULL) return GK_ERR_PARAM;
    for (i = 0; i < GKF_N; ++i)
        if (f->present[i]) f->value[i] = values[i];
    return GK_OK;
}

void gkf_reset(gkf_fmu *f)
{
    if (f == NULL) return;
    f->zeta_valid = 0;
    f->zeta_applied = 0.0;
    f->warned_range = 0;
    f->n_messages = 0;
}

/* the reason the value of `slot` is refused, queued (" at t = ... s" when at_time, then `tail`); 1 */
static int refuse_value(gkf_fmu *f, int slot, int at_time, double t, int level, const char *tail)
{
    char a[NUM_LEN], b[NUM_LEN], at[NUM_LEN + 16] = "";
    double x = f->value[slot];
    const char *why;
    double limit = 0.0;
    if (!isfinite(x)) why = "not finite";
    else if (f->has_min[slot] && x < f->min[slot]) { why = "below its minimum"; limit = f->min[slot]; }
    else { why = "above its maximum"; limit = f->max[slot]; }
    if (at_time) snprintf(at, sizeof at, " at t = %s s", num(t, b));
    if (isfinite(x))
        say(f, level, "%s = %s%s: %s %s%s", f->name[slot], num(x, a), at, why, num(limit, b), tail);
    else
        say(f, level, "%s = %s%s: %s%s", f->name[slot], num(x, a), at, why, tail);
    return 1;
}

/* 0 if the value of `slot` is finite and inside its min/max (this check runs on every
 * doStep: comparisons only); else 1 and the reason queued (refuse_value) */
static int bad_value(gkf_fmu *f, int slot, int at_time, double t, int level, const char *tail)
{
    double x = f->value[slot];
    if (!f->present[slot] || (isfinite(x) && !(f->has_min[slot] && x < f->min[slot]) &&
                              !(f->has_max[slot] && x > f->max[slot])))
        return 0;
    return refuse_value(f, slot, at_time, t, level, tail);
}

/* Select the temperature in the kernel (docs/model.md "Temperature axis"); 1 if refused (queued). */
static int apply_temperature(gkf_fmu *f, double t, int level, const char *tail)
{
    char a[NUM_LEN], b[NUM_LEN], c[NUM_LEN], d[NUM_LEN];
    const gk_model *m = f->model;
    double T = f->value[GKF_TEMPERATURE], lo, hi;
    int st;
    if (!f->present[GKF_TEMPERATURE] || m->temperature_C == NULL) return 0;
    lo = m->temperature_C[0];
    hi = m->temperature_C[m->n_temp - 1];
    if (!isfinite(T) || T < lo || T > hi) {
        say(f, level, "%s = %s degC at t = %s s outside the table range [%s, %s] degC%s", f->name[GKF_TEMPERATURE],
            num(T, a), num(t, b), num(lo, c), num(hi, d), tail);
        return 1;
    }
    st = gk_set_temperature(f->model, T);
    if (st != GK_OK) {
        say(f, level, "%s = %s degC at t = %s s: %s%s", f->name[GKF_TEMPERATURE], num(T, a), num(t, b),
            gkf_kernel_error(st), tail);
        return 1;
    }
    return 0;
}

/* The damping ratio into the kernel when it changed; 1 if refused (queued as GKF_ERROR). */
static int apply_damping(gkf_fmu *f)
{
    char a[NUM_LEN];
    double zeta = f->value[GKF_DAMPING_RATIO];
    int st;
    if (f->zeta_valid && zeta == f->zeta_applied) return 0;
    if (bad_value(f, GKF_DAMPING_RATIO, 0, 0.0, GKF_ERROR, "; rejected")) return 1;
    st = gk_set_damping(f->model, zeta, code_of(f->value[GKF_DAMPING_MODEL], 2));
    if (st != GK_OK) {
        say(f, GKF_ERROR, "damping_ratio = %s: %s; rejected", num(zeta, a), gkf_kernel_error(st));
        return 1;
    }
    f->zeta_applied = zeta;
    f->zeta_valid = 1;
    return 0;
}

static void check_torque_range(gkf_fmu *f, double T1, double t)
{
    char a[NUM_LEN], b[NUM_LEN], c[NUM_LEN], d[NUM_LEN];
    const gk_model *m = f->model;
    double lo, hi;
    if (m->n_torque < 2) return;
    lo = m->torque_Nm[0];
    hi = m->torque_Nm[m->n_torque - 1];
    if (T1 < lo || T1 > hi) {
        if (!f->warned_range)
            say(f, GKF_WARNING, "pinion_torque = %s N.m at t = %s s is outside the tables' torque axis [%s, %s] N.m; "
                "the tables are used at the nearest end (docs/model.md)", num(T1, a), num(t, b), num(lo, c), num(hi, d));
        f->warned_range = 1;
    } else {
        f->warned_range = 0;
    }
}

static void check_envelope(gkf_fmu *f, int q, const char *name, double value, double t)
{
    char msg[GKF_MESSAGE_LEN];
    if (f->envelope != NULL && gk_envelope_check(f->envelope, q, name, value, t, msg, (int)sizeof msg))
        say(f, GKF_WARNING, "%s", msg);
}

/* the applied inputs (torque, temperature) and, when `speed`, the pinion speed of state s */
static void check_inputs_envelope(gkf_fmu *f, const gk_state *s, double t, int speed)
{
    check_envelope(f, GK_ENV_PINION_TORQUE, "pinion_torque", f->value[GKF_PINION_TORQUE], t);
    if (f->present[GKF_TEMPERATURE] && f->model->temperature_C != NULL)
        check_envelope(f, GK_ENV_TEMPERATURE, f->name[GKF_TEMPERATURE], f->value[GKF_TEMPERATURE], t);
    if (speed) check_envelope(f, GK_ENV_PINION_SPEED, "pinion_speed", s->omega1_rad_s, t);
}

int gkf_initialize(gkf_fmu *f, gk_state *s, double t, double *out)
{
    static const char *const tail = "; cannot compute the initial state";
    static const int params[5] = {GKF_DAMPING_RATIO, GKF_PINION_SPEED_START, GKF_PINION_ANGLE_START, GKF_MAX_STEP,
                                  GKF_DAMPING_MODEL};
    char a[NUM_LEN];
    double T1, ig = f->value[GKF_INTEGRATOR];
    int i, bad = 0, st;
    f->n_messages = 0;
    for (i = 0; i < 5; ++i) bad |= bad_value(f, params[i], 0, t, GKF_ERROR, tail);
    bad |= bad_value(f, GKF_PINION_TORQUE, 1, t, GKF_ERROR, tail);
    if (!bad && !(f->value[GKF_MAX_STEP] > 0.0)) {
        say(f, GKF_ERROR, "max_step = %s: must be > 0%s", num(f->value[GKF_MAX_STEP], a), tail);
        bad = 1;
    }
    if (!bad && code_of(f->value[GKF_DAMPING_MODEL], 2) < 0) {
        say(f, GKF_ERROR, "damping_model = %s: must be 0 (elastobacklash) or 1 (contact_zone)%s",
            num(f->value[GKF_DAMPING_MODEL], a), tail);
        bad = 1;
    }
    if (f->present[GKF_INTEGRATOR] && code_of(ig, 4) < 0) {
        say(f, GKF_ERROR, "integrator = %s: must be 0 (rk4), 1 (rk4_kink), 2 (rk4_node) or 3 (rk4_seg)%s", num(ig, a), tail);
        bad = 1;
    }
    if (bad) return 0;
    if (f->present[GKF_INTEGRATOR]) { /* docs/model.md "Integration" */
        st = gk_set_integrator(f->model, code_of(ig, 4));
        if (st != GK_OK) {
            say(f, GKF_ERROR, "integrator = %s: %s%s", num(ig, a), gkf_kernel_error(st), tail);
            return 0;
        }
    }
    if (apply_temperature(f, t, GKF_ERROR, tail)) return 0;
    f->zeta_valid = 0;
    if (apply_damping(f)) return 0;
    T1 = f->value[GKF_PINION_TORQUE];
    st = gk_initialize(f->model, s, f->value[GKF_PINION_ANGLE_START], f->value[GKF_PINION_SPEED_START], T1);
    if (st == GK_OK) st = gk_outputs(f->model, s, T1, out);
    if (st != GK_OK) {
        say(f, GKF_ERROR, "initial state: %s", gkf_kernel_error(st));
        return 0;
    }
    check_torque_range(f, T1, t);
    check_inputs_envelope(f, s, t, 1);
    return 1;
}

int gkf_do_step(gkf_fmu *f, gk_state *s, double t, double H, double *out)
{
    static const char *const tail = "; step rejected, state unchanged";
    char a[NUM_LEN], b[NUM_LEN];
    double T1 = f->value[GKF_PINION_TORQUE];
    int bad = 0, st;
    f->n_messages = 0;
    bad |= bad_value(f, GKF_PINION_TORQUE, 1, t, GKF_DISCARD, tail);
    bad |= bad_value(f, GKF_GEAR_TORQUE, 1, t, GKF_DISCARD, tail);
    if (!(isfinite(H) && H > 0.0)) {
        say(f, GKF_DISCARD, "communication step size %s at t = %s s: must be finite and > 0%s", num(H, a), num(t, b),
            tail);
        bad = 1;
    }
    if (!bad) bad = apply_temperature(f, t, GKF_DISCARD, tail);
    if (bad || apply_damping(f)) return 0;
    check_torque_range(f, T1, t);
    check_inputs_envelope(f, s, t, 0);
    st = gk_do_step(f->model, s, T1, f->value[GKF_GEAR_TORQUE], H, f->value[GKF_MAX_STEP], out);
    if (st != GK_OK) {
        say(f, GKF_DISCARD, "step at t = %s s, H = %s s rejected: %s; state unchanged", num(t, a), num(H, b),
            gkf_kernel_error(st));
        return 0;
    }
    check_envelope(f, GK_ENV_PINION_SPEED, "pinion_speed", s->omega1_rad_s, t + H);
    return 1;
}

int gkf_me_inputs(gkf_fmu *f, double t)
{
    static const char *const tail = "; not evaluated";
    double T1 = f->value[GKF_PINION_TORQUE];
    int bad = 0;
    f->n_messages = 0;
    bad |= bad_value(f, GKF_PINION_TORQUE, 1, t, GKF_DISCARD, tail);
    bad |= bad_value(f, GKF_GEAR_TORQUE, 1, t, GKF_DISCARD, tail);
    if (!bad) bad = apply_temperature(f, t, GKF_DISCARD, tail);
    if (bad || apply_damping(f)) return 0;
    check_torque_range(f, T1, t);
    check_inputs_envelope(f, NULL, t, 0);
    return 1;
}

void gkf_me_speed(gkf_fmu *f, const gk_state *s, double t)
{
    f->n_messages = 0;
    check_envelope(f, GK_ENV_PINION_SPEED, "pinion_speed", s->omega1_rad_s, t);
}

int gkf_restore(gkf_fmu *f, int integrator, int zeta_valid, double zeta, int warned_range)
{
    double ig;
    int st;
    if (f == NULL) return GK_ERR_MODEL;
    ig = f->value[GKF_INTEGRATOR];
    if (integrator && f->present[GKF_INTEGRATOR]) {
        st = gk_set_integrator(f->model, code_of(ig, 4));
        if (st != GK_OK) return st;
    }
    if (zeta_valid) {
        st = gk_set_damping(f->model, zeta, code_of(f->value[GKF_DAMPING_MODEL], 2));
        if (st != GK_OK) return st;
    }
    f->zeta_valid = zeta_valid != 0;
    f->zeta_applied = zeta_valid ? zeta : 0.0;
    f->warned_range = warned_range != 0;
    return GK_OK;
}

int gkf_zeta_valid(const gkf_fmu *f) { return f->zeta_valid; }
double gkf_zeta_applied(const gkf_fmu *f) { return f->zeta_applied; }
int gkf_warned_range(const gkf_fmu *f) { return f->warned_range; }
int gkf_n_messages(const gkf_fmu *f) { return f->n_messages; }
int gkf_message_level(const gkf_fmu *f, int i) { return (i >= 0 && i < f->n_messages) ? f->level[i] : 0; }
const char *gkf_message(const gkf_fmu *f, int i) { return (i >= 0 && i < f->n_messages) ? f->message[i] : ""; }
