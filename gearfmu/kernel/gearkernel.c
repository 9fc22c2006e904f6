/*
 * gearkernel.c -- C99 implementation of docs/model.md (the contract shared
 * with the numba native solver gearfmu/native.py).
 *
 * Physics: seed 003 (Xu et al., Appl. Sci. 2022) eq 1-6: per tooth-pair slot j
 * the deflection d = x - e_j (eq 6), the piecewise-linear backlash force with
 * half backlash b_j, a viscous damping c = 2 zeta sqrt(k_mean m_e) (eq 7-9);
 * two inertias (eq 1-2) written in the pinion angle and the dynamic
 * transmission error x.  The default damping rule is Modelica's ElastoBacklash
 * (damping force never exceeds the spring force, the pair never pulls).
 *
 * Build: gcc -O2 -fPIC -shared -ffp-contract=off -std=c99 gearkernel.c -lm
 * (-ffp-contract=off: no fused multiply-add, so the arithmetic is the one
 * written here, the same as the native solver's).
 *
 * No globals, no allocation, no abort: every function returns a status.
 */
#include "gearkernel.h"

#include <math.h>
#include <stddef.h>

int gk_abi_version(void) { return GK_ABI_VERSION; }
int gk_sizeof_model(void) { return (int)sizeof(gk_model); }
int gk_sizeof_state(void) { return (int)sizeof(gk_state); }
int gk_n_outputs(int P) { return GK_OUT_PAIR_FORCE + 2 * P; }

static int finite_pos(double v) { return isfinite(v) && v > 0.0; }

int gk_init(gk_model *m, int P, int n_phi, int n_torque,
            const double *torque_Nm, const double *k_N_per_m,
            const double *e_m, const double *backlash_half_m,
            double phi_period_rad, double Rb1_m, double Rb2_m,
            double I1_kgm2, double I2_kgm2, double k_mean_N_per_m)
{
    int i;
    if (m == NULL || torque_Nm == NULL || k_N_per_m == NULL || e_m == NULL || backlash_half_m == NULL)
        return GK_ERR_MODEL;
    if (P < 1 || n_phi < 2 || n_torque < 1)
        return GK_ERR_MODEL;
    if (!finite_pos(phi_period_rad) || !finite_pos(Rb1_m) || !finite_pos(Rb2_m) ||
        !finite_pos(I1_kgm2) || !finite_pos(I2_kgm2) || !finite_pos(k_mean_N_per_m))
        return GK_ERR_MODEL;
    for (i = 0; i < n_torque; ++i) {
        if (!isfinite(torque_Nm[i])) return GK_ERR_MODEL;
        if (i > 0 && !(torque_Nm[i] > torque_Nm[i - 1])) return GK_ERR_MODEL;
    }
    m->P = P;
    m->n_phi = n_phi;
    m->n_torque = n_torque;
    m->torque_Nm = torque_Nm;
    m->k_N_per_m = k_N_per_m;
    m->e_m = e_m;
    m->backlash_half_m = backlash_half_m;
    m->phi_period_rad = phi_period_rad;
    m->dphi_rad = phi_period_rad / n_phi;
    m->Rb1_m = Rb1_m;
    m->Rb2_m = Rb2_m;
    m->I1_kgm2 = I1_kgm2;
    m->I2_kgm2 = I2_kgm2;
    m->k_mean_N_per_m = k_mean_N_per_m;
    /* m_e = I1 I2 / (I1 Rb2^2 + I2 Rb1^2), seed 003 below eq 2 */
    m->m_e_kg = I1_kgm2 * I2_kgm2 / (I1_kgm2 * Rb2_m * Rb2_m + I2_kgm2 * Rb1_m * Rb1_m);
    m->damping_ratio = 0.0;
    m->c_Ns_per_m = 0.0;
    m->damping_model = GK_DAMPING_ELASTOBACKLASH;
    return GK_OK;
}

int gk_set_damping(gk_model *m, double damping_ratio, int damping_model)
{
    if (m == NULL) return GK_ERR_MODEL;
    if (!isfinite(damping_ratio) || damping_ratio < 0.0) return GK_ERR_PARAM;
    if (damping_model != GK_DAMPING_ELASTOBACKLASH && damping_model != GK_DAMPING_SEED003)
        return GK_ERR_PARAM;
    m->damping_ratio = damping_ratio;
    m->c_Ns_per_m = 2.0 * damping_ratio * sqrt(m->k_mean_N_per_m * m->m_e_kg);
    m->damping_model = damping_model;
    return GK_OK;
}

/* ---------------------------------------------------------------- lookup */

/* torque row bracket: rows it, it+1 and weight wT (docs/model.md "Torque axis") */
typedef struct {
    int it;
    int two_rows;
    double wT;
} gk_tq;

static gk_tq torque_bracket(const gk_model *m, double T1)
{
    gk_tq t;
    int nt = m->n_torque;
    double Tq;
    t.it = 0;
    t.two_rows = 0;
    t.wT = 0.0;
    if (nt == 1) return t;
    Tq = T1;
    if (Tq < m->torque_Nm[0]) Tq = m->torque_Nm[0];
    if (Tq > m->torque_Nm[nt - 1]) Tq = m->torque_Nm[nt - 1];
    while (t.it < nt - 2 && m->torque_Nm[t.it + 1] <= Tq) t.it++;
    t.two_rows = 1;
    t.wT = (Tq - m->torque_Nm[t.it]) / (m->torque_Nm[t.it + 1] - m->torque_Nm[t.it]);
    return t;
}

/* angle cell: indices i0, i1 (periodic) and weight w (docs/model.md "Table lookup") */
typedef struct {
    int i0, i1;
    double w;
} gk_ph;

static gk_ph phi_cell(const gk_model *m, double theta1)
{
    gk_ph c;
    double Phi = m->phi_period_rad;
    int N = m->n_phi;
    double phim = theta1 - Phi * floor(theta1 / Phi);
    double s = phim / m->dphi_rad;
    double fs = floor(s);
    if (fs >= (double)N) c.i0 = N - 1;
    else if (!(fs >= 0.0)) c.i0 = 0; /* also NaN (a non-finite substep): never index out of bounds */
    else c.i0 = (int)fs;
    c.w = s - c.i0;
    c.i1 = c.i0 + 1;
    if (c.i1 == N) c.i1 = 0;
    return c;
}

/* value and phi-slope of one row of array A at the cell */
static void row_interp(const double *A, const gk_ph *c, double dphi, double *val, double *slope)
{
    double a0 = A[c->i0], a1 = A[c->i1];
    *val = a0 + c->w * (a1 - a0);
    if (slope != NULL) *slope = (a1 - a0) / dphi;
}

/* k, e, de/dphi, b of slot j */
static void slot_tables(const gk_model *m, const gk_tq *t, const gk_ph *c, int j,
                        double *k, double *e, double *de_dphi, double *b)
{
    int P = m->P, N = m->n_phi;
    const double *ka = m->k_N_per_m + ((size_t)t->it * P + j) * N;
    const double *ea = m->e_m + ((size_t)t->it * P + j) * N;
    double kv, ev, es;
    row_interp(ka, c, m->dphi_rad, &kv, NULL);
    row_interp(ea, c, m->dphi_rad, &ev, &es);
    if (t->two_rows) {
        double kv2, ev2, es2;
        row_interp(ka + (size_t)P * N, c, m->dphi_rad, &kv2, NULL);
        row_interp(ea + (size_t)P * N, c, m->dphi_rad, &ev2, &es2);
        kv = kv + t->wT * (kv2 - kv);
        ev = ev + t->wT * (ev2 - ev);
        es = es + t->wT * (es2 - es);
    }
    *k = kv;
    *e = ev;
    if (de_dphi != NULL) *de_dphi = es;
    if (b != NULL) row_interp(m->backlash_half_m + (size_t)j * N, c, m->dphi_rad, b, NULL);
}

/* ----------------------------------------------------------------- forces */

/* Total mesh force F at (theta1, omega1, x, v); optionally per-pair forces
 * (pf[P]) and the stiffness of the pairs in contact (*kmesh). */
static double mesh_force(const gk_model *m, const gk_tq *t, double theta1, double omega1,
                         double x, double v, double *pf, double *kmesh)
{
    gk_ph c = phi_cell(m, theta1);
    double F = 0.0, ks = 0.0;
    int j;
    for (j = 0; j < m->P; ++j) {
        double k, e, es, b, d, fc, fd, Fj;
        int region;
        slot_tables(m, t, &c, j, &k, &e, &es, &b);
        d = x - e;                             /* seed 003 eq 6 */
        if (d > b) { fc = k * (d - b); region = 1; }
        else if (d < -b) { fc = k * (d + b); region = -1; }
        else { fc = 0.0; region = 0; }
        fd = m->c_Ns_per_m * (v - es * omega1);
        if (m->damping_model == GK_DAMPING_SEED003) {
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

static void deriv(const gk_model *m, const gk_tq *t, double T1, double T2,
                  const double *y, double *dy)
{
    double F = mesh_force(m, t, y[0], y[1], y[2], y[3], NULL, NULL);
    double Rb1 = m->Rb1_m, Rb2 = m->Rb2_m;
    dy[0] = y[1];
    dy[1] = (T1 - Rb1 * F) / m->I1_kgm2;
    dy[2] = y[3];
    dy[3] = Rb1 * (T1 - Rb1 * F) / m->I1_kgm2 - Rb2 * (Rb2 * F - T2) / m->I2_kgm2;
}

/* ------------------------------------------------------------ public API */

int gk_initialize(const gk_model *m, gk_state *s, double theta1_0_rad,
                  double omega1_0_rad_s, double T1_Nm)
{
    gk_tq t;
    gk_ph c;
    double Fm, S = 0.0, lo = 0.0, hi = 0.0;
    int j, it, any = 0;
    if (m == NULL || s == NULL) return GK_ERR_MODEL;
    if (!isfinite(theta1_0_rad) || !isfinite(omega1_0_rad_s) || !isfinite(T1_Nm))
        return GK_ERR_INPUT;
    t = torque_bracket(m, T1_Nm);
    c = phi_cell(m, theta1_0_rad);
    Fm = T1_Nm / m->Rb1_m;
    for (j = 0; j < m->P; ++j) {
        double k, e, b;
        slot_tables(m, &t, &c, j, &k, &e, NULL, &b);
        S += k;
        if (k > 0.0) {
            if (!any || e - b < lo) lo = e - b;
            if (!any || e + b > hi) hi = e + b;
            any = 1;
        }
    }
    if (!any || !(S > 0.0)) return GK_ERR_NOCONTACT;
    lo = lo - fabs(Fm) / S - 1e-12;
    hi = hi + fabs(Fm) / S + 1e-12;
    for (it = 0; it < 200; ++it) {
        double mid = 0.5 * (lo + hi), g = 0.0;
        for (j = 0; j < m->P; ++j) {
            double k, e, b, d;
            slot_tables(m, &t, &c, j, &k, &e, NULL, &b);
            if (!(k > 0.0)) continue;
            d = mid - e;
            if (d > b) g += k * (d - b);
            else if (d < -b) g += k * (d + b);
        }
        g = g - Fm;
        if (g < 0.0) lo = mid;
        else hi = mid;
    }
    s->theta1_rad = theta1_0_rad;
    s->omega1_rad_s = omega1_0_rad_s;
    s->x_m = 0.5 * (lo + hi);
    s->v_m_s = 0.0;
    return GK_OK;
}

double gk_substeps(double H_s, double h_max_s)
{
    double n;
    if (!finite_pos(H_s) || !finite_pos(h_max_s)) return 0.0;
    n = ceil(H_s / h_max_s * (1.0 - 1e-12));
    if (n < 1.0) n = 1.0;
    if (!(n <= GK_MAX_SUBSTEPS)) return 0.0;
    return n;
}

int gk_outputs(const gk_model *m, const gk_state *s, double T1_Nm, double *out)
{
    gk_tq t;
    double F, km;
    int j, P;
    if (m == NULL || s == NULL || out == NULL) return GK_ERR_MODEL;
    if (!isfinite(T1_Nm)) return GK_ERR_INPUT;
    P = m->P;
    t = torque_bracket(m, T1_Nm);
    F = mesh_force(m, &t, s->theta1_rad, s->omega1_rad_s, s->x_m, s->v_m_s,
                   out + GK_OUT_PAIR_FORCE, &km);
    /* docs/model.md: mesh_force is the sum of pair_force */
    out[GK_OUT_PINION_ANGLE] = s->theta1_rad;
    out[GK_OUT_PINION_SPEED] = s->omega1_rad_s;
    out[GK_OUT_GEAR_ANGLE] = (s->theta1_rad * m->Rb1_m - s->x_m) / m->Rb2_m;
    out[GK_OUT_GEAR_SPEED] = (s->omega1_rad_s * m->Rb1_m - s->v_m_s) / m->Rb2_m;
    out[GK_OUT_DTE] = s->x_m;
    out[GK_OUT_MESH_FORCE] = F;
    out[GK_OUT_MESH_STIFFNESS] = km;
    for (j = 0; j < P; ++j)
        out[GK_OUT_PAIR_FORCE + P + j] = (F != 0.0) ? out[GK_OUT_PAIR_FORCE + j] / F : 0.0;
    return GK_OK;
}

int gk_do_step(const gk_model *m, gk_state *s, double T1_Nm, double T2_Nm,
               double H_s, double h_max_s, double *out)
{
    gk_tq t;
    double y[4], k1[4], k2[4], k3[4], k4[4], yt[4];
    double n, h;
    long i, nsub;
    int q;
    if (m == NULL || s == NULL) return GK_ERR_MODEL;
    if (!isfinite(T1_Nm) || !isfinite(T2_Nm)) return GK_ERR_INPUT;
    n = gk_substeps(H_s, h_max_s);
    if (n == 0.0) return GK_ERR_STEP;
    nsub = (long)n;
    h = H_s / n;
    t = torque_bracket(m, T1_Nm);
    y[0] = s->theta1_rad;
    y[1] = s->omega1_rad_s;
    y[2] = s->x_m;
    y[3] = s->v_m_s;
    for (i = 0; i < nsub; ++i) {
        deriv(m, &t, T1_Nm, T2_Nm, y, k1);
        for (q = 0; q < 4; ++q) yt[q] = y[q] + 0.5 * h * k1[q];
        deriv(m, &t, T1_Nm, T2_Nm, yt, k2);
        for (q = 0; q < 4; ++q) yt[q] = y[q] + 0.5 * h * k2[q];
        deriv(m, &t, T1_Nm, T2_Nm, yt, k3);
        for (q = 0; q < 4; ++q) yt[q] = y[q] + h * k3[q];
        deriv(m, &t, T1_Nm, T2_Nm, yt, k4);
        for (q = 0; q < 4; ++q)
            y[q] = y[q] + h / 6.0 * (k1[q] + 2.0 * k2[q] + 2.0 * k3[q] + k4[q]);
    }
    for (q = 0; q < 4; ++q)
        if (!isfinite(y[q])) return GK_ERR_NONFINITE;
    s->theta1_rad = y[0];
    s->omega1_rad_s = y[1];
    s->x_m = y[2];
    s->v_m_s = y[3];
    if (out != NULL) return gk_outputs(m, s, T1_Nm, out);
    return GK_OK;
}
