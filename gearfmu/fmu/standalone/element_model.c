/*
 * element_model.c -- the torsional elements that join stage FMUs in an SSP of a gearbox
 * (docs/gearbox.md "The SSP of stage FMUs"): the model side of the contract gf_model.h under the
 * same FMI layers (fmi2_gear.c, fmi3_gear.c) and plumbing (fmi_common.c) as the gear and the
 * gearbox model.  It calls nothing of the plumbing; its messages go through gf_log to the host.
 *
 * Two kinds, chosen by the configuration:
 *
 *   body   a rigid inertia I (the motor or the load of the gearbox): torque inputs T_j, each
 *          driving (sign +1) or resisting (sign -1), held over a communication step H; it moves
 *          exactly as a rigid body under constant torque:
 *              a = sum_j s_j T_j / I,   theta += omega H + a H^2/2,   omega += a H.
 *          Outputs: angle (rad), speed (rad/s).  The torques from neighbouring FMUs (ports) hold their
 *          start values in the first communication step when first_step_start_values = 1 (they are the
 *          neighbours' initial outputs by construction; a master that starts its connections at 0, as
 *          fmpy's SSP master does, would otherwise give the body no shaft torque for a step).
 *
 *   shaft  an elastic shaft of stiffness k and damping c between two ports a (upstream) and b
 *          (downstream) that exchange (torque, angular velocity): it integrates the twist from
 *          the exchanged speeds, v = omega_a - omega_b, by the trapezoidal rule,
 *              x_n = x_{n-1} + H_{n-1} (v_{n-1} + v_n)/2     (x_0 = twist_start),
 *          and returns the torque it predicts for the middle of the next communication step
 *          (the step its output is held over in a master that transfers outputs after the step):
 *              T = k (x_n + 1.5 H v_n) + c v_n,
 *          positive driving away from the motor (on a: -T, on b: +T).  Outputs: torque (N.m),
 *          twist (rad, x_n + H v_n: the twist at the end of the step).
 *
 * What instantiation reads: gearfmu_element.txt (key=value lines written by
 * gearfmu/fmu/element_build.py): format, GUID, kind, the value references of the element's
 * parameters and inputs, and the variable table (var= lines, gf_resources.h).
 *
 * Behaviour (as the gear model's, docs/standalone.md "Behaviour"): a parameter outside its range
 * or an inertia / stiffness that is not finite and > 0: no initial state (Error, reasons logged).
 * A non-finite input or a bad communication step: the step is discarded with a message and the
 * state unchanged.  Nothing here ever aborts.  The FMU state is the element's state (a plain
 * struct) with the variable values in one flat block (gm_snap_*).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "element_model.h"
#include "gf_resources.h"

#define EL_CONFIG_FILE "gearfmu_element.txt"
#define EL_CONFIG_FORMAT "gearfmu-element"
#define EL_CONFIG_VERSION 1
#define EL_MAX_LINE 4096
#define EL_SNAPSHOT_MAGIC 0x47464c45u /* "GFLE" */
#define EL_SNAPSHOT_VERSION 1u

/* The FMU state block (flat, no pointers): header with the element state, then values, outputs. */
typedef struct {
    uint32_t magic;
    uint32_t version;
    uint32_t n_vars;
    uint32_t n_out;
    int32_t kind;
    int32_t mode;
    int32_t initialized;
    int32_t reserved;
    double time;
    el_state state;
    /* followed by double values[n_vars], double out[n_out] */
} el_snap_header;

/* ------------------------------------------------------------- config */
static const char *read_config(gf_inst *c, const char *text, char *guid, char *err, size_t errcap)
{
    gm_data *d = c->data;
    char line[EL_MAX_LINE], *key, *val;
    const char *p = text;
    int nvar_seen = 0, lineno = 0, have_format = 0, have_guid = 0, have_nvars = 0, more;
    d->kind = -1;
    d->vr_inertia = d->vr_angle0 = d->vr_speed0 = d->vr_k = d->vr_c = d->vr_x0 = d->vr_speed_a = d->vr_speed_b = -1;
    d->vr_first_start = -1;
    while ((more = gfr_next_config_line(&p, line, sizeof line, &lineno, &key, &val, err, errcap)) > 0) {
#define EL_VR(name, field)                                                                      \
    else if (strcmp(key, name) == 0) {                                                          \
        long v_;                                                                                \
        if (!gfr_parse_long(val, &v_) || v_ < 0 || v_ > 100000) {                               \
            snprintf(err, errcap, "%s: bad value '%.40s'", name, val);                          \
            return err;                                                                         \
        }                                                                                       \
        d->field = (int)v_;                                                                     \
    }
        if (strcmp(key, "format") == 0) {
            if (strcmp(val, EL_CONFIG_FORMAT) != 0) {
                snprintf(err, errcap, "format is '%.60s', expected '%s'", val, EL_CONFIG_FORMAT);
                return err;
            }
            have_format = 1;
        } else if (strcmp(key, "version") == 0) {
            long ver;
            if (!gfr_parse_long(val, &ver) || ver != EL_CONFIG_VERSION) {
                snprintf(err, errcap, "version '%.40s' unsupported (this runtime reads %d)", val, EL_CONFIG_VERSION);
                return err;
            }
        } else if (strcmp(key, "guid") == 0) {
            gfr_copy_str(guid, GF_MAX_NAME, val);
            have_guid = 1;
        } else if (strcmp(key, "kind") == 0) {
            if (strcmp(val, "body") == 0) d->kind = EL_BODY;
            else if (strcmp(val, "shaft") == 0) d->kind = EL_SHAFT;
            else {
                snprintf(err, errcap, "kind '%.40s' is neither body nor shaft", val);
                return err;
            }
        }
        EL_VR("vr.inertia", vr_inertia)
        EL_VR("vr.angle_start", vr_angle0)
        EL_VR("vr.speed_start", vr_speed0)
        EL_VR("vr.stiffness", vr_k)
        EL_VR("vr.damping", vr_c)
        EL_VR("vr.twist_start", vr_x0)
        EL_VR("vr.speed_a", vr_speed_a)
        EL_VR("vr.speed_b", vr_speed_b)
        EL_VR("vr.first_step_start_values", vr_first_start)
        else if (strcmp(key, "torque") == 0) {   /* vr|sign|port: a torque input of a body */
            char *f[3];
            long vr, sign, port;
            if (d->n_torque >= EL_MAX_TORQUES || gfr_split_fields(val, f, 3) != 3 || !gfr_parse_long(f[0], &vr) ||
                !gfr_parse_long(f[1], &sign) || !gfr_parse_long(f[2], &port) || vr < 0 || vr > 100000 ||
                (sign != 1 && sign != -1) || (port != 0 && port != 1)) {
                snprintf(err, errcap, "line %d: bad torque entry (vr|+1 or -1|0 or 1, at most %d)", lineno,
                         EL_MAX_TORQUES);
                return err;
            }
            d->vr_torque[d->n_torque] = (int)vr;
            d->torque_sign[d->n_torque] = (double)sign;
            d->torque_port[d->n_torque] = (int)port;
            d->n_torque++;
        } else if (strcmp(key, "n_vars") == 0) {
            long nv;
            if (!gfr_parse_long(val, &nv) || nv < 1 || nv > 100000 || c->vars != NULL) {
                snprintf(err, errcap, "n_vars: bad value '%.40s'", val);
                return err;
            }
            c->n_vars = (int)nv;
            c->vars = (gf_var *)calloc((size_t)nv, sizeof(gf_var));
            c->values = (double *)calloc((size_t)nv, sizeof(double));
            if (c->vars == NULL || c->values == NULL) return "out of memory";
            have_nvars = 1;
        } else if (strcmp(key, "var") == 0) {
            if (c->vars == NULL || !gfr_parse_var(c, val, &nvar_seen)) {
                snprintf(err, errcap, "line %d: bad variable entry (n_vars first, then vr 0, 1, ... in order)", lineno);
                return err;
            }
        }
        /* unknown keys are ignored (forward compatible) */
#undef EL_VR
    }
    if (more < 0) return err;
    if (!have_format || !have_guid || !have_nvars || d->kind < 0) {
        snprintf(err, errcap, "missing keys (format, guid, kind, n_vars)");
        return err;
    }
    if (nvar_seen != c->n_vars) {
        snprintf(err, errcap, "n_vars = %d but %d var lines", c->n_vars, nvar_seen);
        return err;
    }
    return NULL;
}

/* vr is one of the variable table's variables of causality `causality` (GF_PARAMETER / GF_INPUT) */
static int vr_is(const gf_inst *c, int vr, int causality)
{
    return vr >= 0 && vr < c->n_vars && c->vars[vr].causality == causality && !c->vars[vr].is_integer;
}

void gm_reset(gf_inst *c)
{
    int i;
    for (i = 0; i < c->n_vars; ++i) c->values[i] = c->vars[i].has_start ? c->vars[i].start : 0.0;
    for (i = 0; i < c->n_out; ++i) c->out[i] = 0.0;
    memset(&c->data->state, 0, sizeof c->data->state);
    c->data->initialized = 0;
    c->dirty = 1;
    c->time = 0.0;
    c->mode = GF_INSTANTIATED;
}

void gm_free(gf_inst *c)
{
    if (c == NULL) return;
    free(c->vars);
    free(c->values);
    free(c->out);
    c->vars = NULL;
    c->values = NULL;
    c->out = NULL;
    c->n_vars = c->n_out = 0;
    free(c->data);
    c->data = NULL;
}

const char *gm_instantiate(gf_inst *c, const char *res_dir, const char *token, char *err, size_t errcap)
{
    gm_data *d;
    char guid[GF_MAX_NAME];
    unsigned char *text;
    size_t size = 0;
    const char *e = NULL;
    int i;
    c->data = d = (gm_data *)calloc(1, sizeof(gm_data));
    if (d == NULL) return "out of memory";
    text = gfr_read_resource(res_dir, EL_CONFIG_FILE, &size, err, errcap);
    if (text == NULL) return err;
    {
        char e2[512];
        guid[0] = '\0';
        e = read_config(c, (const char *)text, guid, e2, sizeof e2);
        free(text);
        if (e != NULL) {
            snprintf(err, errcap, "resources/%s: %s", EL_CONFIG_FILE, e);
            return err;
        }
    }
    if (token == NULL || strcmp(token, guid) != 0) return "GUID differs from the one this FMU was built with";
    if (d->kind == EL_BODY) {
        if (!vr_is(c, d->vr_inertia, GF_PARAMETER) || !vr_is(c, d->vr_angle0, GF_PARAMETER) ||
            !vr_is(c, d->vr_speed0, GF_PARAMETER) || d->n_torque < 1 || d->vr_first_start < 0 ||
            d->vr_first_start >= c->n_vars || c->vars[d->vr_first_start].causality != GF_PARAMETER ||
            !c->vars[d->vr_first_start].is_integer)
            return "a body needs vr.inertia, vr.angle_start, vr.speed_start, vr.first_step_start_values (parameters) "
                   "and a torque input";
        for (i = 0; i < d->n_torque; ++i)
            if (!vr_is(c, d->vr_torque[i], GF_INPUT)) return "a torque entry is not a Real input of the variable table";
        c->n_out = EL_BODY_OUTPUTS;
    } else {
        if (!vr_is(c, d->vr_k, GF_PARAMETER) || !vr_is(c, d->vr_c, GF_PARAMETER) || !vr_is(c, d->vr_x0, GF_PARAMETER) ||
            !vr_is(c, d->vr_speed_a, GF_INPUT) || !vr_is(c, d->vr_speed_b, GF_INPUT))
            return "a shaft needs vr.stiffness, vr.damping, vr.twist_start (parameters), vr.speed_a, vr.speed_b (inputs)";
        c->n_out = EL_SHAFT_OUTPUTS;
    }
    c->out = (double *)calloc((size_t)c->n_out, sizeof(double));
    if (c->out == NULL) return "out of memory";
    for (i = 0; i < c->n_vars; ++i)
        if (c->vars[i].causality == GF_OUTPUT && (c->vars[i].out_index < 0 || c->vars[i].out_index >= c->n_out))
            return "an output's index is outside the element's output vector";
    gfr_mark_arrays(c);
    gm_reset(c);
    gf_log(c, GF_OK, "logAll", "instantiated: %s element", d->kind == EL_BODY ? "body" : "shaft");
    return NULL;
}

/* ------------------------------------------------------------ behaviour */
static double val(const gf_inst *c, int vr) { return vr >= 0 ? c->values[vr] : 0.0; }

/* 1 (the reason logged at `status`) when variable vr is not finite or outside its min/max, or (positive)
 * not > 0 */
static int bad_value(gf_inst *c, int vr, int positive, int status, const char *tail)
{
    const gf_var *v = &c->vars[vr];
    double x = c->values[vr];
    const char *cat = status == GF_DISCARD ? "logStatusDiscard" : "logStatusError";
    if (!isfinite(x)) gf_log(c, status, cat, "%s = %.17g: not finite%s", v->name, x, tail);
    else if (v->has_min && x < v->min) gf_log(c, status, cat, "%s = %.17g: below its minimum %.17g%s", v->name, x, v->min, tail);
    else if (v->has_max && x > v->max) gf_log(c, status, cat, "%s = %.17g: above its maximum %.17g%s", v->name, x, v->max, tail);
    else if (positive && !(x > 0.0)) gf_log(c, status, cat, "%s = %.17g: must be > 0%s", v->name, x, tail);
    else return 0;
    return 1;
}

/* the outputs from the state (the shaft's torque with the step H that its output is held over) */
static void outputs(gf_inst *c, double H)
{
    gm_data *d = c->data;
    el_state *s = &d->state;
    if (d->kind == EL_BODY) {
        c->out[EL_OUT_ANGLE] = s->theta;
        c->out[EL_OUT_SPEED] = s->omega;
    } else {
        double k = val(c, d->vr_k), cd = val(c, d->vr_c);
        c->out[EL_OUT_TORQUE] = k * (s->x + 1.5 * H * s->v) + cd * s->v;
        c->out[EL_OUT_TWIST] = s->x + H * s->v;
    }
}

static int init_state(gf_inst *c)
{
    static const char *const tail = "; cannot compute the initial state";
    gm_data *d = c->data;
    el_state *s = &d->state;
    int bad = 0;
    d->initialized = 0;
    memset(s, 0, sizeof *s);
    if (d->kind == EL_BODY) {
        bad |= bad_value(c, d->vr_inertia, 1, GF_ERROR_STATUS, tail);
        bad |= bad_value(c, d->vr_angle0, 0, GF_ERROR_STATUS, tail);
        bad |= bad_value(c, d->vr_speed0, 0, GF_ERROR_STATUS, tail);
        bad |= bad_value(c, d->vr_first_start, 0, GF_ERROR_STATUS, tail);
        if (bad) return 0;
        s->theta = val(c, d->vr_angle0);
        s->omega = val(c, d->vr_speed0);
        outputs(c, 0.0);
    } else {
        bad |= bad_value(c, d->vr_k, 1, GF_ERROR_STATUS, tail);
        bad |= bad_value(c, d->vr_c, 0, GF_ERROR_STATUS, tail);
        bad |= bad_value(c, d->vr_x0, 0, GF_ERROR_STATUS, tail);
        bad |= bad_value(c, d->vr_speed_a, 0, GF_ERROR_STATUS, tail);
        bad |= bad_value(c, d->vr_speed_b, 0, GF_ERROR_STATUS, tail);
        if (bad) return 0;
        if (val(c, d->vr_c) < 0.0) {
            gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s = %.17g: must be >= 0%s", c->vars[d->vr_c].name,
                   val(c, d->vr_c), tail);
            return 0;
        }
        s->x = val(c, d->vr_x0);
        s->v = val(c, d->vr_speed_a) - val(c, d->vr_speed_b);
        s->h_prev = 0.0;
        outputs(c, 0.0);
    }
    d->initialized = 1;
    return 1;
}

int gm_exit_init(gf_inst *c)
{
    if (c->dirty || !c->data->initialized) {
        if (!init_state(c)) return 0;
        c->dirty = 0;
    }
    return 1;
}

int gm_refresh_outputs(gf_inst *c, const char *fn, const unsigned int vr[], size_t nvr)
{
    size_t i;
    int want = 0;
    if (c->mode != GF_INIT_MODE || !c->dirty) return 1;
    for (i = 0; i < nvr && !want; ++i) want = (long)vr[i] < (long)c->n_vars && c->vars[vr[i]].causality == GF_OUTPUT;
    if (!want) return 1;
    if (!init_state(c)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: the initial outputs cannot be computed from the values set "
               "(reasons above)", fn);
        return 0;
    }
    c->dirty = 0;
    return 1;
}

int gm_do_step(gf_inst *c, double t, double H)
{
    static const char *const tail = "; step rejected, state unchanged";
    gm_data *d = c->data;
    el_state s;
    int bad = 0, i;
    if (isfinite(t)) c->time = t;
    if (!d->initialized && !init_state(c)) return GF_DISCARD;
    if (!(isfinite(H) && H > 0.0)) {
        gf_log(c, GF_DISCARD, "logStatusDiscard", "communication step size %.17g at t = %.17g s: must be finite and "
               "> 0%s", H, c->time, tail);
        return GF_DISCARD;
    }
    s = d->state;
    if (d->kind == EL_BODY) {
        double tau = 0.0, a;
        int first = s.h_prev == 0.0 && val(c, d->vr_first_start) == 1.0;
        for (i = 0; i < d->n_torque; ++i) {
            int vr = d->vr_torque[i];
            bad |= bad_value(c, vr, 0, GF_DISCARD, tail);
            tau += d->torque_sign[i] * (first && d->torque_port[i] ? c->vars[vr].start : val(c, vr));
        }
        if (bad) return GF_DISCARD;
        a = tau / val(c, d->vr_inertia);
        s.theta = s.theta + s.omega * H + 0.5 * a * H * H;
        s.omega = s.omega + a * H;
        s.h_prev = H;
        if (!isfinite(s.theta) || !isfinite(s.omega)) {
            gf_log(c, GF_DISCARD, "logStatusDiscard", "step at t = %.17g s rejected: the state became non-finite; state "
                   "unchanged", c->time);
            return GF_DISCARD;
        }
    } else {
        double v;
        bad |= bad_value(c, d->vr_speed_a, 0, GF_DISCARD, tail);
        bad |= bad_value(c, d->vr_speed_b, 0, GF_DISCARD, tail);
        if (bad) return GF_DISCARD;
        v = val(c, d->vr_speed_a) - val(c, d->vr_speed_b);
        if (s.h_prev > 0.0) s.x = s.x + s.h_prev * 0.5 * (s.v + v);  /* the twist at this step's start */
        s.v = v;
        s.h_prev = H;
        if (!isfinite(s.x)) {
            gf_log(c, GF_DISCARD, "logStatusDiscard", "step at t = %.17g s rejected: the twist became non-finite; state "
                   "unchanged", c->time);
            return GF_DISCARD;
        }
    }
    d->state = s;
    outputs(c, H);
    c->time = c->time + H;
    return GF_OK;
}

/* ------------------------------------------------------------ FMU state */
size_t gm_snap_size(const gf_inst *c)
{
    return sizeof(el_snap_header) + sizeof(double) * ((size_t)c->n_vars + (size_t)c->n_out);
}

void gm_snap_write(const gf_inst *c, unsigned char *p)
{
    el_snap_header h;
    memset(&h, 0, sizeof h);
    h.magic = EL_SNAPSHOT_MAGIC;
    h.version = EL_SNAPSHOT_VERSION;
    h.n_vars = (uint32_t)c->n_vars;
    h.n_out = (uint32_t)c->n_out;
    h.kind = c->data->kind;
    h.mode = c->mode;
    h.initialized = c->data->initialized;
    h.time = c->time;
    h.state = c->data->state;
    memcpy(p, &h, sizeof h);
    memcpy(p + sizeof h, c->values, sizeof(double) * (size_t)c->n_vars);
    memcpy(p + sizeof h + sizeof(double) * (size_t)c->n_vars, c->out, sizeof(double) * (size_t)c->n_out);
}

int gm_snap_is_ours(const gf_inst *c, const unsigned char *p, size_t size)
{
    el_snap_header h;
    if (size < sizeof h) return 0;
    memcpy(&h, p, sizeof h);
    return h.magic == EL_SNAPSHOT_MAGIC && h.version == EL_SNAPSHOT_VERSION && h.kind == c->data->kind &&
           h.n_vars == (uint32_t)c->n_vars && h.n_out == (uint32_t)c->n_out;
}

int gm_snap_read(gf_inst *c, const unsigned char *p, size_t size, const char *fn)
{
    el_snap_header h;
    if (size != gm_snap_size(c) || !gm_snap_is_ours(c, p, size)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: not a state of this FMU", fn);
        return 0;
    }
    memcpy(&h, p, sizeof h);
    if ((h.mode & GF_ANY_STATE) == 0 || (h.mode & (h.mode - 1)) != 0 || (h.initialized & ~1) != 0) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: state has an invalid FMI state %d", fn, (int)h.mode);
        return 0;
    }
    c->mode = h.mode;
    c->dirty = (h.mode == GF_INSTANTIATED || h.mode == GF_INIT_MODE);
    c->time = h.time;
    c->data->state = h.state;
    c->data->initialized = h.initialized;
    memcpy(c->values, p + sizeof h, sizeof(double) * (size_t)c->n_vars);
    memcpy(c->out, p + sizeof h + sizeof(double) * (size_t)c->n_vars, sizeof(double) * (size_t)c->n_out);
    return 1;
}
