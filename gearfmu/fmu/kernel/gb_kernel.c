/*
 * gb_kernel.c -- the gearbox kernel (gbkernel.h; docs/gearbox.md): bodies, shafts and meshes,
 * the right-hand side, classical RK4 and the event-aware substep of rk4_kink / rk4_node over
 * all meshes, the quasi-static initial state and the outputs.
 *
 * Every mesh is looked up, loaded and event-located by the pair's own pieces (gk_pair.h) on its
 * own gk_model and gk_mode, mapped to its local state (theta_p, omega_p, x, v); the loops over
 * bodies, shafts and meshes are those of the numba gearbox solver (gearfmu/gearbox/kernels.py:
 * _rhs, _rk4, _gb_substep, _mesh_start, _mesh_cross, _write_row), operation by operation, so
 * that the two agree bit for bit (tests/fmu_hosts/test_gearbox_fmu.py).  Compiled with the pair kernel's
 * flags (no fused multiply-add, no fast-math).
 *
 * No globals, no allocation, no abort.
 */
#include "gbkernel.h"
#include "gk_pair.h"

struct gb_work {
    gk_tq tq[GB_MAX_MESHES];        /* torque rows of the step */
    gk_ph ph[GB_MAX_MESHES];        /* rk4: the cell carried from one evaluation to the next */
    gk_mode md[GB_MAX_MESHES];      /* rk4_kink, rk4_node: the mode held */
    double tau[GB_MAX_BODIES];      /* torques on the bodies */
    double u[GB_MAX_BODIES], du[GB_MAX_BODIES];   /* every body's deviation and its rate (0 for body 0) */
    double y[GB_MAX_STATE], f0[GB_MAX_STATE], y1[GB_MAX_STATE], f1[GB_MAX_STATE], yt[GB_MAX_STATE];
    double tmp[GB_MAX_STATE], acc[GB_MAX_STATE], kk[GB_MAX_STATE];
    long events;
    const gb_me *me;                /* Model Exchange: the modes held (gb_rhs with locked 2) */
};

int gb_abi_version(void) { return GB_ABI_VERSION; }
int gb_sizeof_model(void) { return (int)sizeof(gb_model); }
int gb_sizeof_work(void) { return (int)sizeof(gb_work); }
long gb_events(const gb_work *w) { return w != NULL ? w->events : 0; }
int gb_sizeof_me(void) { return (int)sizeof(gb_me); }

/* ------------------------------------------------------------------ setup */
int gb_init(gb_model *gb, int n, const double *inv_I, const double *g, int load_body, int motor_input,
            int load_input)
{
    int i;
    if (gb == NULL || inv_I == NULL || g == NULL || n < 2 || n > GB_MAX_BODIES) return GK_ERR_MODEL;
    if (load_body < 1 || load_body >= n || g[0] != 1.0) return GK_ERR_MODEL;
    for (i = 0; i < n; ++i)
        if (!gki_finite_pos(inv_I[i]) || !gki_finite_pos(g[i])) return GK_ERR_MODEL;
    gb->n = n;
    gb->n_mesh = gb->n_shaft = gb->n_edge = 0;
    gb->load_body = load_body;
    gb->motor_input = motor_input != 0;
    gb->load_input = load_input != 0;
    gb->integrator = GB_INTEGRATOR_RK4;
    for (i = 0; i < n; ++i) {
        gb->inv_I[i] = inv_I[i];
        gb->g[i] = g[i];
    }
    return GK_OK;
}

int gb_add_mesh(gb_model *gb, gk_model *pair, int p, int q, int on_path)
{
    gb_mesh *me;
    if (gb == NULL || pair == NULL || gb->n_mesh >= GB_MAX_MESHES) return GK_ERR_MODEL;
    if (p < 0 || p >= gb->n || q < 0 || q >= gb->n || p == q) return GK_ERR_MODEL;
    me = &gb->mesh[gb->n_mesh++];
    me->pair = pair;
    me->p = p;
    me->q = q;
    me->g_p = gb->g[p];
    me->on_path = on_path != 0;
    return GK_OK;
}

int gb_add_shaft(gb_model *gb, int a, int b, double k_Nm_per_rad, double c_Nms_per_rad, int on_path)
{
    int s;
    if (gb == NULL || gb->n_shaft >= GB_MAX_SHAFTS) return GK_ERR_MODEL;
    if (a < 0 || a >= gb->n || b < 0 || b >= gb->n || a == b) return GK_ERR_MODEL;
    if (!gki_finite_pos(k_Nm_per_rad) || !isfinite(c_Nms_per_rad) || c_Nms_per_rad < 0.0) return GK_ERR_MODEL;
    s = gb->n_shaft++;
    gb->shaft_a[s] = a;
    gb->shaft_b[s] = b;
    gb->shaft_k[s] = k_Nm_per_rad;
    gb->shaft_c[s] = c_Nms_per_rad;
    gb->shaft_on_path[s] = on_path != 0;
    return GK_OK;
}

int gb_add_edge(gb_model *gb, int kind, int index, int up, int down)
{
    int e;
    if (gb == NULL || gb->n_edge >= GB_MAX_MESHES + GB_MAX_SHAFTS) return GK_ERR_MODEL;
    if (kind != 0 && kind != 1) return GK_ERR_MODEL;
    if (index < 0 || up < 0 || up >= gb->n || down < 0 || down >= gb->n) return GK_ERR_MODEL;
    e = gb->n_edge++;
    gb->edge_kind[e] = kind;
    gb->edge_index[e] = index;
    gb->edge_up[e] = up;
    gb->edge_down[e] = down;
    return GK_OK;
}

int gb_set_integrator(gb_model *gb, int integrator)
{
    int m, st;
    if (gb == NULL) return GK_ERR_MODEL;
    if (integrator != GB_INTEGRATOR_RK4 && integrator != GB_INTEGRATOR_RK4_KINK && integrator != GB_INTEGRATOR_RK4_NODE
        && integrator != GB_INTEGRATOR_RK4_SEG)
        return GK_ERR_PARAM;
    for (m = 0; m < gb->n_mesh; ++m) {
        st = multimesh_integrator(gb->mesh[m].pair, integrator);
        if (st != GK_OK) return st;
    }
    gb->integrator = integrator;
    return GK_OK;
}

double gb_reference_torque(const gb_model *gb, double T_motor, double T_load)
{
    if (gb->motor_input) return T_motor;
    return T_load * gb->g[gb->load_body];
}

double gb_stage_torque(const gb_model *gb, int m, double T_ref)
{
    return gb->mesh[m].on_path ? T_ref / gb->mesh[m].g_p : 0.0;
}

int gb_mesh_offset(const gb_model *gb, int m)
{
    int k, o = 2 * gb->n;
    for (k = 0; k < m; ++k) o += GB_OUT_PAIR_FORCE + 2 * gb->mesh[k].pair->P;
    return o;
}

int gb_shaft_offset(const gb_model *gb) { return gb_mesh_offset(gb, gb->n_mesh); }
int gb_n_outputs(const gb_model *gb) { return gb_shaft_offset(gb) + gb->n_shaft; }

/* -------------------------------------------------------- the local view
 * u_i (or du_i with o = 1) of body i from the vector v: 0 for body 0 (kernels._u) */
GK_INLINE double body_u(const double *v, int o, int i)
{
    if (i == 0) return 0.0;
    return v[o + 2 * i];
}

/* mesh m's own (theta_p, omega_p, x, v) of the vector v (a state or its derivative: the map is
 * linear; kernels._local): theta_p = g_p psi + u_p, omega_p = g_p omega + du_p,
 * x = Rb_p u_p - Rb_q u_q, v = Rb_p du_p - Rb_q du_q */
GK_INLINE void mesh_local(const gb_mesh *me, const double *v, double *loc)
{
    const gk_model *pm = me->pair;
    double up = body_u(v, 0, me->p), dup = body_u(v, 1, me->p);
    loc[0] = me->g_p * v[0] + up;
    loc[1] = me->g_p * v[1] + dup;
    loc[2] = pm->Rb1_m * up - pm->Rb2_m * body_u(v, 0, me->q);
    loc[3] = pm->Rb1_m * dup - pm->Rb2_m * body_u(v, 1, me->q);
}

/* the torque rows of every mesh at the inputs (the step's rows: kernels.run it_rows, wt_rows) */
static void select_rows(const gb_model *gb, gb_work *w, double T_motor, double T_load)
{
    int m;
    double t_ref = gb_reference_torque(gb, T_motor, T_load);
    for (m = 0; m < gb->n_mesh; ++m) {
        const gk_ph none = GK_PH_NONE;
        w->tq[m] = torque_bracket(gb->mesh[m].pair, gb_stage_torque(gb, m, t_ref));
        w->ph[m] = none;
    }
}

/* --------------------------------------------------------- right-hand side
 * dy at y (kernels._rhs): torques of the inputs, the shafts and the meshes on every body,
 * a_i = tau_i/I_i, psi'' = a_0, u_i'' = a_i - g_i a_0; `locked`: every mesh with its held mode
 * (1: the event integrators' gk_mode; 2: Model Exchange's gk_me, w->me; 3: rk4_seg, the gk_mode held
 * and the tables read in the cell of the evaluation's angle clamped to the held segment,
 * kernels._mesh_seg), else the plain lookup with the carried cell (rk4) */
GK_INLINE void gb_rhs_at(const gb_model *gb, gb_work *w, const double *y, double *dy, double t_in, double t_out,
                         const int locked)
{
    int n = gb->n, i, s, m;
    double *tau = w->tau, *u = w->u, *du = w->du, a0;
    u[0] = 0.0;   /* body 0 has no deviation (kernels._u) */
    du[0] = 0.0;
    tau[0] = 0.0;
    for (i = 1; i < n; ++i) {
        u[i] = y[2 * i];
        du[i] = y[2 * i + 1];
        tau[i] = 0.0;
    }
    tau[0] += t_in;
    tau[gb->load_body] -= t_out;
    for (s = 0; s < gb->n_shaft; ++s) {
        int a = gb->shaft_a[s], b = gb->shaft_b[s];
        double ts = gb->shaft_k[s] * (u[a] - u[b]) + gb->shaft_c[s] * (du[a] - du[b]);
        tau[a] -= ts;
        tau[b] += ts;
    }
    for (m = 0; m < gb->n_mesh; ++m) {
        const gb_mesh *me = &gb->mesh[m];
        const gk_model *pm = me->pair;
        int p = me->p, q = me->q;
        double rb1 = pm->Rb1_m, rb2 = pm->Rb2_m, fm;
        /* the mesh's local state (mesh_local) */
        double th = me->g_p * y[0] + u[p], om = me->g_p * y[1] + du[p];
        double x = rb1 * u[p] - rb2 * u[q], v = rb1 * du[p] - rb2 * du[q];
        if (locked == 3) {
            const gk_mode *md = &w->md[m];
            gk_ph c;
            int j;
            double cc = seg_cell(pm, md, th, &c);
            fm = 0.0;
            for (j = 0; j < pm->P; ++j) {
                double kv, ev, es, bv;
                slot_tables(pm, &w->tq[m], &c, j, seg_sel(pm, md, j, cc, &c), &kv, &ev, &es, &bv);
                fm += pair_force_locked(kv, ev, es, bv, x, v, om, pm->c_Ns_per_m, pm->damping_model, md->reg[j],
                                        md->sub[j], md->kpos[j]);
            }
        } else if (locked == 1) {   /* kernels._mesh_locked: the force loop of deriv_locked */
            const gk_mode *md = &w->md[m];
            int j;
            fm = 0.0;
            for (j = 0; j < pm->P; ++j) {
                double kv, ev, es, bv;
                locked_tables(pm, &w->tq[m], md, th, j, &kv, &ev, &es, &bv);
                fm += pair_force_locked(kv, ev, es, bv, x, v, om, pm->c_Ns_per_m, pm->damping_model, md->reg[j],
                                        md->sub[j], md->kpos[j]);
            }
        } else if (locked == 2) {
            double loc[4];
            loc[0] = th;
            loc[1] = om;
            loc[2] = x;
            loc[3] = v;
            fm = me_force(pm, &w->me->mesh[m], &w->tq[m], loc, NULL, NULL);
        } else {
            fm = mesh_force(pm, &w->tq[m], &w->ph[m], th, om, x, v, NULL, NULL);
        }
        tau[p] -= rb1 * fm;
        tau[q] += rb2 * fm;
    }
    a0 = tau[0] * gb->inv_I[0];
    dy[0] = y[1];
    dy[1] = a0;
    for (i = 1; i < n; ++i) {
        dy[2 * i] = y[2 * i + 1];
        dy[2 * i + 1] = tau[i] * gb->inv_I[i] - gb->g[i] * a0;
    }
}

/* gb_rhs_at with each `locked` compiled once: one call to its copy (the event substep and RK4 call it
 * from many places, and a copy inlined at each would not fit the instruction cache) */
static void gb_rhs(const gb_model *gb, gb_work *w, const double *y, double *dy, double t_in, double t_out,
                   int locked)
{
    switch (locked) {
    case 3: gb_rhs_at(gb, w, y, dy, t_in, t_out, 3); break;
    case 2: gb_rhs_at(gb, w, y, dy, t_in, t_out, 2); break;
    case 1: gb_rhs_at(gb, w, y, dy, t_in, t_out, 1); break;
    default: gb_rhs_at(gb, w, y, dy, t_in, t_out, 0); break;
    }
}

/* one classical RK4 step of length h from y with its first stage f0 into out (kernels._rk4): stages at
 * y + (h/2) k1, y + (h/2) k2, y + h k3, acc = ((k1 + 2 k2) + 2 k3) + k4, y + (h/6) acc */
static void gb_rk4(const gb_model *gb, gb_work *w, const double *y, const double *f0, double h, double *out,
                   double t_in, double t_out, int locked)
{
    int i, n2 = 2 * gb->n;
    double h2 = h / 2.0, h6, *tmp = w->tmp, *acc = w->acc, *kk = w->kk;
    for (i = 0; i < n2; ++i) tmp[i] = y[i] + h2 * f0[i];
    gb_rhs(gb, w, tmp, kk, t_in, t_out, locked);
    for (i = 0; i < n2; ++i) {
        acc[i] = f0[i] + 2.0 * kk[i];
        tmp[i] = y[i] + h2 * kk[i];
    }
    gb_rhs(gb, w, tmp, kk, t_in, t_out, locked);
    for (i = 0; i < n2; ++i) {
        acc[i] = acc[i] + 2.0 * kk[i];
        tmp[i] = y[i] + h * kk[i];
    }
    gb_rhs(gb, w, tmp, kk, t_in, t_out, locked);
    h6 = h / 6.0;
    for (i = 0; i < n2; ++i) out[i] = y[i] + h6 * (acc[i] + kk[i]);
}

/* ------------------------------------------------- the modes of the meshes */
/* mesh m's mode from the state y (kernels._mesh_start; the pair's mode_from_state on its local state) */
static void mesh_start(const gb_model *gb, gb_work *w, int m, const double *y, int node)
{
    double loc[4];
    mesh_local(&gb->mesh[m], y, loc);
    mode_from_state(gb->mesh[m].pair, &w->tq[m], &w->md[m], loc, node);
}

/* move mesh m's held segment across its end (up) or start, then its zone sides and sub-modes at y
 * (kernels._mesh_cross) */
static void mesh_cross(const gb_model *gb, gb_work *w, int m, const double *y, int up, int node)
{
    const gk_model *pm = gb->mesh[m].pair;
    gk_mode *md = &w->md[m];
    double loc[4];
    gki_seg_cross(pm, md, up, node);
    gki_cell_nodes(md, pm->n_phi);
    gki_zone_sel(pm, md);
    mesh_local(&gb->mesh[m], y, loc);
    mode_sync(pm, &w->tq[m], md, loc, 0);
}

/* 1 when no pair guard of mesh m is negative at v (with `segment`, neither of its segment guards), the
 * tables read as gb_rhs with `lk` (kernels._mesh_guards_hold, _pairs_hold_seg) */
static int mesh_guards_hold(const gb_model *gb, gb_work *w, int m, const double *v, int segment, int lk)
{
    const gk_model *pm = gb->mesh[m].pair;
    const gk_mode *md = &w->md[m];
    double loc[4];
    mesh_local(&gb->mesh[m], v, loc);
    if (segment && (loc[0] - md->lo * pm->dphi_rad < 0.0 || md->hi * pm->dphi_rad - loc[0] < 0.0)) return 0;
    if (lk == 3) return pairs_hold_seg(pm, &w->tq[m], md, loc);
    return pairs_hold(pm, &w->tq[m], md, loc);
}

static void copy_state(double *dst, const double *src, int n2)
{
    int i;
    for (i = 0; i < n2; ++i) dst[i] = src[i];
}

/* ---------------------------------------------------------- event substep
 * One substep of length h of rk4_kink (node 0), rk4_node (node 1) or rk4_seg (node 1, lk 3: the tables
 * read in the cell of each evaluation, the guards and root searches too) for the whole gearbox
 * (docs/gearbox.md "Integrators"; kernels._gb_substep): the pair's substep with every mesh holding
 * its own cell, segment and pair modes.  A step ends at the earliest predicted node crossing of
 * any mesh (rk4_node) when no guard of any mesh is negative there; else the trial step's guards
 * of every mesh are located on the step's Hermite interpolant mapped to each mesh's local state,
 * and the earliest event wins (ties: lower mesh, then lower guard).  Returns the events. */
static long gb_substep(const gb_model *gb, gb_work *w, double h, int node, const int lk, double t_in,
                       double t_out)
{
    double *y = w->y, *f0 = w->f0, *y1 = w->y1, *f1 = w->f1, *yt = w->yt;
    double rem = h;
    long nev = 0;
    int n2 = 2 * gb->n, m, seg = lk == 3;
    for (;;) {
        double best = 2.0;
        int best_m = -1, best_gi = -1, any_neg;
        if (seg) {   /* the segments are fixed until the next pass */
            for (m = 0; m < gb->n_mesh; ++m) {
                gk_mode *md = &w->md[m];
                md->cl = floor(md->lo);
                md->ch = ceil(md->hi) - 1.0;
            }
        }
        if (node) {   /* the held cell follows theta_p inside the held segment */
            for (m = 0; m < gb->n_mesh; ++m) {
                const gk_model *pm = gb->mesh[m].pair;
                gk_mode *md = &w->md[m];
                double loc[4], cn;
                mesh_local(&gb->mesh[m], y, loc);
                cn = floor(loc[0] * pm->inv_dphi);
                if (cn + 1.0 > md->lo && cn < md->hi && cn != md->nd) {
                    md->nd = cn;
                    gki_cell_nodes(md, pm->n_phi);
                    gki_zone_sel(pm, md);
                }
            }
        }
        gb_rhs(gb, w, y, f0, t_in, t_out, lk);
        if (node && nev < GK_KINK_MAX_EVENTS) {   /* the earliest segment end ahead: one step to it */
            double best_tau = -1.0;
            best_m = -1;
            for (m = 0; m < gb->n_mesh; ++m) {
                const gk_model *pm = gb->mesh[m].pair;
                const gk_mode *md = &w->md[m];
                double loc[4], dl[4], tau;
                mesh_local(&gb->mesh[m], y, loc);
                mesh_local(&gb->mesh[m], f0, dl);
                tau = node_time(loc[0], loc[1], dl[1], rem, md->lo, md->hi, pm->dphi_rad);
                if (tau > 0.0 && (best_m < 0 || tau < best_tau)) {
                    best_tau = tau;
                    best_m = m;
                }
            }
            if (best_m >= 0) {
                int ok = 1;
                gb_rk4(gb, w, y, f0, best_tau, yt, t_in, t_out, lk);
                for (m = 0; m < gb->n_mesh; ++m)
                    if (!mesh_guards_hold(gb, w, m, yt, m != best_m, lk)) {
                        ok = 0;
                        break;
                    }
                if (ok) {
                    double loc[4];
                    int up;
                    mesh_local(&gb->mesh[best_m], y, loc);
                    up = loc[1] > 0.0;
                    copy_state(y, yt, n2);
                    rem = rem - best_tau;
                    nev += 1;
                    mesh_cross(gb, w, best_m, y, up, 1);
                    if (!(rem > 0.0)) break;
                    continue;
                }
            }
        }
        gb_rk4(gb, w, y, f0, rem, y1, t_in, t_out, lk);
        if (nev >= GK_KINK_MAX_EVENTS) {
            copy_state(y, y1, n2);
            for (m = 0; m < gb->n_mesh; ++m) mesh_start(gb, w, m, y, node);
            break;
        }
        any_neg = 0;
        for (m = 0; m < gb->n_mesh; ++m)
            if (!mesh_guards_hold(gb, w, m, y1, 1, lk)) {
                any_neg = 1;
                break;
            }
        if (!any_neg) {
            copy_state(y, y1, n2);
            break;
        }
        gb_rhs(gb, w, y1, f1, t_in, t_out, lk);
        best_m = -1;
        for (m = 0; m < gb->n_mesh; ++m) {
            const gk_model *pm = gb->mesh[m].pair;
            const gk_mode *md = &w->md[m];
            double l1[4], l0[4], d0[4], d1[4];
            int gi, have = 0, n_guard = 2 + 3 * pm->P;
            mesh_local(&gb->mesh[m], y1, l1);
            for (gi = 0; gi < n_guard; ++gi) {
                double g = seg ? guard_seg(pm, &w->tq[m], md, gi, l1, 0.0, 0.0) : guard_at(pm, &w->tq[m], md, gi, l1);
                double s;
                if (!(g < 0.0)) continue;
                if (!have) {   /* the mesh's Hermite data: its local view of y, f0, y1, f1 */
                    mesh_local(&gb->mesh[m], y, l0);
                    mesh_local(&gb->mesh[m], f0, d0);
                    mesh_local(&gb->mesh[m], f1, d1);
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
            copy_state(y, y1, n2);
            break;
        }
        if (best >= 1.0) {
            copy_state(y, y1, n2);
            rem = 0.0;
        } else if (best > 0.0) {
            double tau = best * rem;
            gb_rk4(gb, w, y, f0, tau, yt, t_in, t_out, lk);
            copy_state(y, yt, n2);
            rem = rem - tau;
        }
        nev += 1;
        if (best_gi < 2) {
            mesh_cross(gb, w, best_m, y, best_gi == 1, node);
        } else {
            const gk_model *pm = gb->mesh[best_m].pair;
            gk_mode *md = &w->md[best_m];
            int j = (best_gi - 2) / 3;
            double loc[4], kv = 0.0, ev = 0.0, es = 0.0, bv = 0.0;
            mesh_local(&gb->mesh[best_m], y, loc);
            if (md->reg[j] == 0 && pm->damping_model == GK_DAMPING_ELASTOBACKLASH)
                held_tables(pm, &w->tq[best_m], md, j, loc[0], &kv, &ev, &es, &bv, seg);
            switch_pair(pm, md, j, (best_gi - 2) - 3 * j, kv, ev, es, bv, loc);
        }
        if (!(rem > 0.0)) break;
    }
    return nev;
}

/* -------------------------------------------------------------- public API */
int gb_initialize(const gb_model *gb, gb_state *s, double psi0, double omega0, double T_ref, int *bad_mesh)
{
    double u[GB_MAX_BODIES];
    int i, e;
    if (bad_mesh != NULL) *bad_mesh = -1;
    if (gb == NULL || s == NULL) return GK_ERR_MODEL;
    if (!isfinite(psi0) || !isfinite(omega0) || !isfinite(T_ref)) return GK_ERR_INPUT;
    for (i = 0; i < gb->n; ++i) u[i] = 0.0;
    /* walked from body 0 along the tree (GearboxModel.static_state): a shaft twisted by its
     * static torque over k, a mesh at the pair's bisection equilibrium at its pinion angle */
    for (e = 0; e < gb->n_edge; ++e) {
        int k = gb->edge_index[e], up = gb->edge_up[e], down = gb->edge_down[e];
        if (gb->edge_kind[e] == 0) {
            double ts = gb->shaft_on_path[k] ? T_ref / gb->g[gb->shaft_a[k]] : 0.0;
            u[down] = u[up] - ts / gb->shaft_k[k];
        } else {
            const gb_mesh *me = &gb->mesh[k];
            gk_state ps;
            int st = gk_initialize(me->pair, &ps, gb->g[me->p] * psi0 + u[me->p], 0.0,
                                   gb_stage_torque(gb, k, T_ref));
            if (st != GK_OK) {
                if (bad_mesh != NULL) *bad_mesh = k;
                return st;
            }
            u[me->q] = (me->pair->Rb1_m * u[me->p] - ps.x_m) / me->pair->Rb2_m;
        }
    }
    s->y[0] = psi0;
    s->y[1] = omega0;
    for (i = 1; i < gb->n; ++i) {
        s->y[2 * i] = u[i];
        s->y[2 * i + 1] = 0.0;
    }
    return GK_OK;
}

int gb_derivatives(const gb_model *gb, gb_work *w, double t_s, const double *y, double T_motor, double T_load,
                   double *dy)
{
    int i;
    double t_in, t_out;
    (void)t_s;
    if (gb == NULL || w == NULL || y == NULL || dy == NULL) return GK_ERR_MODEL;
    if (!isfinite(T_motor) || !isfinite(T_load)) return GK_ERR_INPUT;
    for (i = 0; i < 2 * gb->n; ++i)
        if (!isfinite(y[i])) return GK_ERR_INPUT;
    t_in = gb->motor_input ? T_motor : 0.0;
    t_out = gb->load_input ? T_load : 0.0;
    select_rows(gb, w, T_motor, T_load);
    gb_rhs(gb, w, y, dy, t_in, t_out, 0);
    return GK_OK;
}

int gb_outputs(const gb_model *gb, const gb_state *s, double T_motor, double T_load, double *out)
{
    double t_ref;
    int i, m, o;
    if (gb == NULL || s == NULL || out == NULL) return GK_ERR_MODEL;
    if (!isfinite(T_motor) || !isfinite(T_load)) return GK_ERR_INPUT;
    t_ref = gb_reference_torque(gb, gb->motor_input ? T_motor : 0.0, gb->load_input ? T_load : 0.0);
    /* kernels._write_row */
    for (i = 0; i < gb->n; ++i) {
        out[2 * i] = gb->g[i] * s->y[0] + body_u(s->y, 0, i);
        out[2 * i + 1] = gb->g[i] * s->y[1] + body_u(s->y, 1, i);
    }
    o = 2 * gb->n;
    for (m = 0; m < gb->n_mesh; ++m) {
        const gb_mesh *me = &gb->mesh[m];
        const gk_model *pm = me->pair;
        gk_tq t = torque_bracket(pm, gb_stage_torque(gb, m, t_ref));
        gk_ph c = GK_PH_NONE;
        double loc[4], F, km;
        int j, P = pm->P;
        mesh_local(me, s->y, loc);
        F = mesh_force(pm, &t, &c, loc[0], loc[1], loc[2], loc[3], out + o + GB_OUT_PAIR_FORCE, &km);
        out[o + GB_OUT_DTE] = loc[2];
        out[o + GB_OUT_DTE_RATE] = loc[3];
        out[o + GB_OUT_MESH_FORCE] = F;
        out[o + GB_OUT_MESH_STIFFNESS] = km;
        for (j = 0; j < P; ++j)
            out[o + GB_OUT_PAIR_FORCE + P + j] = (F != 0.0) ? out[o + GB_OUT_PAIR_FORCE + j] / F : 0.0;
        o += GB_OUT_PAIR_FORCE + 2 * P;
    }
    for (i = 0; i < gb->n_shaft; ++i) {
        int a = gb->shaft_a[i], b = gb->shaft_b[i];
        out[o + i] = gb->shaft_k[i] * (body_u(s->y, 0, a) - body_u(s->y, 0, b)) +
                     gb->shaft_c[i] * (body_u(s->y, 1, a) - body_u(s->y, 1, b));
    }
    return GK_OK;
}

int gb_do_step(const gb_model *gb, gb_work *w, gb_state *s, double T_motor, double T_load, double H_s,
               double h_max_s, double *out)
{
    double n, h, t_in, t_out;
    long i, nsub;
    int m, n2, q;
    if (gb == NULL || w == NULL || s == NULL) return GK_ERR_MODEL;
    if (!isfinite(T_motor) || !isfinite(T_load)) return GK_ERR_INPUT;
    n = gk_substeps(H_s, h_max_s);
    if (n == 0.0) return GK_ERR_STEP;
    nsub = (long)n;
    h = H_s / n;
    n2 = 2 * gb->n;
    t_in = gb->motor_input ? T_motor : 0.0;
    t_out = gb->load_input ? T_load : 0.0;
    select_rows(gb, w, t_in, t_out);
    copy_state(w->y, s->y, n2);
    w->events = 0;
    if (gb->integrator == GB_INTEGRATOR_RK4_SEG) {
        for (m = 0; m < gb->n_mesh; ++m) mesh_start(gb, w, m, w->y, 1);
        for (i = 0; i < nsub; ++i) w->events += gb_substep(gb, w, h, 1, 3, t_in, t_out);
    } else if (gb->integrator == GB_INTEGRATOR_RK4_KINK || gb->integrator == GB_INTEGRATOR_RK4_NODE) {
        int node = gb->integrator == GB_INTEGRATOR_RK4_NODE;
        for (m = 0; m < gb->n_mesh; ++m) mesh_start(gb, w, m, w->y, node);
        for (i = 0; i < nsub; ++i) w->events += gb_substep(gb, w, h, node, 1, t_in, t_out);
    } else {
        for (i = 0; i < nsub; ++i) {
            gb_rhs(gb, w, w->y, w->f0, t_in, t_out, 0);
            gb_rk4(gb, w, w->y, w->f0, h, w->yt, t_in, t_out, 0);
            copy_state(w->y, w->yt, n2);
        }
    }
    for (q = 0; q < n2; ++q)
        if (!isfinite(w->y[q])) return GK_ERR_NONFINITE;
    copy_state(s->y, w->y, n2);
    if (out != NULL) return gb_outputs(gb, s, T_motor, T_load, out);
    return GK_OK;
}

/* ---------------------------------------------------------- Model Exchange
 * docs/model.md "Model Exchange", for every mesh: its mode (gk_me) held between the host's events and
 * decided anew from the state at each (gk_pair.h's me_* pieces on the mesh's local state), the
 * right-hand side gb_rhs with the modes held, the indicators of every mesh one after another. */
static int gb_me_check(const gb_model *gb, const gb_work *w, const gb_me *me, const double *y)
{
    int i, m;
    if (gb == NULL || w == NULL || me == NULL || y == NULL) return GK_ERR_MODEL;
    for (m = 0; m < gb->n_mesh; ++m)
        if (gb->mesh[m].pair->P > GK_KINK_MAX_SLOTS) return GK_ERR_PARAM;
    for (i = 0; i < 2 * gb->n; ++i)
        if (!isfinite(y[i])) return GK_ERR_NONFINITE;
    return GK_OK;
}

/* the torque rows and the input torques of T_motor, T_load (as gb_derivatives) */
static void gb_me_inputs(const gb_model *gb, gb_work *w, const gb_me *me, double T_motor, double T_load,
                         double *t_in, double *t_out)
{
    *t_in = gb->motor_input ? T_motor : 0.0;
    *t_out = gb->load_input ? T_load : 0.0;
    select_rows(gb, w, T_motor, T_load);
    w->me = me;
}

int gb_me_n_indicators(const gb_model *gb, int node_events)
{
    int m, n = 0;
    if (gb == NULL) return 0;
    for (m = 0; m < gb->n_mesh; ++m) n += me_n_indicators(gb->mesh[m].pair, node_events);
    return n;
}

/* every mesh's mode from the state y */
static void gb_me_decide(const gb_model *gb, gb_work *w, gb_me *me, const double *y)
{
    int m;
    for (m = 0; m < gb->n_mesh; ++m) {
        double loc[4];
        mesh_local(&gb->mesh[m], y, loc);
        me_decide(gb->mesh[m].pair, &me->mesh[m], &w->tq[m], loc);
    }
}

/* The modes anew at an event: decided at the state, then again a moment ahead, y + delta f(y) with f
 * in the modes decided first and delta the smallest of the meshes' me_ahead_time (as gk_me_update). */
int gb_me_update(const gb_model *gb, gb_work *w, gb_me *me, const double *y, double T_motor, double T_load,
                 int *changed)
{
    double t_in, t_out, delta = HUGE_VAL, *dy = w->kk, *ahead = w->tmp;
    int i, m, finite = 1, diff = 0, n2, st = gb_me_check(gb, w, me, y);
    gb_me old;
    if (st != GK_OK) return st;
    if (!isfinite(T_motor) || !isfinite(T_load)) return GK_ERR_INPUT;
    n2 = 2 * gb->n;
    old = *me;
    gb_me_inputs(gb, w, me, T_motor, T_load, &t_in, &t_out);
    gb_me_decide(gb, w, me, y);
    gb_rhs(gb, w, y, dy, t_in, t_out, 2);
    for (m = 0; m < gb->n_mesh; ++m) {
        double d = me_ahead_time(gb->mesh[m].pair);
        if (d < delta) delta = d;
    }
    for (i = 0; i < n2; ++i) {
        ahead[i] = y[i] + delta * dy[i];
        finite &= isfinite(ahead[i]) != 0;
    }
    if (finite) gb_me_decide(gb, w, me, ahead);
    for (m = 0; m < gb->n_mesh; ++m) diff |= me_differs(gb->mesh[m].pair, &me->mesh[m], &old.mesh[m]);
    if (changed != NULL) *changed = diff;
    return GK_OK;
}

int gb_me_init(const gb_model *gb, gb_work *w, gb_me *me, const double *y, double T_motor, double T_load,
               int node_events)
{
    int m;
    if (gb == NULL || me == NULL) return GK_ERR_MODEL;
    for (m = 0; m < GB_MAX_MESHES; ++m)
        if (!me_clear(&me->mesh[m], node_events)) return GK_ERR_PARAM;
    return gb_me_update(gb, w, me, y, T_motor, T_load, NULL);
}

int gb_me_derivatives(const gb_model *gb, gb_work *w, const gb_me *me, const double *y, double T_motor,
                      double T_load, double *dy)
{
    double t_in, t_out;
    int st = gb_me_check(gb, w, me, y);
    if (st != GK_OK) return st;
    if (dy == NULL) return GK_ERR_MODEL;
    if (!isfinite(T_motor) || !isfinite(T_load)) return GK_ERR_INPUT;
    gb_me_inputs(gb, w, me, T_motor, T_load, &t_in, &t_out);
    gb_rhs(gb, w, y, dy, t_in, t_out, 2);
    return GK_OK;
}

int gb_me_indicators(const gb_model *gb, gb_work *w, const gb_me *me, const double *y, double T_motor,
                     double T_load, double *z)
{
    double t_in, t_out, all[4 * GK_KINK_MAX_SLOTS + 2];
    int m, n = 0, st = gb_me_check(gb, w, me, y);
    if (st != GK_OK) return st;
    if (z == NULL) return GK_ERR_MODEL;
    if (!isfinite(T_motor) || !isfinite(T_load)) return GK_ERR_INPUT;
    gb_me_inputs(gb, w, me, T_motor, T_load, &t_in, &t_out);
    for (m = 0; m < gb->n_mesh; ++m) {
        const gk_model *pm = gb->mesh[m].pair;
        double loc[4];
        mesh_local(&gb->mesh[m], y, loc);
        me_all_indicators(pm, &me->mesh[m], &w->tq[m], loc, all);
        n += me_pack_indicators(pm, &me->mesh[m], all, z + n);
    }
    return GK_OK;
}

int gb_me_outputs(const gb_model *gb, gb_work *w, const gb_me *me, const double *y, double T_motor,
                  double T_load, double *out)
{
    double t_in, t_out;
    int i, m, o, st = gb_me_check(gb, w, me, y);
    if (st != GK_OK) return st;
    if (out == NULL) return GK_ERR_MODEL;
    if (!isfinite(T_motor) || !isfinite(T_load)) return GK_ERR_INPUT;
    gb_me_inputs(gb, w, me, T_motor, T_load, &t_in, &t_out);
    for (i = 0; i < gb->n; ++i) {
        out[2 * i] = gb->g[i] * y[0] + body_u(y, 0, i);
        out[2 * i + 1] = gb->g[i] * y[1] + body_u(y, 1, i);
    }
    o = 2 * gb->n;
    for (m = 0; m < gb->n_mesh; ++m) {
        const gk_model *pm = gb->mesh[m].pair;
        double loc[4], F, km;
        int j, P = pm->P;
        mesh_local(&gb->mesh[m], y, loc);
        F = me_force(pm, &me->mesh[m], &w->tq[m], loc, out + o + GB_OUT_PAIR_FORCE, &km);
        out[o + GB_OUT_DTE] = loc[2];
        out[o + GB_OUT_DTE_RATE] = loc[3];
        out[o + GB_OUT_MESH_FORCE] = F;
        out[o + GB_OUT_MESH_STIFFNESS] = km;
        for (j = 0; j < P; ++j)
            out[o + GB_OUT_PAIR_FORCE + P + j] = (F != 0.0) ? out[o + GB_OUT_PAIR_FORCE + j] / F : 0.0;
        o += GB_OUT_PAIR_FORCE + 2 * P;
    }
    for (i = 0; i < gb->n_shaft; ++i) {
        int a = gb->shaft_a[i], b = gb->shaft_b[i];
        out[o + i] = gb->shaft_k[i] * (body_u(y, 0, a) - body_u(y, 0, b)) +
                     gb->shaft_c[i] * (body_u(y, 1, a) - body_u(y, 1, b));
    }
    return GK_OK;
}
