/*
 * gk_pair.h -- the pair model's pieces that every mesh uses (docs/model.md "Per-pair force",
 * "Outputs", "rk4_kink"; docs/native.md "rk4_node"): the mesh force with the plain lookup, the
 * per-pair force law and guards with the mode held, the mode decisions, the Hermite point and the
 * root finder of the event location, and the same for Model Exchange (the mode held between a
 * host's events, the force and the event indicators with it held).  Included by the pair's hot
 * path (gearkernel.c) and by the gearbox kernel (gb_kernel.c), which applies them to every mesh
 * with its own gk_model and gk_mode (gk_me for Model Exchange),
 * so that a stage is computed exactly as the pair is; the same arithmetic as
 * gearfmu/dynamics/model_rhs.py and integrators.py.  Calls only gk_lookup.h and gk_stops.c.
 */
#ifndef GK_PAIR_H
#define GK_PAIR_H

#include "gk_lookup.h"

/* the larger pieces: inlined where the compiler sees fit (no unused-function warning where a
 * file includes them and does not call them all) */
#define GK_PAIR_FN static inline

/* ----------------------------------------------------------------- forces */

/* Total mesh force F at (theta1, omega1, x, v) in cell c (updated to theta1);
 * optionally per-pair forces (pf[P]) and the stiffness of the pairs in contact
 * (*kmesh). */
GK_INLINE double mesh_force(const gk_model *m, const gk_tq *t, gk_ph *c, double theta1, double omega1,
                                double x, double v, double *pf, double *kmesh)
{
    double F = 0.0, ks = 0.0;
    int j;
    phi_cell(m, theta1, c);
    for (j = 0; j < m->P; ++j) {
        double k, e, es, b, d, fc, fd, Fj;
        int region;
        slot_tables(m, t, c, j, -1, &k, &e, &es, &b);
        d = x - e;                             /* Xu et al. 2022 eq 6 */
        if (d > b) { fc = k * (d - b); region = 1; }
        else if (d < -b) { fc = k * (d + b); region = -1; }
        else { fc = 0.0; region = 0; }
        fd = m->c_Ns_per_m * (v - es * omega1);
        if (m->damping_model == GK_DAMPING_CONTACT_ZONE) {
            Fj = (k > 0.0) ? fc + fd : 0.0;
        } else if (region == 1) {
            double a = fc + ((fc < fd) ? fc : fd);
            Fj = (a > 0.0) ? a : 0.0;
        } else if (region == -1) {
            double a = fc + ((fc > fd) ? fc : fd);
            Fj = (a < 0.0) ? a : 0.0;
        } else {
            Fj = 0.0;
        }
        if (region != 0) ks += k;
        if (pf != NULL) pf[j] = Fj;
        F += Fj;
    }
    if (kmesh != NULL) *kmesh = ks;
    return F;
}

/* --------------------------------------------------------------- the mode held
 * docs/model.md "rk4_kink": the mode (table cell nd and, per pair, region reg,
 * elastobacklash sub-mode sub, contact_zone flag kpos) is held during each RK4
 * step; guards (>= 0 while the mode holds) are tested at the step end, the
 * earliest zero is located on the cubic Hermite interpolant of the step, the
 * step is retaken exactly to it and the mode switched there.  The per-pair pieces
 * of that loop; the same arithmetic as gearfmu/dynamics/integrators.py and model_rhs.py. */

#define KINK_TOL_S 1e-12
#define KINK_MAX_IT 60

/* k, e, de/dphi, b of slot j at angle th with the cell held */
GK_INLINE void locked_tables(const gk_model *m, const gk_tq *t, const gk_mode *md, double th, int j,
                          double *k, double *e, double *es, double *b)
{
    gk_ph c;
    c.nd = GK_CELL_NONE;
    c.i0 = md->i0;
    c.i1 = md->i1;
    c.w = (th - md->nd * m->dphi_rad) * m->inv_dphi;
    slot_tables(m, t, &c, j, md->zsel[j], k, e, es, b);
}

GK_INLINE double pair_force_locked(double kv, double ev, double es, double bv, double x, double v,
                                double om, double c, int model, int reg, int sub, int kpos)
{
    double de = es * om, d = x - ev, fc, fd;
    if (reg == 1) fc = kv * (d - bv);
    else if (reg == -1) fc = kv * (d + bv);
    else fc = 0.0;
    fd = c * (v - de);
    if (model == GK_DAMPING_ELASTOBACKLASH) {
        if (reg == 0 || sub == 2) return 0.0;
        if (sub == 0) return fc + fc;
        return fc + fd;
    }
    if (kpos != 0) return fc + fd;
    return 0.0;
}

/* guard q (0..2) of a pair in mode (reg, sub): >= 0 while the mode holds, 1.0 when the mode has no
 * such guard (model_rhs._pair_guard without its k = 0 rule; Model Exchange's me_guard) */
GK_INLINE double pair_guard_me(int q, double kv, double ev, double es, double bv, double x, double v,
                         double om, double c, int model, int reg, int sub)
{
    double d = x - ev, fc, fd;
    if (reg == 0) {
        if (q == 0) return bv - d;
        if (q == 1) return d + bv;
        return 1.0;
    }
    if (q == 0) {
        if (reg == 1) return d - bv;
        return -(d + bv);
    }
    if (model != GK_DAMPING_ELASTOBACKLASH) return 1.0;
    if (reg == 1) fc = kv * (d - bv);
    else fc = kv * (d + bv);
    fd = c * (v - es * om);
    if (reg == 1) {
        if (sub == 0) return (q == 1) ? fd - fc : 1.0;
        if (sub == 1) return (q == 1) ? fc - fd : fc + fd;
        return (q == 1) ? -(fc + fd) : 1.0;
    }
    if (sub == 0) return (q == 1) ? fc - fd : 1.0;
    if (sub == 1) return (q == 1) ? fd - fc : -(fc + fd);
    return (q == 1) ? fc + fd : 1.0;
}

/* pair_guard_me for the event integrators (rk4_kink, rk4_node, rk4_seg): an elastobacklash pair in
 * contact with k = 0 (out of its contact zone) has no sub-mode guard in its sub-modes 'two' and
 * 'zero', which both give it no force, so a sign change of its damping force is no event (where k
 * turns positive they stop, and mode_sync decides the sub-mode anew; Model Exchange reads k in the
 * cell of each evaluation without such a stop and keeps the guards) */
GK_INLINE double pair_guard(int q, double kv, double ev, double es, double bv, double x, double v,
                         double om, double c, int model, int reg, int sub)
{
    if (q != 0 && reg != 0 && model == GK_DAMPING_ELASTOBACKLASH && kv == 0.0 && sub != 1) return 1.0;
    return pair_guard_me(q, kv, ev, es, bv, x, v, om, c, model, reg, sub);
}

GK_INLINE int decide_sub(int reg, double kv, double ev, double es, double bv, double x, double v,
                      double om, double c)
{
    double d, fd, fc;
    if (reg == 0) return 0;
    d = x - ev;
    fd = c * (v - es * om);
    if (reg == 1) {
        fc = kv * (d - bv);
        if (fc < fd) return 0;
        if (fc + fd < 0.0) return 2;
        return 1;
    }
    fc = kv * (d + bv);
    if (fc > fd) return 0;
    if (fc + fd > 0.0) return 2;
    return 1;
}

/* the mode change of pair j when its guard q reached zero (integrators._switch_pair); kv..bv:
 * the pair's table values at the state y, read only when the pair enters contact under
 * the elastobacklash model */
GK_INLINE void switch_pair(const gk_model *m, gk_mode *md, int j, int q, double kv, double ev, double es,
                           double bv, const double *y)
{
    if (md->reg[j] == 0) {
        md->reg[j] = (q == 0) ? 1 : -1;
        if (m->damping_model == GK_DAMPING_ELASTOBACKLASH)
            md->sub[j] = decide_sub(md->reg[j], kv, ev, es, bv, y[2], y[3], y[1], m->c_Ns_per_m);
    } else if (q == 0) {
        md->reg[j] = 0;
        md->sub[j] = 0;
    } else if (md->sub[j] == 1) {
        md->sub[j] = (q == 1) ? 0 : 2;
    } else {
        md->sub[j] = 1;
    }
}

/* guard gi at state y: 0 cell start, 1 cell end, 2 + 3 j + q guard q of pair j */
GK_INLINE double guard_at(const gk_model *m, const gk_tq *t, const gk_mode *md, int gi, const double *y)
{
    int j, q;
    double kv, ev, es, bv;
    if (gi == 0) return y[0] - md->lo * m->dphi_rad;
    if (gi == 1) return md->hi * m->dphi_rad - y[0];
    j = (gi - 2) / 3;
    q = (gi - 2) - 3 * j;
    locked_tables(m, t, md, y[0], j, &kv, &ev, &es, &bv);
    return pair_guard(q, kv, ev, es, bv, y[2], y[3], y[1], m->c_Ns_per_m, m->damping_model,
                      md->reg[j], md->sub[j]);
}

/* the cubic Hermite interpolant at fraction s of a step of length tau from (y0, f0) to (y1, f1) */
GK_INLINE void hermite_point(double s, const double *y0, const double *f0, const double *y1, const double *f1,
                             double tau, double *yy)
{
    double u = 1.0 - s;
    double h00 = (1.0 + 2.0 * s) * u * u, h10 = s * u * u;
    double h01 = s * s * (3.0 - 2.0 * s), h11 = s * s * (s - 1.0);
    int q;
    for (q = 0; q < 4; ++q)
        yy[q] = ((h00 * y0[q] + h10 * (tau * f0[q])) + h01 * y1[q]) + h11 * (tau * f1[q]);
}

/* kpos of every pair for the held cell and the sub-modes of pairs in contact;
 * with from_state also the regions */
GK_PAIR_FN void mode_sync(const gk_model *m, const gk_tq *t, gk_mode *md, const double *y, int from_state)
{
    int j;
    gk_ph half;
    half.nd = GK_CELL_NONE;
    half.i0 = md->i0;
    half.i1 = md->i1;
    half.w = 0.5;
    for (j = 0; j < m->P; ++j) {
        double km, em, esm, bm, kv, ev, es, bv;
        slot_tables(m, t, &half, j, md->zsel[j], &km, &em, &esm, &bm);
        md->kpos[j] = (km > 0.0) ? 1 : 0;
        locked_tables(m, t, md, y[0], j, &kv, &ev, &es, &bv);
        if (from_state) {
            double d = y[2] - ev;
            if (d > bv) md->reg[j] = 1;
            else if (d < -bv) md->reg[j] = -1;
            else md->reg[j] = 0;
        }
        if (m->damping_model == GK_DAMPING_ELASTOBACKLASH)
            md->sub[j] = decide_sub(md->reg[j], kv, ev, es, bv, y[2], y[3], y[1], m->c_Ns_per_m);
        else
            md->sub[j] = 0;
    }
}

GK_PAIR_FN void mode_from_state(const gk_model *m, const gk_tq *t, gk_mode *md, const double *y, int node)
{
    md->nd = floor(y[0] * m->inv_dphi);
    gki_cell_nodes(md, m->n_phi);
    gki_seg_start(m, md, node, y[1], y[0]);
    gki_zone_sel(m, md);
    mode_sync(m, t, md, y, 1);
}

/* rk4_node: time to the flagged table node ahead of theta1 (the held segment's
 * end hi for om > 0, start lo for om < 0) predicted from the step's first
 * stage, theta1(tau) = th + tau*(om + 0.5*fb*tau); linear start, two
 * Newton iterations; -1 when there is no prediction (as _node_time in
 * gearfmu/dynamics/integrators.py). */
GK_PAIR_FN double node_time(double th, double om, double fb, double rem, double lo, double hi, double dphi)
{
    double dist, tau;
    int it;
    if (om > 0.0) dist = hi * dphi - th;
    else if (om < 0.0) dist = lo * dphi - th;
    else return -1.0;
    tau = dist / om;
    for (it = 0; it < 2; ++it) {
        double d = om + fb * tau;
        if (!(d * om > 0.0)) return -1.0;
        tau = tau - (tau * (om + 0.5 * fb * tau) - dist) / d;
    }
    if (tau > 0.0 && tau < rem) return tau;
    return -1.0;
}

/* 1 when no pair guard is negative at y (cell held) */
GK_PAIR_FN int pairs_hold(const gk_model *m, const gk_tq *t, const gk_mode *md, const double *y)
{
    int gi, n_guard = 2 + 3 * m->P;
    for (gi = 2; gi < n_guard; ++gi)
        if (guard_at(m, t, md, gi, y) < 0.0) return 0;
    return 1;
}

/* The Illinois regula falsi of the root finder (integrators._guard_root) on the step fraction s:
 * bracket [a, b] with the guard > 0 at a (value ga) and < 0 at b (gb); side: which end moved last */
typedef struct {
    double a, b, ga, gb;
    int side;
} gk_root;

/* the next point: the secant through the ends, bisection when it is not inside (a, b) */
GK_INLINE double root_next(const gk_root *r)
{
    double s = (r->a * r->gb - r->b * r->ga) / (r->gb - r->ga);
    if (!(s > r->a && s < r->b)) s = 0.5 * (r->a + r->b);
    return s;
}

/* the bracket after the guard value gs at s (an end kept twice has its value halved); 1 when done:
 * gs == 0 (b = s) or b - a <= KINK_TOL_S */
GK_INLINE int root_update(gk_root *r, double s, double gs)
{
    if (gs < 0.0) {
        r->b = s;
        r->gb = gs;
        if (r->side == -1) r->ga = 0.5 * r->ga;
        r->side = -1;
    } else if (gs == 0.0) {
        r->b = s;
        return 1;
    } else {
        r->a = s;
        r->ga = gs;
        if (r->side == 1) r->gb = 0.5 * r->gb;
        r->side = 1;
    }
    return r->b - r->a <= KINK_TOL_S;
}

/* a mesh of the multi-mesh kernels (gb_kernel.c, pl_kernel.c) stops where their integrator does
 * (gk_stops.c reads it); rk4_seg also where e bends (GK_STOPS_E): those kernels integrate the true
 * velocities, and the damping term c*(de/dphi)*omega jumps there (gearbox/kernels.stop_flags) */
GK_INLINE int multimesh_integrator(gk_model *pair, int integrator)
{
    if (gk_set_integrator(pair, integrator) != GK_OK) return GK_ERR_PARAM;
    pair->seg_stops = GK_STOPS_SEG | GK_STOPS_E;
    return GK_OK;
}

/* ---------------------------------------------------------- rk4_seg's lookup
 * docs/model.md "rk4_seg": every evaluation reads the tables in the cell of its own theta1 clamped
 * to the held segment [lo, hi) (md->cl, md->ch: its first and last cell, set at each pass of the
 * substep); the guards and the root finder on that lookup.  gw, gv: the pair's shifted-velocity
 * gains (the multi-mesh kernels integrate the true velocities: 0, 0). */

/* the cell of th clamped to the held segment (seg_rhs._seg_cell): its nodes and weight in
 * *c, its global index returned */
GK_INLINE double seg_cell(const gk_model *m, const gk_mode *md, double th, gk_ph *c)
{
    int N = m->n_phi;
    double sc = th * m->inv_dphi, cc;
    /* floor(sc), read off the held cell when sc lies in it (nd <= sc < nd + 1: the same value) */
    cc = (sc >= md->nd && sc < md->nd + 1.0) ? md->nd : floor(sc);
    if (!(cc > md->cl)) cc = md->cl;
    if (cc > md->ch) cc = md->ch;
    if (cc == md->nd) {
        c->i0 = md->i0;
        c->i1 = md->i1;
    } else if (cc == md->nd + 1.0) {
        c->i0 = md->i1;
        c->i1 = (md->i1 == N - 1) ? 0 : md->i1 + 1;
    } else if (cc == md->nd - 1.0) {
        c->i1 = md->i0;
        c->i0 = (md->i0 == 0) ? N - 1 : md->i0 - 1;
    } else {
        c->i0 = gki_node_index(N, cc);
        c->i1 = (c->i0 + 1 == N) ? 0 : c->i0 + 1;
    }
    c->nd = GK_CELL_NONE;
    c->w = (th - cc * m->dphi_rad) * m->inv_dphi;
    return cc;
}

/* held side of pair j's contact-zone cut in cell c of the segment (seg_rhs._seg_sel) */
GK_INLINE int seg_sel(const gk_model *m, const gk_mode *md, int j, double cc, const gk_ph *c)
{
    size_t r;
    double clo, a, b, wm;
    if (cc == md->nd || m->zone_cuts == NULL) return md->zsel[j];
    r = (size_t)j * m->n_phi + c->i0;
    clo = m->zone_cuts[r];
    if (!(clo >= 0.0)) return -1;
    a = (md->lo > cc) ? md->lo : cc;
    b = (md->hi < cc + 1.0) ? md->hi : cc + 1.0;
    wm = 0.5 * (a + b) - cc;
    if (wm < clo) return 0;
    if (wm >= m->zone_cuts[(size_t)m->P * m->n_phi + r]) return 2;
    return 1;
}

/* the pair carries the viscous term in its held mode (seg_rhs._seg_damped) */
GK_INLINE int seg_damped(const gk_model *m, const gk_mode *md, int j)
{
    if (m->damping_model == GK_DAMPING_ELASTOBACKLASH) return md->reg[j] != 0 && md->sub[j] == 1;
    return md->kpos[j] != 0;
}

/* guard gi at the shifted state y (seg_rhs._guard_seg): the values and operations of seg_ce,
 * then the guard of the pair, with one table lookup per pair for both */
GK_INLINE double guard_seg(const gk_model *m, const gk_tq *t, const gk_mode *md, int gi, const double *y,
                           double gw, double gv)
{
    gk_ph c;
    double cc, ea = 0.0, ce, kj = 0.0, ej = 0.0, sj = 0.0, bj = 0.0;
    int j, jg, q;
    if (gi == 0) return y[0] - md->lo * m->dphi_rad;
    if (gi == 1) return md->hi * m->dphi_rad - y[0];
    jg = (gi - 2) / 3;
    q = (gi - 2) - 3 * jg;
    cc = seg_cell(m, md, y[0], &c);
    for (j = 0; j < m->P; ++j) {
        int damped = seg_damped(m, md, j);
        if (damped || j == jg) {
            double kv, ev, es, bv;
            slot_tables(m, t, &c, j, seg_sel(m, md, j, cc, &c), &kv, &ev, &es, &bv);
            if (damped) ea += ev;
            if (j == jg) {
                kj = kv;
                ej = ev;
                sj = es;
                bj = bv;
            }
        }
    }
    ce = m->c_Ns_per_m * ea;
    return pair_guard(q, kj, ej, sj, bj, y[2], y[3] + gv * ce, y[1] + gw * ce, m->c_Ns_per_m, m->damping_model,
                      md->reg[jg], md->sub[jg]);
}

/* fraction s in [0, 1] of guard gi's zero on the Hermite interpolant of a step of length tau from
 * (y0, f0) to (y1, f1), the mode held (Illinois; integrators._guard_root): rk4_kink / rk4_node guard_at
 * on the state, rk4_seg (seg) guard_seg on the shifted state (gw, gv its gains; the multi-mesh kernels:
 * 0, 0); 0 when the guard is not > 0 at y0, else the end of the bracket where it is < 0 */
GK_PAIR_FN double guard_root(const gk_model *m, const gk_tq *t, const gk_mode *md, int gi, double g_end,
                             const double *y0, const double *f0, const double *y1, const double *f1, double tau,
                             int seg, double gw, double gv)
{
    gk_root r;
    double s, yy[4];
    int it;
    r.ga = seg ? guard_seg(m, t, md, gi, y0, gw, gv) : guard_at(m, t, md, gi, y0);
    if (!(r.ga > 0.0)) return 0.0;
    r.a = 0.0;
    r.b = 1.0;
    r.gb = g_end;
    r.side = 0;
    for (it = 0; it < KINK_MAX_IT; ++it) {
        s = root_next(&r);
        hermite_point(s, y0, f0, y1, f1, tau, yy);
        if (root_update(&r, s, seg ? guard_seg(m, t, md, gi, yy, gw, gv) : guard_at(m, t, md, gi, yy))) break;
    }
    return r.b;
}

/* k, e, de/dphi, b of pair j at theta1 = th with the mode held (rk4_seg: in th's own cell of the segment) */
GK_INLINE void held_tables(const gk_model *m, const gk_tq *t, const gk_mode *md, int j, double th, double *kv,
                           double *ev, double *es, double *bv, const int seg)
{
    if (seg) {
        gk_ph c;
        double cc = seg_cell(m, md, th, &c);
        slot_tables(m, t, &c, j, seg_sel(m, md, j, cc, &c), kv, ev, es, bv);
    } else {
        locked_tables(m, t, md, th, j, kv, ev, es, bv);
    }
}

/* rk4_seg of the multi-mesh kernels: 1 when no pair guard is negative at the mesh's state y, the tables
 * read in the cell of y[0] clamped to the held segment (kernels._pairs_hold_seg) */
GK_PAIR_FN int pairs_hold_seg(const gk_model *m, const gk_tq *t, const gk_mode *md, const double *y)
{
    gk_ph c;
    int j, q;
    double cc = seg_cell(m, md, y[0], &c);
    for (j = 0; j < m->P; ++j) {
        double kv, ev, es, bv;
        slot_tables(m, t, &c, j, seg_sel(m, md, j, cc, &c), &kv, &ev, &es, &bv);
        for (q = 0; q < 3; ++q)
            if (pair_guard(q, kv, ev, es, bv, y[2], y[3], y[1], m->c_Ns_per_m, m->damping_model, md->reg[j],
                           md->sub[j]) < 0.0)
                return 0;
    }
    return 1;
}

/* ---------------------------------------------------------- Model Exchange
 * docs/model.md "Model Exchange": the host integrates the state; per mesh the mode (gk_me: per pair
 * region, elastobacklash branch and contact-zone flag; with node events the table segment) is held
 * between events and decided anew from the state at each event.  The lookup is the plain one in the
 * cell of theta1 (with node events: clamped to the held segment, the end cells' lines extended),
 * except that a pair out of its contact zone has k = 0 and a pair in it takes the in-zone line of
 * a cell that holds one of its edges.  y is the mesh's own (theta_p, omega_p, x, v). */

/* x on the nearest node when within GK_ZONE_SNAP cells (gk_zones.c zone_wrap, without the wrap) */
GK_INLINE double me_snap(double x)
{
    double rn = floor(x + 0.5);
    return (fabs(x - rn) <= GK_ZONE_SNAP) ? rn : x;
}

/* Signed distance (node units) from s to the nearest edge of slot j's contact zones: > 0 inside a
 * zone, < 0 outside; *inside = 1 when in <= s < out for one of them.  Global pair n has the zone
 * [q N + snap(mm ppm + in), q N + snap(mm ppm + out)), q = floor(n / n_mesh), mm = n - q n_mesh, and
 * belongs to slot mm mod P (gk_zone_cuts); the pairs within 2P meshes of s are looked at. */
GK_PAIR_FN double me_zone_distance(const gk_model *m, int j, double s, int *inside)
{
    double nm = m->zone_n_mesh, ppm = m->zone_ppm, best = -HUGE_VAL, n;
    double n0 = floor((s - m->zone_out) / ppm) - 2.0 * m->P, n1 = floor((s - m->zone_in) / ppm) + 2.0 * m->P;
    int k;
    *inside = 0;
    if (!(fabs(s) < GK_CELL_LIMIT)) {   /* beyond 2^52 cells (or NaN) the pairs cannot be told apart */
        *inside = 1;
        return 1.0;
    }
    for (n = n0, k = 0; n <= n1 && k < 64 * GK_KINK_MAX_SLOTS; n += 1.0, ++k) {
        double q = floor(n / nm), mm = n - q * nm, in, out, g;
        if ((long long)mm % m->P != j) continue;
        in = q * (double)m->n_phi + me_snap(mm * ppm + m->zone_in);
        out = q * (double)m->n_phi + me_snap(mm * ppm + m->zone_out);
        g = (s - in < out - s) ? s - in : out - s;
        if (g > best) best = g;
        if (in <= s && s < out) *inside = 1;
    }
    return (best == -HUGE_VAL) ? -(double)m->n_phi : best;
}

/* a node the held segment stops at (node events): rk4_seg's stops (GK_ME_NODES_KINKS) or rk4_node's */
GK_INLINE int me_node_stop(const gk_model *m, double n, int node_events)
{
    if (m->n_phi > GK_NODE_FLAGS_MAX) return 1;
    return (m->node_kink[gki_node_index(m->n_phi, n)] & (node_events == GK_ME_NODES_KINKS ? 2 : 1)) != 0;
}

/* the segment [lo, hi) of stops around s: lo the last stop at or below floor(s), hi the first above */
GK_PAIR_FN void me_segment(const gk_model *m, gk_me *me, double s)
{
    double c = floor(s), q;
    int k, N = m->n_phi;
    me->seg_lo = c + 1.0 - N;
    for (q = c, k = 0; k < N; ++k, q -= 1.0)
        if (me_node_stop(m, q, me->node_events)) { me->seg_lo = q; break; }
    me->seg_hi = c + N;
    for (q = c + 1.0, k = 0; k < N; ++k, q += 1.0)
        if (me_node_stop(m, q, me->node_events)) { me->seg_hi = q; break; }
}

/* the cell of theta1 = th (with node events clamped to the held segment) */
GK_INLINE void me_cell(const gk_model *m, const gk_me *me, double th, gk_ph *c)
{
    double cc;
    if (me->node_events == GK_ME_NODES_NONE) {
        phi_cell(m, th, c);
        return;
    }
    cc = floor(th * m->inv_dphi);
    if (!(cc >= me->seg_lo)) cc = me->seg_lo;
    if (cc > me->seg_hi - 1.0) cc = me->seg_hi - 1.0;
    c->i0 = gki_node_index(m->n_phi, cc);
    c->i1 = (c->i0 + 1 == m->n_phi) ? 0 : c->i0 + 1;
    c->nd = GK_CELL_NONE;
    c->w = (th - cc * m->dphi_rad) * m->inv_dphi;
}

/* k, e, de/dphi, b of pair j with its contact-zone flag held; 0 (and k = 0) when it is out of its zone */
GK_INLINE int me_tables(const gk_model *m, const gk_tq *t, const gk_me *me, const gk_ph *c, int j, double *kv,
                        double *ev, double *es, double *bv)
{
    int sel = -1;
    if (m->zone_n_mesh > 0.0 && !me->zin[j]) {
        slot_tables(m, t, c, j, -1, kv, ev, es, bv);
        *kv = 0.0;
        return 0;
    }
    if (m->zone_cuts != NULL) {
        size_t r = (size_t)j * m->n_phi + c->i0;
        double lo = m->zone_cuts[r];
        if (lo >= 0.0) sel = (c->w < 0.5 * (lo + m->zone_cuts[(size_t)m->P * m->n_phi + r])) ? 0 : 2;
    }
    slot_tables(m, t, c, j, sel, kv, ev, es, bv);
    return 1;
}

/* contact_zone: the pair is damped (k > 0 in its zone; without zone edges at the middle of the cell) */
GK_INLINE int me_kpos(const gk_model *m, const gk_tq *t, const gk_me *me, const gk_ph *c, int j, int active)
{
    gk_ph half;
    double km, em, esm, bm;
    if (m->damping_model != GK_DAMPING_CONTACT_ZONE || !active) return 0;
    if (m->zone_n_mesh > 0.0) return me->zin[j];
    half = *c;
    half.w = 0.5;
    slot_tables(m, t, &half, j, -1, &km, &em, &esm, &bm);
    return km > 0.0;
}

/* guard q of pair j (pair_guard) in metres: the force guards of elastobacklash divided by k_mean */
GK_INLINE double me_guard(int q, double kv, double ev, double es, double bv, const double *y, double c, int model,
                          int reg, int sub, double inv_k)
{
    double g = pair_guard_me(q, kv, ev, es, bv, y[2], y[3], y[1], c, model, reg, sub);
    if (q == 0 || reg == 0 || model != GK_DAMPING_ELASTOBACKLASH || (q == 2 && sub != 1)) return g;
    return g * inv_k;
}

/* The number of event indicators: 3 per pair (the contact guards), 1 per pair with contact-zone edges,
 * 2 with node events (the held segment's ends). */
GK_INLINE int me_n_indicators(const gk_model *m, int node_events)
{
    return 3 * m->P + ((m->zone_n_mesh > 0.0) ? m->P : 0) + ((node_events != GK_ME_NODES_NONE) ? 2 : 0);
}

/* an empty mode with node_events (GK_ME_NODES_*); 0 for another value */
GK_INLINE int me_clear(gk_me *me, int node_events)
{
    int j;
    if (node_events != GK_ME_NODES_NONE && node_events != GK_ME_NODES_KINKS && node_events != GK_ME_NODES_ALL)
        return 0;
    me->node_events = node_events;
    for (j = 0; j < GK_KINK_MAX_SLOTS; ++j) me->reg[j] = me->sub[j] = me->zin[j] = 0;
    me->seg_lo = me->seg_hi = 0.0;
    return 1;
}

/* 1 when mode a differs from mode b */
GK_INLINE int me_differs(const gk_model *m, const gk_me *a, const gk_me *b)
{
    int j, diff = a->seg_lo != b->seg_lo || a->seg_hi != b->seg_hi;
    for (j = 0; j < m->P; ++j) diff |= a->reg[j] != b->reg[j] || a->sub[j] != b->sub[j] || a->zin[j] != b->zin[j];
    return diff;
}

/* the moment ahead of an event at which the mode is decided a second time: 1e-9 of the natural period
 * 2 pi sqrt(m_e/k_mean) (the choice of gearfmu.dynamics.reference) */
GK_INLINE double me_ahead_time(const gk_model *m)
{
    return 1e-9 * 6.283185307179586 * sqrt(m->m_e_kg / m->k_mean_N_per_m);
}

/* the mode from state y */
GK_PAIR_FN void me_decide(const gk_model *m, gk_me *me, const gk_tq *t, const double *y)
{
    gk_ph c = GK_PH_NONE;
    double sv = y[0] * m->inv_dphi;
    int j;
    if (me->node_events != GK_ME_NODES_NONE) me_segment(m, me, sv);
    if (m->zone_n_mesh > 0.0)
        for (j = 0; j < m->P; ++j) me_zone_distance(m, j, sv, &me->zin[j]);
    me_cell(m, me, y[0], &c);
    for (j = 0; j < m->P; ++j) {
        double kv, ev, es, bv, d;
        if (!me_tables(m, t, me, &c, j, &kv, &ev, &es, &bv)) {
            me->reg[j] = 0;
            me->sub[j] = 0;
            continue;
        }
        d = y[2] - ev;
        me->reg[j] = (d > bv) ? 1 : (d < -bv) ? -1 : 0;
        me->sub[j] = (m->damping_model == GK_DAMPING_ELASTOBACKLASH)
                         ? decide_sub(me->reg[j], kv, ev, es, bv, y[2], y[3], y[1], m->c_Ns_per_m)
                         : 0;
    }
}

/* the total force at y with the mode held; per pair (pf, may be NULL) and the stiffness of the pairs
 * in contact (kmesh, may be NULL) */
GK_PAIR_FN double me_force(const gk_model *m, const gk_me *me, const gk_tq *t, const double *y, double *pf,
                           double *kmesh)
{
    gk_ph c = GK_PH_NONE;
    double F = 0.0, ks = 0.0;
    int j;
    me_cell(m, me, y[0], &c);
    for (j = 0; j < m->P; ++j) {
        double kv, ev, es, bv, Fj = 0.0;
        int active = me_tables(m, t, me, &c, j, &kv, &ev, &es, &bv);
        if (active) {
            Fj = pair_force_locked(kv, ev, es, bv, y[2], y[3], y[1], m->c_Ns_per_m, m->damping_model, me->reg[j],
                                   me->sub[j], me_kpos(m, t, me, &c, j, active));
            if (me->reg[j] != 0) ks += kv;
        }
        if (pf != NULL) pf[j] = Fj;
        F += Fj;
    }
    if (kmesh != NULL) *kmesh = ks;
    return F;
}

/* every indicator into z with room for all (3P guards, P zones, 2 segment ends; those the model does
 * not have 1.0), in metres (guards of forces divided by k_mean, angles times Rb1) */
GK_PAIR_FN void me_all_indicators(const gk_model *m, const gk_me *me, const gk_tq *t, const double *y, double *z)
{
    gk_ph c = GK_PH_NONE;
    double sv = y[0] * m->inv_dphi, len = m->Rb1_m * m->dphi_rad, inv_k = 1.0 / m->k_mean_N_per_m;
    int j, q, P = m->P;
    me_cell(m, me, y[0], &c);
    for (j = 0; j < P; ++j) {
        double kv, ev, es, bv;
        int active = me_tables(m, t, me, &c, j, &kv, &ev, &es, &bv), inside;
        for (q = 0; q < 3; ++q)
            z[q * P + j] = active ? me_guard(q, kv, ev, es, bv, y, m->c_Ns_per_m, m->damping_model, me->reg[j],
                                             me->sub[j], inv_k)
                                  : 1.0;
        if (m->zone_n_mesh > 0.0) {
            double g = me_zone_distance(m, j, sv, &inside) * len;
            z[3 * P + j] = me->zin[j] ? g : -g;
        } else {
            z[3 * P + j] = 1.0;
        }
    }
    z[4 * P] = (me->node_events != GK_ME_NODES_NONE) ? (sv - me->seg_lo) * len : 1.0;
    z[4 * P + 1] = (me->node_events != GK_ME_NODES_NONE) ? (me->seg_hi - sv) * len : 1.0;
}

/* the indicators the mesh has (me_n_indicators of them, in gk_me_indicators' order) from all of
 * me_all_indicators into z; their number */
GK_INLINE int me_pack_indicators(const gk_model *m, const gk_me *me, const double *all, double *z)
{
    int j, n = 0, P = m->P;
    for (j = 0; j < 3 * P; ++j) z[n++] = all[j];
    if (m->zone_n_mesh > 0.0)
        for (j = 0; j < P; ++j) z[n++] = all[3 * P + j];
    if (me->node_events != GK_ME_NODES_NONE) {
        z[n++] = all[4 * P];
        z[n++] = all[4 * P + 1];
    }
    return n;
}

#endif /* GK_PAIR_H */
