/*
 * gk_stops.c -- where the event integrators stop (docs/model.md "rk4_kink", "rk4_seg",
 * docs/native.md "rk4_node"): the node kink flags computed from the tables (rk4_node: the
 * nodes where the tables bend; rk4_seg: the big kinks, the contact_zone-flag changes and the
 * cells with a contact-zone edge) and the held segment between two stops, with the side of
 * every pair's contact-zone cut held in a cell.  The arithmetic of gearfmu/dynamics/model_rhs.py
 * (_node_flags, _seg_flags, _zone_sel) and integrators.py (_seg_up, _seg_down, _seg_start,
 * _seg_cross).
 */
#include "gk_internal.h"

/* rk4_node node kink flags (gearkernel.h; as _node_flags in gearfmu/dynamics/model_rhs.py) */
static int bent_tol(double a0, double a1, double a2, double tol)
{
    double d = (a2 - a1) - (a1 - a0);
    double s = (fabs(a0) + fabs(a1)) + fabs(a2);
    return !(fabs(d) <= tol * s);
}

static int kinked(double a0, double a1, double a2)
{
    return bent_tol(a0, a1, a2, GK_NODE_KINK_TOL);
}

void gki_node_flags(gk_model *m)
{
    int N = m->n_phi, P = m->P, rows = m->n_torque * m->n_temp, i, j, r;
    if (N > GK_NODE_FLAGS_MAX) return;   /* every node counts as flagged (node_flagged) */
    for (i = 0; i < N; ++i) {
        int im = (i == 0) ? N - 1 : i - 1, ip = (i == N - 1) ? 0 : i + 1, bent = 0, zone = 0, ebent = 0;
        for (j = 0; j < P; ++j) {
            const double *b = m->backlash_half_m + (size_t)j * N;
            int pos = 0, nonpos = 0;
            if (kinked(b[im], b[i], b[ip])) bent = 1;
            if (bent_tol(b[im], b[i], b[ip], GK_SEG_KINK_TOL)) zone = 1;   /* rk4_seg: a big kink */
            for (r = 0; r < rows; ++r) {
                const double *k = m->k_N_per_m + ((size_t)r * P + j) * N;
                const double *e = m->e_m + ((size_t)r * P + j) * N;
                double ka = k[im], kb = k[i], kc = k[ip], ml, mr;
                if (kinked(e[im], e[i], e[ip])) ebent = 1;
                if (kinked(ka, kb, kc) || ebent) bent = 1;
                if (bent_tol(ka, kb, kc, GK_SEG_KINK_TOL) || bent_tol(e[im], e[i], e[ip], GK_SEG_KINK_TOL)) zone = 1;
                ml = ka + 0.5 * (kb - ka);
                mr = kb + 0.5 * (kc - kb);
                if (ml > 0.0 && mr > 0.0) pos = 1;
                else if (!(ml > 0.0) && !(mr > 0.0)) nonpos = 1;
                else { pos = 1; nonpos = 1; }
            }
            if (pos && nonpos) {
                bent = 1;
                zone = 1;
            }
            if (m->zone_cuts != NULL && (m->zone_cuts[(size_t)j * N + im] >= 0.0 || m->zone_cuts[(size_t)j * N + i] >= 0.0))
                zone = 1;   /* rk4_seg: a contact-zone edge in a cell of the node */
        }
        m->node_kink[i] = (unsigned char)(bent | (zone << 1) | (ebent << 2));
    }
}

/* stop flag of global node n (an integer value), node n mod N: rk4_node the kink flag;
 * rk4_seg the contact_zone-flag change, a big kink (GK_SEG_KINK_TOL) or a contact-zone edge
 * in one of the node's two cells (model_rhs._seg_flags), in the multi-mesh kernels also a node
 * where e bends (m->seg_stops; gearbox/kernels.stop_flags) */
static int node_flagged(const gk_model *m, double n)
{
    int N = m->n_phi, i0;
    double r;
    if (N > GK_NODE_FLAGS_MAX) return 1;
    r = n - (double)N * floor(n / (double)N);
    i0 = (int)r;
    if (i0 < 0) i0 = 0;
    if (i0 >= N) i0 = N - 1;
    return (m->node_kink[i0] & ((m->integrator == GK_INTEGRATOR_RK4_SEG) ? m->seg_stops : GK_STOPS_NODE)) != 0;
}

/* first stop above position n (global node units; model_rhs / integrators._seg_up): a
 * contact-zone cut, or the next node (rk4_kink) or flagged node (rk4_node), at most
 * floor(n) + N; last stop below n (_seg_down), at least ceil(n) - N */
static double seg_up(const gk_model *m, double n, int node)
{
    double c, top, q, f;
    if (!(fabs(n) < GK_CELL_LIMIT)) return n + 1.0;   /* doubles no longer count single nodes */
    c = floor(n);
    if (m->zone_cuts != NULL) {
        int i0 = gki_node_index(m->n_phi, c);
        f = gki_cut_above(m, i0, n - c, 0);
        while (f < 1.0 && !(c + f > n)) f = gki_cut_above(m, i0, f, 0);   /* n - c rounds: above n */
        if (f < 1.0) return c + f;
    }
    if (!node) return c + 1.0;
    top = c + m->n_phi;
    q = c + 1.0;
    if (m->integrator == GK_INTEGRATOR_RK4_SEG && m->n_phi <= GK_NODE_FLAGS_MAX) {
        /* every cell with a cut has both nodes flagged: the first flag comes first */
        int i = gki_node_index(m->n_phi, q);
        while (q < top) {
            if ((m->node_kink[i] & m->seg_stops) != 0) return q;
            q += 1.0;
            if (++i == m->n_phi) i = 0;
        }
        return q;
    }
    while (q < top) {
        if (node_flagged(m, q)) return q;
        if (m->zone_cuts != NULL) {
            f = gki_cut_above(m, gki_node_index(m->n_phi, q), 0.0, 0);
            if (f < 1.0) return q + f;
        }
        q += 1.0;
    }
    return q;
}

static double seg_down(const gk_model *m, double n, int node)
{
    double c, bottom, q, f;
    if (!(fabs(n) < GK_CELL_LIMIT)) return n - 1.0;
    c = ceil(n) - 1.0;
    if (m->zone_cuts != NULL) {
        int i0 = gki_node_index(m->n_phi, c);
        f = gki_cut_below(m, i0, n - c, 0);
        while (f > 0.0 && !(c + f < n)) f = gki_cut_below(m, i0, f, 0);   /* below n */
        if (f > 0.0) return c + f;
    }
    if (!node) return c;
    bottom = c + 1.0 - m->n_phi;
    q = c;
    if (m->integrator == GK_INTEGRATOR_RK4_SEG && m->n_phi <= GK_NODE_FLAGS_MAX) {
        int i = gki_node_index(m->n_phi, q);
        while (q > bottom) {
            if ((m->node_kink[i] & m->seg_stops) != 0) return q;
            q -= 1.0;
            if (--i < 0) i = m->n_phi - 1;
        }
        return q;
    }
    while (q > bottom) {
        if (node_flagged(m, q)) return q;
        if (m->zone_cuts != NULL) {
            f = gki_cut_below(m, gki_node_index(m->n_phi, q - 1.0), 1.0, 0);
            if (f > 0.0) return q - 1.0 + f;
        }
        q -= 1.0;
    }
    return q;
}

/* held segment at a step start (theta1 = th): [nd, nd + 1] (rk4_kink); rk4_node: nd to the
 * next flagged node above for om >= 0, the last flagged node below nd + 1 to nd + 1 for
 * om < 0; a contact-zone cut in cell nd splits it (integrators._seg_start) */
void gki_seg_start(const gk_model *m, gk_mode *md, int node, double om, double th)
{
    double lo = md->nd, hi = md->nd + 1.0;
    if (m->zone_cuts != NULL) {
        int i0 = gki_node_index(m->n_phi, md->nd);
        double f = th * m->inv_dphi - md->nd, fb = gki_cut_below(m, i0, f, 1), fa = gki_cut_above(m, i0, f, 1);
        if (fb > 0.0) lo = md->nd + fb;
        if (fa < 1.0) hi = md->nd + fa;
    }
    if (node && om < 0.0) {
        md->hi = hi;
        md->lo = seg_down(m, hi, 1);
    } else {
        md->lo = lo;
        md->hi = seg_up(m, lo, node);
    }
}

/* move the held segment across its end (up) or start; the held cell follows */
void gki_seg_cross(const gk_model *m, gk_mode *md, int up, int node)
{
    if (up) {
        double lo = md->hi;
        md->lo = lo;
        md->hi = seg_up(m, lo, node);
        md->nd = floor(lo);
    } else {
        double hi = md->lo;
        md->hi = hi;
        md->lo = seg_down(m, hi, node);
        md->nd = ceil(hi) - 1.0;
    }
}

/* the side of every pair's contact-zone cut held in cell nd of the segment [lo, hi), by the
 * segment's midpoint in the cell (model_rhs._zone_sel); -1 without an edge */
void gki_zone_sel(const gk_model *m, gk_mode *md)
{
    double a = (md->lo > md->nd) ? md->lo : md->nd;
    double b = (md->hi < md->nd + 1.0) ? md->hi : md->nd + 1.0;
    double wm = 0.5 * (a + b) - md->nd;
    int j, PN = m->P * m->n_phi;
    for (j = 0; j < m->P; ++j) {
        int sel = -1;
        if (m->zone_cuts != NULL) {
            size_t r = (size_t)j * m->n_phi + md->i0;
            double clo = m->zone_cuts[r];
            if (clo >= 0.0) {
                if (wm < clo) sel = 0;
                else if (wm >= m->zone_cuts[PN + r]) sel = 2;
                else sel = 1;
            }
        }
        md->zsel[j] = sel;
    }
}

