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
 * Behaviour: the multi-mesh models' (gf_meshes.c, shared with the planetary model): a parameter
 * outside its range, a bad integrator or damping model, a stage with no tooth pair in contact at the
 * start: no initial state (Error, reasons logged); a non-finite input, a bad communication step or a
 * state turned non-finite: the step is discarded, the state unchanged; a stage torque outside its
 * tables' torque axis: one warning per excursion.  Nothing here ever aborts.  The FMU state is the
 * kernel state (plain structs) with the variable values in one flat block.
 */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gearbox_model.h"

#define GB_CONFIG_FILE "gearfmu_gearbox.txt"
#define GB_CONFIG_FORMAT "gearfmu-gearbox"
#define GB_CONFIG_VERSION 1
#define GB_MAX_LINE 4096
#define GB_SNAPSHOT_MAGIC 0x47464742u /* "GFGB" */
#define GB_SNAPSHOT_VERSION 3u

/* the gearbox's own keys of a stage (beside the table keys of gf_meshes.h) */
enum { S_BODIES = GFM_K_NEXT, S_PATH = GFM_K_NEXT << 1, S_ALL = GFM_K_ALL | S_BODIES | S_PATH };

typedef struct {
    gfm_mesh_cfg t;
    long p, q, on_path;
} gb_stage_cfg;

typedef struct {
    gfm_common_cfg cc;
    long n_body, load_body, n_stage, n_shaft;
    double inv_I[GB_MAX_BODIES], g[GB_MAX_BODIES];
    int body_seen[GB_MAX_BODIES];
    gb_stage_cfg st[GB_MAX_MESHES];
    long sh_a[GB_MAX_SHAFTS], sh_b[GB_MAX_SHAFTS], sh_path[GB_MAX_SHAFTS];
    double sh_k[GB_MAX_SHAFTS], sh_c[GB_MAX_SHAFTS];
    long e_kind[GB_MAX_MESHES + GB_MAX_SHAFTS], e_index[GB_MAX_MESHES + GB_MAX_SHAFTS];
    long e_up[GB_MAX_MESHES + GB_MAX_SHAFTS], e_down[GB_MAX_MESHES + GB_MAX_SHAFTS];
    int shafts_seen, edges_seen;
} gb_config;

/* ------------------------------------------------------------- config */
/* a stage.<i>.<key>=<val> line */
static const char *stage_key(gb_config *cfg, const char *key, char *val, char *err, size_t errcap)
{
    char *end;
    long i = strtol(key, &end, 10);
    gb_stage_cfg *s;
    const char *k;
    int r;
    if (end == key || *end != '.' || i < 0 || i >= cfg->n_stage) {
        snprintf(err, errcap, "stage.%.40s: stage index outside 0 .. stages - 1 (stages first)", key);
        return err;
    }
    s = &cfg->st[i];
    k = end + 1;
    r = gfm_mesh_key(&s->t, k, val);
    if (r == 0 && strcmp(k, "bodies") == 0) {
        long pq[2];
        r = gfm_parse_ints(val, pq, 2) ? 1 : -1;
        s->p = pq[0];
        s->q = pq[1];
        s->t.have |= S_BODIES;
    } else if (r == 0 && strcmp(k, "on_path") == 0) {
        r = gfr_parse_long(val, &s->on_path) ? 1 : -1;
        s->t.have |= S_PATH;
    }
    /* unknown keys are ignored (forward compatible) */
    if (r < 0) {
        snprintf(err, errcap, "stage.%.40s: bad value", key);
        return err;
    }
    return NULL;
}

/* one line key=val of the gearbox's own keys; NULL or a message */
static const char *gearbox_key(gb_config *cfg, const char *key, char *val, int lineno, char *err, size_t errcap)
{
#define GB_L(name, field, lo, hi)                                                                \
    else if (strcmp(key, name) == 0) {                                                           \
        if (!gfr_parse_long(val, &cfg->field) || cfg->field < (lo) || cfg->field > (hi)) {       \
            snprintf(err, errcap, "%s: bad value '%.40s'", name, val);                           \
            return err;                                                                          \
        }                                                                                        \
    }
    if (0) {
    }
    GB_L("bodies", n_body, 2, GB_MAX_BODIES)
    GB_L("load_body", load_body, 1, GB_MAX_BODIES - 1)
    GB_L("stages", n_stage, 1, GB_MAX_MESHES)
    GB_L("shafts", n_shaft, 0, GB_MAX_SHAFTS)
#undef GB_L
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
        if (e >= GB_MAX_MESHES + GB_MAX_SHAFTS || !gfm_parse_ints(val, v, 4)) {
            snprintf(err, errcap, "line %d: bad edge entry", lineno);
            return err;
        }
        cfg->e_kind[e] = v[0];
        cfg->e_index[e] = v[1];
        cfg->e_up[e] = v[2];
        cfg->e_down[e] = v[3];
        cfg->edges_seen++;
    } else if (strncmp(key, "stage.", 6) == 0) {
        return stage_key(cfg, key + 6, val, err, errcap);
    }
    /* unknown keys are ignored (forward compatible) */
    return NULL;
}

/* returns NULL on success, else a message (written into err) */
static const char *read_config(gf_inst *c, const char *text, gb_config *cfg, char *err, size_t errcap)
{
    char line[GB_MAX_LINE], *key, *val;
    const char *p = text, *e;
    int lineno = 0, i, r;
    memset(cfg, 0, sizeof *cfg);
    cfg->cc.vr_motor_torque = cfg->cc.vr_load_torque = -1;
    cfg->cc.vr_speed0 = cfg->cc.vr_angle0 = cfg->cc.vr_hmax = cfg->cc.vr_integrator = -2;
    while ((r = gfr_next_config_line(&p, line, sizeof line, &lineno, &key, &val, err, errcap)) > 0) {
        r = gfm_common_key(c, &cfg->cc, GB_CONFIG_FORMAT, GB_CONFIG_VERSION, key, val, err, errcap);
        if (r < 0) return err;
        if (r == 0 && (e = gearbox_key(cfg, key, val, lineno, err, errcap)) != NULL) return e;
    }
    if (r < 0) return err;
    if ((e = gfm_common_check(c, &cfg->cc, err, errcap)) != NULL) return e;
    if (cfg->n_body < 2 || cfg->n_stage < 1) {
        snprintf(err, errcap, "missing keys (bodies, stages)");
        return err;
    }
    for (i = 0; i < cfg->n_body; ++i)
        if (!cfg->body_seen[i]) {
            snprintf(err, errcap, "body %d: no entry", i);
            return err;
        }
    for (i = 0; i < cfg->n_stage; ++i)
        if ((cfg->st[i].t.have & S_ALL) != S_ALL) {
            snprintf(err, errcap, "stage.%d: missing keys (mask 0x%x of 0x%x)", i, cfg->st[i].t.have, (unsigned)S_ALL);
            return err;
        }
    if (cfg->shafts_seen != cfg->n_shaft || cfg->edges_seen != cfg->n_stage + cfg->n_shaft) {
        snprintf(err, errcap, "%d shaft and %d edge entries for %ld shafts and %ld stages", cfg->shafts_seen,
                 cfg->edges_seen, cfg->n_shaft, cfg->n_stage);
        return err;
    }
    return NULL;
}

/* ------------------------------------------------------------- the kernel (gf_meshes.h gfm_kernel) */
static int gbk_integrator(void *kd, int code) { return gb_set_integrator(((gm_data *)kd)->gb, code); }
static double gbk_tref(const void *kd, double Tm, double Tl)
{
    return gb_reference_torque(((const gm_data *)kd)->gb, Tm, Tl);
}
static double gbk_mesh_torque(const void *kd, int m, double t_ref)
{
    return gb_stage_torque(((const gm_data *)kd)->gb, m, t_ref);
}
static int gbk_initialize(void *kd, double psi0, double w0, double t_ref, int *bad_mesh)
{
    gm_data *d = (gm_data *)kd;
    return gb_initialize(d->gb, &d->state, psi0, w0, t_ref, bad_mesh);
}
static int gbk_outputs(void *kd, double Tm, double Tl, double *out)
{
    gm_data *d = (gm_data *)kd;
    return gb_outputs(d->gb, &d->state, Tm, Tl, out);
}
static int gbk_step(void *kd, double Tm, double Tl, double H, double hmax, double *out)
{
    gm_data *d = (gm_data *)kd;
    return gb_do_step(d->gb, d->work, &d->state, Tm, Tl, H, hmax, out);
}
static int gbk_me_n_ind(const void *kd, int node_events) { return gb_me_n_indicators(((const gm_data *)kd)->gb, node_events); }
static int gbk_me_init(void *kd, double Tm, double Tl, int node_events)
{
    gm_data *d = (gm_data *)kd;
    return gb_me_init(d->gb, d->work, &d->me, d->state.y, Tm, Tl, node_events);
}
static int gbk_me_update(void *kd, double Tm, double Tl, int *changed)
{
    gm_data *d = (gm_data *)kd;
    return gb_me_update(d->gb, d->work, &d->me, d->state.y, Tm, Tl, changed);
}
static int gbk_me_deriv(void *kd, double Tm, double Tl, double *dy)
{
    gm_data *d = (gm_data *)kd;
    return gb_me_derivatives(d->gb, d->work, &d->me, d->state.y, Tm, Tl, dy);
}
static int gbk_me_ind(void *kd, double Tm, double Tl, double *z)
{
    gm_data *d = (gm_data *)kd;
    return gb_me_indicators(d->gb, d->work, &d->me, d->state.y, Tm, Tl, z);
}
static int gbk_me_out(void *kd, double Tm, double Tl, double *out)
{
    gm_data *d = (gm_data *)kd;
    return gb_me_outputs(d->gb, d->work, &d->me, d->state.y, Tm, Tl, out);
}

static const gfm_kernel GB_KERNEL = {"stage", "docs/gearbox.md", gbk_integrator, gbk_tref, gbk_mesh_torque, gbk_initialize,
                                     gbk_outputs, gbk_step, gbk_me_n_ind, gbk_me_init, gbk_me_update, gbk_me_deriv, gbk_me_ind,
                                     gbk_me_out};

/* ------------------------------------------------------------- instantiation */
void gm_reset(gf_inst *c) { gfm_reset(c, &c->data->core); }

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
        gfm_free(&c->data->core);
        free(c->data->gb);
        free(c->data->work);
        free(c->data);
        c->data = NULL;
    }
}

/* the gearbox kernel's model from the configuration (the stages' tables loaded); NULL or a message */
static const char *build_kernel(gf_inst *c, const char *res_dir, const gb_config *cfg, gf_sha256 *tag, char *err,
                                size_t errcap)
{
    gm_data *d = c->data;
    const char *e = NULL;
    int i, m;
    if (gb_init(d->gb, (int)cfg->n_body, cfg->inv_I, cfg->g, (int)cfg->load_body, (int)cfg->cc.motor_input,
                (int)cfg->cc.load_input) != GK_OK)
        return "the bodies (inertias, ratios, load body) are refused by the kernel";
    for (m = 0; e == NULL && m < (int)cfg->n_stage; ++m) {
        const gb_stage_cfg *s = &cfg->st[m];
        e = gfm_load_mesh(c, &d->core, res_dir, &s->t, m, tag, err, errcap);
        if (e == NULL && gb_add_mesh(d->gb, d->core.pair[m], (int)s->p, (int)s->q, (int)s->on_path) != GK_OK) {
            snprintf(err, errcap, "stage %.60s: bodies %ld, %ld refused", s->t.name, s->p, s->q);
            e = err;
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
    return e;
}

const char *gm_instantiate(gf_inst *c, const char *res_dir, const char *token, char *err, size_t errcap)
{
    gb_config *cfg;
    gm_data *d;
    unsigned char *text;
    size_t size = 0;
    gf_sha256 tag;
    const char *e;
    c->data = d = (gm_data *)calloc(1, sizeof(gm_data));
    if (d == NULL) return "out of memory";
    d->core.k = &GB_KERNEL;
    d->core.y_offset = offsetof(gm_data, state) + offsetof(gb_state, y);
    d->core.kstate_offset = offsetof(gm_data, state);
    d->core.kstate_bytes = sizeof d->state;
    d->core.kme_offset = offsetof(gm_data, me);
    d->core.kme_bytes = sizeof d->me;
    d->core.snap_magic = GB_SNAPSHOT_MAGIC;
    d->core.snap_version = GB_SNAPSHOT_VERSION;
    text = gfr_read_resource(res_dir, GB_CONFIG_FILE, &size, err, errcap);
    if (text == NULL) return err;
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
    if (token == NULL || strcmp(token, cfg->cc.guid) != 0) e = "GUID differs from the one this FMU was built with";
    d->gb = (gb_model *)calloc(1, sizeof(gb_model));
    d->work = (gb_work *)calloc(1, (size_t)gb_sizeof_work());
    if (e == NULL && (d->gb == NULL || d->work == NULL)) e = "out of memory";
    gfr_sha_init(&tag);
    if (e == NULL) e = build_kernel(c, res_dir, cfg, &tag, err, errcap);
    if (e == NULL) {
        d->core.n_state = (size_t)(2 * d->gb->n);
        e = gfm_bind(c, &d->core, &cfg->cc, gb_n_outputs(d->gb), &tag, err, errcap);
    }
    free(cfg);
    if (e != NULL) return e;
    gf_log(c, GF_OK, "logAll", "instantiated: gearbox of %d bodies, %d stages, %d shafts, tables SHA-256 ok",
           d->gb->n, d->core.n_mesh, d->gb->n_shaft);
    return NULL;
}

/* ------------------------------------------------------------ behaviour (gf_meshes.c) */
int gm_exit_init(gf_inst *c) { return gfm_exit_init(c); }
int gm_refresh_outputs(gf_inst *c, const char *fn, const unsigned int vr[], size_t nvr)
{
    return gfm_refresh_outputs(c, fn, vr, nvr);
}
int gm_do_step(gf_inst *c, double t, double H) { return gfm_do_step(c, t, H); }
size_t gm_snap_size(const gf_inst *c) { return gfm_snap_size(c); }
void gm_snap_write(const gf_inst *c, unsigned char *p) { gfm_snap_write(c, p); }
int gm_snap_read(gf_inst *c, const unsigned char *p, size_t size, const char *fn)
{
    return gfm_snap_read(c, p, size, fn);
}
int gm_snap_is_ours(const gf_inst *c, const unsigned char *p, size_t size) { return gfm_snap_is_ours(c, p, size); }
