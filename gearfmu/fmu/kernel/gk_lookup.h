/*
 * gk_lookup.h -- the table lookup of the kernel (docs/model.md "Table lookup", "Torque axis",
 * "Temperature axis", "Contact-zone edges"): the torque row bracket, the angle cell, the
 * linear interpolation of a table row (with the temperature blend of its nodes) and the
 * sub-cell lookup at a contact-zone edge.  Included by the hot path (gearkernel.c) only, so
 * that every lookup is inlined into the integrator loops; the same arithmetic as
 * gearfmu/dynamics/model_rhs.py.
 */
#ifndef GK_LOOKUP_H
#define GK_LOOKUP_H

#include "gk_internal.h"

/* torque row bracket: rows it, it+1 and weight wT (docs/model.md "Torque axis"),
 * with the table rows of the selected temperature slice resolved once per step:
 * k0, e0 point at slot 0 of row it (slice temp_ia); the same slot of row it+1 is
 * next_torque further, of slice temp_ia+1 next_temp further */
typedef struct {
    int it;
    int two_rows;
    double wT;
    const double *k0, *e0;
    size_t next_torque, next_temp;
} gk_tq;

static gk_tq torque_bracket(const gk_model *m, double T1)
{
    gk_tq t;
    int nt = m->n_torque;
    size_t row;
    t.it = 0;
    t.two_rows = 0;
    t.wT = 0.0;
    if (nt > 1) {
        double Tq = T1;
        if (Tq < m->torque_Nm[0]) Tq = m->torque_Nm[0];
        if (Tq > m->torque_Nm[nt - 1]) Tq = m->torque_Nm[nt - 1];
        while (t.it < nt - 2 && m->torque_Nm[t.it + 1] <= Tq) t.it++;
        t.two_rows = 1;
        t.wT = (Tq - m->torque_Nm[t.it]) / (m->torque_Nm[t.it + 1] - m->torque_Nm[t.it]);
    }
    row = ((size_t)t.it * m->n_temp + m->temp_ia) * m->P * m->n_phi;  /* [it][ia][0][:] */
    t.k0 = m->k_N_per_m + row;
    t.e0 = m->e_m + row;
    t.next_temp = (size_t)m->P * m->n_phi;
    t.next_torque = (size_t)m->n_temp * t.next_temp;
    return t;
}

/* angle cell (docs/model.md "Table lookup"): global cell nd = floor(theta1/dphi),
 * nodes i0 = nd mod N, i1 (periodic) and weight w.  The cell is carried from
 * one evaluation to the next: when nd moved by 0 or +-1 (always, within an RK4
 * step of a resolved angle grid) i0 follows without an integer division.  The
 * value does not depend on the carried cell, only the work does. */
typedef struct {
    long long nd;
    int i0, i1;
    double w;
} gk_ph;

/* no carried cell: more than one cell away from every nd that occurs */
#define GK_CELL_NONE (-(1LL << 62))
#define GK_PH_NONE {GK_CELL_NONE, 0, 1, 0.0}

GK_INLINE void phi_cell(const gk_model *m, double theta1, gk_ph *c)
{
    int N = m->n_phi, i0;
    double s = theta1 * m->inv_dphi;
    long long nd, dn;
    if (!(s > -GK_CELL_LIMIT && s < GK_CELL_LIMIT)) {
        /* an angle of 2^52 cells or more is an integer number of cells (w = 0);
         * non-finite: node 0 and w = NaN (the state is non-finite, gk_do_step
         * reports it); never index out of bounds */
        if (isfinite(s)) {
            double r = fmod(s, (double)N);
            if (r < 0.0) r += (double)N;
            i0 = (int)r;
            c->w = 0.0;
        } else {
            i0 = 0;
            c->w = s - s;
        }
        c->nd = GK_CELL_NONE;
        c->i0 = i0;
        c->i1 = (i0 + 1 == N) ? 0 : i0 + 1;
        return;
    }
    nd = (long long)s;               /* toward zero ... */
    if ((double)nd > s) nd -= 1;     /* ... so floor(s) */
    dn = nd - c->nd;
    if (dn == 0) {
        i0 = c->i0;
    } else if (dn == 1) {
        i0 = (c->i0 + 1 == N) ? 0 : c->i0 + 1;
    } else if (dn == -1) {
        i0 = (c->i0 == 0) ? N - 1 : c->i0 - 1;
    } else {
        long long r = nd % N;
        if (r < 0) r += N;
        i0 = (int)r;
    }
    c->nd = nd;
    c->i0 = i0;
    c->i1 = (i0 + 1 == N) ? 0 : i0 + 1;
    c->w = s - (double)nd;
}

/* value and phi-slope of one row of array A at the cell */
GK_INLINE void row_interp(const double *A, const gk_ph *c, double inv_dphi, double *val, double *slope)
{
    double a0 = A[c->i0], a1 = A[c->i1];
    *val = a0 + c->w * (a1 - a0);
    if (slope != NULL) *slope = (a1 - a0) * inv_dphi;
}

/* row_interp on the nodes of the selected temperature: with two slices each node
 * is A[i] + wT*(B[i] - A[i]) first (docs/model.md "Temperature axis"); B is the
 * next temperature slice of the same torque row */
GK_INLINE void row_interp_t(const gk_model *m, const gk_tq *t, const double *A, const gk_ph *c,
                                double *val, double *slope)
{
    double a0, a1;
    const double *B;
    if (!m->temp_two) {
        row_interp(A, c, m->inv_dphi, val, slope);
        return;
    }
    B = A + t->next_temp;
    a0 = A[c->i0];
    a1 = A[c->i1];
    a0 = a0 + m->temp_w * (B[c->i0] - a0);
    a1 = a1 + m->temp_w * (B[c->i1] - a1);
    *val = a0 + c->w * (a1 - a0);
    if (slope != NULL) *slope = (a1 - a0) * m->inv_dphi;
}

/* node i of row A at the selected temperature (row_interp_t's node blend) */
GK_INLINE double node_t(const gk_model *m, const gk_tq *t, const double *A, int i)
{
    double a = A[i];
    if (m->temp_two) a = a + m->temp_w * (A[t->next_temp + i] - a);
    return a;
}

/* value and slope at cell weight w in a cell holding a contact-zone edge (cuts lo, hi), on
 * the side ws selects (model_rhs._edge_line); returns 1 inside the zone.  tb: temperature
 * blend of the nodes (NULL: the row as stored, the backlash) */
GK_INLINE int edge_line(const gk_model *m, const gk_tq *tb, const double *A, const gk_ph *c, double ws,
                        double lo, double hi, double *val, double *slope)
{
    int N = m->n_phi;
    double a, b;
    if (ws < lo) {
        int im = (c->i0 == 0) ? N - 1 : c->i0 - 1;
        a = tb ? node_t(m, tb, A, im) : A[im];
        b = tb ? node_t(m, tb, A, c->i0) : A[c->i0];
        *val = b + c->w * (b - a);
        if (slope != NULL) *slope = (b - a) * m->inv_dphi;
        return 1;
    }
    if (ws >= hi) {
        int i2 = (c->i1 == N - 1) ? 0 : c->i1 + 1;
        a = tb ? node_t(m, tb, A, c->i1) : A[c->i1];
        b = tb ? node_t(m, tb, A, i2) : A[i2];
        *val = a + (c->w - 1.0) * (b - a);
        if (slope != NULL) *slope = (b - a) * m->inv_dphi;
        return 1;
    }
    a = tb ? node_t(m, tb, A, c->i0) : A[c->i0];
    b = tb ? node_t(m, tb, A, c->i1) : A[c->i1];
    *val = a + c->w * (b - a);
    if (slope != NULL) *slope = (b - a) * m->inv_dphi;
    return 0;
}

/* slot_tables in a cell holding a contact-zone edge (model_rhs._kvals_edge) */
static void slot_tables_edge(const gk_model *m, const gk_tq *t, const gk_ph *c, int j, double ws, double lo,
                             double hi, double *k, double *e, double *de_dphi, double *b)
{
    size_t off = (size_t)j * m->n_phi;
    const double *ka = t->k0 + off;
    const double *ea = t->e0 + off;
    double kv, ev, es, kd;
    int inz = edge_line(m, t, ka, c, ws, lo, hi, &kv, &kd);
    edge_line(m, t, ea, c, ws, lo, hi, &ev, &es);
    if (t->two_rows) {
        double kv2, ev2, es2;
        edge_line(m, t, ka + t->next_torque, c, ws, lo, hi, &kv2, &kd);
        edge_line(m, t, ea + t->next_torque, c, ws, lo, hi, &ev2, &es2);
        kv = kv + t->wT * (kv2 - kv);
        ev = ev + t->wT * (ev2 - ev);
        es = es + t->wT * (es2 - es);
    }
    if (!inz || kv < 0.0) kv = 0.0;
    *k = kv;
    *e = ev;
    if (de_dphi != NULL) *de_dphi = es;
    if (b != NULL) {
        double bv;
        edge_line(m, NULL, m->backlash_half_m + off, c, ws, lo, hi, &bv, NULL);
        *b = bv;
    }
}

/* k, e, de/dphi, b of slot j; sel: the side of a contact-zone cut (model_rhs._kvals_sel:
 * -1 the side of the weight, 0 in-zone left, 1 outside, 2 in-zone right) */
GK_INLINE void slot_tables(const gk_model *m, const gk_tq *t, const gk_ph *c, int j, int sel,
                               double *k, double *e, double *de_dphi, double *b)
{
    size_t off = (size_t)j * m->n_phi;
    const double *ka = t->k0 + off;
    const double *ea = t->e0 + off;
    double kv, ev, es;
    if (m->zone_cuts != NULL) {
        double lo = m->zone_cuts[off + c->i0];
        if (lo >= 0.0) {
            double ws = c->w;
            if (sel == 0) ws = -1.0;
            else if (sel == 1) ws = lo;
            else if (sel == 2) ws = 2.0;
            slot_tables_edge(m, t, c, j, ws, lo, m->zone_cuts[(size_t)m->P * m->n_phi + off + c->i0], k, e,
                             de_dphi, b);
            return;
        }
    }
    row_interp_t(m, t, ka, c, &kv, NULL);
    row_interp_t(m, t, ea, c, &ev, &es);
    if (t->two_rows) {
        double kv2, ev2, es2;
        row_interp_t(m, t, ka + t->next_torque, c, &kv2, NULL);
        row_interp_t(m, t, ea + t->next_torque, c, &ev2, &es2);
        kv = kv + t->wT * (kv2 - kv);
        ev = ev + t->wT * (ev2 - ev);
        es = es + t->wT * (es2 - es);
    }
    *k = kv;
    *e = ev;
    if (de_dphi != NULL) *de_dphi = es;
    if (b != NULL) row_interp(m->backlash_half_m + off, c, m->inv_dphi, b, NULL);
}

#endif /* GK_LOOKUP_H */
