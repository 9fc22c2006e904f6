/*
 * gf_meshes.c -- the behaviour the multi-mesh models of the standalone runtime share (gf_meshes.h):
 * the gearbox model (gearbox_model.c) and the planetary model (planetary_model.c).
 *
 * Behaviour (the pair FMU's, docs/standalone.md "Behaviour"): a parameter outside its range, a
 * max_step <= 0, an integrator or damping model that does not exist, or a mesh with no tooth pair
 * in contact at the start: no initial state (Error, reasons logged).  A non-finite input, a bad
 * communication step or a state turned non-finite: the step is discarded with a message and the
 * state unchanged.  A mesh torque outside its tables' torque axis: one warning per excursion and
 * mesh (the tables are used at the nearest end).  Nothing here ever aborts.  The FMU state is the
 * kernel state (plain structs) with the variable values in one flat block (gfm_snap_*).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gf_meshes.h"

/* The FMU state block (flat, no pointers): this header, the kernel state, its Model Exchange modes,
 * then double values[n_vars], double out[n_out]. */
typedef struct {
    uint32_t magic;
    uint32_t version;
    uint32_t n_vars;
    uint32_t n_out;
    uint64_t tables_tag;
    int32_t mode;
    int32_t initialized;
    uint32_t warned;
    int32_t dirty;
    double time;
} gfm_snap_header;

static gfm_core *core_of(const gf_inst *c) { return (gfm_core *)(void *)c->data; }
/* the model's data (handed to the kernel functions) and what lies at an offset into it */
static void *kd_of(const gfm_core *d) { return (void *)(uintptr_t)d; }
static void *at(const gfm_core *d, size_t offset) { return (void *)((char *)kd_of(d) + offset); }
static double *y_of(const gfm_core *d) { return (double *)at(d, d->y_offset); }

const char *gfm_num(double x, char buf[GFM_NUM])
{
    int p, e;
    const char *ep;
    if (isnan(x)) return "nan";
    if (isinf(x)) return x > 0 ? "inf" : "-inf";
    for (p = 1; p < 17; ++p) {
        snprintf(buf, GFM_NUM, "%.*g", p, x);
        if (strtod(buf, NULL) == x) break;
    }
    snprintf(buf, GFM_NUM, "%.*e", p - 1, x);
    ep = strchr(buf, 'e');
    e = ep != NULL ? atoi(ep + 1) : 0;
    if (e >= 0 && e < 16 && p < e + 1) p = e + 1;
    snprintf(buf, GFM_NUM, "%.*g", p, x);
    if (strpbrk(buf, ".e") == NULL) strcat(buf, ".0");
    return buf;
}

int gfm_parse_ints(char *val, long *out, int n)
{
    char *f[16];
    int i;
    if (n > 16 || gfr_split_fields(val, f, n) != n) return 0;
    for (i = 0; i < n; ++i)
        if (!gfr_parse_long(f[i], &out[i])) return 0;
    return 1;
}

/* ------------------------------------------------------------- configuration */
int gfm_common_key(gf_inst *c, gfm_common_cfg *cc, const char *format, long version, const char *key, char *val,
                   char *err, size_t errcap)
{
#define GFM_L(name, field, lo, hi)                                                               \
    if (strcmp(key, name) == 0) {                                                                \
        if (!gfr_parse_long(val, &cc->field) || cc->field < (lo) || cc->field > (hi)) {          \
            snprintf(err, errcap, "%s: bad value '%.40s'", name, val);                           \
            return -1;                                                                           \
        }                                                                                        \
        return 1;                                                                                \
    }
    GFM_L("motor_torque_input", motor_input, 0, 1)
    GFM_L("load_torque_input", load_input, 0, 1)
    GFM_L("vr.motor_torque", vr_motor_torque, -1, 100000)
    GFM_L("vr.load_torque", vr_load_torque, -1, 100000)
    GFM_L("vr.motor_speed_start", vr_speed0, 0, 100000)
    GFM_L("vr.motor_angle_start", vr_angle0, 0, 100000)
    GFM_L("vr.max_step", vr_hmax, 0, 100000)
    GFM_L("vr.integrator", vr_integrator, 0, 100000)
    GFM_L("extra_outputs", extra_outputs, 0, 64)
    GFM_L("state_outputs", state_outputs, 0, 1)
    GFM_L("me.event_indicators", me_indicators, 0, 1000000)
#undef GFM_L
    if (strcmp(key, "format") == 0) {
        if (strcmp(val, format) != 0) {
            snprintf(err, errcap, "format is '%.60s', expected '%s'", val, format);
            return -1;
        }
        cc->have_format = 1;
    } else if (strcmp(key, "version") == 0) {
        long ver;
        if (!gfr_parse_long(val, &ver) || ver != version) {
            snprintf(err, errcap, "version '%.40s' unsupported (this runtime reads %ld)", val, version);
            return -1;
        }
    } else if (strcmp(key, "guid") == 0) {
        gfr_copy_str(cc->guid, sizeof cc->guid, val);
        cc->have_guid = 1;
    } else if (strcmp(key, "interfaces") == 0) {
        if (strcmp(val, "cs") == 0) cc->offers = GF_COSIMULATION;
        else if (strcmp(val, "me") == 0) cc->offers = GF_MODEL_EXCHANGE;
        else if (strcmp(val, "cs,me") == 0) cc->offers = GF_COSIMULATION | GF_MODEL_EXCHANGE;
        else {
            snprintf(err, errcap, "interfaces: '%.40s' is not cs, me or cs,me", val);
            return -1;
        }
    } else if (strcmp(key, "me.node_events") == 0) {
        long ne;
        if (!gfr_parse_long(val, &ne) || ne < GK_ME_NODES_NONE || ne > GK_ME_NODES_ALL) {
            snprintf(err, errcap, "me.node_events: bad value '%.40s'", val);
            return -1;
        }
        cc->me_node_events = (int)ne;
    } else if (strcmp(key, "me.nominals") == 0) {   /* one per state, '|'-separated */
        char *f[GFM_MAX_STATE];
        int q, n = gfr_split_fields(val, f, GFM_MAX_STATE);
        for (q = 0; q < n; ++q)
            if (!gfr_parse_double(f[q], &cc->me_nominal[q]) || !(cc->me_nominal[q] > 0.0) ||
                !isfinite(cc->me_nominal[q])) {
                snprintf(err, errcap, "me.nominals: need finite numbers > 0");
                return -1;
            }
        cc->me_n_nominals = n;
        cc->have_nominals = 1;
    } else if (strcmp(key, "n_vars") == 0) {
        long nv;
        if (!gfr_parse_long(val, &nv) || nv < 1 || nv > 100000 || c->vars != NULL) {
            snprintf(err, errcap, "n_vars: bad value '%.40s'", val);
            return -1;
        }
        c->n_vars = (int)nv;
        c->vars = (gf_var *)calloc((size_t)nv, sizeof(gf_var));
        c->values = (double *)calloc((size_t)nv, sizeof(double));
        if (c->vars == NULL || c->values == NULL) {
            snprintf(err, errcap, "out of memory");
            return -1;
        }
        cc->have_nvars = 1;
    } else if (strcmp(key, "var") == 0) {
        if (c->vars == NULL || !gfr_parse_var(c, val, &cc->nvar_seen)) {
            snprintf(err, errcap, "bad variable entry (n_vars first, then vr 0, 1, ... in order)");
            return -1;
        }
    } else {
        return 0;
    }
    return 1;
}

int gfm_mesh_key(gfm_mesh_cfg *s, const char *k, char *val)
{
#define GFM_D(key, field, bit)                                                                   \
    if (strcmp(k, key) == 0) {                                                                   \
        if (!gfr_parse_double(val, &s->field)) return -1;                                        \
        s->have |= bit;                                                                          \
        return 1;                                                                                \
    }
#define GFM_I(key, field, bit)                                                                   \
    if (strcmp(k, key) == 0) {                                                                   \
        if (!gfr_parse_long(val, &s->field)) return -1;                                          \
        s->have |= bit;                                                                          \
        return 1;                                                                                \
    }
    if (strcmp(k, "name") == 0) {
        gfr_copy_str(s->name, sizeof s->name, val);
        s->have |= GFM_K_NAME;
        return 1;
    }
    if (strcmp(k, "tables") == 0) {
        if (strstr(val, "..") != NULL || val[0] == '/' || val[0] == '\\') return -1;
        gfr_copy_str(s->file, sizeof s->file, val);
        s->have |= GFM_K_FILE;
        return 1;
    }
    if (strcmp(k, "tables_sha256") == 0) {
        if (strlen(val) != 64) return -1;
        gfr_copy_str(s->sha, sizeof s->sha, val);
        s->have |= GFM_K_SHA;
        return 1;
    }
    GFM_I("slots", P, GFM_K_P)
    GFM_I("n_phi", n_phi, GFM_K_NPHI)
    GFM_I("n_torque", n_torque, GFM_K_NT)
    GFM_I("tables_bytes", bytes, GFM_K_BYTES)
    GFM_I("offset.torque_Nm", off_torque, GFM_K_OT)
    GFM_I("offset.k_N_per_m", off_k, GFM_K_OK)
    GFM_I("offset.e_m", off_e, GFM_K_OE)
    GFM_I("offset.backlash_half_m", off_b, GFM_K_OB)
    GFM_I("vr.damping_ratio", vr_zeta, GFM_K_VRZ)
    GFM_I("vr.damping_model", vr_dm, GFM_K_VRDM)
    GFM_D("phi_period_rad", phi_period, GFM_K_PHI)
    GFM_D("base_radius_pinion_m", Rb1, GFM_K_RB1)
    GFM_D("base_radius_gear_m", Rb2, GFM_K_RB2)
    GFM_D("inertia_pinion_kgm2", I1, GFM_K_I1)
    GFM_D("inertia_gear_kgm2", I2, GFM_K_I2)
    GFM_D("k_mean_N_per_m", k_mean, GFM_K_KM)
    GFM_D("mesh_period_rad", mesh_period, 0)
    GFM_D("engagement_in_rad", eng_in, 0)
    GFM_D("engagement_out_rad", eng_out, 0)
#undef GFM_D
#undef GFM_I
    return 0;
}

const char *gfm_common_check(const gf_inst *c, const gfm_common_cfg *cc, char *err, size_t errcap)
{
    if (!cc->have_format || !cc->have_guid || !cc->have_nvars) {
        snprintf(err, errcap, "missing keys (format, guid, n_vars)");
        return err;
    }
    if (cc->nvar_seen != c->n_vars) {
        snprintf(err, errcap, "n_vars = %d but %d var lines", c->n_vars, cc->nvar_seen);
        return err;
    }
    if (cc->vr_speed0 < 0 || cc->vr_angle0 < 0 || cc->vr_hmax < 0 || cc->vr_integrator < 0) {
        snprintf(err, errcap, "missing vr.motor_speed_start, vr.motor_angle_start, vr.max_step or vr.integrator");
        return err;
    }
    return NULL;
}

/* a value reference of the configuration: -1 (none) or one of the variable table's parameters or
 * inputs; 0 if it is not */
int gfm_vr_ok(const gf_inst *c, long vr, int optional)
{
    if (vr == -1) return optional;
    return vr >= 0 && vr < c->n_vars && (c->vars[vr].causality == GF_PARAMETER || c->vars[vr].causality == GF_INPUT);
}

/* ------------------------------------------------------------- tables */
const char *gfm_load_mesh(gf_inst *c, gfm_core *core, const char *res_dir, const gfm_mesh_cfg *s, int m,
                          gf_sha256 *tag, char *err, size_t errcap)
{
    char path[4096], hex[65];
    size_t size = (size_t)s->bytes;
    gf_sha256 sha;
    long P = s->P, N = s->n_phi, NT = s->n_torque, need[4], offs[4];
    int i, st, j;
    if (!gfr_join_path(res_dir, s->file, path, sizeof path)) return "resource location too long";
    for (j = 0; j < m; ++j)   /* an earlier mesh of the same tables file: its bytes, read and checked once */
        if (core->blob[j] != NULL && strcmp(core->file[j], s->file) == 0) break;
    if (j < m) {
        if (strcmp(core->sha[j], s->sha) != 0 || core->bytes[j] != s->bytes) {
            snprintf(err, errcap, "%s %.60s: tables file %.200s given with another size or SHA-256 than before",
                     core->k->mesh_word, s->name, s->file);
            return err;
        }
        core->blob[m] = core->blob[j];
        core->blob_shared[m] = 1;
        size = (size_t)s->bytes;
        gfr_copy_str(hex, sizeof hex, s->sha);
    } else {
        core->blob[m] = gfr_read_file(path, &size);
        if (core->blob[m] == NULL) {
            snprintf(err, errcap, "cannot read resources/%.200s (%s %.60s)", s->file, core->k->mesh_word, s->name);
            return err;
        }
        if ((long)size != s->bytes) {
            snprintf(err, errcap, "resources/%.200s: wrong size (file corrupted)", s->file);
            return err;
        }
        gfr_sha_init(&sha);
        gfr_sha_update(&sha, core->blob[m], size);
        gfr_sha_final_hex(&sha, hex);
        if (strcmp(hex, s->sha) != 0) {
            snprintf(err, errcap, "resources/%.200s: SHA-256 checksum mismatch (file corrupted or tampered with)",
                     s->file);
            return err;
        }
    }
    gfr_copy_str(core->file[m], sizeof core->file[m], s->file);
    gfr_copy_str(core->sha[m], sizeof core->sha[m], s->sha);
    core->bytes[m] = s->bytes;
    gfr_sha_update(tag, (const unsigned char *)hex, 64);
    if (P < 1 || N < 2 || NT < 1 || P > 1000 || N > 100000000L / P || NT > 10000) {
        snprintf(err, errcap, "%s %.60s: table dimensions out of range", core->k->mesh_word, s->name);
        return err;
    }
    need[0] = NT; need[1] = NT * P * N; need[2] = NT * P * N; need[3] = P * N;
    offs[0] = s->off_torque; offs[1] = s->off_k; offs[2] = s->off_e; offs[3] = s->off_b;
    for (i = 0; i < 4; ++i)
        if (offs[i] < 0 || offs[i] % 8 != 0 || offs[i] + 8 * need[i] > (long)size) {
            snprintf(err, errcap, "%s %.60s: table array offsets outside its tables file", core->k->mesh_word, s->name);
            return err;
        }
    if (!core->blob_shared[m] && !gfr_host_little_endian()) gfr_swap8(core->blob[m], size / 8); /* stored little-endian (docs/tables.md) */
    core->pair[m] = (gk_model *)calloc(1, (size_t)gk_sizeof_model());
    if (core->pair[m] == NULL) return "out of memory";
    st = gk_init(core->pair[m], (int)P, (int)N, (int)NT, (const double *)(void *)(core->blob[m] + s->off_torque),
                 (const double *)(void *)(core->blob[m] + s->off_k), (const double *)(void *)(core->blob[m] + s->off_e),
                 (const double *)(void *)(core->blob[m] + s->off_b), s->phi_period, s->Rb1, s->Rb2, s->I1, s->I2,
                 s->k_mean);
    if (st != GK_OK) {
        snprintf(err, errcap, "%s %.60s: the kernel rejects its tables (status %d)", core->k->mesh_word, s->name, st);
        return err;
    }
    if (s->mesh_period > 0.0) { /* contact-zone edges (docs/model.md "Contact-zone edges") */
        core->cuts[m] = (double *)calloc((size_t)(2 * P * N), sizeof(double));
        if (core->cuts[m] == NULL) return "out of memory";
        if (gk_zone_cuts((int)P, (int)N, s->phi_period, s->mesh_period, s->eng_in, s->eng_out, core->cuts[m]) == GK_OK) {
            gk_set_zone_cuts(core->pair[m], core->cuts[m]);
            /* the zone edges: read by Model Exchange only (its zone indicators and in-zone flags) */
            gk_set_zone_edges(core->pair[m], s->mesh_period, s->eng_in, s->eng_out);
        }
    }
    if (!(gfm_vr_ok(c, s->vr_zeta, 0) && gfm_vr_ok(c, s->vr_dm, 0))) {
        snprintf(err, errcap, "%s %.60s: its damping parameters are not parameters of the table", core->k->mesh_word,
                 s->name);
        return err;
    }
    core->vr_zeta[m] = (int)s->vr_zeta;
    core->vr_dm[m] = (int)s->vr_dm;
    gfr_copy_str(core->name[m], sizeof core->name[m], s->name);
    core->n_mesh = m + 1;
    return NULL;
}

static const gf_me_model GFM_ME;

/* Model Exchange at instantiation: the indicators the model description declares must be the
 * kernel's; the nominals; the block of the outputs after the kernel's (the states, their
 * derivatives, the indicators); NULL or a message */
static const char *me_setup(gf_inst *c, gfm_core *core, const gfm_common_cfg *cc, char *err, size_t errcap)
{
    int q, n2 = (int)core->n_state, nz, m;
    for (m = 0; m < core->n_mesh; ++m)
        if (core->pair[m]->P > GK_KINK_MAX_SLOTS) {
            snprintf(err, errcap, "Model Exchange: %s %.60s has more than %d tooth-pair slots", core->k->mesh_word,
                     core->name[m], GK_KINK_MAX_SLOTS);
            return err;
        }
    nz = core->k->k_me_n_ind(kd_of(core), cc->me_node_events);
    if (nz < 0 || (long)nz != cc->me_indicators) {
        snprintf(err, errcap, "Model Exchange: the tables give %d event indicators, the model description declares "
                 "%ld", nz, cc->me_indicators);
        return err;
    }
    if (cc->have_nominals && cc->me_n_nominals != n2) {
        snprintf(err, errcap, "me.nominals: %ld values for %d states", cc->me_n_nominals, n2);
        return err;
    }
    core->me_node_events = cc->me_node_events;
    for (q = 0; q < n2; ++q) core->me_nominal[q] = cc->have_nominals ? cc->me_nominal[q] : 1.0;
    c->n_states = (size_t)n2;
    c->n_indicators = (size_t)nz;
    core->me_base = c->n_out;
    c->n_out += 2 * n2 + nz;
    return NULL;
}

const char *gfm_bind(gf_inst *c, gfm_core *core, const gfm_common_cfg *cc, int n_kernel_out, gf_sha256 *tag,
                     char *err, size_t errcap)
{
    char hex[65], t16[17];
    const char *e = NULL;
    int i;
    if (!(gfm_vr_ok(c, cc->vr_motor_torque, 1) && gfm_vr_ok(c, cc->vr_load_torque, 1) && gfm_vr_ok(c, cc->vr_speed0, 0) &&
          gfm_vr_ok(c, cc->vr_angle0, 0) && gfm_vr_ok(c, cc->vr_hmax, 0) && gfm_vr_ok(c, cc->vr_integrator, 0)))
        return "a value reference of the configuration is not a parameter or input of the variable table";
    if ((cc->motor_input != 0) != (cc->vr_motor_torque >= 0) || (cc->load_input != 0) != (cc->vr_load_torque >= 0))
        return "the torque inputs of the variable table are not the ends that are torque inputs";
    if (core->n_state > GFM_MAX_STATE) return "too many states";
    core->vr_motor_torque = (int)cc->vr_motor_torque;
    core->vr_load_torque = (int)cc->vr_load_torque;
    core->vr_speed0 = (int)cc->vr_speed0;
    core->vr_angle0 = (int)cc->vr_angle0;
    core->vr_hmax = (int)cc->vr_hmax;
    core->vr_integrator = (int)cc->vr_integrator;
    c->n_out = n_kernel_out + (int)cc->extra_outputs;
    c->offers = cc->offers ? cc->offers : GF_COSIMULATION;
    core->me_offered = (c->offers & GF_MODEL_EXCHANGE) != 0;
    core->state_base = -1;
    if (core->me_offered) e = me_setup(c, core, cc, err, errcap);
    if (e != NULL) return e;
    if (core->me_offered) {
        core->state_base = core->me_base;   /* the Model Exchange block starts with the states */
    } else if (cc->state_outputs) {
        core->state_base = c->n_out;
        c->n_out += (int)core->n_state;
    }
    c->out = (double *)calloc((size_t)c->n_out, sizeof(double));
    if (c->out == NULL) return "out of memory";
    for (i = 0; i < c->n_vars; ++i)
        if (c->vars[i].causality == GF_OUTPUT && (c->vars[i].out_index < 0 || c->vars[i].out_index >= c->n_out))
            return "an output's kernel index is outside the output vector";
    if (core->me_offered) c->me = &GFM_ME;
    gfr_sha_final_hex(tag, hex);
    memcpy(t16, hex, 16);
    t16[16] = '\0';
    core->tables_tag = (uint64_t)strtoull(t16, NULL, 16);
    gfr_mark_arrays(c);
    gfm_reset(c, core);
    return NULL;
}

void gfm_free(gfm_core *core)
{
    int m;
    for (m = 0; m < GFM_MAX_MESHES; ++m) {
        if (!core->blob_shared[m]) free(core->blob[m]);
        free(core->cuts[m]);
        free(core->pair[m]);
        core->blob[m] = NULL;
        core->cuts[m] = NULL;
        core->pair[m] = NULL;
    }
}

void gfm_reset(gf_inst *c, gfm_core *core)
{
    int i;
    for (i = 0; i < c->n_vars; ++i) c->values[i] = c->vars[i].has_start ? c->vars[i].start : 0.0;
    for (i = 0; i < c->n_out; ++i) c->out[i] = 0.0;
    memset(at(core, core->kstate_offset), 0, core->kstate_bytes);
    if (core->kme_bytes) memset(at(core, core->kme_offset), 0, core->kme_bytes);
    core->initialized = 0;
    core->zeta_valid = 0;
    core->warned = 0;
    c->dirty = 1;
    c->time = 0.0;
    c->mode = GF_INSTANTIATED;
}

/* ------------------------------------------------------------ behaviour */
double gfm_val(const gf_inst *c, int vr) { return vr >= 0 ? c->values[vr] : 0.0; }

/* an Integer parameter's value as one of the codes 0 .. n-1; -1 if it is not one (never a cast of an
 * arbitrary double) */
int gfm_code_of(double x, int n)
{
    int i;
    for (i = 0; i < n; ++i)
        if (x == (double)i) return i;
    return -1;
}

/* 1 (with the reason logged at `status`) when parameter/input vr is not finite or outside its min/max */
int gfm_bad_value(gf_inst *c, int vr, int status, const char *tail)
{
    char a[GFM_NUM], b[GFM_NUM];
    const gf_var *v;
    double x;
    const char *cat = status == GF_DISCARD ? "logStatusDiscard" : "logStatusError";
    if (vr < 0) return 0;
    v = &c->vars[vr];
    x = c->values[vr];
    if (!isfinite(x))
        gf_log(c, status, cat, "%s = %s: not finite%s", v->name, gfm_num(x, a), tail);
    else if (v->has_min && x < v->min)
        gf_log(c, status, cat, "%s = %s: below its minimum %s%s", v->name, gfm_num(x, a), gfm_num(v->min, b), tail);
    else if (v->has_max && x > v->max)
        gf_log(c, status, cat, "%s = %s: above its maximum %s%s", v->name, gfm_num(x, a), gfm_num(v->max, b), tail);
    else
        return 0;
    return 1;
}

static double tm_of(const gf_inst *c) { return gfm_val(c, core_of(c)->vr_motor_torque); }
static double tl_of(const gf_inst *c) { return gfm_val(c, core_of(c)->vr_load_torque); }

/* the damping ratio and law of every mesh into its pair model when they changed; 0 if refused (logged) */
static int apply_damping(gf_inst *c)
{
    gfm_core *d = core_of(c);
    int m;
    for (m = 0; m < d->n_mesh; ++m) {
        double zeta = gfm_val(c, d->vr_zeta[m]);
        int st;
        if (d->zeta_valid && zeta == d->zeta_applied[m]) continue;
        if (gfm_bad_value(c, d->vr_zeta[m], GF_ERROR_STATUS, "; rejected")) return 0;
        st = gk_set_damping(d->pair[m], zeta, gfm_code_of(gfm_val(c, d->vr_dm[m]), 2));
        if (st != GK_OK) {
            char a[GFM_NUM];
            gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s = %s: refused by the kernel (status %d)",
                   c->vars[d->vr_zeta[m]].name, gfm_num(zeta, a), st);
            return 0;
        }
        d->zeta_applied[m] = zeta;
    }
    d->zeta_valid = 1;
    return 1;
}

/* a mesh torque outside its tables' torque axis: one warning per excursion and mesh */
static void check_torque_axes(gf_inst *c, double t)
{
    gfm_core *d = core_of(c);
    double t_ref = d->k->k_tref(kd_of(d), tm_of(c), tl_of(c));
    int m;
    for (m = 0; m < d->n_mesh; ++m) {
        const gk_model *pm = d->pair[m];
        double tq = d->k->k_mesh_torque(kd_of(d), m, t_ref);
        char a[GFM_NUM], b[GFM_NUM], e[GFM_NUM], f[GFM_NUM];
        if (pm->n_torque < 2) continue;
        if (tq < pm->torque_Nm[0] || tq > pm->torque_Nm[pm->n_torque - 1]) {
            if (!(d->warned & (1u << m)))
                gf_log(c, GF_WARNING, "logStatusWarning", "%s %s: pinion torque %s N.m at t = %s s is outside "
                       "its tables' torque axis [%s, %s] N.m; the tables are used at the nearest end (%s)",
                       d->k->mesh_word, d->name[m], gfm_num(tq, a), gfm_num(t, b), gfm_num(pm->torque_Nm[0], e),
                       gfm_num(pm->torque_Nm[pm->n_torque - 1], f), d->k->doc);
            d->warned |= 1u << m;
        } else {
            d->warned &= ~(1u << m);
        }
    }
}

/* An FMU that offers Model Exchange: the modes decided anew from the state (decide), its block of the
 * outputs (states, derivatives, indicators with the modes held) and, with `outputs`, the kernel's
 * outputs with the modes held; 1 on success.  Without Model Exchange: the state block, if any. */
static int me_fill(gf_inst *c, int decide, int outputs)
{
    gfm_core *d = core_of(c);
    double Tm = tm_of(c), Tl = tl_of(c), *blk;
    int n2, st = GK_OK;
    if (!d->me_offered) {   /* the state block alone, when the FMU shows its state */
        if (d->state_base >= 0) memcpy(c->out + d->state_base, y_of(d), sizeof(double) * d->n_state);
        return 1;
    }
    n2 = (int)d->n_state;
    blk = c->out + d->me_base;
    if (decide) st = d->k->k_me_init(kd_of(d), Tm, Tl, d->me_node_events);
    if (st == GK_OK && outputs) st = d->k->k_me_out(kd_of(d), Tm, Tl, c->out);
    if (st == GK_OK) st = d->k->k_me_deriv(kd_of(d), Tm, Tl, blk + n2);
    if (st == GK_OK) st = d->k->k_me_ind(kd_of(d), Tm, Tl, blk + 2 * n2);
    if (st == GK_OK) memcpy(blk, y_of(d), sizeof(double) * (size_t)n2);
    return st == GK_OK;
}

int gfm_init_state(gf_inst *c)
{
    static const char *const tail = "; cannot compute the initial state";
    gfm_core *d = core_of(c);
    char a[GFM_NUM];
    double ig, hmax, t_ref;
    int m, bad = 0, st, bad_mesh = -1;
    d->initialized = 0;
    bad |= gfm_bad_value(c, d->vr_speed0, GF_ERROR_STATUS, tail);
    bad |= gfm_bad_value(c, d->vr_angle0, GF_ERROR_STATUS, tail);
    bad |= gfm_bad_value(c, d->vr_hmax, GF_ERROR_STATUS, tail);
    bad |= gfm_bad_value(c, d->vr_integrator, GF_ERROR_STATUS, tail);
    bad |= gfm_bad_value(c, d->vr_motor_torque, GF_ERROR_STATUS, tail);
    bad |= gfm_bad_value(c, d->vr_load_torque, GF_ERROR_STATUS, tail);
    for (m = 0; m < d->n_mesh; ++m) {
        double dm = gfm_val(c, d->vr_dm[m]);
        bad |= gfm_bad_value(c, d->vr_zeta[m], GF_ERROR_STATUS, tail);
        if (!bad && gfm_code_of(dm, 2) < 0) {
            gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s = %s: must be 0 (elastobacklash) or 1 (contact_zone)%s",
                   c->vars[d->vr_dm[m]].name, gfm_num(dm, a), tail);
            bad = 1;
        }
    }
    hmax = gfm_val(c, d->vr_hmax);
    if (!bad && !(hmax > 0.0)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s = %s: must be > 0%s", c->vars[d->vr_hmax].name,
               gfm_num(hmax, a), tail);
        bad = 1;
    }
    ig = gfm_val(c, d->vr_integrator);
    if (!bad && gfm_code_of(ig, GFM_INTEGRATORS) < 0) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s = %s: must be 0 (rk4), 1 (rk4_kink), 2 (rk4_node) or 3 "
               "(rk4_seg)%s",
               c->vars[d->vr_integrator].name, gfm_num(ig, a), tail);
        bad = 1;
    }
    if (bad) return 0;
    st = d->k->k_integrator(kd_of(d), gfm_code_of(ig, GFM_INTEGRATORS));
    if (st != GK_OK) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s = %s: refused by the kernel (a %s has more than %d "
               "slots)%s", c->vars[d->vr_integrator].name, gfm_num(ig, a), d->k->mesh_word, GK_KINK_MAX_SLOTS, tail);
        return 0;
    }
    d->zeta_valid = 0;
    if (!apply_damping(c)) return 0;
    t_ref = d->k->k_tref(kd_of(d), tm_of(c), tl_of(c));
    st = d->k->k_initialize(kd_of(d), gfm_val(c, d->vr_angle0), gfm_val(c, d->vr_speed0), t_ref, &bad_mesh);
    if (st == GK_OK) st = d->k->k_outputs(kd_of(d), tm_of(c), tl_of(c), c->out);
    if (st != GK_OK) {
        if (st == GK_ERR_NOCONTACT && bad_mesh >= 0 && bad_mesh < d->n_mesh)
            gf_log(c, GF_ERROR_STATUS, "logStatusError", "initial state: %s %s has no tooth pair in contact at its "
                   "initial pinion angle (its tables have k = 0 there)", d->k->mesh_word, d->name[bad_mesh]);
        else
            gf_log(c, GF_ERROR_STATUS, "logStatusError", "initial state: refused by the kernel (status %d%s)", st,
                   st == GK_ERR_NOCONTACT ? ": no quasi-static equilibrium found" : "");
        return 0;
    }
    check_torque_axes(c, c->time);
    if (!me_fill(c, 1, 0)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "initial state: the contact modes cannot be decided (state or "
               "torques not finite)");
        return 0;
    }
    d->initialized = 1;
    return 1;
}

/* the end of initialization mode: the initial state from the values set, unless the outputs
 * are already those of the current values */
int gfm_exit_init(gf_inst *c)
{
    if (c->dirty || !core_of(c)->initialized) {
        if (!gfm_init_state(c)) return 0;
        c->dirty = 0;
    }
    return 1;
}

static int me_outputs(gf_inst *c, const char *fn);

int gfm_refresh_outputs(gf_inst *c, const char *fn, const unsigned int vr[], size_t nvr)
{
    size_t i;
    int want = 0;
    if (!c->dirty || !(c->mode & (GF_INIT_MODE | GF_EVENT_MODE | GF_CONT_MODE))) return 1;
    for (i = 0; i < nvr && !want; ++i) want = (long)vr[i] < (long)c->n_vars && c->vars[vr[i]].out_index >= 0;
    if (!want) return 1;
    if (c->mode != GF_INIT_MODE) return me_outputs(c, fn) == GF_OK;
    if (!gfm_init_state(c)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: the initial outputs cannot be computed from the values set "
               "(reasons above)", fn);
        return 0;
    }
    c->dirty = 0;
    return 1;
}

int gfm_do_step(gf_inst *c, double t, double H)
{
    static const char *const tail = "; step rejected, state unchanged";
    gfm_core *d = core_of(c);
    char a[GFM_NUM], b[GFM_NUM];
    int bad = 0, st;
    if (isfinite(t)) c->time = t;
    if (!d->initialized && !gfm_init_state(c)) return GF_DISCARD;
    bad |= gfm_bad_value(c, d->vr_motor_torque, GF_DISCARD, tail);
    bad |= gfm_bad_value(c, d->vr_load_torque, GF_DISCARD, tail);
    if (!(isfinite(H) && H > 0.0)) {
        gf_log(c, GF_DISCARD, "logStatusDiscard", "communication step size %s at t = %s s: must be finite and > 0%s",
               gfm_num(H, a), gfm_num(c->time, b), tail);
        bad = 1;
    }
    if (bad || !apply_damping(c)) return GF_DISCARD;
    check_torque_axes(c, c->time);
    st = d->k->k_step(kd_of(d), tm_of(c), tl_of(c), H, gfm_val(c, d->vr_hmax), c->out);
    if (st != GK_OK) {
        gf_log(c, GF_DISCARD, "logStatusDiscard", "step at t = %s s, H = %s s rejected: %s; state unchanged",
               gfm_num(c->time, a), gfm_num(H, b),
               st == GK_ERR_NONFINITE ? "the state became non-finite (step too large for the stiffness? lower max_step)"
               : st == GK_ERR_STEP ? "communication step or max_step not finite and > 0 (or more than 1e8 substeps)"
               : "refused by the kernel");
        return GF_DISCARD;
    }
    me_fill(c, 1, 0);   /* an FMU that offers Model Exchange: its block of the outputs at the new state */
    c->time = c->time + H;
    return GF_OK;
}

/* --------------------------------------------------------- Model Exchange
 * The model side of gf_model.h's gf_me_model (docs/gearbox.md "Model Exchange"): the state of the
 * host's solver is the kernel's state vector, every mesh's mode is held between events and decided
 * anew in event mode; c->dirty marks values, states or time set since the outputs were computed, and
 * before an evaluation with new values the torques and damping ratios pass their checks. */
static int me_inputs(gf_inst *c, const char *fn)
{
    static const char *const tail = "; not evaluated";
    gfm_core *d = core_of(c);
    int bad = 0;
    (void)fn;
    if (!c->dirty) return GF_OK;
    bad |= gfm_bad_value(c, d->vr_motor_torque, GF_DISCARD, tail);
    bad |= gfm_bad_value(c, d->vr_load_torque, GF_DISCARD, tail);
    if (bad || !apply_damping(c)) return GF_DISCARD;
    check_torque_axes(c, c->time);
    return GF_OK;
}

/* the kernel's status of an evaluation as the FMI layer's, logged */
static int me_status(gf_inst *c, const char *fn, int st)
{
    char a[GFM_NUM];
    if (st == GK_OK) return GF_OK;
    gf_log(c, GF_DISCARD, "logStatusDiscard", "%s: at t = %s s: %s; not evaluated", fn, gfm_num(c->time, a),
           st == GK_ERR_NONFINITE ? "the continuous states are not finite"
           : st == GK_ERR_INPUT ? "a torque is not finite" : "refused by the kernel");
    return GF_DISCARD;
}

/* the outputs (with the modes held) at the current time, states and inputs */
static int me_outputs(gf_inst *c, const char *fn)
{
    int st = me_inputs(c, fn);
    if (st != GF_OK) return st;
    st = me_status(c, fn, me_fill(c, 0, 1) ? GK_OK : GK_ERR_NONFINITE);
    if (st == GF_OK) c->dirty = 0;
    return st;
}

/* in initialization mode, the initial state from the values set when they changed */
static int me_initial(gf_inst *c, const char *fn)
{
    if (c->mode == GF_INIT_MODE && (c->dirty || !core_of(c)->initialized)) {
        if (!gfm_init_state(c)) {
            gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: the initial state cannot be computed from the values "
                   "set (reasons above)", fn);
            return GF_ERROR_STATUS;
        }
        c->dirty = 0;
    }
    return GF_OK;
}

static int me_states(gf_inst *c, const char *fn, double x[])
{
    int st = me_initial(c, fn);
    if (st != GF_OK) return st;
    memcpy(x, y_of(core_of(c)), sizeof(double) * c->n_states);
    return GF_OK;
}

static int me_nominals(gf_inst *c, const char *fn, double x[])
{
    (void)fn;
    memcpy(x, core_of(c)->me_nominal, sizeof(double) * c->n_states);
    return GF_OK;
}

static int me_set_states(gf_inst *c, const char *fn, const double x[])
{
    (void)fn;
    memcpy(y_of(core_of(c)), x, sizeof(double) * c->n_states);
    c->dirty = 1;
    return GF_OK;
}

static int me_derivatives(gf_inst *c, const char *fn, double dx[])
{
    gfm_core *d = core_of(c);
    int st = (c->mode == GF_INIT_MODE) ? me_initial(c, fn) : me_inputs(c, fn);
    if (st != GF_OK) return st;
    return me_status(c, fn, d->k->k_me_deriv(kd_of(d), tm_of(c), tl_of(c), dx));
}

static int me_indicators(gf_inst *c, const char *fn, double z[])
{
    gfm_core *d = core_of(c);
    int st = (c->mode == GF_INIT_MODE) ? me_initial(c, fn) : me_inputs(c, fn);
    if (st != GF_OK) return st;
    return me_status(c, fn, d->k->k_me_ind(kd_of(d), tm_of(c), tl_of(c), z));
}

static int me_event_update(gf_inst *c, const char *fn, int *again, int *values_changed)
{
    gfm_core *d = core_of(c);
    int st = me_inputs(c, fn), changed = 0;
    *again = 0;
    *values_changed = 0;
    if (st != GF_OK) return st;
    st = me_status(c, fn, d->k->k_me_update(kd_of(d), tm_of(c), tl_of(c), &changed));
    if (st != GF_OK) return st;
    c->dirty = 1;   /* the outputs follow the new modes */
    return GF_OK;
}

static int me_completed_step(gf_inst *c, const char *fn, int *enter_event)
{
    (void)c;
    (void)fn;
    *enter_event = 0;
    return GF_OK;
}

static const gf_me_model GFM_ME = {me_states, me_nominals, me_set_states, me_derivatives, me_indicators,
                                   me_event_update, me_completed_step};

/* ------------------------------------------------------------ FMU state */
size_t gfm_snap_size(const gf_inst *c)
{
    const gfm_core *d = core_of(c);
    return sizeof(gfm_snap_header) + d->kstate_bytes + d->kme_bytes +
           sizeof(double) * ((size_t)c->n_vars + (size_t)c->n_out);
}

void gfm_snap_write(const gf_inst *c, unsigned char *p)
{
    const gfm_core *d = core_of(c);
    gfm_snap_header h;
    memset(&h, 0, sizeof h);
    h.magic = d->snap_magic;
    h.version = d->snap_version;
    h.n_vars = (uint32_t)c->n_vars;
    h.n_out = (uint32_t)c->n_out;
    h.tables_tag = d->tables_tag;
    h.mode = c->mode;
    h.initialized = d->initialized;
    h.warned = d->warned;
    h.time = c->time;
    h.dirty = c->dirty;
    memcpy(p, &h, sizeof h);
    p += sizeof h;
    memcpy(p, at(d, d->kstate_offset), d->kstate_bytes);
    p += d->kstate_bytes;
    if (d->kme_bytes) memcpy(p, at(d, d->kme_offset), d->kme_bytes);
    p += d->kme_bytes;
    memcpy(p, c->values, sizeof(double) * (size_t)c->n_vars);
    memcpy(p + sizeof(double) * (size_t)c->n_vars, c->out, sizeof(double) * (size_t)c->n_out);
}

int gfm_snap_is_ours(const gf_inst *c, const unsigned char *p, size_t size)
{
    const gfm_core *d = core_of(c);
    gfm_snap_header h;
    if (size < sizeof h) return 0;
    memcpy(&h, p, sizeof h);
    return h.magic == d->snap_magic && h.version == d->snap_version && h.tables_tag == d->tables_tag;
}

int gfm_snap_read(gf_inst *c, const unsigned char *p, size_t size, const char *fn)
{
    gfm_snap_header h;
    gfm_core *d = core_of(c);
    if (size != gfm_snap_size(c)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: state has %lu bytes, this FMU's has %lu", fn,
               (unsigned long)size, (unsigned long)gfm_snap_size(c));
        return 0;
    }
    memcpy(&h, p, sizeof h);
    if (!gfm_snap_is_ours(c, p, size) || h.n_vars != (uint32_t)c->n_vars || h.n_out != (uint32_t)c->n_out) {
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
    c->time = h.time;
    p += sizeof h;
    memcpy(at(d, d->kstate_offset), p, d->kstate_bytes);
    p += d->kstate_bytes;
    if (d->kme_bytes) memcpy(at(d, d->kme_offset), p, d->kme_bytes);
    p += d->kme_bytes;
    d->warned = h.warned;
    memcpy(c->values, p, sizeof(double) * (size_t)c->n_vars);
    memcpy(c->out, p + sizeof(double) * (size_t)c->n_vars, sizeof(double) * (size_t)c->n_out);
    d->initialized = h.initialized;
    d->zeta_valid = 0;
    if (d->initialized) {   /* the integrator and the damping are derived from the restored values */
        int ig = gfm_code_of(gfm_val(c, d->vr_integrator), GFM_INTEGRATORS);
        if (d->k->k_integrator(kd_of(d), ig) != GK_OK || !apply_damping(c)) {
            gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: the state's integrator or damping is refused", fn);
            return 0;
        }
    }
    return 1;
}
