/*
 * planetary_model.c -- the planetary model of the standalone gearfmu runtime (docs/planetary.md "The
 * planetary FMU"): a drivetrain with planetary stages (alone, or with parallel-axis stages and
 * shafts) as the model side of the contract gf_model.h, under the same FMI layers (fmi2_gear.c,
 * fmi3_gear.c) and plumbing (fmi_common.c) as the pair and gearbox FMUs.  It calls nothing of the
 * plumbing; its messages go through gf_log to the host.
 *
 * What instantiation reads (from the resource folder the layer resolves):
 *   gearfmu_planetary.txt  key=value lines written by gearfmu/fmu/planetary_build.py: GUID, the
 *       degrees of freedom (1/m and the kinematic ratio, hexadecimal floats: exact), the springs
 *       (shafts, bearings, supports: their DOF map, k, c), the rotating frames, the meshes (their
 *       tables file, size, SHA-256, dimensions, byte offsets and scalars as the gearbox's stages have
 *       them; the transmission-error and table-angle maps, the phase, the static torque per reference
 *       torque), the load-sharing groups, the drives of driven members (their DOF, the value reference
 *       of their speed input, their rigid motion), the value references the model drives and the
 *       variable table (var= lines, gf_resources.h);
 *   <file>.bin  the tables of the meshes (the pair FMU's format, docs/tables.md; the sun-planet meshes
 *       of a stage with identical tables share one file); its SHA-256 must equal the recorded one.
 *
 * Behaviour: the multi-mesh models' (gf_meshes.c, shared with the gearbox model) over the planetary
 * kernel (../kernel/pl_kernel.c) through the function table PL_KERNEL below: a parameter outside its
 * range, a bad integrator or damping model, a mesh with no tooth pair in its contact zone or no static
 * equilibrium at the start: no initial state (Error, reasons logged); a driven member's speed input is
 * set into the state at the start of every communication step (Model Exchange: at every evaluation);
 * a non-finite input, a bad
 * communication step or a state turned non-finite: the step is discarded, the state unchanged; a mesh
 * torque outside its tables' torque axis: one warning per excursion.  Nothing here ever aborts.
 */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "planetary_model.h"

#define PL_CONFIG_FILE "gearfmu_planetary.txt"
#define PL_CONFIG_FORMAT "gearfmu-planetary"
#define PL_CONFIG_VERSION 1
#define PL_MAX_LINE 4096
#define PL_SNAPSHOT_MAGIC 0x47465050u /* "PPFG" */
#define PL_SNAPSHOT_VERSION 1u

/* the planetary model's own keys of a mesh (beside the table keys of gf_meshes.h) */
enum { M_X = GFM_K_NEXT, M_A = GFM_K_NEXT << 1, M_TQ = GFM_K_NEXT << 2, M_ALL = GFM_K_ALL | M_X | M_A | M_TQ };

typedef struct {
    gfm_mesh_cfg t;
    long nx, na, x_dof[PL_MESH_MAX_X], a_dof[PL_MESH_MAX_A];
    double x_coef[PL_MESH_MAX_X], a_coef[PL_MESH_MAX_A], a_ref, phase, torque_per_ref;
} pl_mesh_cfg;

typedef struct {
    gfm_common_cfg cc;
    long n_dof, load_dof, n_mesh, n_spring, n_frame, n_group;
    double inv_m[PL_MAX_DOF], g[PL_MAX_DOF];
    int dof_seen[PL_MAX_DOF];
    pl_mesh_cfg ms[PL_MAX_MESHES];
    long sp_count[PL_MAX_SPRINGS], sp_dof[PL_MAX_SPRINGS][PL_SPRING_MAX];
    double sp_coef[PL_MAX_SPRINGS][PL_SPRING_MAX], sp_k[PL_MAX_SPRINGS], sp_c[PL_MAX_SPRINGS];
    long fr_a[PL_MAX_FRAMES], fr_b[PL_MAX_FRAMES], fr_drive[PL_MAX_FRAMES];
    double fr_r0[PL_MAX_FRAMES], fr_ratio[PL_MAX_FRAMES], fr_drive_ratio[PL_MAX_FRAMES];
    long gr_count[PL_MAX_GROUPS], gr_mesh[PL_MAX_GROUPS][PL_MAX_GROUP];
    long n_drive, dr_dof[PL_MAX_DRIVES], dr_vr[PL_MAX_DRIVES];
    double dr_mode[PL_MAX_DRIVES][PL_MAX_DOF];
    int springs_seen, frames_seen, groups_seen, drives_seen;
} pl_config;

/* ------------------------------------------------------------- config */
/* "n|d_1|..|d_n|c_1|..|c_n" (n <= nmax) into dof[], coef[]; 1 on success */
static int parse_map(char *val, int nmax, long *n, long *dof, double *coef)
{
    char *f[2 * PL_MESH_MAX_X + 1];
    int i, nf = gfr_split_fields(val, f, 2 * nmax + 1);
    if (nf < 1 || !gfr_parse_long(f[0], n) || *n < 0 || *n > nmax || nf != 1 + 2 * *n) return 0;
    for (i = 0; i < *n; ++i)
        if (!gfr_parse_long(f[1 + i], &dof[i]) || !gfr_parse_double(f[1 + *n + i], &coef[i])) return 0;
    return 1;
}

/* a mesh.<i>.<key>=<val> line */
static const char *mesh_key(pl_config *cfg, const char *key, char *val, char *err, size_t errcap)
{
    char *end;
    long i = strtol(key, &end, 10);
    pl_mesh_cfg *s;
    const char *k;
    int r;
    if (end == key || *end != '.' || i < 0 || i >= cfg->n_mesh) {
        snprintf(err, errcap, "mesh.%.40s: mesh index outside 0 .. meshes - 1 (meshes first)", key);
        return err;
    }
    s = &cfg->ms[i];
    k = end + 1;
    r = gfm_mesh_key(&s->t, k, val);
    if (r == 0 && strcmp(k, "x") == 0) {
        r = parse_map(val, PL_MESH_MAX_X, &s->nx, s->x_dof, s->x_coef) ? 1 : -1;
        s->t.have |= M_X;
    } else if (r == 0 && strcmp(k, "angle") == 0) {   /* na|dofs|coefs|a_ref|phase */
        char *f[2 * PL_MESH_MAX_A + 3];
        int nf = gfr_split_fields(val, f, 2 * PL_MESH_MAX_A + 3), j;
        r = nf >= 3 && gfr_parse_long(f[0], &s->na) && s->na >= 0 && s->na <= PL_MESH_MAX_A && nf == 3 + 2 * s->na &&
            gfr_parse_double(f[nf - 2], &s->a_ref) && gfr_parse_double(f[nf - 1], &s->phase) ? 1 : -1;
        for (j = 0; r > 0 && j < s->na; ++j)
            if (!gfr_parse_long(f[1 + j], &s->a_dof[j]) || !gfr_parse_double(f[1 + s->na + j], &s->a_coef[j])) r = -1;
        s->t.have |= M_A;
    } else if (r == 0 && strcmp(k, "torque_per_ref") == 0) {
        r = gfr_parse_double(val, &s->torque_per_ref) ? 1 : -1;
        s->t.have |= M_TQ;
    }
    /* unknown keys are ignored (forward compatible) */
    if (r < 0) {
        snprintf(err, errcap, "mesh.%.40s: bad value", key);
        return err;
    }
    return NULL;
}

/* a spring=index|count|dof_1..dof_S|coef_1..coef_S|k|c|name line (S = PL_SPRING_MAX) */
#define PL_SPRING_FIELDS (2 * PL_SPRING_MAX + 5)
static int spring_line(pl_config *cfg, char *val)
{
    char *f[PL_SPRING_FIELDS];
    long s, j;
    if (gfr_split_fields(val, f, PL_SPRING_FIELDS) != PL_SPRING_FIELDS || !gfr_parse_long(f[0], &s) ||
        s != cfg->springs_seen || s >= cfg->n_spring || !gfr_parse_long(f[1], &cfg->sp_count[s]) ||
        cfg->sp_count[s] < 1 || cfg->sp_count[s] > PL_SPRING_MAX ||
        !gfr_parse_double(f[2 + 2 * PL_SPRING_MAX], &cfg->sp_k[s]) ||
        !gfr_parse_double(f[3 + 2 * PL_SPRING_MAX], &cfg->sp_c[s]))
        return 0;
    for (j = 0; j < PL_SPRING_MAX; ++j)
        if (!gfr_parse_long(f[2 + j], &cfg->sp_dof[s][j]) ||
            !gfr_parse_double(f[2 + PL_SPRING_MAX + j], &cfg->sp_coef[s][j]))
            return 0;
    cfg->springs_seen++;
    return 1;
}

/* one line key=val of the planetary model's own keys; NULL or a message */
static const char *planetary_key(pl_config *cfg, const char *key, char *val, int lineno, char *err, size_t errcap)
{
#define PL_L(name, field, lo, hi)                                                                \
    else if (strcmp(key, name) == 0) {                                                           \
        if (!gfr_parse_long(val, &cfg->field) || cfg->field < (lo) || cfg->field > (hi)) {       \
            snprintf(err, errcap, "%s: bad value '%.40s'", name, val);                           \
            return err;                                                                          \
        }                                                                                        \
    }
    if (0) {
    }
    PL_L("dofs", n_dof, 2, PL_MAX_DOF)
    PL_L("load_dof", load_dof, 0, PL_MAX_DOF - 1)
    PL_L("meshes", n_mesh, 1, PL_MAX_MESHES)
    PL_L("springs", n_spring, 0, PL_MAX_SPRINGS)
    PL_L("frames", n_frame, 0, PL_MAX_FRAMES)
    PL_L("groups", n_group, 0, PL_MAX_GROUPS)
    PL_L("drives", n_drive, 0, PL_MAX_DRIVES)
#undef PL_L
    else if (strcmp(key, "dof") == 0) {   /* index|1/m|g|name */
        char *f[4];
        long b;
        if (gfr_split_fields(val, f, 4) != 4 || !gfr_parse_long(f[0], &b) || b < 0 || b >= cfg->n_dof ||
            !gfr_parse_double(f[1], &cfg->inv_m[b]) || !gfr_parse_double(f[2], &cfg->g[b])) {
            snprintf(err, errcap, "line %d: bad dof entry (dofs first)", lineno);
            return err;
        }
        cfg->dof_seen[b] = 1;
    } else if (strcmp(key, "spring") == 0) {
        if (!spring_line(cfg, val)) {
            snprintf(err, errcap, "line %d: bad spring entry (springs first, then 0, 1, ... in order)", lineno);
            return err;
        }
    } else if (strcmp(key, "frame") == 0) {   /* index|a|b|R0|ratio */
        char *f[5];
        long i;
        if (gfr_split_fields(val, f, 5) != 5 || !gfr_parse_long(f[0], &i) || i != cfg->frames_seen ||
            i >= cfg->n_frame || !gfr_parse_long(f[1], &cfg->fr_a[i]) || !gfr_parse_long(f[2], &cfg->fr_b[i]) ||
            !gfr_parse_double(f[3], &cfg->fr_r0[i]) || !gfr_parse_double(f[4], &cfg->fr_ratio[i])) {
            snprintf(err, errcap, "line %d: bad frame entry (frames first, then 0, 1, ... in order)", lineno);
            return err;
        }
        cfg->fr_drive[i] = -1;
        cfg->frames_seen++;
    } else if (strcmp(key, "frame_drive") == 0) {   /* frame index|drive DOF|drive ratio (after its frame) */
        char *f[3];
        long i;
        if (gfr_split_fields(val, f, 3) != 3 || !gfr_parse_long(f[0], &i) || i < 0 || i >= cfg->frames_seen ||
            !gfr_parse_long(f[1], &cfg->fr_drive[i]) || !gfr_parse_double(f[2], &cfg->fr_drive_ratio[i])) {
            snprintf(err, errcap, "line %d: bad frame_drive entry (after its frame)", lineno);
            return err;
        }
    } else if (strcmp(key, "group") == 0) {   /* index|count|mesh_1|..|mesh_count */
        char *f[PL_MAX_GROUP + 2];
        long i, n, j;
        int nf = gfr_split_fields(val, f, PL_MAX_GROUP + 2);
        if (nf < 2 || !gfr_parse_long(f[0], &i) || i != cfg->groups_seen || i >= cfg->n_group ||
            !gfr_parse_long(f[1], &n) || n < 1 || n > PL_MAX_GROUP || nf != 2 + n) {
            snprintf(err, errcap, "line %d: bad group entry (groups first, then 0, 1, ... in order)", lineno);
            return err;
        }
        for (j = 0; j < n; ++j)
            if (!gfr_parse_long(f[2 + j], &cfg->gr_mesh[i][j])) {
                snprintf(err, errcap, "line %d: bad group entry", lineno);
                return err;
            }
        cfg->gr_count[i] = n;
        cfg->groups_seen++;
    } else if (strcmp(key, "drive") == 0) {   /* index|dof|value reference of its speed input|n|mode_1..mode_n */
        char *f[PL_MAX_DOF + 4];
        long i, n, j;
        int nf = gfr_split_fields(val, f, PL_MAX_DOF + 4);
        if (nf < 4 || !gfr_parse_long(f[0], &i) || i != cfg->drives_seen || i >= cfg->n_drive ||
            !gfr_parse_long(f[1], &cfg->dr_dof[i]) || !gfr_parse_long(f[2], &cfg->dr_vr[i]) ||
            !gfr_parse_long(f[3], &n) || n != cfg->n_dof || nf != 4 + n) {
            snprintf(err, errcap, "line %d: bad drive entry (dofs and drives first, then 0, 1, ... in order)", lineno);
            return err;
        }
        for (j = 0; j < n; ++j)
            if (!gfr_parse_double(f[4 + j], &cfg->dr_mode[i][j])) {
                snprintf(err, errcap, "line %d: bad drive entry", lineno);
                return err;
            }
        cfg->drives_seen++;
    } else if (strncmp(key, "mesh.", 5) == 0) {
        return mesh_key(cfg, key + 5, val, err, errcap);
    }
    /* unknown keys are ignored (forward compatible) */
    return NULL;
}

/* returns NULL on success, else a message (written into err) */
static const char *read_config(gf_inst *c, const char *text, pl_config *cfg, char *err, size_t errcap)
{
    char line[PL_MAX_LINE], *key, *val;
    const char *p = text, *e;
    int lineno = 0, i, r;
    memset(cfg, 0, sizeof *cfg);
    cfg->cc.vr_motor_torque = cfg->cc.vr_load_torque = -1;
    cfg->cc.vr_speed0 = cfg->cc.vr_angle0 = cfg->cc.vr_hmax = cfg->cc.vr_integrator = -2;
    while ((r = gfr_next_config_line(&p, line, sizeof line, &lineno, &key, &val, err, errcap)) > 0) {
        r = gfm_common_key(c, &cfg->cc, PL_CONFIG_FORMAT, PL_CONFIG_VERSION, key, val, err, errcap);
        if (r < 0) return err;
        if (r == 0 && (e = planetary_key(cfg, key, val, lineno, err, errcap)) != NULL) return e;
    }
    if (r < 0) return err;
    if ((e = gfm_common_check(c, &cfg->cc, err, errcap)) != NULL) return e;
    if (cfg->n_dof < 2 || cfg->n_mesh < 1) {
        snprintf(err, errcap, "missing keys (dofs, meshes)");
        return err;
    }
    for (i = 0; i < cfg->n_dof; ++i)
        if (!cfg->dof_seen[i]) {
            snprintf(err, errcap, "dof %d: no entry", i);
            return err;
        }
    for (i = 0; i < cfg->n_mesh; ++i)
        if ((cfg->ms[i].t.have & M_ALL) != M_ALL) {
            snprintf(err, errcap, "mesh.%d: missing keys (mask 0x%x of 0x%x)", i, cfg->ms[i].t.have, (unsigned)M_ALL);
            return err;
        }
    if (cfg->drives_seen != cfg->n_drive) {
        snprintf(err, errcap, "%d drive entries for %ld", cfg->drives_seen, cfg->n_drive);
        return err;
    }
    if (cfg->springs_seen != cfg->n_spring || cfg->frames_seen != cfg->n_frame || cfg->groups_seen != cfg->n_group) {
        snprintf(err, errcap, "%d spring, %d frame and %d group entries for %ld, %ld and %ld", cfg->springs_seen,
                 cfg->frames_seen, cfg->groups_seen, cfg->n_spring, cfg->n_frame, cfg->n_group);
        return err;
    }
    return NULL;
}

/* ------------------------------------------------------------- the kernel (gf_meshes.h gfm_kernel) */
static int pmk_integrator(void *kd, int code) { return pl_set_integrator(((gm_data *)kd)->pl, code); }
static double pmk_tref(const void *kd, double Tm, double Tl)
{
    return pl_reference_torque(((const gm_data *)kd)->pl, Tm, Tl);
}
static double pmk_mesh_torque(const void *kd, int m, double t_ref) { return pl_mesh_torque(((const gm_data *)kd)->pl, m, t_ref); }
/* the drives' speed inputs (rad/s) into w; 0 (reasons logged at `status`) when one is not finite */
static int drive_speeds(gm_data *d, double *w, int status, const char *tail)
{
    int j, bad = 0;
    for (j = 0; j < d->pl->n_drive; ++j) {
        bad |= gfm_bad_value(d->inst, d->drive_vr[j], status, tail);
        w[j] = gfm_val(d->inst, d->drive_vr[j]);
    }
    return !bad;
}
static int pmk_initialize(void *kd, double psi0, double w0, double t_ref, int *bad_mesh)
{
    gm_data *d = (gm_data *)kd;
    double w[PL_MAX_DRIVES];
    if (!drive_speeds(d, w, GF_ERROR_STATUS, "; cannot compute the initial state")) return GK_ERR_INPUT;
    return pl_initialize_driven(d->pl, d->work, &d->state, psi0, w0, t_ref, d->pl->n_drive ? w : NULL, bad_mesh);
}
static int pmk_outputs(void *kd, double Tm, double Tl, double *out)
{
    gm_data *d = (gm_data *)kd;
    return pl_outputs(d->pl, d->work, &d->state, Tm, Tl, out);
}
/* a communication step: the drives' speeds set at its start (docs/planetary.md "Driven members"); on an
 * error the state as it was */
static int pmk_step(void *kd, double Tm, double Tl, double H, double hmax, double *out)
{
    gm_data *d = (gm_data *)kd;
    double w[PL_MAX_DRIVES], was[PL_MAX_DRIVES];
    int j, st;
    if (!drive_speeds(d, w, GF_DISCARD, "; step rejected, state unchanged")) return GK_ERR_INPUT;
    for (j = 0; j < d->pl->n_drive; ++j) was[j] = d->state.y[2 * d->pl->drive_dof[j] + 1];
    st = pl_set_drive_speeds(d->pl, &d->state, w);
    if (st == GK_OK) st = pl_do_step(d->pl, d->work, &d->state, Tm, Tl, H, hmax, out);
    if (st != GK_OK)
        for (j = 0; j < d->pl->n_drive; ++j) d->state.y[2 * d->pl->drive_dof[j] + 1] = was[j];
    return st;
}
/* Model Exchange: a drive's rate state is its speed input at every evaluation (the host integrates the
 * drive's angle with it; the rate's own derivative is 0); GK_ERR_INPUT (logged) for a non-finite one */
static int me_drives(gm_data *d)
{
    double w[PL_MAX_DRIVES];
    if (d->pl->n_drive == 0) return GK_OK;
    if (!drive_speeds(d, w, GF_DISCARD, "; not evaluated")) return GK_ERR_INPUT;
    return pl_set_drive_speeds(d->pl, &d->state, w);
}
static int pmk_me_n_ind(const void *kd, int node_events) { return pl_me_n_indicators(((const gm_data *)kd)->pl, node_events); }
static int pmk_me_init(void *kd, double Tm, double Tl, int node_events)
{
    gm_data *d = (gm_data *)kd;
    int st = me_drives(d);
    return st != GK_OK ? st : pl_me_init(d->pl, d->work, &d->me, d->state.y, Tm, Tl, node_events);
}
static int pmk_me_update(void *kd, double Tm, double Tl, int *changed)
{
    gm_data *d = (gm_data *)kd;
    int st = me_drives(d);
    return st != GK_OK ? st : pl_me_update(d->pl, d->work, &d->me, d->state.y, Tm, Tl, changed);
}
static int pmk_me_deriv(void *kd, double Tm, double Tl, double *dy)
{
    gm_data *d = (gm_data *)kd;
    int st = me_drives(d);
    return st != GK_OK ? st : pl_me_derivatives(d->pl, d->work, &d->me, d->state.y, Tm, Tl, dy);
}
static int pmk_me_ind(void *kd, double Tm, double Tl, double *z)
{
    gm_data *d = (gm_data *)kd;
    int st = me_drives(d);
    return st != GK_OK ? st : pl_me_indicators(d->pl, d->work, &d->me, d->state.y, Tm, Tl, z);
}
static int pmk_me_out(void *kd, double Tm, double Tl, double *out)
{
    gm_data *d = (gm_data *)kd;
    int st = me_drives(d);
    return st != GK_OK ? st : pl_me_outputs(d->pl, d->work, &d->me, d->state.y, Tm, Tl, out);
}

static const gfm_kernel PL_KERNEL = {"mesh", "docs/planetary.md", pmk_integrator, pmk_tref, pmk_mesh_torque, pmk_initialize,
                                     pmk_outputs, pmk_step, pmk_me_n_ind, pmk_me_init, pmk_me_update, pmk_me_deriv, pmk_me_ind,
                                     pmk_me_out};

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
        free(c->data->pl);
        free(c->data->work);
        free(c->data);
        c->data = NULL;
    }
}

/* the planetary kernel's model from the configuration (the meshes' tables loaded); NULL or a message */
static const char *build_kernel(gf_inst *c, const char *res_dir, const pl_config *cfg, gf_sha256 *tag, char *err,
                                size_t errcap)
{
    gm_data *d = c->data;
    const char *e = NULL;
    int i, j, m;
    if (pl_init(d->pl, (int)cfg->n_dof, cfg->inv_m, cfg->g, (int)cfg->load_dof, (int)cfg->cc.motor_input,
                (int)cfg->cc.load_input) != GK_OK)
        return "the degrees of freedom (masses, ratios, load DOF) are refused by the kernel";
    for (m = 0; e == NULL && m < (int)cfg->n_mesh; ++m) {
        const pl_mesh_cfg *s = &cfg->ms[m];
        int xd[PL_MESH_MAX_X], ad[PL_MESH_MAX_A];
        for (j = 0; j < s->nx; ++j) xd[j] = (int)s->x_dof[j];
        for (j = 0; j < s->na; ++j) ad[j] = (int)s->a_dof[j];
        e = gfm_load_mesh(c, &d->core, res_dir, &s->t, m, tag, err, errcap);
        if (e == NULL && pl_add_mesh(d->pl, d->core.pair[m], (int)s->nx, xd, s->x_coef, (int)s->na, ad, s->a_coef,
                                     s->a_ref, s->phase, s->torque_per_ref) != GK_OK) {
            snprintf(err, errcap, "mesh %.60s: its maps are refused by the kernel", s->t.name);
            e = err;
        }
    }
    for (i = 0; e == NULL && i < cfg->n_spring; ++i) {
        int dof[PL_SPRING_MAX];
        for (j = 0; j < PL_SPRING_MAX; ++j) dof[j] = (int)cfg->sp_dof[i][j];
        if (pl_add_spring(d->pl, (int)cfg->sp_count[i], dof, cfg->sp_coef[i], cfg->sp_k[i], cfg->sp_c[i]) != GK_OK)
            e = "a spring (DOFs, stiffness, damping) is refused by the kernel";
    }
    for (i = 0; e == NULL && i < cfg->n_frame; ++i)
        if (pl_add_frame(d->pl, (int)cfg->fr_a[i], (int)cfg->fr_b[i], cfg->fr_r0[i], cfg->fr_ratio[i]) != GK_OK)
            e = "a rotating frame is refused by the kernel";
    for (i = 0; e == NULL && i < cfg->n_group; ++i) {
        int ms[PL_MAX_GROUP];
        for (j = 0; j < cfg->gr_count[i]; ++j) ms[j] = (int)cfg->gr_mesh[i][j];
        if (pl_add_group(d->pl, (int)cfg->gr_count[i], ms) != GK_OK) e = "a load-sharing group is refused by the kernel";
    }
    for (i = 0; e == NULL && i < cfg->n_drive; ++i) {
        if (!gfm_vr_ok(c, cfg->dr_vr[i], 0) || c->vars[cfg->dr_vr[i]].causality != GF_INPUT)
            e = "a drive's speed input is not an input of the variable table";
        else if (pl_add_drive(d->pl, (int)cfg->dr_dof[i], cfg->dr_mode[i]) != GK_OK)
            e = "a drive (its DOF: 1/m 0 and g 0; its rigid motion) is refused by the kernel";
        else
            d->drive_vr[i] = (int)cfg->dr_vr[i];
    }
    for (i = 0; e == NULL && i < cfg->n_frame; ++i)
        if (cfg->fr_drive[i] >= 0 && pl_set_frame_drive(d->pl, i, (int)cfg->fr_drive[i], cfg->fr_drive_ratio[i]) != GK_OK)
            e = "a rotating frame's drive is refused by the kernel";
    return e;
}

const char *gm_instantiate(gf_inst *c, const char *res_dir, const char *token, char *err, size_t errcap)
{
    pl_config *cfg;
    gm_data *d;
    unsigned char *text;
    size_t size = 0;
    gf_sha256 tag;
    const char *e;
    c->data = d = (gm_data *)calloc(1, sizeof(gm_data));
    if (d == NULL) return "out of memory";
    d->core.k = &PL_KERNEL;
    d->inst = c;
    d->core.y_offset = offsetof(gm_data, state) + offsetof(pl_state, y);
    d->core.kstate_offset = offsetof(gm_data, state);
    d->core.kstate_bytes = sizeof d->state;
    d->core.kme_offset = offsetof(gm_data, me);
    d->core.kme_bytes = sizeof d->me;
    d->core.snap_magic = PL_SNAPSHOT_MAGIC;
    d->core.snap_version = PL_SNAPSHOT_VERSION;
    text = gfr_read_resource(res_dir, PL_CONFIG_FILE, &size, err, errcap);
    if (text == NULL) return err;
    cfg = (pl_config *)calloc(1, sizeof(pl_config));
    if (cfg == NULL) {
        free(text);
        return "out of memory";
    }
    {
        char e2[512];
        e = read_config(c, (const char *)text, cfg, e2, sizeof e2);
        free(text);
        if (e != NULL) {
            snprintf(err, errcap, "resources/%s: %s", PL_CONFIG_FILE, e);
            free(cfg);
            return err;
        }
    }
    e = NULL;
    if (token == NULL || strcmp(token, cfg->cc.guid) != 0) e = "GUID differs from the one this FMU was built with";
    d->pl = (pl_model *)calloc(1, (size_t)pl_sizeof_model());
    d->work = (pl_work *)calloc(1, (size_t)pl_sizeof_work());
    if (e == NULL && (d->pl == NULL || d->work == NULL)) e = "out of memory";
    gfr_sha_init(&tag);
    if (e == NULL) e = build_kernel(c, res_dir, cfg, &tag, err, errcap);
    if (e == NULL) {
        d->core.n_state = (size_t)(2 * d->pl->n);
        e = gfm_bind(c, &d->core, &cfg->cc, pl_n_outputs(d->pl), &tag, err, errcap);
    }
    free(cfg);
    if (e != NULL) return e;
    gf_log(c, GF_OK, "logAll", "instantiated: planetary drivetrain of %d DOFs, %d meshes, %d springs, %d frames, "
           "tables SHA-256 ok", d->pl->n, d->core.n_mesh, d->pl->n_spring, d->pl->n_frame);
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
