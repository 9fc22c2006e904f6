/*
 * gk_pair.h -- the pair model's pieces that every mesh uses (docs/model.md "Per-pair force",
 * "Outputs", "rk4_kink"; docs/native.md "rk4_node"): the mesh force with the plain lookup, the
 * per-pair force law and guards with the mode held, the mode decisions, the Hermite point and the
 * root finder of the event location.  Included by the pair's hot path (gearkernel.c) and by the
 * gearbox kernel (gb_kernel.c), which applies them to every mesh with its own gk_model and gk_mode,
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

GK_INLINE double pair_guard(int q, double kv, double ev, double es, double bv, double x, double v,
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

/* fraction s in [0, 1] of guard gi's zero on the Hermite interpolant of a step of length tau from
 * (y0, f0) to (y1, f1), the mode held (rk4_kink, rk4_node; integrators._guard_root with seg False):
 * 0 when the guard is not > 0 at y0, else the end of the bracket where it is < 0 */
GK_PAIR_FN double held_guard_root(const gk_model *m, const gk_tq *t, const gk_mode *md, int gi, double g_end,
                                  const double *y0, const double *f0, const double *y1, const double *f1, double tau)
{
    gk_root r;
    double s, yy[4];
    int it;
    r.ga = guard_at(m, t, md, gi, y0);
    if (!(r.ga > 0.0)) return 0.0;
    r.a = 0.0;
    r.b = 1.0;
    r.gb = g_end;
    r.side = 0;
    for (it = 0; it < KINK_MAX_IT; ++it) {
        s = root_next(&r);
        hermite_point(s, y0, f0, y1, f1, tau, yy);
        if (root_update(&r, s, guard_at(m, t, md, gi, yy))) break;
    }
    return r.b;
}

#endif /* GK_PAIR_H */
