/*
 * gear_model.c -- the gear model of the standalone gearfmu runtime, one
 * definition for its FMI 2.0 layer (fmi2_gear.c) and its FMI 3.0 layer
 * (fmi3_gear.c): the model side of the contract gf_model.h (which says how the plumbing
 * fmi_common.c and this file split the work).  It calls nothing of the plumbing; its
 * messages go through gf_log to the host.
 *
 * What instantiation reads (from the resource folder the layer resolves: FMI 2
 * gives a file:// URI, FMI 3 a native path):
 *   gearfmu_standalone.txt  key=value lines written by
 *       gearfmu/fmu/standalone_build.py: GUID (FMI 3: instantiation token),
 *       table dimensions and byte offsets, scalars as C99 hexadecimal floats
 *       (exact), the SHA-256 of tables.bin and the variable table (value
 *       reference, causality, variability, type, kernel output index, start,
 *       min, max, name) -- the same value references as
 *       modeldescription/variables.toml via gearfmu/fmu/modeldesc.py.
 *   tables.bin  the tables (little-endian float64 arrays,
 *       gearfmu/tables/mesh_tables.py format); its SHA-256 (FIPS 180-4, computed here)
 *       must equal the recorded one, else instantiation is refused.
 *
 * Behaviour (docs/fmu.md): the checks, kernel calls and messages are the ones of
 * ../kernel/gkfmu.c, which the pythonfmu runtime calls too: non-finite or
 * out-of-range inputs, a bad communication step or a kernel failure -> a log
 * message and Discard with the state unchanged; nothing here ever aborts
 * or calls exit.  The FMU state is a plain struct (the kernel state), copied
 * with the variable values into one flat block (gm_snap_*).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gear_model.h"
#include "gf_resources.h"

#define GF_CONFIG_FILE "gearfmu_standalone.txt"
#define GF_CONFIG_FORMAT "gearfmu-standalone"
#define GF_CONFIG_VERSION 1
#define GF_MAX_LINE 4096
#define GF_SNAPSHOT_MAGIC 0x47464d55u /* "GFMU" */
#define GF_SNAPSHOT_VERSION 3u /* 2: mode is a GF_* state bit; 3: Model Exchange's mode and dirty flag */

/* The FMU state block (flat, no pointers): header, kernel state, values, outputs. */
typedef struct {
    uint32_t magic;
    uint32_t version;
    uint32_t n_vars;
    uint32_t n_out;
    uint64_t tables_tag;  /* first 8 bytes of the tables' SHA-256: a state fits one FMU only */
    int32_t mode;
    int32_t initialized;
    int32_t warned_range;
    int32_t zeta_valid;
    double time;
    double zeta_applied;
    gk_state state;
    gk_me me;             /* Model Exchange: the mode held */
    int32_t dirty;
    int32_t pad;
    /* followed by double values[n_vars], double out[n_out] */
} gf_snap_header;

/* ------------------------------------------------------------- config */
typedef struct {
    char guid[GF_MAX_NAME];
    char sha[65];
    long P, n_phi, n_torque, bin_size;
    long off_torque, off_k, off_e, off_b;
    long n_temp, off_temp;  /* optional: temperature axis (n_temp = 0: none) */
    double phi_period, Rb1, Rb2, I1, I2, k_mean;
    double mesh_period, eng_in, eng_out;  /* optional: contact-zone edges (all three or none) */
    int have_mask;
    /* optional: the interfaces offered (interfaces=cs,me; default cs) and Model Exchange's settings
     * (me.node_events, me.event_indicators: the count the model description declares, me.nominals) */
    int offers, me_node_events;
    long me_indicators;
    double me_nominal[4];
    int have_nominals;
    /* optional: the verified envelope (envelope.kind, envelope.<quantity>=lo|hi) */
    int env_kind, env_have[GK_ENV_N];
    double env_lo[GK_ENV_N], env_hi[GK_ENV_N];
} gf_config;

enum {
    HAVE_GUID = 1 << 0, HAVE_SHA = 1 << 1, HAVE_P = 1 << 2, HAVE_NPHI = 1 << 3, HAVE_NT = 1 << 4,
    HAVE_SIZE = 1 << 5, HAVE_OT = 1 << 6, HAVE_OK = 1 << 7, HAVE_OE = 1 << 8, HAVE_OB = 1 << 9,
    HAVE_PHI = 1 << 10, HAVE_RB1 = 1 << 11, HAVE_RB2 = 1 << 12, HAVE_I1 = 1 << 13, HAVE_I2 = 1 << 14,
    HAVE_KM = 1 << 15, HAVE_FORMAT = 1 << 16, HAVE_NVARS = 1 << 17, HAVE_ALL = (1 << 18) - 1
};

/* returns NULL on success, else a message (written into err) */
static const char *read_config(gf_inst *c, const char *text, gf_config *cfg, char *err, size_t errcap)
{
    char line[GF_MAX_LINE], *key, *val;
    const char *p = text;
    int nvar_seen = 0, lineno = 0, more;
    memset(cfg, 0, sizeof *cfg);
    cfg->env_kind = GK_ENV_NOT_VERIFIED;
    while ((more = gfr_next_config_line(&p, line, sizeof line, &lineno, &key, &val, err, errcap)) > 0) {
#define GF_D(name, field, bit)                                                                   \
    else if (strcmp(key, name) == 0) {                                                           \
        if (!gfr_parse_double(val, &cfg->field)) { snprintf(err, errcap, "%s: bad number", name); return err; } \
        cfg->have_mask |= bit;                                                                   \
    }
#define GF_L(name, field, bit)                                                                   \
    else if (strcmp(key, name) == 0) {                                                           \
        if (!gfr_parse_long(val, &cfg->field)) { snprintf(err, errcap, "%s: bad integer", name); return err; } \
        cfg->have_mask |= bit;                                                                   \
    }
        if (strcmp(key, "format") == 0) {
            if (strcmp(val, GF_CONFIG_FORMAT) != 0) {
                snprintf(err, errcap, "format is '%s', expected '%s'", val, GF_CONFIG_FORMAT);
                return err;
            }
            cfg->have_mask |= HAVE_FORMAT;
        } else if (strcmp(key, "version") == 0) {
            long ver;
            if (!gfr_parse_long(val, &ver) || ver != GF_CONFIG_VERSION) {
                snprintf(err, errcap, "version '%s' unsupported (this runtime reads %d)", val, GF_CONFIG_VERSION);
                return err;
            }
        } else if (strcmp(key, "guid") == 0) {
            gfr_copy_str(cfg->guid, sizeof cfg->guid, val);
            cfg->have_mask |= HAVE_GUID;
        } else if (strcmp(key, "tables_sha256") == 0) {
            if (strlen(val) != 64) { snprintf(err, errcap, "tables_sha256: need 64 hex digits"); return err; }
            gfr_copy_str(cfg->sha, sizeof cfg->sha, val);
            cfg->have_mask |= HAVE_SHA;
        }
        GF_L("slots", P, HAVE_P)
        GF_L("n_phi", n_phi, HAVE_NPHI)
        GF_L("n_torque", n_torque, HAVE_NT)
        GF_L("tables_bytes", bin_size, HAVE_SIZE)
        GF_L("offset.torque_Nm", off_torque, HAVE_OT)
        GF_L("offset.k_N_per_m", off_k, HAVE_OK)
        GF_L("offset.e_m", off_e, HAVE_OE)
        GF_L("offset.backlash_half_m", off_b, HAVE_OB)
        GF_L("n_temperature", n_temp, 0)
        GF_L("offset.temperature_C", off_temp, 0)
        GF_D("phi_period_rad", phi_period, HAVE_PHI)
        GF_D("base_radius_pinion_m", Rb1, HAVE_RB1)
        GF_D("base_radius_gear_m", Rb2, HAVE_RB2)
        GF_D("inertia_pinion_kgm2", I1, HAVE_I1)
        GF_D("inertia_gear_kgm2", I2, HAVE_I2)
        GF_D("k_mean_N_per_m", k_mean, HAVE_KM)
        GF_D("mesh_period_rad", mesh_period, 0)
        GF_D("engagement_in_rad", eng_in, 0)
        GF_D("engagement_out_rad", eng_out, 0)
        else if (strcmp(key, "n_vars") == 0) {
            long nv;
            if (!gfr_parse_long(val, &nv) || nv < 1 || nv > 100000 || c->vars != NULL) {
                snprintf(err, errcap, "n_vars: bad value '%s'", val);
                return err;
            }
            c->n_vars = (int)nv;
            c->vars = (gf_var *)calloc((size_t)nv, sizeof(gf_var));
            c->values = (double *)calloc((size_t)nv, sizeof(double));
            if (c->vars == NULL || c->values == NULL) { snprintf(err, errcap, "out of memory"); return err; }
            cfg->have_mask |= HAVE_NVARS;
        } else if (strcmp(key, "var") == 0) {
            if (c->vars == NULL || !gfr_parse_var(c, val, &nvar_seen)) {
                snprintf(err, errcap, "line %d: bad variable entry (n_vars first, then vr 0, 1, ... in order)", lineno);
                return err;
            }
        }
        else if (strcmp(key, "interfaces") == 0) {
            if (strcmp(val, "cs") == 0) cfg->offers = GF_COSIMULATION;
            else if (strcmp(val, "me") == 0) cfg->offers = GF_MODEL_EXCHANGE;
            else if (strcmp(val, "cs,me") == 0) cfg->offers = GF_COSIMULATION | GF_MODEL_EXCHANGE;
            else {
                snprintf(err, errcap, "interfaces: '%.40s' is not cs, me or cs,me", val);
                return err;
            }
        } else if (strcmp(key, "me.node_events") == 0) {
            long ne;
            if (!gfr_parse_long(val, &ne) || ne < GK_ME_NODES_NONE || ne > GK_ME_NODES_ALL) {
                snprintf(err, errcap, "me.node_events: bad value '%.40s'", val);
                return err;
            }
            cfg->me_node_events = (int)ne;
        } else if (strcmp(key, "me.event_indicators") == 0) {
            if (!gfr_parse_long(val, &cfg->me_indicators) || cfg->me_indicators < 0) {
                snprintf(err, errcap, "me.event_indicators: bad value '%.40s'", val);
                return err;
            }
        } else if (strcmp(key, "me.nominals") == 0) {
            char *f[4];
            int q;
            if (gfr_split_fields(val, f, 4) != 4) { snprintf(err, errcap, "me.nominals: need four numbers"); return err; }
            for (q = 0; q < 4; ++q)
                if (!gfr_parse_double(f[q], &cfg->me_nominal[q]) || !(cfg->me_nominal[q] > 0.0) || !isfinite(cfg->me_nominal[q])) {
                    snprintf(err, errcap, "me.nominals: need four finite numbers > 0");
                    return err;
                }
            cfg->have_nominals = 1;
        }
        else if (strcmp(key, "envelope.kind") == 0) {
            long kind;
            if (!gfr_parse_long(val, &kind) || kind < GK_ENV_VERIFIED || kind > GK_ENV_NOT_VERIFIED) {
                snprintf(err, errcap, "envelope.kind: bad value '%s'", val);
                return err;
            }
            cfg->env_kind = (int)kind;
        } else if (strncmp(key, "envelope.", 9) == 0) {
            static const char *const env_keys[GK_ENV_N] = {"pinion_torque_Nm", "pinion_speed_rad_s", "temperature_C"};
            char *f[2];
            int q;
            for (q = 0; q < GK_ENV_N; ++q)
                if (strcmp(key + 9, env_keys[q]) == 0) break;
            if (q < GK_ENV_N) { /* lo|hi, finite, lo <= hi */
                if (gfr_split_fields(val, f, 2) != 2 || !gfr_parse_double(f[0], &cfg->env_lo[q]) ||
                    !gfr_parse_double(f[1], &cfg->env_hi[q]) || !(cfg->env_lo[q] <= cfg->env_hi[q])) {
                    snprintf(err, errcap, "%.64s: need low|high numbers with low <= high", key);
                    return err;
                }
                cfg->env_have[q] = 1;
            }
        }
        /* unknown keys are ignored (forward compatible) */
#undef GF_D
#undef GF_L
    }
    if (more < 0) return err;
    if ((cfg->have_mask & HAVE_ALL) != HAVE_ALL) {
        snprintf(err, errcap, "missing keys (mask 0x%x of 0x%x)", (unsigned)cfg->have_mask, (unsigned)HAVE_ALL);
        return err;
    }
    if (nvar_seen != c->n_vars) {
        snprintf(err, errcap, "n_vars = %d but %d var lines", c->n_vars, nvar_seen);
        return err;
    }
    return NULL;
}

/* ------------------------------------------------------------ checks */
/* The checks, the kernel calls and their messages are gkfmu.c's, the ones the pythonfmu
 * runtime calls too; here the current values go in and the messages go to the host. */
static void to_fmu_layer(gf_inst *c)
{
    double v[GKF_N];
    int k;
    for (k = 0; k < GKF_N; ++k) v[k] = c->data->slot_vr[k] >= 0 ? c->values[c->data->slot_vr[k]] : 0.0;
    gkf_set_values(c->data->fmu, v);
}

static void log_fmu_messages(gf_inst *c)
{
    static const char *const category[4] = {"logAll", "logStatusWarning", "logStatusDiscard", "logStatusError"};
    int i, n = gkf_n_messages(c->data->fmu);
    for (i = 0; i < n; ++i) {
        int level = gkf_message_level(c->data->fmu, i);
        gf_log(c, level, category[level & 3], "%s", gkf_message(c->data->fmu, i));
    }
}

/* the mode decided from the state and the outputs of Model Exchange after gk_n_outputs(P) ones
 * (derivatives, indicators; a Co-Simulation instance of an FMU that offers Model Exchange has them
 * too); 1 on success */
static int me_fill(gf_inst *c, int decide)
{
    gm_data *d = c->data;
    double T1 = c->values[d->vr_T1], T2 = c->values[d->vr_T2];
    int st = GK_OK;
    if (!d->me_offered) return 1;
    if (decide) st = gk_me_init(d->model, &d->me, &d->state, T1, T2, d->me_node_events);
    if (st == GK_OK) st = gk_me_outputs(d->model, &d->me, &d->state, T1, T2, d->scratch, c->out + d->me_base);
    return st == GK_OK;
}

static int init_state(gf_inst *c)
{
    int ok;
    c->data->initialized = 0;
    to_fmu_layer(c);
    ok = gkf_initialize(c->data->fmu, &c->data->state, c->time, c->out);
    log_fmu_messages(c);
    if (ok && !me_fill(c, 1)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "the mode of the initial state cannot be decided (state or "
               "gear_torque not finite)");
        ok = 0;
    }
    c->data->initialized = ok;
    return ok;
}

/* --------------------------------------------------------- Model Exchange
 * The model side of gf_model.h's gf_me_model (docs/standalone.md "Model Exchange"): the state of the
 * host's solver is the kernel's gk_state, the mode gk_me is held between events and decided anew in
 * event mode (gk_me_update); c->dirty marks values, states or time set since the outputs were
 * computed, and before an evaluation with new values the inputs pass gkfmu.c's checks. */
static int me_inputs(gf_inst *c, const char *fn)
{
    int ok;
    (void)fn;
    if (!c->dirty) return GF_OK;
    to_fmu_layer(c);
    ok = gkf_me_inputs(c->data->fmu, c->time);
    if (gkf_n_messages(c->data->fmu) > 0) log_fmu_messages(c);
    return ok ? GF_OK : GF_DISCARD;
}

/* the kernel's status of an evaluation as the FMI layer's, logged */
static int me_status(gf_inst *c, const char *fn, int st)
{
    if (st == GK_OK) return GF_OK;
    gf_log(c, GF_DISCARD, "logStatusDiscard", "%s: at t = %.17g s: %s; not evaluated", fn, c->time,
           st == GK_ERR_NONFINITE ? "the continuous states are not finite" : gkf_kernel_error(st));
    return GF_DISCARD;
}

/* the outputs (with the mode held) at the current time, states and inputs */
static int me_outputs(gf_inst *c, const char *fn)
{
    gm_data *d = c->data;
    int st = me_inputs(c, fn);
    if (st != GF_OK) return st;
    st = me_status(c, fn, gk_me_outputs(d->model, &d->me, &d->state, c->values[d->vr_T1], c->values[d->vr_T2],
                                        c->out, c->out + d->me_base));
    if (st == GF_OK) c->dirty = 0;
    return st;
}

static int me_states(gf_inst *c, const char *fn, double x[])
{
    gm_data *d = c->data;
    if (c->mode == GF_INIT_MODE && (c->dirty || !d->initialized)) {   /* the initial state from the values set */
        if (!init_state(c)) {
            gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: the initial state cannot be computed from the values "
                   "set (reasons above)", fn);
            return GF_ERROR_STATUS;
        }
        c->dirty = 0;
    }
    x[0] = d->state.theta1_rad;
    x[1] = d->state.omega1_rad_s;
    x[2] = d->state.x_m;
    x[3] = d->state.v_m_s;
    return GF_OK;
}

static int me_nominals(gf_inst *c, const char *fn, double x[])
{
    int q;
    (void)fn;
    for (q = 0; q < 4; ++q) x[q] = c->data->me_nominal[q];
    return GF_OK;
}

static int me_set_states(gf_inst *c, const char *fn, const double x[])
{
    gm_data *d = c->data;
    (void)fn;
    d->state.theta1_rad = x[0];
    d->state.omega1_rad_s = x[1];
    d->state.x_m = x[2];
    d->state.v_m_s = x[3];
    c->dirty = 1;
    return GF_OK;
}

static int me_derivatives(gf_inst *c, const char *fn, double dx[])
{
    gm_data *d = c->data;
    double x0[4];
    int st = (c->mode == GF_INIT_MODE) ? me_states(c, fn, x0) : me_inputs(c, fn);
    if (st != GF_OK) return st;
    return me_status(c, fn, gk_me_derivatives(d->model, &d->me, &d->state, c->values[d->vr_T1],
                                              c->values[d->vr_T2], dx));
}

static int me_indicators(gf_inst *c, const char *fn, double z[])
{
    gm_data *d = c->data;
    double x0[4];
    int st = (c->mode == GF_INIT_MODE) ? me_states(c, fn, x0) : me_inputs(c, fn);
    if (st != GF_OK) return st;
    return me_status(c, fn, gk_me_indicators(d->model, &d->me, &d->state, c->values[d->vr_T1], z));
}

static int me_event_update(gf_inst *c, const char *fn, int *again, int *values_changed)
{
    gm_data *d = c->data;
    int st = me_inputs(c, fn), changed = 0;
    *again = 0;
    *values_changed = 0;
    if (st != GF_OK) return st;
    st = me_status(c, fn, gk_me_update(d->model, &d->me, &d->state, c->values[d->vr_T1], c->values[d->vr_T2],
                                       &changed));
    if (st != GF_OK) return st;
    gkf_me_speed(d->fmu, &d->state, c->time);
    if (gkf_n_messages(d->fmu) > 0) log_fmu_messages(c);
    c->dirty = 1;   /* the outputs follow the new mode */
    return GF_OK;
}

static int me_completed_step(gf_inst *c, const char *fn, int *enter_event)
{
    (void)fn;
    *enter_event = 0;
    gkf_me_speed(c->data->fmu, &c->data->state, c->time);
    if (gkf_n_messages(c->data->fmu) > 0) log_fmu_messages(c);
    return GF_OK;
}

static const gf_me_model GM_ME = {me_states, me_nominals, me_set_states, me_derivatives, me_indicators,
                                  me_event_update, me_completed_step};

void gm_reset(gf_inst *c)
{
    int i;
    for (i = 0; i < c->n_vars; ++i) c->values[i] = c->vars[i].has_start ? c->vars[i].start : 0.0;
    for (i = 0; i < c->n_out; ++i) c->out[i] = 0.0;
    memset(&c->data->state, 0, sizeof c->data->state);
    c->data->initialized = 0;
    c->dirty = 1;
    gk_envelope_rearm(&c->data->env);
    gkf_reset(c->data->fmu);
    memset(&c->data->me, 0, sizeof c->data->me);
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
    if (c->data != NULL) {
        free(c->data->blob);
        free(c->data->cuts);
        free(c->data->model);
        free(c->data->fmu);
        free(c->data->scratch);
        free(c->data);
        c->data = NULL;
    }
}

const char *gm_instantiate(gf_inst *c, const char *res_dir, const char *token, char *err, size_t errcap)
{
    gf_config cfg;
    char path[4096], hex[65];
    unsigned char *text;
    size_t size = 0;
    int st, i;
    gf_sha256 sha;
    c->data = (gm_data *)calloc(1, sizeof(gm_data));
    if (c->data == NULL) return "out of memory";
    c->data->vr_integrator = -1;
    c->data->vr_temp = -1;
    text = gfr_read_resource(res_dir, GF_CONFIG_FILE, &size, err, errcap);
    if (text == NULL) return err;
    {
        char e2[512];
        const char *e = read_config(c, (const char *)text, &cfg, e2, sizeof e2);
        free(text);
        if (e != NULL) {
            snprintf(err, errcap, "resources/%s: %s", GF_CONFIG_FILE, e);
            return err;
        }
    }
    if (token == NULL || strcmp(token, cfg.guid) != 0) return "GUID differs from the one this FMU was built with";
    /* tables.bin: size and SHA-256 */
    if (!gfr_join_path(res_dir, "tables.bin", path, sizeof path)) return "resource location too long";
    c->data->blob = gfr_read_file(path, &size);
    if (c->data->blob == NULL) return "cannot read resources/tables.bin";
    if ((long)size != cfg.bin_size) return "resources/tables.bin: wrong size (file corrupted)";
    gfr_sha_init(&sha);
    gfr_sha_update(&sha, c->data->blob, size);
    gfr_sha_final_hex(&sha, hex);
    if (strcmp(hex, cfg.sha) != 0)
        return "resources/tables.bin: SHA-256 checksum mismatch (file corrupted or tampered with)";
    {   /* the first 16 hex digits of the checksum (equal to hex: checked above) */
        char tag[17];
        memcpy(tag, hex, 16);
        tag[16] = '\0';
        c->data->tables_tag = (uint64_t)strtoull(tag, NULL, 16);
    }
    {
        long P = cfg.P, N = cfg.n_phi, NT = cfg.n_torque, NTemp = cfg.n_temp > 0 ? cfg.n_temp : 1;
        long need[5], offs[5];
        int n_arr = cfg.n_temp > 0 ? 5 : 4;
        if (P < 1 || N < 2 || NT < 1 || P > 1000 || N > 100000000L / P || NT > 10000 || NTemp > 10000 ||
            NT * NTemp > 10000)
            return "table dimensions out of range";
        need[0] = NT; need[1] = NT * NTemp * P * N; need[2] = NT * NTemp * P * N; need[3] = P * N; need[4] = NTemp;
        offs[0] = cfg.off_torque; offs[1] = cfg.off_k; offs[2] = cfg.off_e; offs[3] = cfg.off_b;
        offs[4] = cfg.off_temp;
        for (i = 0; i < n_arr; ++i)
            if (offs[i] < 0 || offs[i] % 8 != 0 || offs[i] + 8 * need[i] > (long)size)
                return "table array offsets outside resources/tables.bin";
        if (!gfr_host_little_endian()) gfr_swap8(c->data->blob, size / 8); /* stored little-endian (docs/tables.md) */
        c->data->arr_torque = (double *)(void *)(c->data->blob + cfg.off_torque);
        c->data->arr_k = (double *)(void *)(c->data->blob + cfg.off_k);
        c->data->arr_e = (double *)(void *)(c->data->blob + cfg.off_e);
        c->data->arr_b = (double *)(void *)(c->data->blob + cfg.off_b);
        c->data->arr_temp = (double *)(void *)(c->data->blob + cfg.off_temp);
        c->data->P = (int)P;
        c->data->model = (gk_model *)calloc(1, (size_t)gk_sizeof_model());
        c->n_out = gk_n_outputs(c->data->P);
        c->data->me_base = c->n_out;
        c->data->me_offered = (cfg.offers & GF_MODEL_EXCHANGE) != 0;
        if (c->data->me_offered) {
            if (P > GK_KINK_MAX_SLOTS) return "Model Exchange: more than 32 tooth-pair slots";
            c->n_out += gk_me_n_outputs(c->data->P);
        }
        c->out = (double *)calloc((size_t)c->n_out, sizeof(double));
        c->data->scratch = (double *)calloc((size_t)gk_n_outputs(c->data->P), sizeof(double));
        if (c->data->model == NULL || c->out == NULL || c->data->scratch == NULL) return "out of memory";
        st = gk_init(c->data->model, c->data->P, (int)N, (int)NT, c->data->arr_torque, c->data->arr_k, c->data->arr_e, c->data->arr_b,
                     cfg.phi_period, cfg.Rb1, cfg.Rb2, cfg.I1, cfg.I2, cfg.k_mean);
        if (st != GK_OK) {
            snprintf(err, errcap, "kernel rejects the tables (%s)", gkf_kernel_error(st));
            return err;
        }
        if (cfg.n_temp > 0) { /* temperature axis: k, e are [NT][NTemp][P][N] */
            if (gk_set_temperature_axis(c->data->model, (int)NTemp, c->data->arr_temp) != GK_OK)
                return "kernel rejects the temperature axis (not finite and ascending)";
        }
        if (cfg.mesh_period > 0.0) { /* contact-zone edges (docs/model.md "Contact-zone edges") */
            c->data->cuts = (double *)calloc((size_t)(2 * P * N), sizeof(double));
            if (c->data->cuts == NULL) return "out of memory";
            if (gk_zone_cuts((int)P, (int)N, cfg.phi_period, cfg.mesh_period, cfg.eng_in, cfg.eng_out, c->data->cuts) == GK_OK) {
                gk_set_zone_cuts(c->data->model, c->data->cuts);
                gk_set_zone_edges(c->data->model, cfg.mesh_period, cfg.eng_in, cfg.eng_out);
            }
        }
        gk_envelope_init(&c->data->env, cfg.env_kind);
        for (i = 0; i < GK_ENV_N; ++i)
            if (cfg.env_have[i]) gk_envelope_set(&c->data->env, i, cfg.env_lo[i], cfg.env_hi[i]);
        c->data->fmu = (gkf_fmu *)calloc(1, (size_t)gkf_sizeof());
        if (c->data->fmu == NULL) return "out of memory";
        gkf_init(c->data->fmu, c->data->model, &c->data->env);
    }
    /* the variables the layer drives, by name (the spec's contract) */
    c->data->vr_T1 = gfr_find_var(c, "pinion_torque");
    c->data->vr_T2 = gfr_find_var(c, "gear_torque");
    c->data->vr_zeta = gfr_find_var(c, "damping_ratio");
    c->data->vr_w0 = gfr_find_var(c, "pinion_speed_start");
    c->data->vr_th0 = gfr_find_var(c, "pinion_angle_start");
    c->data->vr_hmax = gfr_find_var(c, "max_step");
    c->data->vr_dm = gfr_find_var(c, "damping_model");
    c->data->vr_integrator = gfr_find_var(c, "integrator");
    if (cfg.n_temp > 0) {
        /* the one temperature input the interface declares (docs/thermal.md: what the axis is) */
        static const char *const temp_names[3] = {"bulk_temperature", "oil_temperature", "gearbox_temperature"};
        int ti, found = 0;
        for (ti = 0; ti < 3; ti++) {
            int vr = gfr_find_var(c, temp_names[ti]);
            if (vr >= 0) { c->data->vr_temp = vr; found++; }
        }
        if (found != 1)
            return "tables have a temperature axis but not exactly one bulk_temperature, "
                   "oil_temperature or gearbox_temperature input";
    }
    if (c->data->vr_T1 < 0 || c->data->vr_T2 < 0 || c->data->vr_zeta < 0 || c->data->vr_w0 < 0 || c->data->vr_th0 < 0 || c->data->vr_hmax < 0 ||
        c->data->vr_dm < 0)
        return "variable table lacks one of pinion_torque, gear_torque, damping_ratio, "
               "pinion_speed_start, pinion_angle_start, max_step, damping_model";
    for (i = 0; i < c->n_vars; ++i)
        if ((c->vars[i].causality == GF_OUTPUT && c->vars[i].out_index < 0) || c->vars[i].out_index >= c->n_out)
            return "an output's kernel index is outside the output vector";
    /* Model Exchange (docs/standalone.md "Model Exchange") */
    c->offers = cfg.offers ? cfg.offers : GF_COSIMULATION;
    if (c->data->me_offered) {
        int q;
        c->data->me_node_events = cfg.me_node_events;
        c->n_states = 4;
        c->n_indicators = (size_t)gk_me_n_indicators(c->data->model, cfg.me_node_events);
        if ((long)c->n_indicators != cfg.me_indicators) {
            snprintf(err, errcap, "Model Exchange: the tables give %lu event indicators, the model description "
                     "declares %ld", (unsigned long)c->n_indicators, cfg.me_indicators);
            return err;
        }
        for (q = 0; q < 4; ++q) c->data->me_nominal[q] = cfg.have_nominals ? cfg.me_nominal[q] : 1.0;
        c->me = &GM_ME;
    }
    /* the variables gkfmu.c checks and drives, with their names and min/max */
    c->data->slot_vr[GKF_DAMPING_RATIO] = c->data->vr_zeta;
    c->data->slot_vr[GKF_PINION_SPEED_START] = c->data->vr_w0;
    c->data->slot_vr[GKF_PINION_ANGLE_START] = c->data->vr_th0;
    c->data->slot_vr[GKF_MAX_STEP] = c->data->vr_hmax;
    c->data->slot_vr[GKF_DAMPING_MODEL] = c->data->vr_dm;
    c->data->slot_vr[GKF_INTEGRATOR] = c->data->vr_integrator;
    c->data->slot_vr[GKF_PINION_TORQUE] = c->data->vr_T1;
    c->data->slot_vr[GKF_GEAR_TORQUE] = c->data->vr_T2;
    c->data->slot_vr[GKF_TEMPERATURE] = c->data->vr_temp;
    for (i = 0; i < GKF_N; ++i) {
        const gf_var *v;
        if (c->data->slot_vr[i] < 0) continue;
        v = &c->vars[c->data->slot_vr[i]];
        if (gkf_declare(c->data->fmu, i, v->name, v->has_min, v->min, v->has_max, v->max) != GK_OK)
            return "a variable name is too long";
    }
    gfr_mark_arrays(c);
    gm_reset(c);
    gf_log(c, GF_OK, "logAll", "instantiated: %d slots, %ld angle points, %ld torque rows, tables SHA-256 ok",
           c->data->P, cfg.n_phi, cfg.n_torque);
    return NULL;
}

/* the end of initialization mode (gf_enter_init): the initial state from the values set, unless
 * the outputs are already those of the current values */
int gm_exit_init(gf_inst *c)
{
    if (c->dirty || !c->data->initialized) {
        if (!init_state(c)) return 0;
        c->dirty = 0;
    }
    return 1;
}

/* In initialization mode, bring the outputs up to date with the values set
 * (only when an output is asked for); 0 if they cannot be computed (logged). */
int gm_refresh_outputs(gf_inst *c, const char *fn, const unsigned int vr[], size_t nvr)
{
    size_t i;
    int want = 0;
    if (!c->dirty || !(c->mode & (GF_INIT_MODE | GF_EVENT_MODE | GF_CONT_MODE))) return 1;
    for (i = 0; i < nvr && !want; ++i) want = (long)vr[i] < (long)c->n_vars && c->vars[vr[i]].out_index >= 0;
    if (!want) return 1;
    if (c->mode != GF_INIT_MODE) return me_outputs(c, fn) == GF_OK;
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
    int ok;
    if (isfinite(t)) c->time = t;
    if (!c->data->initialized && !init_state(c)) return GF_DISCARD;
    to_fmu_layer(c);
    ok = gkf_do_step(c->data->fmu, &c->data->state, c->time, H, c->out);
    if (gkf_n_messages(c->data->fmu) > 0) log_fmu_messages(c);
    if (!ok) return GF_DISCARD;
    me_fill(c, 1);   /* an FMU that offers Model Exchange: its derivatives and indicators as outputs */
    c->time = c->time + H;
    return GF_OK;
}

/* ------------------------------------------------------------ FMU state */
size_t gm_snap_size(const gf_inst *c)
{
    return sizeof(gf_snap_header) + sizeof(double) * ((size_t)c->n_vars + (size_t)c->n_out);
}

void gm_snap_write(const gf_inst *c, unsigned char *p)
{
    gf_snap_header h;
    memset(&h, 0, sizeof h);
    h.magic = GF_SNAPSHOT_MAGIC;
    h.version = GF_SNAPSHOT_VERSION;
    h.n_vars = (uint32_t)c->n_vars;
    h.n_out = (uint32_t)c->n_out;
    h.tables_tag = c->data->tables_tag;
    h.mode = c->mode;
    h.initialized = c->data->initialized;
    h.warned_range = gkf_warned_range(c->data->fmu);
    h.zeta_valid = gkf_zeta_valid(c->data->fmu);
    h.time = c->time;
    h.zeta_applied = gkf_zeta_applied(c->data->fmu);
    h.state = c->data->state;
    h.me = c->data->me;
    h.dirty = c->dirty;
    memcpy(p, &h, sizeof h);
    memcpy(p + sizeof h, c->values, sizeof(double) * (size_t)c->n_vars);
    memcpy(p + sizeof h + sizeof(double) * (size_t)c->n_vars, c->out, sizeof(double) * (size_t)c->n_out);
}

int gm_snap_is_ours(const gf_inst *c, const unsigned char *p, size_t size)
{
    gf_snap_header h;
    if (size < sizeof h) return 0;
    memcpy(&h, p, sizeof h);
    return h.magic == GF_SNAPSHOT_MAGIC && h.version == GF_SNAPSHOT_VERSION && h.tables_tag == c->data->tables_tag;
}

int gm_snap_read(gf_inst *c, const unsigned char *p, size_t size, const char *fn)
{
    gf_snap_header h;
    int st;
    if (size != gm_snap_size(c)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: state has %lu bytes, this FMU's has %lu", fn,
               (unsigned long)size, (unsigned long)gm_snap_size(c));
        return 0;
    }
    memcpy(&h, p, sizeof h);
    if (!gm_snap_is_ours(c, p, size) || h.n_vars != (uint32_t)c->n_vars || h.n_out != (uint32_t)c->n_out) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: not a state of this FMU (header mismatch)", fn);
        return 0;
    }
    if ((h.mode & GF_ANY_STATE) == 0 || (h.mode & (h.mode - 1)) != 0 || (h.initialized & ~1) != 0) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: state has an invalid FMI state %d", fn, (int)h.mode);
        return 0;
    }
    if (((h.mode & (GF_EVENT_MODE | GF_CONT_MODE)) != 0 && c->fmu_type != GF_MODEL_EXCHANGE) ||
        (h.mode == GF_STEP_MODE && c->fmu_type == GF_MODEL_EXCHANGE)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: the state is of a %s instance, this one is %s", fn,
               h.mode == GF_STEP_MODE ? "Co-Simulation" : "Model Exchange",
               c->fmu_type == GF_MODEL_EXCHANGE ? "Model Exchange" : "Co-Simulation");
        return 0;
    }
    c->mode = h.mode;
    c->dirty = (h.mode == GF_INSTANTIATED || h.mode == GF_INIT_MODE) || h.dirty != 0;
    c->data->initialized = h.initialized;
    c->time = h.time;
    c->data->state = h.state;
    c->data->me = h.me;
    memcpy(c->values, p + sizeof h, sizeof(double) * (size_t)c->n_vars);
    memcpy(c->out, p + sizeof h + sizeof(double) * (size_t)c->n_vars, sizeof(double) * (size_t)c->n_out);
    /* the kernel model's integrator and damping are derived from the restored values */
    to_fmu_layer(c);
    st = gkf_restore(c->data->fmu, 1, h.zeta_valid, h.zeta_applied, h.warned_range);
    if (st != GK_OK) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: the state's integrator or damping is refused (%s)", fn,
               gkf_kernel_error(st));
        return 0;
    }
    return 1;
}
