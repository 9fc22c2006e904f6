/*
 * gearbox_model.c -- the gearbox model of the standalone gearfmu runtime (docs/gearbox.md "The
 * gearbox FMU"): the model side of the contract gf_model.h, beside the gear model (gear_model.c),
 * under the same FMI layers (fmi2_gear.c, fmi3_gear.c) and plumbing (fmi_common.c).  It calls
 * nothing of the plumbing; its messages go through gf_log to the host.
 *
 * What instantiation reads (from the resource folder the layer resolves):
 *   gearfmu_gearbox.txt  key=value lines written by gearfmu/fmu/gearbox_build.py: GUID, the bodies
 *       (1/I and the kinematic ratio, hexadecimal floats: exact), the stages (their tables file,
 *       size, SHA-256, dimensions, byte offsets and scalars, as gearfmu_standalone.txt has them for
 *       one pair; the pinion and gear body), the elastic shafts, the tree walked from the motor, the
 *       value references the model drives and the variable table (var= lines, gf_resources.h);
 *   <stage>/tables.bin  every stage's tables (the pair FMU's format, docs/tables.md); its SHA-256
 *       must equal the recorded one, else instantiation is refused.
 *
 * Behaviour (the pair FMU's, docs/standalone.md "Behaviour"): a parameter outside its range, a
 * max_step <= 0, an integrator or damping model that does not exist, or a stage with no tooth pair
 * in contact at the start: no initial state (Error, reasons logged).  A non-finite input, a bad
 * communication step or a state turned non-finite: the step is discarded with a message and the
 * state unchanged.  A stage torque outside its tables' torque axis: one warning per excursion and
 * stage (the tables are used at the nearest end).  Nothing here ever aborts.  The FMU state is the
 * kernel state (a plain struct) with the variable values in one flat block (gm_snap_*).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gearbox_model.h"
#include "gf_resources.h"

#define GB_CONFIG_FILE "gearfmu_gearbox.txt"
#define GB_CONFIG_FORMAT "gearfmu-gearbox"
#define GB_CONFIG_VERSION 1
#define GB_MAX_LINE 4096
#define GB_SNAPSHOT_MAGIC 0x47464742u /* "GFGB" */
#define GB_SNAPSHOT_VERSION 1u
#define GB_NUM 40

/* The FMU state block (flat, no pointers): header with the kernel state, then values, outputs. */
typedef struct {
    uint32_t magic;
    uint32_t version;
    uint32_t n_vars;
    uint32_t n_out;
    uint64_t tables_tag;
    int32_t mode;
    int32_t initialized;
    uint32_t warned;
    int32_t reserved;
    double time;
    gb_state state;
    /* followed by double values[n_vars], double out[n_out] */
} gb_snap_header;

/* one stage as the configuration gives it */
typedef struct {
    char name[GF_MAX_NAME], file[GF_MAX_NAME * 2], sha[65];
    long P, n_phi, n_torque, bytes, off_torque, off_k, off_e, off_b, p, q, on_path;
    double phi_period, Rb1, Rb2, I1, I2, k_mean, mesh_period, eng_in, eng_out;
    long vr_zeta, vr_dm;
    unsigned have;
} gb_stage_cfg;

enum {
    S_NAME = 1 << 0, S_FILE = 1 << 1, S_SHA = 1 << 2, S_P = 1 << 3, S_NPHI = 1 << 4, S_NT = 1 << 5, S_BYTES = 1 << 6,
    S_OT = 1 << 7, S_OK = 1 << 8, S_OE = 1 << 9, S_OB = 1 << 10, S_PHI = 1 << 11, S_RB1 = 1 << 12, S_RB2 = 1 << 13,
    S_I1 = 1 << 14, S_I2 = 1 << 15, S_KM = 1 << 16, S_BODIES = 1 << 17, S_PATH = 1 << 18, S_VRZ = 1 << 19,
    S_VRDM = 1 << 20, S_ALL = (1 << 21) - 1
};

typedef struct {
    char guid[GF_MAX_NAME];
    long n_body, load_body, motor_input, load_input, n_stage, n_shaft, n_edge;
    double inv_I[GB_MAX_BODIES], g[GB_MAX_BODIES];
    int body_seen[GB_MAX_BODIES];
    gb_stage_cfg st[GB_MAX_MESHES];
    long sh_a[GB_MAX_SHAFTS], sh_b[GB_MAX_SHAFTS], sh_path[GB_MAX_SHAFTS];
    double sh_k[GB_MAX_SHAFTS], sh_c[GB_MAX_SHAFTS];
    long e_kind[GB_MAX_MESHES + GB_MAX_SHAFTS], e_index[GB_MAX_MESHES + GB_MAX_SHAFTS];
    long e_up[GB_MAX_MESHES + GB_MAX_SHAFTS], e_down[GB_MAX_MESHES + GB_MAX_SHAFTS];
    long vr_motor_torque, vr_load_torque, vr_speed0, vr_angle0, vr_hmax, vr_integrator;
    long extra_outputs;   /* outputs past the kernel's, filled by a model around this one (stage_model.c) */
    int have_format, have_guid, have_nvars, shafts_seen, edges_seen;
} gb_config;

/* x as Python's repr writes a float (the rule of ../kernel/gkfmu.c num: the shortest form that
 * reads back to the same double, ".0" after a whole number) */
static const char *num(double x, char buf[GB_NUM])
{
    int p, e;
    const char *ep;
    if (isnan(x)) return "nan";
    if (isinf(x)) return x > 0 ? "inf" : "-inf";
    for (p = 1; p < 17; ++p) {
        snprintf(buf, GB_NUM, "%.*g", p, x);
        if (strtod(buf, NULL) == x) break;
    }
    snprintf(buf, GB_NUM, "%.*e", p - 1, x);
    ep = strchr(buf, 'e');
    e = ep != NULL ? atoi(ep + 1) : 0;
    if (e >= 0 && e < 16 && p < e + 1) p = e + 1;
    snprintf(buf, GB_NUM, "%.*g", p, x);
    if (strpbrk(buf, ".e") == NULL) strcat(buf, ".0");
    return buf;
}

/* ------------------------------------------------------------- config */
static int parse_ints(char *val, long *out, int n)
{
    char *f[8];
    int i;
    if (n > 8 || gfr_split_fields(val, f, n) != n) return 0;
    for (i = 0; i < n; ++i)
        if (!gfr_parse_long(f[i], &out[i])) return 0;
    return 1;
}

/* a stage.<i>.<key>=<val> line */
static const char *stage_key(gb_config *cfg, const char *key, char *val, char *err, size_t errcap)
{
    char *end;
    long i = strtol(key, &end, 10);
    gb_stage_cfg *s;
    const char *k;
    if (end == key || *end != '.' || i < 0 || i >= cfg->n_stage) {
        snprintf(err, errcap, "stage.%.40s: stage index outside 0 .. stages - 1 (stages first)", key);
        return err;
    }
    s = &cfg->st[i];
    k = end + 1;
#define GB_SD(name, field, bit)                                                                  \
    else if (strcmp(k, name) == 0) {                                                             \
        if (!gfr_parse_double(val, &s->field)) goto bad;                                         \
        s->have |= bit;                                                                          \
    }
#define GB_SL(name, field, bit)                                                                  \
    else if (strcmp(k, name) == 0) {                                                             \
        if (!gfr_parse_long(val, &s->field)) goto bad;                                           \
        s->have |= bit;                                                                          \
    }
    if (strcmp(k, "name") == 0) {
        gfr_copy_str(s->name, sizeof s->name, val);
        s->have |= S_NAME;
    } else if (strcmp(k, "tables") == 0) {
        if (strstr(val, "..") != NULL || val[0] == '/' || val[0] == '\\') goto bad;
        gfr_copy_str(s->file, sizeof s->file, val);
        s->have |= S_FILE;
    } else if (strcmp(k, "tables_sha256") == 0) {
        if (strlen(val) != 64) goto bad;
        gfr_copy_str(s->sha, sizeof s->sha, val);
        s->have |= S_SHA;
    } else if (strcmp(k, "bodies") == 0) {
        long pq[2];
        if (!parse_ints(val, pq, 2)) goto bad;
        s->p = pq[0];
        s->q = pq[1];
        s->have |= S_BODIES;
    }
    GB_SL("slots", P, S_P)
    GB_SL("n_phi", n_phi, S_NPHI)
    GB_SL("n_torque", n_torque, S_NT)
    GB_SL("tables_bytes", bytes, S_BYTES)
    GB_SL("offset.torque_Nm", off_torque, S_OT)
    GB_SL("offset.k_N_per_m", off_k, S_OK)
    GB_SL("offset.e_m", off_e, S_OE)
    GB_SL("offset.backlash_half_m", off_b, S_OB)
    GB_SL("on_path", on_path, S_PATH)
    GB_SL("vr.damping_ratio", vr_zeta, S_VRZ)
    GB_SL("vr.damping_model", vr_dm, S_VRDM)
    GB_SD("phi_period_rad", phi_period, S_PHI)
    GB_SD("base_radius_pinion_m", Rb1, S_RB1)
    GB_SD("base_radius_gear_m", Rb2, S_RB2)
    GB_SD("inertia_pinion_kgm2", I1, S_I1)
    GB_SD("inertia_gear_kgm2", I2, S_I2)
    GB_SD("k_mean_N_per_m", k_mean, S_KM)
    GB_SD("mesh_period_rad", mesh_period, 0)
    GB_SD("engagement_in_rad", eng_in, 0)
    GB_SD("engagement_out_rad", eng_out, 0)
    /* unknown keys are ignored (forward compatible) */
#undef GB_SD
#undef GB_SL
    return NULL;
bad:
    snprintf(err, errcap, "stage.%.40s: bad value", key);
    return err;
}

/* returns NULL on success, else a message (written into err) */
static const char *read_config(gf_inst *c, const char *text, gb_config *cfg, char *err, size_t errcap)
{
    char line[GB_MAX_LINE];
    const char *p = text;
    int nvar_seen = 0, lineno = 0, i;
    memset(cfg, 0, sizeof *cfg);
    cfg->vr_motor_torque = cfg->vr_load_torque = -1;
    cfg->vr_speed0 = cfg->vr_angle0 = cfg->vr_hmax = cfg->vr_integrator = -2;
    while (*p != '\0') {
        size_t n = strcspn(p, "\n");
        char *eq, *key, *val;
        lineno++;
        if (n >= sizeof line) {
            snprintf(err, errcap, "line %d too long", lineno);
            return err;
        }
        memcpy(line, p, n);
        line[n] = '\0';
        if (n > 0 && line[n - 1] == '\r') line[n - 1] = '\0';
        p += n;
        if (*p == '\n') p++;
        if (line[0] == '\0' || line[0] == '#') continue;
        eq = strchr(line, '=');
        if (eq == NULL) {
            snprintf(err, errcap, "line %d: no '='", lineno);
            return err;
        }
        *eq = '\0';
        key = line;
        val = eq + 1;
#define GB_L(name, field, lo, hi)                                                                \
    else if (strcmp(key, name) == 0) {                                                           \
        if (!gfr_parse_long(val, &cfg->field) || cfg->field < (lo) || cfg->field > (hi)) {       \
            snprintf(err, errcap, "%s: bad value '%.40s'", name, val);                           \
            return err;                                                                          \
        }                                                                                        \
    }
        if (strcmp(key, "format") == 0) {
            if (strcmp(val, GB_CONFIG_FORMAT) != 0) {
                snprintf(err, errcap, "format is '%.60s', expected '%s'", val, GB_CONFIG_FORMAT);
                return err;
            }
            cfg->have_format = 1;
        } else if (strcmp(key, "version") == 0) {
            long ver;
            if (!gfr_parse_long(val, &ver) || ver != GB_CONFIG_VERSION) {
                snprintf(err, errcap, "version '%.40s' unsupported (this runtime reads %d)", val, GB_CONFIG_VERSION);
                return err;
            }
        } else if (strcmp(key, "guid") == 0) {
            gfr_copy_str(cfg->guid, sizeof cfg->guid, val);
            cfg->have_guid = 1;
        }
        GB_L("bodies", n_body, 2, GB_MAX_BODIES)
        GB_L("load_body", load_body, 1, GB_MAX_BODIES - 1)
        GB_L("motor_torque_input", motor_input, 0, 1)
        GB_L("load_torque_input", load_input, 0, 1)
        GB_L("stages", n_stage, 1, GB_MAX_MESHES)
        GB_L("shafts", n_shaft, 0, GB_MAX_SHAFTS)
        GB_L("vr.motor_torque", vr_motor_torque, -1, 100000)
        GB_L("vr.load_torque", vr_load_torque, -1, 100000)
        GB_L("vr.motor_speed_start", vr_speed0, 0, 100000)
        GB_L("vr.motor_angle_start", vr_angle0, 0, 100000)
        GB_L("vr.max_step", vr_hmax, 0, 100000)
        GB_L("vr.integrator", vr_integrator, 0, 100000)
        GB_L("extra_outputs", extra_outputs, 0, 64)
        else if (strcmp(key, "body") == 0) {   /* index|1/I|g|name */
            char *f[4];
            long b;
            if (gfr_split_fields(val, f, 4) != 4 || !gfr_parse_long(f[0], &b) || b < 0 || b >= cfg->n_body ||
                !gfr_parse_double(f[1], &cfg->inv_I[b]) || !gfr_parse_double(f[2], &cfg->g[b])) {
                snprintf(err, errcap, "line %d: bad body entry (bodies first)", lineno);
                return err;
            }
            cfg->body_seen[b] = 1;
        } else if (strcmp(key, "shaft") == 0) {   /* index|a|b|k|c|on_path|name */
            char *f[7];
            long s;
            if (gfr_split_fields(val, f, 7) != 7 || !gfr_parse_long(f[0], &s) || s != cfg->shafts_seen ||
                s >= cfg->n_shaft || !gfr_parse_long(f[1], &cfg->sh_a[s]) || !gfr_parse_long(f[2], &cfg->sh_b[s]) ||
                !gfr_parse_double(f[3], &cfg->sh_k[s]) || !gfr_parse_double(f[4], &cfg->sh_c[s]) ||
                !gfr_parse_long(f[5], &cfg->sh_path[s])) {
                snprintf(err, errcap, "line %d: bad shaft entry (shafts first, then 0, 1, ... in order)", lineno);
                return err;
            }
            cfg->shafts_seen++;
        } else if (strcmp(key, "edge") == 0) {   /* kind|index|up|down */
            long v[4];
            int e = cfg->edges_seen;
            if (e >= GB_MAX_MESHES + GB_MAX_SHAFTS || !parse_ints(val, v, 4)) {
                snprintf(err, errcap, "line %d: bad edge entry", lineno);
                return err;
            }
            cfg->e_kind[e] = v[0];
            cfg->e_index[e] = v[1];
            cfg->e_up[e] = v[2];
            cfg->e_down[e] = v[3];
            cfg->edges_seen++;
        } else if (strncmp(key, "stage.", 6) == 0) {
            const char *e = stage_key(cfg, key + 6, val, err, errcap);
            if (e != NULL) return e;
        } else if (strcmp(key, "n_vars") == 0) {
            long nv;
            if (!gfr_parse_long(val, &nv) || nv < 1 || nv > 100000 || c->vars != NULL) {
                snprintf(err, errcap, "n_vars: bad value '%.40s'", val);
                return err;
            }
            c->n_vars = (int)nv;
            c->vars = (gf_var *)calloc((size_t)nv, sizeof(gf_var));
            c->values = (double *)calloc((size_t)nv, sizeof(double));
            if (c->vars == NULL || c->values == NULL) {
                snprintf(err, errcap, "out of memory");
                return err;
            }
            cfg->have_nvars = 1;
        } else if (strcmp(key, "var") == 0) {
            if (c->vars == NULL || !gfr_parse_var(c, val, &nvar_seen)) {
                snprintf(err, errcap, "line %d: bad variable entry (n_vars first, then vr 0, 1, ... in order)", lineno);
                return err;
            }
        }
        /* unknown keys are ignored (forward compatible) */
#undef GB_L
    }
    if (!cfg->have_format || !cfg->have_guid || !cfg->have_nvars || cfg->n_body < 2 || cfg->n_stage < 1) {
        snprintf(err, errcap, "missing keys (format, guid, bodies, stages, n_vars)");
        return err;
    }
    if (nvar_seen != c->n_vars) {
        snprintf(err, errcap, "n_vars = %d but %d var lines", c->n_vars, nvar_seen);
        return err;
    }
    for (i = 0; i < cfg->n_body; ++i)
        if (!cfg->body_seen[i]) {
            snprintf(err, errcap, "body %d: no entry", i);
            return err;
        }
    for (i = 0; i < cfg->n_stage; ++i)
        if ((cfg->st[i].have & S_ALL) != S_ALL) {
            snprintf(err, errcap, "stage.%d: missing keys (mask 0x%x of 0x%x)", i, cfg->st[i].have, (unsigned)S_ALL);
            return err;
        }
    if (cfg->shafts_seen != cfg->n_shaft || cfg->edges_seen != cfg->n_stage + cfg->n_shaft) {
        snprintf(err, errcap, "%d shaft and %d edge entries for %ld shafts and %ld stages", cfg->shafts_seen,
                 cfg->edges_seen, cfg->n_shaft, cfg->n_stage);
        return err;
    }
    if (cfg->vr_speed0 < 0 || cfg->vr_angle0 < 0 || cfg->vr_hmax < 0 || cfg->vr_integrator < 0) {
        snprintf(err, errcap, "missing vr.motor_speed_start, vr.motor_angle_start, vr.max_step or vr.integrator");
        return err;
    }
    return NULL;
}

/* a value reference of the configuration: -1 (none) or one of the variable table's parameters or
 * inputs; 0 if it is not */
static int vr_ok(const gf_inst *c, long vr, int optional)
{
    if (vr == -1) return optional;
    return vr >= 0 && vr < c->n_vars && (c->vars[vr].causality == GF_PARAMETER || c->vars[vr].causality == GF_INPUT);
}

/* one stage: its tables file read, size and SHA-256 checked, the pair model and cuts set up */
static const char *load_stage(gf_inst *c, const char *res_dir, const gb_stage_cfg *s, int m, gf_sha256 *tag,
                              char *err, size_t errcap)
{
    gm_data *d = c->data;
    char path[4096], hex[65];
    size_t size = 0;
    gf_sha256 sha;
    long P = s->P, N = s->n_phi, NT = s->n_torque, need[4], offs[4];
    int i, st;
    if (!gfr_join_path(res_dir, s->file, path, sizeof path)) return "resource location too long";
    d->blob[m] = gfr_read_file(path, &size);
    if (d->blob[m] == NULL) {
        snprintf(err, errcap, "cannot read resources/%.200s (stage %.60s)", s->file, s->name);
        return err;
    }
    if ((long)size != s->bytes) {
        snprintf(err, errcap, "resources/%.200s: wrong size (file corrupted)", s->file);
        return err;
    }
    gfr_sha_init(&sha);
    gfr_sha_update(&sha, d->blob[m], size);
    gfr_sha_final_hex(&sha, hex);
    if (strcmp(hex, s->sha) != 0) {
        snprintf(err, errcap, "resources/%.200s: SHA-256 checksum mismatch (file corrupted or tampered with)",
                 s->file);
        return err;
    }
    gfr_sha_update(tag, (const unsigned char *)hex, 64);
    if (P < 1 || N < 2 || NT < 1 || P > 1000 || N > 100000000L / P || NT > 10000) {
        snprintf(err, errcap, "stage %.60s: table dimensions out of range", s->name);
        return err;
    }
    need[0] = NT; need[1] = NT * P * N; need[2] = NT * P * N; need[3] = P * N;
    offs[0] = s->off_torque; offs[1] = s->off_k; offs[2] = s->off_e; offs[3] = s->off_b;
    for (i = 0; i < 4; ++i)
        if (offs[i] < 0 || offs[i] % 8 != 0 || offs[i] + 8 * need[i] > (long)size) {
            snprintf(err, errcap, "stage %.60s: table array offsets outside its tables file", s->name);
            return err;
        }
    if (!gfr_host_little_endian()) gfr_swap8(d->blob[m], size / 8); /* stored little-endian (docs/tables.md) */
    d->pair[m] = (gk_model *)calloc(1, (size_t)gk_sizeof_model());
    if (d->pair[m] == NULL) return "out of memory";
    st = gk_init(d->pair[m], (int)P, (int)N, (int)NT, (const double *)(void *)(d->blob[m] + s->off_torque),
                 (const double *)(void *)(d->blob[m] + s->off_k), (const double *)(void *)(d->blob[m] + s->off_e),
                 (const double *)(void *)(d->blob[m] + s->off_b), s->phi_period, s->Rb1, s->Rb2, s->I1, s->I2,
                 s->k_mean);
    if (st != GK_OK) {
        snprintf(err, errcap, "stage %.60s: the kernel rejects its tables (status %d)", s->name, st);
        return err;
    }
    if (s->mesh_period > 0.0) { /* contact-zone edges (docs/model.md "Contact-zone edges") */
        d->cuts[m] = (double *)calloc((size_t)(2 * P * N), sizeof(double));
        if (d->cuts[m] == NULL) return "out of memory";
        if (gk_zone_cuts((int)P, (int)N, s->phi_period, s->mesh_period, s->eng_in, s->eng_out, d->cuts[m]) == GK_OK)
            gk_set_zone_cuts(d->pair[m], d->cuts[m]);
    }
    gfr_copy_str(d->stage_name[m], sizeof d->stage_name[m], s->name);
    return NULL;
}

void gm_reset(gf_inst *c)
{
    int i;
    for (i = 0; i < c->n_vars; ++i) c->values[i] = c->vars[i].has_start ? c->vars[i].start : 0.0;
    for (i = 0; i < c->n_out; ++i) c->out[i] = 0.0;
    memset(&c->data->state, 0, sizeof c->data->state);
    c->data->initialized = 0;
    c->data->zeta_valid = 0;
    c->data->warned = 0;
    c->dirty = 1;
    c->time = 0.0;
    c->mode = GF_INSTANTIATED;
}

void gm_free(gf_inst *c)
{
    int m;
    if (c == NULL) return;
    free(c->vars);
    free(c->values);
    free(c->out);
    c->vars = NULL;
    c->values = NULL;
    c->out = NULL;
    c->n_vars = c->n_out = 0;
    if (c->data != NULL) {
        for (m = 0; m < GB_MAX_MESHES; ++m) {
            free(c->data->blob[m]);
            free(c->data->cuts[m]);
            free(c->data->pair[m]);
        }
        free(c->data->gb);
        free(c->data->work);
        free(c->data);
        c->data = NULL;
    }
}

const char *gm_instantiate(gf_inst *c, const char *res_dir, const char *token, char *err, size_t errcap)
{
    gb_config *cfg;
    gm_data *d;
    char path[4096], hex[65];
    unsigned char *text;
    size_t size = 0;
    gf_sha256 tag;
    int i, m, st;
    const char *e;
    c->data = d = (gm_data *)calloc(1, sizeof(gm_data));
    if (d == NULL) return "out of memory";
    if (!gfr_join_path(res_dir, GB_CONFIG_FILE, path, sizeof path)) return "resource location too long";
    text = gfr_read_file(path, &size);
    if (text == NULL) {
        snprintf(err, errcap, "cannot read resources/%s (path %.500s)", GB_CONFIG_FILE, path);
        return err;
    }
    cfg = (gb_config *)calloc(1, sizeof(gb_config));
    if (cfg == NULL) {
        free(text);
        return "out of memory";
    }
    {
        char e2[512];
        e = read_config(c, (const char *)text, cfg, e2, sizeof e2);
        free(text);
        if (e != NULL) {
            snprintf(err, errcap, "resources/%s: %s", GB_CONFIG_FILE, e);
            free(cfg);
            return err;
        }
    }
    e = NULL;
    if (token == NULL || strcmp(token, cfg->guid) != 0) e = "GUID differs from the one this FMU was built with";
    d->gb = (gb_model *)calloc(1, sizeof(gb_model));
    d->work = (gb_work *)calloc(1, (size_t)gb_sizeof_work());
    if (e == NULL && (d->gb == NULL || d->work == NULL)) e = "out of memory";
    if (e == NULL && gb_init(d->gb, (int)cfg->n_body, cfg->inv_I, cfg->g, (int)cfg->load_body, (int)cfg->motor_input,
                             (int)cfg->load_input) != GK_OK)
        e = "the bodies (inertias, ratios, load body) are refused by the kernel";
    gfr_sha_init(&tag);
    d->n_stage = (int)cfg->n_stage;
    for (m = 0; e == NULL && m < d->n_stage; ++m) {
        const gb_stage_cfg *s = &cfg->st[m];
        e = load_stage(c, res_dir, s, m, &tag, err, errcap);
        if (e == NULL && gb_add_mesh(d->gb, d->pair[m], (int)s->p, (int)s->q, (int)s->on_path) != GK_OK) {
            snprintf(err, errcap, "stage %.60s: bodies %ld, %ld refused", s->name, s->p, s->q);
            e = err;
        }
        if (e == NULL && !(vr_ok(c, s->vr_zeta, 0) && vr_ok(c, s->vr_dm, 0))) {
            snprintf(err, errcap, "stage %.60s: its damping parameters are not parameters of the table", s->name);
            e = err;
        }
        if (e == NULL) {
            d->vr_zeta[m] = (int)s->vr_zeta;
            d->vr_dm[m] = (int)s->vr_dm;
        }
    }
    for (i = 0; e == NULL && i < cfg->n_shaft; ++i)
        if (gb_add_shaft(d->gb, (int)cfg->sh_a[i], (int)cfg->sh_b[i], cfg->sh_k[i], cfg->sh_c[i],
                         (int)cfg->sh_path[i]) != GK_OK)
            e = "a shaft (bodies, stiffness, damping) is refused by the kernel";
    for (i = 0; e == NULL && i < cfg->edges_seen; ++i) {
        long k = cfg->e_index[i];
        if ((cfg->e_kind[i] == 0 && k >= cfg->n_shaft) || (cfg->e_kind[i] == 1 && k >= cfg->n_stage) ||
            gb_add_edge(d->gb, (int)cfg->e_kind[i], (int)k, (int)cfg->e_up[i], (int)cfg->e_down[i]) != GK_OK)
            e = "an edge of the tree is refused";
    }
    if (e == NULL && !(vr_ok(c, cfg->vr_motor_torque, 1) && vr_ok(c, cfg->vr_load_torque, 1) &&
                       vr_ok(c, cfg->vr_speed0, 0) && vr_ok(c, cfg->vr_angle0, 0) && vr_ok(c, cfg->vr_hmax, 0) &&
                       vr_ok(c, cfg->vr_integrator, 0)))
        e = "a value reference of the configuration is not a parameter or input of the variable table";
    if (e == NULL && ((cfg->motor_input != 0) != (cfg->vr_motor_torque >= 0) ||
                      (cfg->load_input != 0) != (cfg->vr_load_torque >= 0)))
        e = "the torque inputs of the variable table are not the ends that are torque inputs";
    if (e == NULL) {
        d->vr_motor_torque = (int)cfg->vr_motor_torque;
        d->vr_load_torque = (int)cfg->vr_load_torque;
        d->vr_speed0 = (int)cfg->vr_speed0;
        d->vr_angle0 = (int)cfg->vr_angle0;
        d->vr_hmax = (int)cfg->vr_hmax;
        d->vr_integrator = (int)cfg->vr_integrator;
        c->n_out = gb_n_outputs(d->gb) + (int)cfg->extra_outputs;
        c->out = (double *)calloc((size_t)c->n_out, sizeof(double));
        if (c->out == NULL) e = "out of memory";
    }
    for (i = 0; e == NULL && i < c->n_vars; ++i)
        if (c->vars[i].causality == GF_OUTPUT && (c->vars[i].out_index < 0 || c->vars[i].out_index >= c->n_out))
            e = "an output's kernel index is outside the output vector";
    free(cfg);
    if (e != NULL) return e;
    gfr_sha_final_hex(&tag, hex);
    {
        char t16[17];
        memcpy(t16, hex, 16);
        t16[16] = '\0';
        d->tables_tag = (uint64_t)strtoull(t16, NULL, 16);
    }
    gfr_mark_arrays(c);
    gm_reset(c);
    st = d->n_stage;
    gf_log(c, GF_OK, "logAll", "instantiated: gearbox of %d bodies, %d stages, %d shafts, tables SHA-256 ok",
           d->gb->n, st, d->gb->n_shaft);
    return NULL;
}

/* ------------------------------------------------------------ behaviour */
static double val(const gf_inst *c, int vr) { return vr >= 0 ? c->values[vr] : 0.0; }

/* an Integer parameter's value as one of the codes 0 .. n-1; -1 if it is not one (never a cast of an
 * arbitrary double) */
static int code_of(double x, int n)
{
    int i;
    for (i = 0; i < n; ++i)
        if (x == (double)i) return i;
    return -1;
}

/* 1 (with the reason logged at `status`) when parameter/input vr is not finite or outside its min/max */
static int bad_value(gf_inst *c, int vr, int status, const char *tail)
{
    char a[GB_NUM], b[GB_NUM];
    const gf_var *v;
    double x;
    if (vr < 0) return 0;
    v = &c->vars[vr];
    x = c->values[vr];
    if (!isfinite(x))
        gf_log(c, status, status == GF_DISCARD ? "logStatusDiscard" : "logStatusError", "%s = %s: not finite%s",
               v->name, num(x, a), tail);
    else if (v->has_min && x < v->min)
        gf_log(c, status, status == GF_DISCARD ? "logStatusDiscard" : "logStatusError", "%s = %s: below its minimum %s%s",
               v->name, num(x, a), num(v->min, b), tail);
    else if (v->has_max && x > v->max)
        gf_log(c, status, status == GF_DISCARD ? "logStatusDiscard" : "logStatusError", "%s = %s: above its maximum %s%s",
               v->name, num(x, a), num(v->max, b), tail);
    else
        return 0;
    return 1;
}

/* the damping ratio and law of every stage into its pair model when they changed; 0 if refused (logged) */
static int apply_damping(gf_inst *c)
{
    gm_data *d = c->data;
    int m;
    for (m = 0; m < d->n_stage; ++m) {
        double zeta = val(c, d->vr_zeta[m]);
        int st;
        if (d->zeta_valid && zeta == d->zeta_applied[m]) continue;
        if (bad_value(c, d->vr_zeta[m], GF_ERROR_STATUS, "; rejected")) return 0;
        st = gk_set_damping(d->pair[m], zeta, code_of(val(c, d->vr_dm[m]), 2));
        if (st != GK_OK) {
            char a[GB_NUM];
            gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s = %s: refused by the kernel (status %d)",
                   c->vars[d->vr_zeta[m]].name, num(zeta, a), st);
            return 0;
        }
        d->zeta_applied[m] = zeta;
    }
    d->zeta_valid = 1;
    return 1;
}

/* a stage torque outside its tables' torque axis: one warning per excursion and stage */
static void check_torque_axes(gf_inst *c, double t)
{
    gm_data *d = c->data;
    double t_ref = gb_reference_torque(d->gb, val(c, d->vr_motor_torque), val(c, d->vr_load_torque));
    int m;
    for (m = 0; m < d->n_stage; ++m) {
        const gk_model *pm = d->pair[m];
        double tq = gb_stage_torque(d->gb, m, t_ref);
        char a[GB_NUM], b[GB_NUM], e[GB_NUM], f[GB_NUM];
        if (pm->n_torque < 2) continue;
        if (tq < pm->torque_Nm[0] || tq > pm->torque_Nm[pm->n_torque - 1]) {
            if (!(d->warned & (1u << m)))
                gf_log(c, GF_WARNING, "logStatusWarning", "stage %s: pinion torque %s N.m at t = %s s is outside "
                       "its tables' torque axis [%s, %s] N.m; the tables are used at the nearest end (docs/gearbox.md)",
                       d->stage_name[m], num(tq, a), num(t, b), num(pm->torque_Nm[0], e),
                       num(pm->torque_Nm[pm->n_torque - 1], f));
            d->warned |= 1u << m;
        } else {
            d->warned &= ~(1u << m);
        }
    }
}

static int init_state(gf_inst *c)
{
    static const char *const tail = "; cannot compute the initial state";
    gm_data *d = c->data;
    char a[GB_NUM];
    double ig, hmax, t_ref;
    int m, bad = 0, st, bad_mesh = -1;
    d->initialized = 0;
    bad |= bad_value(c, d->vr_speed0, GF_ERROR_STATUS, tail);
    bad |= bad_value(c, d->vr_angle0, GF_ERROR_STATUS, tail);
    bad |= bad_value(c, d->vr_hmax, GF_ERROR_STATUS, tail);
    bad |= bad_value(c, d->vr_integrator, GF_ERROR_STATUS, tail);
    bad |= bad_value(c, d->vr_motor_torque, GF_ERROR_STATUS, tail);
    bad |= bad_value(c, d->vr_load_torque, GF_ERROR_STATUS, tail);
    for (m = 0; m < d->n_stage; ++m) {
        double dm = val(c, d->vr_dm[m]);
        bad |= bad_value(c, d->vr_zeta[m], GF_ERROR_STATUS, tail);
        if (!bad && code_of(dm, 2) < 0) {
            gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s = %s: must be 0 (elastobacklash) or 1 (contact_zone)%s",
                   c->vars[d->vr_dm[m]].name, num(dm, a), tail);
            bad = 1;
        }
    }
    hmax = val(c, d->vr_hmax);
    if (!bad && !(hmax > 0.0)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s = %s: must be > 0%s", c->vars[d->vr_hmax].name, num(hmax, a),
               tail);
        bad = 1;
    }
    ig = val(c, d->vr_integrator);
    if (!bad && code_of(ig, 3) < 0) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s = %s: must be 0 (rk4), 1 (rk4_kink) or 2 (rk4_node)%s",
               c->vars[d->vr_integrator].name, num(ig, a), tail);
        bad = 1;
    }
    if (bad) return 0;
    st = gb_set_integrator(d->gb, code_of(ig, 3));
    if (st != GK_OK) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s = %s: refused by the kernel (a stage has more than %d "
               "slots)%s", c->vars[d->vr_integrator].name, num(ig, a), GK_KINK_MAX_SLOTS, tail);
        return 0;
    }
    d->zeta_valid = 0;
    if (!apply_damping(c)) return 0;
    t_ref = gb_reference_torque(d->gb, val(c, d->vr_motor_torque), val(c, d->vr_load_torque));
    st = gb_initialize(d->gb, &d->state, val(c, d->vr_angle0), val(c, d->vr_speed0), t_ref, &bad_mesh);
    if (st == GK_OK) st = gb_outputs(d->gb, &d->state, val(c, d->vr_motor_torque), val(c, d->vr_load_torque), c->out);
    if (st != GK_OK) {
        if (st == GK_ERR_NOCONTACT && bad_mesh >= 0)
            gf_log(c, GF_ERROR_STATUS, "logStatusError", "initial state: stage %s has no tooth pair in contact at its "
                   "initial pinion angle (its tables have k = 0 there)", d->stage_name[bad_mesh]);
        else
            gf_log(c, GF_ERROR_STATUS, "logStatusError", "initial state: refused by the kernel (status %d)", st);
        return 0;
    }
    check_torque_axes(c, c->time);
    d->initialized = 1;
    return 1;
}

/* the end of initialization mode: the initial state from the values set, unless the outputs
 * are already those of the current values */
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
    char a[GB_NUM], b[GB_NUM];
    int bad = 0, st;
    if (isfinite(t)) c->time = t;
    if (!d->initialized && !init_state(c)) return GF_DISCARD;
    bad |= bad_value(c, d->vr_motor_torque, GF_DISCARD, tail);
    bad |= bad_value(c, d->vr_load_torque, GF_DISCARD, tail);
    if (!(isfinite(H) && H > 0.0)) {
        gf_log(c, GF_DISCARD, "logStatusDiscard", "communication step size %s at t = %s s: must be finite and > 0%s",
               num(H, a), num(c->time, b), tail);
        bad = 1;
    }
    if (bad || !apply_damping(c)) return GF_DISCARD;
    check_torque_axes(c, c->time);
    st = gb_do_step(d->gb, d->work, &d->state, val(c, d->vr_motor_torque), val(c, d->vr_load_torque), H,
                    val(c, d->vr_hmax), c->out);
    if (st != GK_OK) {
        gf_log(c, GF_DISCARD, "logStatusDiscard", "step at t = %s s, H = %s s rejected: %s; state unchanged",
               num(c->time, a), num(H, b),
               st == GK_ERR_NONFINITE ? "the state became non-finite (step too large for the stiffness? lower max_step)"
               : st == GK_ERR_STEP ? "communication step or max_step not finite and > 0 (or more than 1e8 substeps)"
               : "refused by the kernel");
        return GF_DISCARD;
    }
    c->time = c->time + H;
    return GF_OK;
}

/* ------------------------------------------------------------ FMU state */
size_t gm_snap_size(const gf_inst *c)
{
    return sizeof(gb_snap_header) + sizeof(double) * ((size_t)c->n_vars + (size_t)c->n_out);
}

void gm_snap_write(const gf_inst *c, unsigned char *p)
{
    gb_snap_header h;
    memset(&h, 0, sizeof h);
    h.magic = GB_SNAPSHOT_MAGIC;
    h.version = GB_SNAPSHOT_VERSION;
    h.n_vars = (uint32_t)c->n_vars;
    h.n_out = (uint32_t)c->n_out;
    h.tables_tag = c->data->tables_tag;
    h.mode = c->mode;
    h.initialized = c->data->initialized;
    h.warned = c->data->warned;
    h.time = c->time;
    h.state = c->data->state;
    memcpy(p, &h, sizeof h);
    memcpy(p + sizeof h, c->values, sizeof(double) * (size_t)c->n_vars);
    memcpy(p + sizeof h + sizeof(double) * (size_t)c->n_vars, c->out, sizeof(double) * (size_t)c->n_out);
}

int gm_snap_is_ours(const gf_inst *c, const unsigned char *p, size_t size)
{
    gb_snap_header h;
    if (size < sizeof h) return 0;
    memcpy(&h, p, sizeof h);
    return h.magic == GB_SNAPSHOT_MAGIC && h.version == GB_SNAPSHOT_VERSION && h.tables_tag == c->data->tables_tag;
}

int gm_snap_read(gf_inst *c, const unsigned char *p, size_t size, const char *fn)
{
    gb_snap_header h;
    gm_data *d = c->data;
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
    c->mode = h.mode;
    c->dirty = (h.mode == GF_INSTANTIATED || h.mode == GF_INIT_MODE);
    c->time = h.time;
    d->state = h.state;
    d->warned = h.warned;
    memcpy(c->values, p + sizeof h, sizeof(double) * (size_t)c->n_vars);
    memcpy(c->out, p + sizeof h + sizeof(double) * (size_t)c->n_vars, sizeof(double) * (size_t)c->n_out);
    d->initialized = h.initialized;
    d->zeta_valid = 0;
    if (d->initialized) {   /* the integrator and the damping are derived from the restored values */
        if (gb_set_integrator(d->gb, code_of(val(c, d->vr_integrator), 3)) != GK_OK || !apply_damping(c)) {
            gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: the state's integrator or damping is refused", fn);
            return 0;
        }
    }
    return 1;
}
