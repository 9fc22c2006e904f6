/*
 * gk_zones.c -- the contact-zone edges of the kernel (docs/model.md "Contact-zone edges"):
 * gk_zone_cuts, the sub-cell cuts of the table lookup, with the arithmetic of
 * gearfmu.tables.zones.zone_cuts, and the cuts of one cell the event integrators stop at.
 */
#include "gk_internal.h"

/* x mod n for a double x, on the nearest node within GK_ZONE_SNAP cells (gearfmu/tables/zones.py _wrap) */
static double zone_wrap(double x, int n)
{
    double r = fmod(x, (double)n), rn;
    if (r < 0.0) r += (double)n;
    rn = floor(r + 0.5);
    if (fabs(r - rn) <= GK_ZONE_SNAP) r = rn;   /* an edge on a node stays on it */
    return r;
}

static int imod(long long a, int n)
{
    long long r = a % n;
    if (r < 0) r += n;
    return (int)r;
}

/* the arithmetic of gearfmu.tables.zones.zone_cuts (docs/model.md "Contact-zone edges") */
int gk_zone_cuts(int P, int n_phi, double phi_period_rad, double mesh_period_rad,
                 double in_rad, double out_rad, double *cuts)
{
    double inv, ppm, a_in, a_out, nm;
    double *lo, *hi;
    long long n_mesh, mm;
    int N = n_phi, i;
    if (cuts == NULL || P < 1 || N < 2 || !gki_finite_pos(phi_period_rad) || !gki_finite_pos(mesh_period_rad))
        return GK_ERR_MODEL;
    if (!isfinite(in_rad) || !isfinite(out_rad)) return GK_ERR_PARAM;
    inv = (double)N / phi_period_rad;
    if (!((out_rad - in_rad) * inv >= GK_ZONE_MIN_CELLS)) return GK_ERR_PARAM;
    nm = floor(phi_period_rad / mesh_period_rad + 0.5);
    if (!(nm >= 1.0 && nm <= 1e9)) return GK_ERR_MODEL;
    n_mesh = (long long)nm;
    ppm = (double)N / (double)n_mesh;
    a_in = in_rad * inv;
    a_out = out_rad * inv;
    lo = cuts;
    hi = cuts + (size_t)P * N;
    for (i = 0; i < P * N; ++i) {
        lo[i] = -1.0;
        hi[i] = 1.0;
    }
    for (mm = 0; mm < n_mesh; ++mm) {
        size_t r = (size_t)(mm % P) * N;
        double start = (double)mm * ppm, sv, fl, f;
        int c;
        sv = zone_wrap(start + a_in, N);     /* meshing-in */
        fl = floor(sv);
        f = sv - fl;
        c = (f == 0.0) ? imod((long long)fl - 1, N) : imod((long long)fl, N);
        if (lo[r + c] < 0.0) lo[r + c] = 0.0;
        if (((f == 0.0) ? 1.0 : f) < hi[r + c]) hi[r + c] = (f == 0.0) ? 1.0 : f;
        sv = zone_wrap(start + a_out, N);    /* meshing-out */
        fl = floor(sv);
        f = sv - fl;
        if (f == 0.0) {
            c = imod((long long)fl - 1, N);
            if (lo[r + c] < 0.0) lo[r + c] = 0.0;
            if (lo[r + c] < 1.0) lo[r + c] = 1.0;
            c = imod((long long)fl, N);
            if (lo[r + c] < 0.0) lo[r + c] = 0.0;
        } else {
            c = imod((long long)fl, N);
            if (lo[r + c] < 0.0) lo[r + c] = 0.0;
            if (lo[r + c] < f) lo[r + c] = f;
        }
    }
    return GK_OK;
}

/* the zones of Model Exchange (gearkernel.h): the arithmetic of gk_zone_cuts before its marks */
int gk_set_zone_edges(gk_model *m, double mesh_period_rad, double in_rad, double out_rad)
{
    double inv, nm;
    if (m == NULL || !gki_finite_pos(mesh_period_rad)) return GK_ERR_MODEL;
    if (!isfinite(in_rad) || !isfinite(out_rad)) return GK_ERR_PARAM;
    inv = (double)m->n_phi / m->phi_period_rad;
    if (!((out_rad - in_rad) * inv >= GK_ZONE_MIN_CELLS)) return GK_ERR_PARAM;
    nm = floor(m->phi_period_rad / mesh_period_rad + 0.5);
    if (!(nm >= 1.0 && nm <= 1e9)) return GK_ERR_MODEL;
    m->zone_n_mesh = nm;
    m->zone_ppm = (double)m->n_phi / nm;
    m->zone_in = in_rad * inv;
    m->zone_out = out_rad * inv;
    return GK_OK;
}

/* contact-zone cuts of cell i0 over all slots (model_rhs._cut_above / _cut_below): the
 * smallest above f (at or above with incl) and below 1, 2.0 for none; the largest below f
 * (at or below with incl) and above 0, -1.0 for none */
double gki_cut_above(const gk_model *m, int i0, double f, int incl)
{
    double best = 2.0;
    int j, PN = m->P * m->n_phi;
    if (m->zone_cuts == NULL) return best;
    for (j = 0; j < m->P; ++j) {
        size_t r = (size_t)j * m->n_phi + i0;
        double clo = m->zone_cuts[r], chi;
        if (!(clo >= 0.0)) continue;
        chi = m->zone_cuts[PN + r];
        if ((clo > f || (incl && clo == f)) && clo < 1.0 && clo < best) best = clo;
        if ((chi > f || (incl && chi == f)) && chi < 1.0 && chi < best) best = chi;
    }
    return best;
}

double gki_cut_below(const gk_model *m, int i0, double f, int incl)
{
    double best = -1.0;
    int j, PN = m->P * m->n_phi;
    if (m->zone_cuts == NULL) return best;
    for (j = 0; j < m->P; ++j) {
        size_t r = (size_t)j * m->n_phi + i0;
        double clo = m->zone_cuts[r], chi;
        if (!(clo >= 0.0)) continue;
        chi = m->zone_cuts[PN + r];
        if ((clo < f || (incl && clo == f)) && clo > 0.0 && clo > best) best = clo;
        if ((chi < f || (incl && chi == f)) && chi > 0.0 && chi > best) best = chi;
    }
    return best;
}
