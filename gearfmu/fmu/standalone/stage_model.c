/*
 * stage_model.c -- the stage model of the standalone gearfmu runtime: one stage of a gearbox with the
 * elastic shafts that end at its flanges, for an SSP of stage FMUs (docs/gearbox.md "The SSP of stage
 * FMUs").  The model side of the contract gf_model.h under the same FMI layers (fmi2_gear.c,
 * fmi3_gear.c) and plumbing (fmi_common.c) as the gear and the gearbox model.
 *
 * A stage is a gearbox of its own (gearbox_model.c over the gearbox kernel gb_kernel.c, which
 * computes the mesh with the pair kernel's pieces): the stage's pinion and gear, the shafts assigned
 * to it, and at the far end of each such shaft a *flange*: a body whose motion is the neighbouring
 * FMU's.  The flange's speed is an input (the neighbour's speed at the communication point); its
 * angle is integrated from the speeds received, by the trapezoidal rule
 *     theta_n = theta_{n-1} + H_{n-1} (omega_{n-1} + omega_n)/2      (theta_0: the initial state),
 * and over the step the flange turns at the constant speed omega_n (its inverse inertia is 0 in the
 * kernel, so no torque moves it: it is a prescribed motion).  The stiff shaft is thus integrated
 * together with the light pinion it drives, by the stage's own integrator, and only the flange's
 * motion is extrapolated.  After the step the stage outputs, for every flange, the torque the shaft
 * transmits, predicted for the middle of the next step (the step the neighbour holds it over in a
 * master that transfers outputs after the step):
 *     T_port = T_s + (H/2) k (omega_a - omega_b)        (T_s the shaft torque at the end of the step).
 * A stage whose gear drives the next stage's shaft instead has a torque input there: the gearbox
 * model's load torque (docs/gearbox.md).  With first_step_start_values = 1, the first communication
 * step after the initial state takes the flanges' motion from the initial state and the torque inputs
 * from neighbouring FMUs (port_torque= lines) at their start values, whatever the master set: they
 * are the neighbours' initial outputs by construction, which a master that transfers the initial
 * outputs (libcosim) sets anyway, and which a master that starts its connections at 0 (fmpy's SSP
 * master) does not.
 *
 * This file includes gearbox_model.c under other names (gbm_*, declared in stage_model.h) and
 * wraps it: the gearbox model reads the configuration (gearfmu_gearbox.txt; its extra_outputs are the
 * flanges' torque outputs), the tables, the variable table and does the steps; this file reads the
 * flange= lines of the same file, sets the flanges before each step and writes their torques after
 * it.  What a step rejects (a non-finite flange speed, anything the gearbox model rejects) leaves the
 * state and the flanges unchanged.  The FMU state is the gearbox model's with the flanges after it.
 */
#include "stage_model.h"

#define gm_instantiate gbm_instantiate
#define gm_free gbm_free
#define gm_reset gbm_reset
#define gm_exit_init gbm_exit_init
#define gm_refresh_outputs gbm_refresh_outputs
#define gm_do_step gbm_do_step
#define gm_snap_size gbm_snap_size
#define gm_snap_write gbm_snap_write
#define gm_snap_read gbm_snap_read
#define gm_snap_is_ours gbm_snap_is_ours
#include "gearbox_model.c"
#undef gm_instantiate
#undef gm_free
#undef gm_reset
#undef gm_exit_init
#undef gm_refresh_outputs
#undef gm_do_step
#undef gm_snap_size
#undef gm_snap_write
#undef gm_snap_read
#undef gm_snap_is_ours

static st_flanges *flanges(const gf_inst *c) { return &((st_data *)(void *)c->data)->fl; }

/* the flange= lines (body|shaft|vr of the speed input|output index of the torque) of the configuration */
static const char *read_flanges(gf_inst *c, const char *text, char *err, size_t errcap)
{
    st_flanges *fl = flanges(c);
    const gb_model *gb = c->data->gb;
    char line[GB_MAX_LINE];
    const char *p = text;
    int k;
    memset(fl, 0, sizeof *fl);
    fl->vr_first_start = fl->vr_order = -1;
    while (*p != '\0') {
        size_t n = strcspn(p, "\n");
        long v[4];
        if (n < sizeof line) {
            memcpy(line, p, n);
            line[n] = '\0';
            if (n > 0 && line[n - 1] == '\r') line[n - 1] = '\0';
            if (strncmp(line, "flange=", 7) == 0) {
                int ok = fl->n < ST_MAX_FLANGES && gfm_parse_ints(line + 7, v, 4);
                if (ok) ok = v[0] >= 0 && v[0] < gb->n && v[1] >= 0 && v[1] < gb->n_shaft &&
                             (gb->shaft_a[v[1]] == v[0] || gb->shaft_b[v[1]] == v[0]) &&
                             gfm_vr_ok(c, v[2], 0) && c->vars[v[2]].causality == GF_INPUT &&
                             v[3] >= gb_n_outputs(gb) && v[3] < c->n_out;
                if (!ok) {
                    snprintf(err, errcap, "flange entry '%.80s': body|shaft|speed input|torque output index of "
                             "one of the shaft's ends (at most %d)", line + 7, ST_MAX_FLANGES);
                    return err;
                }
                fl->body[fl->n] = (int)v[0];
                fl->shaft[fl->n] = (int)v[1];
                fl->vr_speed[fl->n] = (int)v[2];
                fl->out_torque[fl->n] = (int)v[3];
                fl->n++;
            } else if (strncmp(line, "port_torque=", 12) == 0) {
                if (fl->n_port >= 2 || !gfm_parse_ints(line + 12, v, 1) || !gfm_vr_ok(c, v[0], 0) ||
                    c->vars[v[0]].causality != GF_INPUT) {
                    snprintf(err, errcap, "port_torque entry '%.80s': a torque input (at most 2)", line + 12);
                    return err;
                }
                fl->vr_port[fl->n_port++] = (int)v[0];
            } else if (strncmp(line, "vr.flange_order=", 16) == 0) {
                if (!gfm_parse_ints(line + 16, v, 1) || !gfm_vr_ok(c, v[0], 0) || c->vars[v[0]].causality != GF_PARAMETER) {
                    snprintf(err, errcap, "vr.flange_order: not a parameter");
                    return err;
                }
                fl->vr_order = (int)v[0];
            } else if (strncmp(line, "vr.first_step_start_values=", 27) == 0) {
                if (!gfm_parse_ints(line + 27, v, 1) || !gfm_vr_ok(c, v[0], 0) || c->vars[v[0]].causality != GF_PARAMETER) {
                    snprintf(err, errcap, "vr.first_step_start_values: not a parameter");
                    return err;
                }
                fl->vr_first_start = (int)v[0];
            }
        }
        p += n;
        if (*p == '\n') p++;
    }
    if (fl->vr_first_start < 0 || (fl->n > 0 && fl->vr_order < 0)) {
        snprintf(err, errcap, "vr.first_step_start_values or (with flanges) vr.flange_order missing");
        return err;
    }
    for (k = 0; k < fl->n; ++k)
        if (fl->body[k] != 0 && fl->body[k] != gb->load_body) {
            snprintf(err, errcap, "flange %d: body %d is neither the reference body nor the load body", k, fl->body[k]);
            return err;
        }
    return NULL;
}

const char *gm_instantiate(gf_inst *c, const char *res_dir, const char *token, char *err, size_t errcap)
{
    char path[4096];
    unsigned char *text;
    size_t size = 0;
    st_data *sd;
    const char *e = gbm_instantiate(c, res_dir, token, err, errcap);
    int k;
    if (e != NULL) return e;
    sd = (st_data *)realloc(c->data, sizeof(st_data));
    if (sd == NULL) return "out of memory";
    c->data = &sd->gb;
    if (!gfr_join_path(res_dir, GB_CONFIG_FILE, path, sizeof path)) return "resource location too long";
    text = gfr_read_file(path, &size);
    if (text == NULL) return "cannot read the configuration again";
    {
        char e2[512];
        e = read_flanges(c, (const char *)text, e2, sizeof e2);
        free(text);
        if (e != NULL) {
            snprintf(err, errcap, "resources/%s: %s", GB_CONFIG_FILE, e);
            return err;
        }
    }
    for (k = 0; k < sd->fl.n; ++k) sd->gb.gb->inv_I[sd->fl.body[k]] = 0.0;  /* prescribed motion */
    gf_log(c, GF_OK, "logAll", "stage model: %d flange(s)", sd->fl.n);
    return NULL;
}

void gm_free(gf_inst *c) { gbm_free(c); }

void gm_reset(gf_inst *c)
{
    gbm_reset(c);
    if (c->data != NULL) {
        st_flanges *fl = flanges(c);
        int k;
        for (k = 0; k < fl->n; ++k) fl->theta[k] = fl->omega[k] = 0.0;
        fl->h_prev = 0.0;
    }
}

/* the absolute angle and speed of body b at state s */
static void body_motion(const gb_model *gb, const gb_state *s, int b, double *theta, double *omega)
{
    *theta = b == 0 ? s->y[0] : gb->g[b] * s->y[0] + s->y[2 * b];
    *omega = b == 0 ? s->y[1] : gb->g[b] * s->y[1] + s->y[2 * b + 1];
}

/* the flanges' torque outputs after a step of H (0: at the initial state), the flanges at speeds w_end:
 * the shaft torque at the end of the step, T = k (theta_a - theta_b) + c (w_a - w_b) (it replaces the
 * kernel's, which saw the flange at the speed of the last substep), and the torque the shaft transmits
 * predicted for the middle of the next step, T + (H/2) k (w_a - w_b) */
static void flange_outputs(gf_inst *c, double H, const double *w_end)
{
    const gb_model *gb = c->data->gb;
    st_flanges *fl = flanges(c);
    int k;
    for (k = 0; k < fl->n; ++k) {
        int s = fl->shaft[k], a = gb->shaft_a[s], b = gb->shaft_b[s];
        double ta, wa, tb, wb, T;
        body_motion(gb, &c->data->state, a, &ta, &wa);
        body_motion(gb, &c->data->state, b, &tb, &wb);
        if (a == fl->body[k]) wa = w_end[k];
        else wb = w_end[k];
        T = gb->shaft_k[s] * (ta - tb) + gb->shaft_c[s] * (wa - wb);
        if (H > 0.0) c->out[gb_shaft_offset(gb) + s] = T;
        c->out[fl->out_torque[k]] = (H > 0.0 ? T : c->out[gb_shaft_offset(gb) + s]) + 0.5 * H * gb->shaft_k[s] * (wa - wb);
    }
}

/* the flanges from the initial state */
static void flanges_from_state(gf_inst *c)
{
    st_flanges *fl = flanges(c);
    int k;
    for (k = 0; k < fl->n; ++k) body_motion(c->data->gb, &c->data->state, fl->body[k], &fl->theta[k], &fl->omega[k]);
    fl->h_prev = 0.0;
    flange_outputs(c, 0.0, fl->omega);
}

int gm_exit_init(gf_inst *c)
{
    if (!gbm_exit_init(c)) return 0;
    flanges_from_state(c);
    return 1;
}

int gm_refresh_outputs(gf_inst *c, const char *fn, const unsigned int vr[], size_t nvr)
{
    int was_dirty = c->mode == GF_INIT_MODE && c->dirty;
    if (!gbm_refresh_outputs(c, fn, vr, nvr)) return 0;
    if (was_dirty && !c->dirty && c->data->core.initialized) flanges_from_state(c);
    return 1;
}

/* the flanges at angles theta[] and speeds w[]: the reference body first (the other bodies keep their
 * absolute motion), then a flange at the load body */
static void set_flanges(gf_inst *c, const double *theta, const double *w)
{
    gm_data *d = c->data;
    st_flanges *fl = flanges(c);
    double *y = d->state.y;
    int k, i;
    for (k = 0; k < fl->n; ++k)
        if (fl->body[k] == 0) {
            double dpsi = y[0] - theta[k], dom = y[1] - w[k];
            for (i = 1; i < d->gb->n; ++i) {
                y[2 * i] += d->gb->g[i] * dpsi;
                y[2 * i + 1] += d->gb->g[i] * dom;
            }
            y[0] = theta[k];
            y[1] = w[k];
        }
    for (k = 0; k < fl->n; ++k)
        if (fl->body[k] != 0) {
            int b = fl->body[k];
            y[2 * b] = theta[k] - d->gb->g[b] * y[0];
            y[2 * b + 1] = w[k] - d->gb->g[b] * y[1];
        }
}

/* One communication step.  The flange's angle at its start by the trapezoidal rule, its speed the input
 * (first step: the initial state's); over the step it turns at that speed (flange_order 1), or with the
 * acceleration of the last two speeds received (flange_order 2): then the step is cut into the substeps
 * of the integrator, n = ceil(H/max_step), the flange on the parabola at each substep's start and turning
 * at its chord's speed over it. */
int gm_do_step(gf_inst *c, double t, double H)
{
    gm_data *d = c->data;
    st_flanges *fl = flanges(c), fl0;
    gb_state s0;
    double w[ST_MAX_FLANGES], acc[ST_MAX_FLANGES], th[ST_MAX_FLANGES], wc[ST_MAX_FLANGES], w_end[ST_MAX_FLANGES];
    double held[2], hmax;
    long n_sub = 1, j;
    int k, st = GF_OK, bad = 0, first, quad;
    if (!d->core.initialized) {
        if (isfinite(t)) c->time = t;
        if (!gfm_init_state(c)) return GF_DISCARD;
        flanges_from_state(c);
    }
    first = fl->h_prev == 0.0 && gfm_val(c, fl->vr_first_start) == 1.0;
    for (k = 0; k < fl->n; ++k) {
        bad |= gfm_bad_value(c, fl->vr_speed[k], GF_DISCARD, "; step rejected, state unchanged");
        w[k] = first ? fl->omega[k] : gfm_val(c, fl->vr_speed[k]);
    }
    if (fl->n > 0) bad |= gfm_bad_value(c, fl->vr_order, GF_DISCARD, "; step rejected, state unchanged");
    if (bad) return GF_DISCARD;
    if (!(isfinite(H) && H > 0.0)) return gbm_do_step(c, t, H);   /* rejected there, with its message */
    quad = fl->n > 0 && gfm_val(c, fl->vr_order) == 2.0 && fl->h_prev > 0.0;
    hmax = gfm_val(c, d->core.vr_hmax);
    if (quad && hmax > 0.0 && H / hmax < 1e8) n_sub = (long)ceil(H / hmax * (1.0 - 1e-12));
    if (n_sub < 1) n_sub = 1;
    s0 = d->state;
    fl0 = *fl;
    for (k = 0; k < fl->n; ++k) {
        if (fl->h_prev > 0.0) fl->theta[k] = fl->theta[k] + fl->h_prev * 0.5 * (fl->omega[k] + w[k]);
        acc[k] = quad ? (w[k] - fl->omega[k]) / fl->h_prev : 0.0;
        w_end[k] = w[k] + acc[k] * H;
    }
    for (k = 0; k < fl->n_port; ++k) {   /* the first step: the ports' torques at their start values */
        held[k] = c->values[fl->vr_port[k]];
        if (first) c->values[fl->vr_port[k]] = c->vars[fl->vr_port[k]].start;
    }
    for (j = 0; j < n_sub && st == GF_OK; ++j) {
        double t0 = H * (double)j / (double)n_sub, t1 = j + 1 == n_sub ? H : H * (double)(j + 1) / (double)n_sub;
        for (k = 0; k < fl->n; ++k) {
            th[k] = fl->theta[k] + w[k] * t0 + 0.5 * acc[k] * t0 * t0;
            wc[k] = w[k] + 0.5 * acc[k] * (t0 + t1);
        }
        set_flanges(c, th, wc);
        st = gbm_do_step(c, t + t0, t1 - t0);
    }
    for (k = 0; k < fl->n_port; ++k) c->values[fl->vr_port[k]] = held[k];
    if (st != GF_OK) {
        d->state = s0;
        *fl = fl0;
        c->time = t;
        return st;
    }
    c->time = t + H;
    for (k = 0; k < fl->n; ++k) fl->omega[k] = w[k];
    fl->h_prev = H;
    flange_outputs(c, H, w_end);
    return GF_OK;
}

size_t gm_snap_size(const gf_inst *c) { return gbm_snap_size(c) + sizeof(st_flanges); }

void gm_snap_write(const gf_inst *c, unsigned char *p)
{
    gbm_snap_write(c, p);
    memcpy(p + gbm_snap_size(c), flanges(c), sizeof(st_flanges));
}

int gm_snap_is_ours(const gf_inst *c, const unsigned char *p, size_t size)
{
    st_flanges f;
    size_t n = gbm_snap_size(c);
    if (size != n + sizeof f || !gbm_snap_is_ours(c, p, n)) return 0;
    memcpy(&f, p + n, sizeof f);
    return memcmp(f.body, flanges(c)->body, sizeof f.body) == 0 && f.n == flanges(c)->n;
}

int gm_snap_read(gf_inst *c, const unsigned char *p, size_t size, const char *fn)
{
    size_t n = gbm_snap_size(c);
    if (!gm_snap_is_ours(c, p, size)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: not a state of this FMU", fn);
        return 0;
    }
    if (!gbm_snap_read(c, p, n, fn)) return 0;
    memcpy(flanges(c), p + n, sizeof(st_flanges));
    return 1;
}
