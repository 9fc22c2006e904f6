/*
 * pl_kernel.c -- the planetary drivetrain kernel (plkernel.h; docs/planetary.md): DOFs, springs,
 * rotating frames and meshes, the right-hand side, classical RK4 and the event-aware substep of
 * rk4_kink / rk4_node over all meshes, the step, the outputs with the load-sharing factors
 * (Kahraman 1994) and Model Exchange.  The static state is pl_static.c.
 *
 * Every mesh is looked up, loaded and event-located by the pair's own pieces (gk_pair.h) on its own
 * gk_model and gk_mode, mapped to its local state (theta, omega, x, v); the loops over the DOFs,
 * springs, frames and meshes are those of the numba planetary solver (gearfmu/planetary/kernels.py:
 * _rhs, _rk4, _substep, _mesh_start, _mesh_cross, _mesh_guards_hold, _write_row), operation by
 * operation, so that the two agree bit for bit (tests/fmu_hosts/test_planetary_kernel.py); the
 * event substep is gb_kernel.c's over the generalised meshes.  Compiled with the pair kernel's flags
 * (no fused multiply-add, no fast-math).
 *
 * No globals, no allocation, no abort.
 */
#include "pl_internal.h"

int pl_abi_version(void) { return PL_ABI_VERSION; }
int pl_sizeof_model(void) { return (int)sizeof(pl_model); }
int pl_sizeof_work(void) { return (int)sizeof(pl_work); }
int pl_sizeof_state(void) { return (int)sizeof(pl_state); }
int pl_sizeof_me(void) { return (int)sizeof(pl_me); }
long pl_events(const pl_work *w) { return w != NULL ? w->events : 0; }

/* ------------------------------------------------------------------ setup */
int pl_init(pl_model *pl, int n, const double *inv_m, const double *g, int load_dof, int motor_input,
            int load_input)
{
    int i;
    if (pl == NULL || inv_m == NULL || g == NULL || n < 2 || n > PL_MAX_DOF) return GK_ERR_MODEL;
    if (load_dof < 0 || load_dof >= n || g[0] != 1.0) return GK_ERR_MODEL;
    for (i = 0; i < n; ++i)   /* 1/m 0: a drive (g 0, not the motor DOF) */
        if (!(gki_finite_pos(inv_m[i]) || (inv_m[i] == 0.0 && g[i] == 0.0 && i > 0)) || !isfinite(g[i]))
            return GK_ERR_MODEL;
    if (g[load_dof] == 0.0 || (!motor_input && !load_input)) return GK_ERR_MODEL;
    pl->n = n;
    pl->n_mesh = pl->n_spring = pl->n_frame = pl->n_group = pl->n_drive = 0;
    pl->load_dof = load_dof;
    pl->motor_input = motor_input != 0;
    pl->load_input = load_input != 0;
    pl->integrator = PL_INTEGRATOR_RK4;
    pl->n_g = 0;
    for (i = 0; i < n; ++i) {
        pl->inv_m[i] = inv_m[i];
        pl->g[i] = g[i];
        if (i > 0 && g[i] != 0.0) pl->g_dof[pl->n_g++] = i;
    }
    return GK_OK;
}

int pl_add_drive(pl_model *pl, int dof, const double *mode)
{
    int i, j;
    if (pl == NULL || mode == NULL || pl->n_drive >= PL_MAX_DRIVES || dof < 1 || dof >= pl->n) return GK_ERR_MODEL;
    if (pl->inv_m[dof] != 0.0 || pl->g[dof] != 0.0 || mode[dof] != 1.0 || mode[0] != 0.0) return GK_ERR_MODEL;
    for (j = 0; j < pl->n_drive; ++j)
        if (pl->drive_dof[j] == dof) return GK_ERR_MODEL;
    for (i = 0; i < pl->n; ++i)
        if (!isfinite(mode[i])) return GK_ERR_MODEL;
    for (i = 0; i < pl->n; ++i) pl->drive_mode[pl->n_drive][i] = mode[i];
    pl->drive_dof[pl->n_drive] = dof;
    pl->n_drive++;
    return GK_OK;
}

int pl_set_drive_speeds(const pl_model *pl, pl_state *s, const double *speed)
{
    int j;
    if (pl == NULL || s == NULL || (speed == NULL && pl->n_drive > 0)) return GK_ERR_MODEL;
    for (j = 0; j < pl->n_drive; ++j)
        if (!isfinite(speed[j])) return GK_ERR_INPUT;
    for (j = 0; j < pl->n_drive; ++j) s->y[2 * pl->drive_dof[j] + 1] = speed[j];
    return GK_OK;
}

int pl_start_drives(const pl_model *pl, pl_state *s, const double *speed)
{
    int i, j;
    if (pl == NULL || s == NULL || (speed == NULL && pl->n_drive > 0)) return GK_ERR_MODEL;
    for (j = 0; j < pl->n_drive; ++j)
        if (!isfinite(speed[j])) return GK_ERR_INPUT;
    for (j = 0; j < pl->n_drive; ++j)   /* as PlanetaryModel.static_state: y[3::2] += mode[1:] * speed */
        for (i = 1; i < pl->n; ++i) s->y[2 * i + 1] += pl->drive_mode[j][i] * speed[j];
    return GK_OK;
}

/* 1 when count DOF indices lie in [0, n) and their coefficients are finite */
static int plk_map_ok(const pl_model *pl, int count, const int *dof, const double *coef)
{
    int j;
    if (count > 0 && (dof == NULL || coef == NULL)) return 0;
    for (j = 0; j < count; ++j)
        if (dof[j] < 0 || dof[j] >= pl->n || !isfinite(coef[j])) return 0;
    return 1;
}

/* the map (count DOFs) without its DOF-0 terms, as the step reads it: DOF, coefficient and state offset
 * 2 DOF of each kept term, the rest of the cap entries zero; returns the terms kept */
static int plk_step_map(int count, const int *dof, const double *coef, int cap, int *hdof, double *hcoef,
                        int *hoff)
{
    int j, nh = 0;
    for (j = 0; j < cap; ++j) {
        hdof[j] = 0;
        hcoef[j] = 0.0;
        hoff[j] = 0;
    }
    for (j = 0; j < count; ++j)
        if (dof[j] != 0) {
            hdof[nh] = dof[j];
            hcoef[nh] = coef[j];
            hoff[nh++] = 2 * dof[j];
        }
    return nh;
}

int pl_add_spring(pl_model *pl, int count, const int *dof, const double *coef, double k, double c)
{
    pl_spring *s;
    int j;
    if (pl == NULL || pl->n_spring >= PL_MAX_SPRINGS || count < 1 || count > PL_SPRING_MAX) return GK_ERR_MODEL;
    if (!plk_map_ok(pl, count, dof, coef)) return GK_ERR_MODEL;
    if (!gki_finite_pos(k) || !isfinite(c) || c < 0.0) return GK_ERR_MODEL;
    s = &pl->spring[pl->n_spring++];
    s->count = count;
    for (j = 0; j < PL_SPRING_MAX; ++j) {
        s->dof[j] = j < count ? dof[j] : 0;
        s->coef[j] = j < count ? coef[j] : 0.0;
    }
    s->nh = plk_step_map(count, dof, coef, PL_SPRING_MAX, s->hdof, s->hcoef, s->hoff);
    s->k = k;
    s->c = c;
    return GK_OK;
}

int pl_add_frame(pl_model *pl, int dof_a, int dof_b, double R0_m, double frame_ratio)
{
    pl_frame *f;
    if (pl == NULL || pl->n_frame >= PL_MAX_FRAMES) return GK_ERR_MODEL;
    if (dof_a < 1 || dof_a >= pl->n || dof_b < 1 || dof_b >= pl->n || dof_a == dof_b) return GK_ERR_MODEL;
    if (!isfinite(R0_m) || !isfinite(frame_ratio)) return GK_ERR_MODEL;
    f = &pl->frame[pl->n_frame++];
    f->a = dof_a;
    f->b = dof_b;
    f->R0_m = R0_m;
    f->ratio = frame_ratio;
    f->drive = -1;
    f->drive_ratio = 0.0;
    return GK_OK;
}

int pl_set_frame_drive(pl_model *pl, int frame, int drive_dof, double drive_ratio)
{
    int j, ok = 0;
    if (pl == NULL || frame < 0 || frame >= pl->n_frame || !isfinite(drive_ratio)) return GK_ERR_MODEL;
    for (j = 0; j < pl->n_drive; ++j) ok |= pl->drive_dof[j] == drive_dof;
    if (!ok) return GK_ERR_MODEL;
    pl->frame[frame].drive = drive_dof;
    pl->frame[frame].drive_ratio = drive_ratio;
    return GK_OK;
}

int pl_add_mesh(pl_model *pl, gk_model *pair, int nx, const int *x_dof, const double *x_coef, int na,
                const int *a_dof, const double *a_coef, double a_ref, double phase_rad, double torque_per_ref)
{
    pl_mesh *me;
    int j;
    if (pl == NULL || pair == NULL || pl->n_mesh >= PL_MAX_MESHES) return GK_ERR_MODEL;
    if (nx < 1 || nx > PL_MESH_MAX_X || na < 0 || na > PL_MESH_MAX_A) return GK_ERR_MODEL;
    if (!plk_map_ok(pl, nx, x_dof, x_coef) || !plk_map_ok(pl, na, a_dof, a_coef)) return GK_ERR_MODEL;
    if (!isfinite(a_ref) || !isfinite(phase_rad) || !isfinite(torque_per_ref)) return GK_ERR_MODEL;
    if (pair->P < 1 || pair->n_phi < 1) return GK_ERR_MODEL;
    me = &pl->mesh[pl->n_mesh++];
    me->pair = pair;
    me->nx = nx;
    me->na = na;
    for (j = 0; j < PL_MESH_MAX_X; ++j) {
        me->x_dof[j] = j < nx ? x_dof[j] : 0;
        me->x_coef[j] = j < nx ? x_coef[j] : 0.0;
    }
    me->nxh = plk_step_map(nx, x_dof, x_coef, PL_MESH_MAX_X, me->xh_dof, me->xh_coef, me->xh_off);
    me->a_has0 = 0;
    for (j = 0; j < PL_MESH_MAX_A; ++j) {
        me->a_dof[j] = j < na ? a_dof[j] : 0;
        me->a_coef[j] = j < na ? a_coef[j] : 0.0;
        me->a_off[j] = 2 * me->a_dof[j];
        if (j < na && a_dof[j] == 0) me->a_has0 = 1;
    }
    me->a_ref = a_ref;
    me->phase = phase_rad;
    me->torque_per_ref = torque_per_ref;
    return multimesh_integrator(pair, pl->integrator);
}

int pl_add_group(pl_model *pl, int count, const int *mesh)
{
    pl_group *gr;
    int j;
    if (pl == NULL || mesh == NULL || pl->n_group >= PL_MAX_GROUPS || count < 1 || count > PL_MAX_GROUP)
        return GK_ERR_MODEL;
    for (j = 0; j < count; ++j)
        if (mesh[j] < 0 || mesh[j] >= pl->n_mesh) return GK_ERR_MODEL;
    gr = &pl->group[pl->n_group++];
    gr->count = count;
    for (j = 0; j < PL_MAX_GROUP; ++j) gr->mesh[j] = j < count ? mesh[j] : 0;
    return GK_OK;
}

int pl_set_integrator(pl_model *pl, int integrator)
{
    int m, st;
    if (pl == NULL) return GK_ERR_MODEL;
    if (integrator != PL_INTEGRATOR_RK4 && integrator != PL_INTEGRATOR_RK4_KINK && integrator != PL_INTEGRATOR_RK4_NODE
        && integrator != PL_INTEGRATOR_RK4_SEG)
        return GK_ERR_PARAM;
    for (m = 0; m < pl->n_mesh; ++m) {
        st = multimesh_integrator(pl->mesh[m].pair, integrator);
        if (st != GK_OK) return st;
    }
    pl->integrator = integrator;
    return GK_OK;
}

double pl_reference_torque(const pl_model *pl, double T_motor, double T_load)
{
    if (pl == NULL) return 0.0;
    if (pl->motor_input) return T_motor;
    return T_load * pl->g[pl->load_dof];
}

double pl_mesh_torque(const pl_model *pl, int m, double T_ref)
{
    if (pl == NULL || m < 0 || m >= pl->n_mesh) return 0.0;
    return fabs(pl->mesh[m].torque_per_ref * T_ref);
}

int pl_mesh_offset(const pl_model *pl, int m)
{
    int k, o;
    if (pl == NULL || m < 0 || m > pl->n_mesh) return -1;
    o = 2 * pl->n;
    for (k = 0; k < m; ++k) o += PL_OUT_PAIR_FORCE + 2 * pl->mesh[k].pair->P;
    return o;
}

int pl_spring_offset(const pl_model *pl) { return pl_mesh_offset(pl, pl != NULL ? pl->n_mesh : 0); }

int pl_group_offset(const pl_model *pl, int g)
{
    int k, o;
    if (pl == NULL || g < 0 || g > pl->n_group) return -1;
    o = pl_spring_offset(pl) + pl->n_spring;
    for (k = 0; k < g; ++k) o += pl->group[k].count;
    return o;
}

int pl_n_outputs(const pl_model *pl) { return pl != NULL ? pl_group_offset(pl, pl->n_group) : 0; }

/* the torque rows of every mesh at the inputs (kernels.run: it_rows, wt_rows of the step) and no
 * carried cell */
static void plk_select_rows(const pl_model *pl, pl_work *w, double T_motor, double T_load)
{
    int m;
    double t_ref = pl_reference_torque(pl, T_motor, T_load);
    for (m = 0; m < pl->n_mesh; ++m) {
        const gk_ph none = GK_PH_NONE;
        w->tq[m] = torque_bracket(pl->mesh[m].pair, pl_mesh_torque(pl, m, t_ref));
        w->ph[m] = none;
    }
}

/* --------------------------------------------------------- right-hand side
 * dy at y (kernels._rhs; docs/planetary.md "Model"): the generalised forces Q_i of the springs and
 * meshes; the reference's acceleration from the balance of the generalised momentum,
 * psi'' = (T_in - sum_i>0 g_i Q_i - sum_frames g_f ((R0 + q_a) Q_b - q_b Q_a))/m_0, the load torque on
 * its DOF after that sum; q_i'' = Q_i/m_i - g_i psi'' plus the inertial terms of the rotating frames
 * (Lin & Parker 1999).  `locked`: every mesh with its held mode (1: the event integrators' gk_mode;
 * 2: Model Exchange's gk_me, w->me; 3: rk4_seg, the gk_mode held and the tables read in the cell of
 * the evaluation's angle clamped to the held segment, kernels._mesh_seg), else the plain lookup with
 * the carried cell (rk4). */
GK_INLINE void plk_rhs_at(const pl_model *pl, pl_work *w, const double *y, double *dy, double t_in, double t_out,
                          const int locked)
{
    int n = pl->n, i, s, m, j, lb = pl->load_dof;
    double *tau = w->tau, sg, ext0, a0;
    for (i = 0; i < n; ++i) tau[i] = 0.0;
    for (s = 0; s < pl->n_spring; ++s) {   /* the DOF-0 terms left out (plkernel.h nh; plk_mesh_local) */
        const pl_spring *sp = &pl->spring[s];
        double v = 0.0, vd = 0.0, fs;
        for (j = 0; j < sp->nh; ++j) {
            const double *q = y + sp->hoff[j];
            v += sp->hcoef[j] * q[0];
            vd += sp->hcoef[j] * q[1];
        }
        fs = sp->k * v + sp->c * vd;
        for (j = 0; j < sp->nh; ++j) tau[sp->hdof[j]] -= sp->hcoef[j] * fs;
    }
    for (m = 0; m < pl->n_mesh; ++m) {
        const pl_mesh *me = &pl->mesh[m];
        const gk_model *pm = me->pair;
        double loc[4], fm;
        plk_mesh_local(me, y, 1.0, loc);
        if (locked == 3) {
            const gk_mode *md = &w->md[m];
            gk_ph c;
            double cc = seg_cell(pm, md, loc[0], &c);
            fm = 0.0;
            for (j = 0; j < pm->P; ++j) {
                double kv, ev, es, bv;
                slot_tables(pm, &w->tq[m], &c, j, seg_sel(pm, md, j, cc, &c), &kv, &ev, &es, &bv);
                fm += pair_force_locked(kv, ev, es, bv, loc[2], loc[3], loc[1], pm->c_Ns_per_m, pm->damping_model,
                                        md->reg[j], md->sub[j], md->kpos[j]);
            }
        } else if (locked == 1) {   /* kernels._mesh_locked: the force loop of deriv_locked */
            const gk_mode *md = &w->md[m];
            fm = 0.0;
            for (j = 0; j < pm->P; ++j) {
                double kv, ev, es, bv;
                locked_tables(pm, &w->tq[m], md, loc[0], j, &kv, &ev, &es, &bv);
                fm += pair_force_locked(kv, ev, es, bv, loc[2], loc[3], loc[1], pm->c_Ns_per_m, pm->damping_model,
                                        md->reg[j], md->sub[j], md->kpos[j]);
            }
        } else if (locked == 2) {
            fm = me_force(pm, &w->me->mesh[m], &w->tq[m], loc, NULL, NULL);
        } else {
            fm = mesh_force(pm, &w->tq[m], &w->ph[m], loc[0], loc[1], loc[2], loc[3], NULL, NULL);
        }
        for (j = 0; j < me->nxh; ++j) tau[me->xh_dof[j]] -= me->xh_coef[j] * fm;
    }
    sg = 0.0;   /* over the DOFs with g_i != 0: +-0 terms leave a sum that starts at +0.0 unchanged */
    for (j = 0; j < pl->n_g; ++j) sg += pl->g[pl->g_dof[j]] * tau[pl->g_dof[j]];
    for (s = 0; s < pl->n_frame; ++s) {
        const pl_frame *f = &pl->frame[s];
        sg += f->ratio * ((f->R0_m + y[2 * f->a]) * tau[f->b] - y[2 * f->b] * tau[f->a]);
    }
    ext0 = t_in;
    if (lb == 0) ext0 -= t_out;
    else tau[lb] -= t_out;
    a0 = (ext0 - sg) * pl->inv_m[0];
    dy[0] = y[1];
    dy[1] = a0;
    for (i = 1; i < n; ++i) {
        dy[2 * i] = y[2 * i + 1];
        dy[2 * i + 1] = tau[i] * pl->inv_m[i] - pl->g[i] * a0;
    }
    for (s = 0; s < pl->n_frame; ++s) {
        const pl_frame *f = &pl->frame[s];
        int ia = f->a, ib = f->b;
        double R0 = f->R0_m, gfr = f->ratio, Om = gfr * y[1], Od = gfr * a0;
        if (f->drive >= 0) Om += f->drive_ratio * y[2 * f->drive + 1];   /* a drive turns the frame too */
        double qa = y[2 * ia], qb = y[2 * ib], va = y[2 * ia + 1], vb = y[2 * ib + 1];
        dy[2 * ia + 1] += 2.0 * Om * vb + Od * qb + Om * Om * (R0 + qa);
        dy[2 * ib + 1] += -2.0 * Om * va - Od * (R0 + qa) + Om * Om * qb;
    }
}

/* plk_rhs_at with each `locked` compiled once: one call to its copy (the event substep and RK4 call it
 * from many places, and a copy inlined at each would not fit the instruction cache) */
static void plk_rhs(const pl_model *pl, pl_work *w, const double *y, double *dy, double t_in, double t_out,
                    int locked)
{
    switch (locked) {
    case 3: plk_rhs_at(pl, w, y, dy, t_in, t_out, 3); break;
    case 2: plk_rhs_at(pl, w, y, dy, t_in, t_out, 2); break;
    case 1: plk_rhs_at(pl, w, y, dy, t_in, t_out, 1); break;
    default: plk_rhs_at(pl, w, y, dy, t_in, t_out, 0); break;
    }
}

/* one classical RK4 step of length h from y with its first stage f0 into out (kernels._rk4) */
static void plk_rk4(const pl_model *pl, pl_work *w, const double *y, const double *f0, double h, double *out,
                    double t_in, double t_out, int locked)
{
    int i, n2 = 2 * pl->n;
    double h2 = h / 2.0, h6, *tmp = w->tmp, *acc = w->acc, *kk = w->kk;
    for (i = 0; i < n2; ++i) tmp[i] = y[i] + h2 * f0[i];
    plk_rhs(pl, w, tmp, kk, t_in, t_out, locked);
    for (i = 0; i < n2; ++i) {
        acc[i] = f0[i] + 2.0 * kk[i];
        tmp[i] = y[i] + h2 * kk[i];
    }
    plk_rhs(pl, w, tmp, kk, t_in, t_out, locked);
    for (i = 0; i < n2; ++i) {
        acc[i] = acc[i] + 2.0 * kk[i];
        tmp[i] = y[i] + h * kk[i];
    }
    plk_rhs(pl, w, tmp, kk, t_in, t_out, locked);
    h6 = h / 6.0;
    for (i = 0; i < n2; ++i) out[i] = y[i] + h6 * (acc[i] + kk[i]);
}

/* ------------------------------------------------- the modes of the meshes */
/* mesh m's mode from the state y (kernels._mesh_start) */
static void plk_mesh_start(const pl_model *pl, pl_work *w, int m, const double *y, int node)
{
    double loc[4];
    plk_mesh_local(&pl->mesh[m], y, 1.0, loc);
    mode_from_state(pl->mesh[m].pair, &w->tq[m], &w->md[m], loc, node);
}

/* move mesh m's held segment across its end (up) or start, then its zone sides and sub-modes at y
 * (kernels._mesh_cross) */
static void plk_mesh_cross(const pl_model *pl, pl_work *w, int m, const double *y, int up, int node)
{
    const gk_model *pm = pl->mesh[m].pair;
    gk_mode *md = &w->md[m];
    double loc[4];
    gki_seg_cross(pm, md, up, node);
    gki_cell_nodes(md, pm->n_phi);
    gki_zone_sel(pm, md);
    plk_mesh_local(&pl->mesh[m], y, 1.0, loc);
    mode_sync(pm, &w->tq[m], md, loc, 0);
}

/* 1 when no pair guard of mesh m is negative at v (with `segment`, neither of its segment guards), the
 * tables read as plk_rhs with `lk` (kernels._mesh_guards_hold, _pairs_hold_seg) */
static int plk_guards_hold(const pl_model *pl, pl_work *w, int m, const double *v, int segment, int lk)
{
    const gk_model *pm = pl->mesh[m].pair;
    const gk_mode *md = &w->md[m];
    double loc[4];
    plk_mesh_local(&pl->mesh[m], v, 1.0, loc);
    if (segment && (loc[0] - md->lo * pm->dphi_rad < 0.0 || md->hi * pm->dphi_rad - loc[0] < 0.0)) return 0;
    if (lk == 3) return pairs_hold_seg(pm, &w->tq[m], md, loc);
    return pairs_hold(pm, &w->tq[m], md, loc);
}

static void plk_copy(double *dst, const double *src, int n2)
{
    int i;
    for (i = 0; i < n2; ++i) dst[i] = src[i];
}

/* ---------------------------------------------------------- event substep
 * One substep of length h of rk4_kink (node 0), rk4_node (node 1) or rk4_seg (node 1, lk 3: the
 * tables read in the cell of each evaluation, the guards and root searches too) for the whole drivetrain
 * (kernels._substep, gb_kernel.c's gb_substep over the generalised meshes): every mesh holds its own
 * cell, segment and pair modes; a step ends at the earliest predicted node crossing of any mesh
 * (rk4_node) when no guard of any mesh is negative there; else the trial step's guards of every mesh
 * are located on the step's Hermite interpolant mapped to each mesh's local state, and the earliest
 * event wins (ties: lower mesh, then lower guard).  Returns the events. */
static long plk_substep(const pl_model *pl, pl_work *w, double h, int node, const int lk, double t_in,
                        double t_out)
{
    double *y = w->y, *f0 = w->f0, *y1 = w->y1, *f1 = w->f1, *yt = w->yt;
    double rem = h;
    long nev = 0;
    int n2 = 2 * pl->n, m, seg = lk == 3;
    for (;;) {
        double best = 2.0;
        int best_m = -1, best_gi = -1, any_neg;
        if (seg) {   /* the segments are fixed until the next pass */
            for (m = 0; m < pl->n_mesh; ++m) {
                gk_mode *md = &w->md[m];
                md->cl = floor(md->lo);
                md->ch = ceil(md->hi) - 1.0;
            }
        }
        if (node) {   /* the held cell follows theta inside the held segment */
            for (m = 0; m < pl->n_mesh; ++m) {
                const gk_model *pm = pl->mesh[m].pair;
                gk_mode *md = &w->md[m];
                double th, om, cn;
                plk_mesh_angle(&pl->mesh[m], y, 1.0, &th, &om);
                cn = floor(th * pm->inv_dphi);
                if (cn + 1.0 > md->lo && cn < md->hi && cn != md->nd) {
                    md->nd = cn;
                    gki_cell_nodes(md, pm->n_phi);
                    gki_zone_sel(pm, md);
                }
            }
        }
        plk_rhs(pl, w, y, f0, t_in, t_out, lk);
        if (node && nev < GK_KINK_MAX_EVENTS) {   /* the earliest segment end ahead: one step to it */
            double best_tau = -1.0;
            best_m = -1;
            for (m = 0; m < pl->n_mesh; ++m) {
                const gk_model *pm = pl->mesh[m].pair;
                const gk_mode *md = &w->md[m];
                double th, om, dth, dom, tau;
                plk_mesh_angle(&pl->mesh[m], y, 1.0, &th, &om);
                plk_mesh_angle(&pl->mesh[m], f0, 0.0, &dth, &dom);
                tau = node_time(th, om, dom, rem, md->lo, md->hi, pm->dphi_rad);
                if (tau > 0.0 && (best_m < 0 || tau < best_tau)) {
                    best_tau = tau;
                    best_m = m;
                }
            }
            if (best_m >= 0) {
                int ok = 1;
                plk_rk4(pl, w, y, f0, best_tau, yt, t_in, t_out, lk);
                for (m = 0; m < pl->n_mesh; ++m)
                    if (!plk_guards_hold(pl, w, m, yt, m != best_m, lk)) {
                        ok = 0;
                        break;
                    }
                if (ok) {
                    double th, om;
                    int up;
                    plk_mesh_angle(&pl->mesh[best_m], y, 1.0, &th, &om);
                    up = om > 0.0;
                    plk_copy(y, yt, n2);
                    rem = rem - best_tau;
                    nev += 1;
                    plk_mesh_cross(pl, w, best_m, y, up, 1);
                    if (!(rem > 0.0)) break;
                    continue;
                }
            }
        }
        plk_rk4(pl, w, y, f0, rem, y1, t_in, t_out, lk);
        if (nev >= GK_KINK_MAX_EVENTS) {
            plk_copy(y, y1, n2);
            for (m = 0; m < pl->n_mesh; ++m) plk_mesh_start(pl, w, m, y, node);
            break;
        }
        any_neg = 0;
        for (m = 0; m < pl->n_mesh; ++m)
            if (!plk_guards_hold(pl, w, m, y1, 1, lk)) {
                any_neg = 1;
                break;
            }
        if (!any_neg) {
            plk_copy(y, y1, n2);
            break;
        }
        plk_rhs(pl, w, y1, f1, t_in, t_out, lk);
        best_m = -1;
        for (m = 0; m < pl->n_mesh; ++m) {
            const gk_model *pm = pl->mesh[m].pair;
            const gk_mode *md = &w->md[m];
            double l1[4], l0[4], d0[4], d1[4];
            int gi, have = 0, n_guard = 2 + 3 * pm->P;
            plk_mesh_local(&pl->mesh[m], y1, 1.0, l1);
            for (gi = 0; gi < n_guard; ++gi) {
                double g = seg ? guard_seg(pm, &w->tq[m], md, gi, l1, 0.0, 0.0) : guard_at(pm, &w->tq[m], md, gi, l1);
                double s;
                if (!(g < 0.0)) continue;
                if (!have) {   /* the mesh's Hermite data: its local view of y, f0, y1, f1 */
                    plk_mesh_local(&pl->mesh[m], y, 1.0, l0);
                    plk_mesh_local(&pl->mesh[m], f0, 0.0, d0);
                    plk_mesh_local(&pl->mesh[m], f1, 0.0, d1);
                    have = 1;
                }
                s = guard_root(pm, &w->tq[m], md, gi, g, l0, d0, l1, d1, rem, seg, 0.0, 0.0);
                if (s < best) {
                    best = s;
                    best_m = m;
                    best_gi = gi;
                }
            }
        }
        if (best_m < 0) {
            plk_copy(y, y1, n2);
            break;
        }
        if (best >= 1.0) {
            plk_copy(y, y1, n2);
            rem = 0.0;
        } else if (best > 0.0) {
            double tau = best * rem;
            plk_rk4(pl, w, y, f0, tau, yt, t_in, t_out, lk);
            plk_copy(y, yt, n2);
            rem = rem - tau;
        }
        nev += 1;
        if (best_gi < 2) {
            plk_mesh_cross(pl, w, best_m, y, best_gi == 1, node);
        } else {
            const gk_model *pm = pl->mesh[best_m].pair;
            gk_mode *md = &w->md[best_m];
            int j = (best_gi - 2) / 3;
            double loc[4], kv = 0.0, ev = 0.0, es = 0.0, bv = 0.0;
            plk_mesh_local(&pl->mesh[best_m], y, 1.0, loc);
            if (md->reg[j] == 0 && pm->damping_model == GK_DAMPING_ELASTOBACKLASH)
                held_tables(pm, &w->tq[best_m], md, j, loc[0], &kv, &ev, &es, &bv, seg);
            switch_pair(pm, md, j, (best_gi - 2) - 3 * j, kv, ev, es, bv, loc);
        }
        if (!(rem > 0.0)) break;
    }
    return nev;
}

/* -------------------------------------------------------------- public API */
static int plk_check_y(const pl_model *pl, const double *y)
{
    int i;
    for (i = 0; i < 2 * pl->n; ++i)
        if (!isfinite(y[i])) return 0;
    return 1;
}

int pl_derivatives(const pl_model *pl, pl_work *w, double t_s, const double *y, double T_motor, double T_load,
                   double *dy)
{
    double t_in, t_out;
    (void)t_s;
    if (pl == NULL || w == NULL || y == NULL || dy == NULL) return GK_ERR_MODEL;
    if (!isfinite(T_motor) || !isfinite(T_load) || !plk_check_y(pl, y)) return GK_ERR_INPUT;
    t_in = pl->motor_input ? T_motor : 0.0;
    t_out = pl->load_input ? T_load : 0.0;
    plk_select_rows(pl, w, t_in, t_out);
    plk_rhs(pl, w, y, dy, t_in, t_out, 0);
    return GK_OK;
}

/* the mesh blocks of the outputs from o: x, v, force, stiffness in contact, pair forces, load sharings
 * (kernels._write_row with the pair's output rule); me: the Model Exchange modes held, else the plain
 * lookup; the mesh forces into F */
static int plk_mesh_outputs(const pl_model *pl, pl_work *w, const pl_me *me, const double *y, double *out,
                            double *F)
{
    int m, j, o = 2 * pl->n;
    for (m = 0; m < pl->n_mesh; ++m) {
        const gk_model *pm = pl->mesh[m].pair;
        double loc[4], km;
        int P = pm->P;
        plk_mesh_local(&pl->mesh[m], y, 1.0, loc);
        if (me != NULL) {
            F[m] = me_force(pm, &me->mesh[m], &w->tq[m], loc, out + o + PL_OUT_PAIR_FORCE, &km);
        } else {
            gk_ph c = GK_PH_NONE;
            F[m] = mesh_force(pm, &w->tq[m], &c, loc[0], loc[1], loc[2], loc[3], out + o + PL_OUT_PAIR_FORCE, &km);
        }
        out[o + PL_OUT_DTE] = loc[2];
        out[o + PL_OUT_DTE_RATE] = loc[3];
        out[o + PL_OUT_MESH_FORCE] = F[m];
        out[o + PL_OUT_MESH_STIFFNESS] = km;
        for (j = 0; j < P; ++j)
            out[o + PL_OUT_PAIR_FORCE + P + j] = (F[m] != 0.0) ? out[o + PL_OUT_PAIR_FORCE + j] / F[m] : 0.0;
        o += PL_OUT_PAIR_FORCE + 2 * P;
    }
    return o;
}

/* every output at y: the DOFs, the meshes (plk_mesh_outputs), the springs, the load-sharing factors
 * L_j = N F_j / sum_k F_k of every group (Kahraman 1994; NaN when the sum is 0) */
static void plk_outputs(const pl_model *pl, pl_work *w, const pl_me *me, const double *y, double *out)
{
    double F[PL_MAX_MESHES];
    int i, s, j, o;
    for (i = 0; i < pl->n; ++i) {
        out[2 * i] = pl->g[i] * y[0] + plk_u(y, 0, i);
        out[2 * i + 1] = pl->g[i] * y[1] + plk_u(y, 1, i);
    }
    o = plk_mesh_outputs(pl, w, me, y, out, F);
    for (s = 0; s < pl->n_spring; ++s) {
        const pl_spring *sp = &pl->spring[s];
        double v = 0.0, vd = 0.0;
        for (j = 0; j < sp->count; ++j) {
            v += sp->coef[j] * plk_u(y, 0, sp->dof[j]);
            vd += sp->coef[j] * plk_u(y, 1, sp->dof[j]);
        }
        out[o + s] = sp->k * v + sp->c * vd;
    }
    o += pl->n_spring;
    for (s = 0; s < pl->n_group; ++s) {
        const pl_group *gr = &pl->group[s];
        double tot = F[gr->mesh[0]];
        for (j = 1; j < gr->count; ++j) tot += F[gr->mesh[j]];
        for (j = 0; j < gr->count; ++j)
            out[o + j] = (tot != 0.0) ? (double)gr->count * F[gr->mesh[j]] / tot : NAN;
        o += gr->count;
    }
}

int pl_outputs(const pl_model *pl, pl_work *w, const pl_state *s, double T_motor, double T_load, double *out)
{
    if (pl == NULL || w == NULL || s == NULL || out == NULL) return GK_ERR_MODEL;
    if (!isfinite(T_motor) || !isfinite(T_load)) return GK_ERR_INPUT;
    plk_select_rows(pl, w, pl->motor_input ? T_motor : 0.0, pl->load_input ? T_load : 0.0);
    plk_outputs(pl, w, NULL, s->y, out);
    return GK_OK;
}

int pl_do_step(const pl_model *pl, pl_work *w, pl_state *s, double T_motor, double T_load, double H_s,
               double h_max_s, double *out)
{
    double n, h, t_in, t_out;
    long i, nsub;
    int m, n2, q;
    if (pl == NULL || w == NULL || s == NULL) return GK_ERR_MODEL;
    if (!isfinite(T_motor) || !isfinite(T_load)) return GK_ERR_INPUT;
    if (!plk_check_y(pl, s->y)) return GK_ERR_INPUT;
    n = gk_substeps(H_s, h_max_s);
    if (n == 0.0) return GK_ERR_STEP;
    nsub = (long)n;
    h = H_s / n;
    n2 = 2 * pl->n;
    t_in = pl->motor_input ? T_motor : 0.0;
    t_out = pl->load_input ? T_load : 0.0;
    plk_select_rows(pl, w, t_in, t_out);
    plk_copy(w->y, s->y, n2);
    w->events = 0;
    if (pl->integrator == PL_INTEGRATOR_RK4_SEG) {
        for (m = 0; m < pl->n_mesh; ++m) plk_mesh_start(pl, w, m, w->y, 1);
        for (i = 0; i < nsub; ++i) w->events += plk_substep(pl, w, h, 1, 3, t_in, t_out);
    } else if (pl->integrator == PL_INTEGRATOR_RK4_KINK || pl->integrator == PL_INTEGRATOR_RK4_NODE) {
        int node = pl->integrator == PL_INTEGRATOR_RK4_NODE;
        for (m = 0; m < pl->n_mesh; ++m) plk_mesh_start(pl, w, m, w->y, node);
        for (i = 0; i < nsub; ++i) w->events += plk_substep(pl, w, h, node, 1, t_in, t_out);
    } else {
        for (i = 0; i < nsub; ++i) {
            plk_rhs(pl, w, w->y, w->f0, t_in, t_out, 0);
            plk_rk4(pl, w, w->y, w->f0, h, w->yt, t_in, t_out, 0);
            plk_copy(w->y, w->yt, n2);
        }
    }
    for (q = 0; q < n2; ++q)
        if (!isfinite(w->y[q])) return GK_ERR_NONFINITE;
    plk_copy(s->y, w->y, n2);
    if (out != NULL) plk_outputs(pl, w, NULL, s->y, out);
    return GK_OK;
}

/* ---------------------------------------------------------- Model Exchange
 * docs/model.md "Model Exchange", for every mesh (as gb_kernel.c's gb_me_*): its mode (gk_me) held
 * between the host's events and decided anew from the state at each (gk_pair.h's me_* pieces on the
 * mesh's local state), the right-hand side plk_rhs with the modes held, the indicators of every mesh
 * one after another. */
static int plk_me_check(const pl_model *pl, const pl_work *w, const pl_me *me, const double *y)
{
    int m;
    if (pl == NULL || w == NULL || me == NULL || y == NULL) return GK_ERR_MODEL;
    for (m = 0; m < pl->n_mesh; ++m)
        if (pl->mesh[m].pair->P > GK_KINK_MAX_SLOTS) return GK_ERR_PARAM;
    if (!plk_check_y(pl, y)) return GK_ERR_NONFINITE;
    return GK_OK;
}

/* the torque rows and the input torques of T_motor, T_load (as pl_derivatives) */
static void plk_me_inputs(const pl_model *pl, pl_work *w, const pl_me *me, double T_motor, double T_load,
                          double *t_in, double *t_out)
{
    *t_in = pl->motor_input ? T_motor : 0.0;
    *t_out = pl->load_input ? T_load : 0.0;
    plk_select_rows(pl, w, *t_in, *t_out);
    w->me = me;
}

int pl_me_n_indicators(const pl_model *pl, int node_events)
{
    int m, n = 0;
    if (pl == NULL) return 0;
    for (m = 0; m < pl->n_mesh; ++m) n += me_n_indicators(pl->mesh[m].pair, node_events);
    return n;
}

static void plk_me_decide(const pl_model *pl, pl_work *w, pl_me *me, const double *y)
{
    int m;
    for (m = 0; m < pl->n_mesh; ++m) {
        double loc[4];
        plk_mesh_local(&pl->mesh[m], y, 1.0, loc);
        me_decide(pl->mesh[m].pair, &me->mesh[m], &w->tq[m], loc);
    }
}

/* The modes anew at an event: decided at the state, then again a moment ahead, y + delta f(y) with f
 * in the modes decided first and delta the smallest of the meshes' me_ahead_time (as gb_me_update). */
int pl_me_update(const pl_model *pl, pl_work *w, pl_me *me, const double *y, double T_motor, double T_load,
                 int *changed)
{
    double t_in, t_out, delta = HUGE_VAL, *dy, *ahead;
    int i, m, finite = 1, diff = 0, n2, st = plk_me_check(pl, w, me, y);
    pl_me old;
    if (st != GK_OK) return st;
    if (!isfinite(T_motor) || !isfinite(T_load)) return GK_ERR_INPUT;
    dy = w->kk;
    ahead = w->tmp;
    n2 = 2 * pl->n;
    old = *me;
    plk_me_inputs(pl, w, me, T_motor, T_load, &t_in, &t_out);
    plk_me_decide(pl, w, me, y);
    plk_rhs(pl, w, y, dy, t_in, t_out, 2);
    for (m = 0; m < pl->n_mesh; ++m) {
        double d = me_ahead_time(pl->mesh[m].pair);
        if (d < delta) delta = d;
    }
    for (i = 0; i < n2; ++i) {
        ahead[i] = y[i] + delta * dy[i];
        finite &= isfinite(ahead[i]) != 0;
    }
    if (finite) plk_me_decide(pl, w, me, ahead);
    for (m = 0; m < pl->n_mesh; ++m) diff |= me_differs(pl->mesh[m].pair, &me->mesh[m], &old.mesh[m]);
    if (changed != NULL) *changed = diff;
    return GK_OK;
}

int pl_me_init(const pl_model *pl, pl_work *w, pl_me *me, const double *y, double T_motor, double T_load,
               int node_events)
{
    int m;
    if (pl == NULL || me == NULL) return GK_ERR_MODEL;
    for (m = 0; m < PL_MAX_MESHES; ++m)
        if (!me_clear(&me->mesh[m], node_events)) return GK_ERR_PARAM;
    return pl_me_update(pl, w, me, y, T_motor, T_load, NULL);
}

int pl_me_derivatives(const pl_model *pl, pl_work *w, const pl_me *me, const double *y, double T_motor,
                      double T_load, double *dy)
{
    double t_in, t_out;
    int st = plk_me_check(pl, w, me, y);
    if (st != GK_OK) return st;
    if (dy == NULL) return GK_ERR_MODEL;
    if (!isfinite(T_motor) || !isfinite(T_load)) return GK_ERR_INPUT;
    plk_me_inputs(pl, w, me, T_motor, T_load, &t_in, &t_out);
    plk_rhs(pl, w, y, dy, t_in, t_out, 2);
    return GK_OK;
}

int pl_me_indicators(const pl_model *pl, pl_work *w, const pl_me *me, const double *y, double T_motor,
                     double T_load, double *z)
{
    double t_in, t_out, all[4 * GK_KINK_MAX_SLOTS + 2];
    int m, n = 0, st = plk_me_check(pl, w, me, y);
    if (st != GK_OK) return st;
    if (z == NULL) return GK_ERR_MODEL;
    if (!isfinite(T_motor) || !isfinite(T_load)) return GK_ERR_INPUT;
    plk_me_inputs(pl, w, me, T_motor, T_load, &t_in, &t_out);
    for (m = 0; m < pl->n_mesh; ++m) {
        const gk_model *pm = pl->mesh[m].pair;
        double loc[4];
        plk_mesh_local(&pl->mesh[m], y, 1.0, loc);
        me_all_indicators(pm, &me->mesh[m], &w->tq[m], loc, all);
        n += me_pack_indicators(pm, &me->mesh[m], all, z + n);
    }
    return GK_OK;
}

int pl_me_outputs(const pl_model *pl, pl_work *w, const pl_me *me, const double *y, double T_motor,
                  double T_load, double *out)
{
    double t_in, t_out;
    int st = plk_me_check(pl, w, me, y);
    if (st != GK_OK) return st;
    if (out == NULL) return GK_ERR_MODEL;
    if (!isfinite(T_motor) || !isfinite(T_load)) return GK_ERR_INPUT;
    plk_me_inputs(pl, w, me, T_motor, T_load, &t_in, &t_out);
    plk_outputs(pl, w, me, y, out);
    return GK_OK;
}
