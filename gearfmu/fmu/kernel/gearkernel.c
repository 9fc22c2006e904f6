/*
 * gearkernel.c -- C99 implementation of docs/model.md (the contract shared
 * with the numba native solver gearfmu/dynamics/native.py).
 *
 * Physics: seed 003 (Xu et al., Appl. Sci. 2022) eq 1-6: per tooth-pair slot j
 * the deflection d = x - e_j (eq 6), the piecewise-linear backlash force with
 * half backlash b_j, a viscous damping c = 2 zeta sqrt(k_mean m_e) (eq 7-9);
 * two inertias (eq 1-2) written in the pinion angle and the dynamic
 * transmission error x.  The default damping rule is Modelica's ElastoBacklash
 * (damping force never exceeds the spring force, the pair never pulls).
 *
 * Build: gcc -O2 -fPIC -shared -ffp-contract=off -std=c99 gearkernel.c -lm
 * (the flags are gearfmu.fmu.pythonfmu_build.CFLAGS).  -ffp-contract=off: no fused
 * multiply-add, so the arithmetic is the one written here, the same as the
 * native solver's.  -O2 rather than -O3: no optimisation level changes a
 * floating-point result as long as fast-math stays off (no -Ofast, -ffast-math
 * or -fassociative-math), so -O2 and -O3 give the same doubles; -O2 is the
 * level gcc, clang and MSVC (/O2) all treat alike, and the hot path does not
 * depend on -O3's inlining and loop peeling because it is inlined explicitly
 * (GK_INLINE) and the RK4 combinations are written per component.  Identical results on every platform further need IEEE double
 * arithmetic (SSE2 on x86; the x87 unit of 32-bit x86 rounds to 80 bits) and
 * a correctly rounded sqrt (IEEE 754; used once, for c).  The table lookup
 * multiplies by the precomputed 1/dphi and takes floor by an integer
 * conversion (docs/model.md "Table lookup"), so the RK4 loop calls no libm
 * function.
 *
 * No globals, no allocation, no abort: every function returns a status.
 */
#include "gearkernel.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>

/* the right-hand side and its lookups are inlined into the integrator loops
 * (inlining changes no result: every operation stays as written) */
#if defined(__GNUC__) || defined(__clang__)
#define GK_INLINE static inline __attribute__((always_inline))
#elif defined(_MSC_VER)
#define GK_INLINE static __forceinline
#else
#define GK_INLINE static inline
#endif

int gk_abi_version(void) { return GK_ABI_VERSION; }
int gk_sizeof_model(void) { return (int)sizeof(gk_model); }
int gk_sizeof_state(void) { return (int)sizeof(gk_state); }
int gk_n_outputs(int P) { return GK_OUT_PAIR_FORCE + 2 * P; }

static inline int finite_pos(double v) { return isfinite(v) && v > 0.0; }

static void node_flags(gk_model *m);

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
    m->inv_dphi = (double)n_phi / phi_period_rad;
    m->Rb1_m = Rb1_m;
    m->Rb2_m = Rb2_m;
    m->I1_kgm2 = I1_kgm2;
    m->I2_kgm2 = I2_kgm2;
    m->inv_I1 = 1.0 / I1_kgm2;
    m->inv_I2 = 1.0 / I2_kgm2;
    m->seg_gw = Rb1_m / I1_kgm2;
    m->seg_gv = Rb1_m * (Rb1_m / I1_kgm2) + Rb2_m * (Rb2_m / I2_kgm2);
    m->k_mean_N_per_m = k_mean_N_per_m;
    /* m_e = I1 I2 / (I1 Rb2^2 + I2 Rb1^2), seed 003 below eq 2 */
    m->m_e_kg = I1_kgm2 * I2_kgm2 / (I1_kgm2 * Rb2_m * Rb2_m + I2_kgm2 * Rb1_m * Rb1_m);
    m->damping_ratio = 0.0;
    m->c_Ns_per_m = 0.0;
    m->damping_model = GK_DAMPING_ELASTOBACKLASH;
    m->integrator = GK_INTEGRATOR_RK4;
    m->n_temp = 1;
    m->temperature_C = NULL;
    m->temp_ia = 0;
    m->temp_two = 0;
    m->temp_w = 0.0;
    m->temperature_now_C = 0.0;
    m->zone_cuts = NULL;
    node_flags(m);
    return GK_OK;
}

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
    if (cuts == NULL || P < 1 || N < 2 || !finite_pos(phi_period_rad) || !finite_pos(mesh_period_rad))
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

int gk_set_zone_cuts(gk_model *m, const double *cuts)
{
    if (m == NULL) return GK_ERR_MODEL;
    m->zone_cuts = cuts;
    node_flags(m);   /* the rk4_seg stops include the cells with an edge */
    return GK_OK;
}

int gk_set_temperature_axis(gk_model *m, int n_temp, const double *temperature_C)
{
    int i;
    if (m == NULL || temperature_C == NULL || n_temp < 1) return GK_ERR_MODEL;
    for (i = 0; i < n_temp; ++i) {
        if (!isfinite(temperature_C[i])) return GK_ERR_MODEL;
        if (i > 0 && !(temperature_C[i] > temperature_C[i - 1])) return GK_ERR_MODEL;
    }
    m->n_temp = n_temp;
    m->temperature_C = temperature_C;
    m->temp_ia = 0;
    m->temp_two = 0;
    m->temp_w = 0.0;
    m->temperature_now_C = temperature_C[0];
    node_flags(m);
    return GK_OK;
}

int gk_set_temperature(gk_model *m, double T)
{
    int ia = 0, nt;
    if (m == NULL) return GK_ERR_MODEL;
    if (!isfinite(T)) return GK_ERR_INPUT;
    nt = m->n_temp;
    if (m->temperature_C == NULL) return GK_ERR_INPUT; /* no axis: nothing to select */
    if (T < m->temperature_C[0] || T > m->temperature_C[nt - 1]) return GK_ERR_INPUT;
    while (ia < nt - 1 && m->temperature_C[ia + 1] <= T) ia++;
    m->temp_ia = ia;
    if (m->temperature_C[ia] == T) {
        m->temp_two = 0;
        m->temp_w = 0.0;
    } else {
        m->temp_two = 1;
        m->temp_w = (T - m->temperature_C[ia]) / (m->temperature_C[ia + 1] - m->temperature_C[ia]);
    }
    m->temperature_now_C = T;
    return GK_OK;
}

int gk_set_integrator(gk_model *m, int integrator)
{
    if (m == NULL) return GK_ERR_MODEL;
    if (integrator == GK_INTEGRATOR_RK4) {
        m->integrator = integrator;
        return GK_OK;
    }
    if ((integrator == GK_INTEGRATOR_RK4_KINK || integrator == GK_INTEGRATOR_RK4_NODE
         || integrator == GK_INTEGRATOR_RK4_SEG) && m->P <= GK_KINK_MAX_SLOTS) {
        m->integrator = integrator;
        return GK_OK;
    }
    return GK_ERR_PARAM;
}

int gk_set_damping(gk_model *m, double damping_ratio, int damping_model)
{
    if (m == NULL) return GK_ERR_MODEL;
    if (!isfinite(damping_ratio) || damping_ratio < 0.0) return GK_ERR_PARAM;
    if (damping_model != GK_DAMPING_ELASTOBACKLASH && damping_model != GK_DAMPING_CONTACT_ZONE)
        return GK_ERR_PARAM;
    m->damping_ratio = damping_ratio;
    m->c_Ns_per_m = 2.0 * damping_ratio * sqrt(m->k_mean_N_per_m * m->m_e_kg);
    m->damping_model = damping_model;
    return GK_OK;
}

/* ---------------------------------------------------------------- lookup */

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
/* |s| below 2^52: nd and s - nd are exact in doubles and fit a long long */
#define GK_CELL_LIMIT 4503599627370496.0

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
        d = x - e;                             /* seed 003 eq 6 */
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

GK_INLINE void deriv(const gk_model *m, const gk_tq *t, gk_ph *c, double T1, double T2,
                         const double *y, double *dy)
{
    double F = mesh_force(m, t, c, y[0], y[1], y[2], y[3], NULL, NULL);
    double Rb1 = m->Rb1_m, Rb2 = m->Rb2_m;
    dy[0] = y[1];
    dy[1] = (T1 - Rb1 * F) * m->inv_I1;
    dy[2] = y[3];
    dy[3] = Rb1 * (T1 - Rb1 * F) * m->inv_I1 - Rb2 * (Rb2 * F - T2) * m->inv_I2;
}


/* RK4 stage input out = y + a*k and the update y + h/6.0*(((k1 + 2k2) + 2k3) + k4),
 * written out per component so that the state stays in registers at -O2 */
GK_INLINE void axpy4(const double *y, double a, const double *k, double *out)
{
    out[0] = y[0] + a * k[0];
    out[1] = y[1] + a * k[1];
    out[2] = y[2] + a * k[2];
    out[3] = y[3] + a * k[3];
}

GK_INLINE void rk4_update(double *y, double h, const double *k1, const double *k2, const double *k3,
                          const double *k4)
{
    double h6 = h / 6.0;
    y[0] = y[0] + h6 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]);
    y[1] = y[1] + h6 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]);
    y[2] = y[2] + h6 * (k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2]);
    y[3] = y[3] + h6 * (k1[3] + 2.0 * k2[3] + 2.0 * k3[3] + k4[3]);
}

/* --------------------------------------------------------------- rk4_kink
 * docs/model.md "rk4_kink": the mode (table cell nd and, per pair, region reg,
 * elastobacklash sub-mode sub, contact_zone flag kpos) is held during each RK4
 * step; guards (>= 0 while the mode holds) are tested at the step end, the
 * earliest zero is located on the cubic Hermite interpolant of the step, the
 * step is retaken exactly to it and the mode switched there.  Same arithmetic
 * as gearfmu/dynamics/native.py (_kink_substep and friends). */

#define KINK_TOL_S 1e-12
#define KINK_MAX_IT 60

typedef struct {
    double nd;                       /* global cell index (integer value) */
    double lo, hi;                   /* held segment [lo, hi): global node indices (rk4_kink: nd, nd + 1) */
    int i0, i1;
    int reg[GK_KINK_MAX_SLOTS];      /* 1 drive, -1 back, 0 separated */
    int sub[GK_KINK_MAX_SLOTS];      /* 0 two (2 fc), 1 sum (fc + fd), 2 zero */
    int kpos[GK_KINK_MAX_SLOTS];     /* contact_zone: k > 0 inside the cell */
    int zsel[GK_KINK_MAX_SLOTS];     /* side of a contact-zone cut held in the cell (zone_sel) */
    double cl, ch;                   /* rk4_seg: floor(lo), ceil(hi) - 1 (the cells of the segment) */
    /* rk4_seg: the table values of every pair at theta1 = fth read by the last seg_end, and
     * fsal = 1 when the substep ended there with the segment [flo, fhi) and the mode unchanged
     * (seg_first reuses them: the same lookup) */
    int fsal;
    double fth, flo, fhi;
    double fkv[GK_KINK_MAX_SLOTS], fev[GK_KINK_MAX_SLOTS], fes[GK_KINK_MAX_SLOTS], fbv[GK_KINK_MAX_SLOTS];
} gk_mode;

GK_INLINE void cell_nodes(gk_mode *md, int N)
{
    double r = md->nd - (double)N * floor(md->nd / (double)N);
    int i0 = (int)r;
    if (i0 < 0) i0 = 0;
    if (i0 >= N) i0 = N - 1;
    md->i0 = i0;
    md->i1 = (i0 + 1 == N) ? 0 : i0 + 1;
}

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

static void node_flags(gk_model *m)
{
    int N = m->n_phi, P = m->P, rows = m->n_torque * m->n_temp, i, j, r;
    if (N > GK_NODE_FLAGS_MAX) return;   /* every node counts as flagged (node_flagged) */
    for (i = 0; i < N; ++i) {
        int im = (i == 0) ? N - 1 : i - 1, ip = (i == N - 1) ? 0 : i + 1, bent = 0, zone = 0;
        for (j = 0; j < P; ++j) {
            const double *b = m->backlash_half_m + (size_t)j * N;
            int pos = 0, nonpos = 0;
            if (kinked(b[im], b[i], b[ip])) bent = 1;
            if (bent_tol(b[im], b[i], b[ip], GK_SEG_KINK_TOL)) zone = 1;   /* rk4_seg: a big kink */
            for (r = 0; r < rows; ++r) {
                const double *k = m->k_N_per_m + ((size_t)r * P + j) * N;
                const double *e = m->e_m + ((size_t)r * P + j) * N;
                double ka = k[im], kb = k[i], kc = k[ip], ml, mr;
                if (kinked(ka, kb, kc) || kinked(e[im], e[i], e[ip])) bent = 1;
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
        m->node_kink[i] = (unsigned char)(bent | (zone << 1));
    }
}

/* stop flag of global node n (an integer value), node n mod N: rk4_node the kink flag;
 * rk4_seg the contact_zone-flag change, a big kink (GK_SEG_KINK_TOL) or a contact-zone edge
 * in one of the node's two cells (model_rhs._seg_flags) */
static int node_flagged(const gk_model *m, double n)
{
    int N = m->n_phi, i0;
    double r;
    if (N > GK_NODE_FLAGS_MAX) return 1;
    r = n - (double)N * floor(n / (double)N);
    i0 = (int)r;
    if (i0 < 0) i0 = 0;
    if (i0 >= N) i0 = N - 1;
    return (m->node_kink[i0] & ((m->integrator == GK_INTEGRATOR_RK4_SEG) ? 2 : 1)) != 0;
}

/* contact-zone cuts of cell i0 over all slots (model_rhs._cut_above / _cut_below): the
 * smallest above f (at or above with incl) and below 1, 2.0 for none; the largest below f
 * (at or below with incl) and above 0, -1.0 for none */
static double cut_above(const gk_model *m, int i0, double f, int incl)
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

static double cut_below(const gk_model *m, int i0, double f, int incl)
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

/* node index (n mod N) of global node n (an integer value); as cell_nodes */
static int node_index(int N, double n)
{
    double r = n - (double)N * floor(n / (double)N);
    int i0 = (int)r;
    if (i0 < 0) i0 = 0;
    if (i0 >= N) i0 = N - 1;
    return i0;
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
        int i0 = node_index(m->n_phi, c);
        f = cut_above(m, i0, n - c, 0);
        while (f < 1.0 && !(c + f > n)) f = cut_above(m, i0, f, 0);   /* n - c rounds: above n */
        if (f < 1.0) return c + f;
    }
    if (!node) return c + 1.0;
    top = c + m->n_phi;
    q = c + 1.0;
    if (m->integrator == GK_INTEGRATOR_RK4_SEG && m->n_phi <= GK_NODE_FLAGS_MAX) {
        /* every cell with a cut has both nodes flagged: the first flag comes first */
        int i = node_index(m->n_phi, q);
        while (q < top) {
            if ((m->node_kink[i] & 2) != 0) return q;
            q += 1.0;
            if (++i == m->n_phi) i = 0;
        }
        return q;
    }
    while (q < top) {
        if (node_flagged(m, q)) return q;
        if (m->zone_cuts != NULL) {
            f = cut_above(m, node_index(m->n_phi, q), 0.0, 0);
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
        int i0 = node_index(m->n_phi, c);
        f = cut_below(m, i0, n - c, 0);
        while (f > 0.0 && !(c + f < n)) f = cut_below(m, i0, f, 0);   /* below n */
        if (f > 0.0) return c + f;
    }
    if (!node) return c;
    bottom = c + 1.0 - m->n_phi;
    q = c;
    if (m->integrator == GK_INTEGRATOR_RK4_SEG && m->n_phi <= GK_NODE_FLAGS_MAX) {
        int i = node_index(m->n_phi, q);
        while (q > bottom) {
            if ((m->node_kink[i] & 2) != 0) return q;
            q -= 1.0;
            if (--i < 0) i = m->n_phi - 1;
        }
        return q;
    }
    while (q > bottom) {
        if (node_flagged(m, q)) return q;
        if (m->zone_cuts != NULL) {
            f = cut_below(m, node_index(m->n_phi, q - 1.0), 1.0, 0);
            if (f > 0.0) return q - 1.0 + f;
        }
        q -= 1.0;
    }
    return q;
}

/* held segment at a step start (theta1 = th): [nd, nd + 1] (rk4_kink); rk4_node: nd to the
 * next flagged node above for om >= 0, the last flagged node below nd + 1 to nd + 1 for
 * om < 0; a contact-zone cut in cell nd splits it (integrators._seg_start) */
static void seg_start(const gk_model *m, gk_mode *md, int node, double om, double th)
{
    double lo = md->nd, hi = md->nd + 1.0;
    if (m->zone_cuts != NULL) {
        int i0 = node_index(m->n_phi, md->nd);
        double f = th * m->inv_dphi - md->nd, fb = cut_below(m, i0, f, 1), fa = cut_above(m, i0, f, 1);
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
static void seg_cross(const gk_model *m, gk_mode *md, int up, int node)
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
static void zone_sel(const gk_model *m, gk_mode *md)
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

GK_INLINE void deriv_locked(const gk_model *m, const gk_tq *t, const gk_mode *md, double T1, double T2,
                         const double *y, double *dy)
{
    double f = 0.0, Rb1 = m->Rb1_m, Rb2 = m->Rb2_m;
    int j;
    for (j = 0; j < m->P; ++j) {
        double kv, ev, es, bv;
        locked_tables(m, t, md, y[0], j, &kv, &ev, &es, &bv);
        f += pair_force_locked(kv, ev, es, bv, y[2], y[3], y[1], m->c_Ns_per_m, m->damping_model,
                               md->reg[j], md->sub[j], md->kpos[j]);
    }
    dy[0] = y[1];
    dy[1] = (T1 - Rb1 * f) * m->inv_I1;
    dy[2] = y[3];
    dy[3] = Rb1 * (T1 - Rb1 * f) * m->inv_I1 - Rb2 * (Rb2 * f - T2) * m->inv_I2;
}

/* classical RK4 of length h from y with first stage f0 given, mode held */
GK_INLINE void rk4_locked(const gk_model *m, const gk_tq *t, const gk_mode *md, double T1, double T2,
                       const double *y, const double *f0, double h, double *yn)
{
    double h2 = h / 2.0, h6, k[4], sum[4], yt[4];
    axpy4(y, h2, f0, yt);
    deriv_locked(m, t, md, T1, T2, yt, k);
    axpy4(f0, 2.0, k, sum);                 /* k1 + 2 k2 */
    axpy4(y, h2, k, yt);
    deriv_locked(m, t, md, T1, T2, yt, k);
    axpy4(sum, 2.0, k, sum);                /* + 2 k3 */
    axpy4(y, h, k, yt);
    deriv_locked(m, t, md, T1, T2, yt, k);
    axpy4(sum, 1.0, k, sum);                /* + k4 */
    h6 = h / 6.0;
    axpy4(y, h6, sum, yn);
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

static double guard_root(const gk_model *m, const gk_tq *t, const gk_mode *md, int gi, double g_end,
                         const double *y0, const double *f0, const double *y1, const double *f1, double tau,
                         int seg, double gw, double gv);

/* kpos of every pair for the held cell and the sub-modes of pairs in contact;
 * with from_state also the regions */
static void mode_sync(const gk_model *m, const gk_tq *t, gk_mode *md, const double *y, int from_state)
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

static void mode_from_state(const gk_model *m, const gk_tq *t, gk_mode *md, const double *y, int node)
{
    md->nd = floor(y[0] * m->inv_dphi);
    cell_nodes(md, m->n_phi);
    seg_start(m, md, node, y[1], y[0]);
    zone_sel(m, md);
    mode_sync(m, t, md, y, 1);
}

/* rk4_node: time to the flagged table node ahead of theta1 (the held segment's
 * end hi for om > 0, start lo for om < 0) predicted from the step's first
 * stage, theta1(tau) = th + tau*(om + 0.5*fb*tau); linear start, two
 * Newton iterations; -1 when there is no prediction (as _node_time in
 * gearfmu/dynamics/integrators.py). */
static double node_time(double th, double om, double fb, double rem, double lo, double hi, double dphi)
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
static int pairs_hold(const gk_model *m, const gk_tq *t, const gk_mode *md, const double *y)
{
    int gi, n_guard = 2 + 3 * m->P;
    for (gi = 2; gi < n_guard; ++gi)
        if (guard_at(m, t, md, gi, y) < 0.0) return 0;
    return 1;
}

/* node != 0: rk4_node (segments between flagged nodes, the crossing of a flagged
 * node predicted; see _kink_substep) */
static void kink_substep(const gk_model *m, const gk_tq *t, gk_mode *md, double T1, double T2,
                         double *y, double h, int node)
{
    double rem = h, f0[4], y1[4], f1[4];
    int nev = 0, n_guard = 2 + 3 * m->P, q;
    for (;;) {
        double best = 2.0;
        int best_gi = -1, have_f1 = 0, gi, any_neg;
        if (node) {   /* the held cell follows theta1 inside the segment */
            double cn = floor(y[0] * m->inv_dphi);
            if (cn + 1.0 > md->lo && cn < md->hi && cn != md->nd) {
                md->nd = cn;
                cell_nodes(md, m->n_phi);
                zone_sel(m, md);
            }
        }
        deriv_locked(m, t, md, T1, T2, y, f0);
        if (node && nev < GK_KINK_MAX_EVENTS) {
            double tau = node_time(y[0], y[1], f0[1], rem, md->lo, md->hi, m->dphi_rad);
            if (tau > 0.0) {
                rk4_locked(m, t, md, T1, T2, y, f0, tau, y1);
                if (pairs_hold(m, t, md, y1)) {
                    seg_cross(m, md, y[1] > 0.0, 1);
                    for (q = 0; q < 4; ++q) y[q] = y1[q];
                    rem = rem - tau;
                    nev += 1;
                    cell_nodes(md, m->n_phi);
                    zone_sel(m, md);
                    mode_sync(m, t, md, y, 0);
                    if (!(rem > 0.0)) break;
                    continue;
                }
            }
        }
        rk4_locked(m, t, md, T1, T2, y, f0, rem, y1);
        if (nev >= GK_KINK_MAX_EVENTS) {
            for (q = 0; q < 4; ++q) y[q] = y1[q];
            mode_from_state(m, t, md, y, node);
            break;
        }
        any_neg = 0;
        for (gi = 0; gi < n_guard && !any_neg; ++gi)
            if (guard_at(m, t, md, gi, y1) < 0.0) any_neg = 1;
        for (gi = 0; any_neg && gi < n_guard; ++gi) {
            double g = guard_at(m, t, md, gi, y1), s;
            if (!(g < 0.0)) continue;
            if (!have_f1) {
                deriv_locked(m, t, md, T1, T2, y1, f1);
                have_f1 = 1;
            }
            s = guard_root(m, t, md, gi, g, y, f0, y1, f1, rem, 0, 0.0, 0.0);
            if (s < best) {
                best = s;
                best_gi = gi;
            }
        }
        if (best_gi < 0) {
            for (q = 0; q < 4; ++q) y[q] = y1[q];
            break;
        }
        if (best >= 1.0) {
            for (q = 0; q < 4; ++q) y[q] = y1[q];
            rem = 0.0;
        } else if (best > 0.0) {
            double tau = best * rem, ye[4];
            rk4_locked(m, t, md, T1, T2, y, f0, tau, ye);
            for (q = 0; q < 4; ++q) y[q] = ye[q];
            rem = rem - tau;
        }
        nev += 1;
        if (best_gi < 2) {
            seg_cross(m, md, best_gi == 1, node);
            cell_nodes(md, m->n_phi);
            zone_sel(m, md);
            mode_sync(m, t, md, y, 0);
        } else {
            int j = (best_gi - 2) / 3;
            double kv = 0.0, ev = 0.0, es = 0.0, bv = 0.0;
            if (md->reg[j] == 0 && m->damping_model == GK_DAMPING_ELASTOBACKLASH)
                locked_tables(m, t, md, y[0], j, &kv, &ev, &es, &bv);
            switch_pair(m, md, j, (best_gi - 2) - 3 * j, kv, ev, es, bv, y);
        }
        if (!(rem > 0.0)) break;
    }
}


/* --------------------------------------------------------------- rk4_seg
 * docs/model.md "rk4_seg": rk4_node's held segments, stops and event location, the
 * segments running from contact-zone edge to edge (node_flagged), every evaluation
 * reading the tables in the cell of its own theta1 clamped to the segment, and the RK4
 * steps taken in the shifted state (theta1, Omega, x, V) = (theta1, omega1 - g_w*C, x,
 * v - g_v*C), C = c*sum e_j over the damped pairs.  Same arithmetic as _seg_substep and
 * friends in gearfmu/dynamics/integrators.py and model_rhs.py. */

/* the cell of th clamped to the held segment (seg_rhs._seg_cell): its nodes and weight in
 * *c, its global index returned */
GK_INLINE double seg_cell(const gk_model *m, const gk_mode *md, double th, gk_ph *c)
{
    int N = m->n_phi;
    double cc = floor(th * m->inv_dphi);
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
        c->i0 = node_index(N, cc);
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

/* C = c*sum e_j over the damped pairs at th (seg_rhs._seg_ce) */
GK_INLINE double seg_ce(const gk_model *m, const gk_tq *t, const gk_mode *md, double th)
{
    gk_ph c;
    double ea = 0.0;
    int j;
    double cc = seg_cell(m, md, th, &c);
    for (j = 0; j < m->P; ++j) {
        if (seg_damped(m, md, j)) {
            double kv, ev, es, bv;
            slot_tables(m, t, &c, j, seg_sel(m, md, j, cc, &c), &kv, &ev, &es, &bv);
            ea += ev;
        }
    }
    return m->c_Ns_per_m * ea;
}

/* pair j's terms of seg_rhs added to the sums fs, ea, sa, na (seg_rhs._pair_terms) */
GK_INLINE void seg_pair_terms(const gk_model *m, const gk_mode *md, int j, double kv, double ev, double es,
                              double bv, double x, double *fs, double *ea, double *sa, double *na)
{
    double fc;
    int reg = md->reg[j];
    if (reg == 1) fc = kv * ((x - ev) - bv);
    else if (reg == -1) fc = kv * ((x - ev) + bv);
    else fc = 0.0;
    if (m->damping_model == GK_DAMPING_ELASTOBACKLASH) {
        if (reg != 0) {
            int sub = md->sub[j];
            if (sub == 0) {
                *fs += fc + fc;
            } else if (sub == 1) {
                *fs += fc;
                *ea += ev;
                *sa += es;
                *na += 1.0;
            }
        }
    } else if (md->kpos[j] != 0) {
        *fs += fc;
        *ea += ev;
        *sa += es;
        *na += 1.0;
    }
}

/* dy = (omega1, Omega', v, V') and *sk = S of seg_rhs from the shifted velocities wo, wv and
 * the sums of seg_pair_terms (seg_rhs._seg_accel); multiplied by 1/I1, 1/I2 of gk_init */
GK_INLINE void seg_accel(const gk_model *m, double T1, double T2, double gw, double gv, double wo, double wv,
                         double fs, double ea, double sa, double na, double *dy, double *sk)
{
    double cd = m->c_Ns_per_m, Rb1 = m->Rb1_m, Rb2 = m->Rb2_m;
    double ce = cd * ea, v = wv + gv * ce, f = fs + na * (cd * v);
    dy[0] = wo + gw * ce;
    dy[1] = (T1 - Rb1 * f) * m->inv_I1;
    dy[2] = v;
    dy[3] = Rb1 * (T1 - Rb1 * f) * m->inv_I1 - Rb2 * (Rb2 * f - T2) * m->inv_I2;
    *sk = cd * sa;
}

/* right-hand side in the shifted state y = (theta1, Omega, x, V) (seg_rhs._seg_rhs);
 * *sk = c*sum de_j/dphi over the damped pairs */
GK_INLINE void seg_rhs(const gk_model *m, const gk_tq *t, const gk_mode *md, double T1, double T2,
                       double gw, double gv, const double *y, double *dy, double *sk)
{
    gk_ph c;
    double fs = 0.0, ea = 0.0, sa = 0.0, na = 0.0;
    int j;
    double cc = seg_cell(m, md, y[0], &c);
    for (j = 0; j < m->P; ++j) {
        double kv, ev, es, bv;
        slot_tables(m, t, &c, j, seg_sel(m, md, j, cc, &c), &kv, &ev, &es, &bv);
        seg_pair_terms(m, md, j, kv, ev, es, bv, y[2], &fs, &ea, &sa, &na);
    }
    seg_accel(m, T1, T2, gw, gv, y[1], y[3], fs, ea, sa, na, dy, sk);
}

/* classical RK4 of the shifted state, first stage f0 given (integrators._rk4_seg) */
GK_INLINE void rk4_seg(const gk_model *m, const gk_tq *t, const gk_mode *md, double T1, double T2,
                       double gw, double gv, const double *y, const double *f0, double h, double *yn)
{
    double h2 = h / 2.0, h6, k[4], sum[4], yt[4], sk;
    axpy4(y, h2, f0, yt);
    seg_rhs(m, t, md, T1, T2, gw, gv, yt, k, &sk);
    axpy4(f0, 2.0, k, sum);
    axpy4(y, h2, k, yt);
    seg_rhs(m, t, md, T1, T2, gw, gv, yt, k, &sk);
    axpy4(sum, 2.0, k, sum);
    axpy4(y, h, k, yt);
    seg_rhs(m, t, md, T1, T2, gw, gv, yt, k, &sk);
    axpy4(sum, 1.0, k, sum);
    h6 = h / 6.0;
    axpy4(y, h6, sum, yn);
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

/* fraction s in [0, 1] of guard gi's zero on the Hermite interpolant of the step (Illinois;
 * integrators._guard_root): rk4_kink / rk4_node guard_at on the state, rk4_seg (seg) guard_seg
 * on the shifted state */
static double guard_root(const gk_model *m, const gk_tq *t, const gk_mode *md, int gi, double g_end,
                         const double *y0, const double *f0, const double *y1, const double *f1, double tau,
                         int seg, double gw, double gv)
{
    double ga = seg ? guard_seg(m, t, md, gi, y0, gw, gv) : guard_at(m, t, md, gi, y0);
    double gb = g_end, a = 0.0, b = 1.0, s, gs, yy[4];
    int side = 0, it;
    if (!(ga > 0.0)) return 0.0;
    for (it = 0; it < KINK_MAX_IT; ++it) {
        s = (a * gb - b * ga) / (gb - ga);
        if (!(s > a && s < b)) s = 0.5 * (a + b);
        hermite_point(s, y0, f0, y1, f1, tau, yy);
        gs = seg ? guard_seg(m, t, md, gi, yy, gw, gv) : guard_at(m, t, md, gi, yy);
        if (gs < 0.0) {
            b = s;
            gb = gs;
            if (side == -1) ga = 0.5 * ga;
            side = -1;
        } else if (gs == 0.0) {
            b = s;
            break;
        } else {
            a = s;
            ga = gs;
            if (side == 1) gb = 0.5 * gb;
            side = 1;
        }
        if (b - a <= KINK_TOL_S) break;
    }
    return b;
}

/* the state (theta1, omega1, x, v) of the shifted state y, in place (integrators._seg_true) */
GK_INLINE void seg_true(const gk_model *m, const gk_tq *t, const gk_mode *md, double gw, double gv, double *y)
{
    double ce = seg_ce(m, t, md, y[0]);
    y[1] = y[1] + gw * ce;
    y[3] = y[3] + gv * ce;
}

/* the first stage at the state y: the shifted state ys (C at y) and f0 = seg_rhs(ys), with one
 * table lookup per pair for both (the values and operations of seg_ce, then seg_rhs); the
 * lookup of the last seg_end when the substep ended at y (md->fsal: the same cell, segment
 * and mode, so the same values) */
static void seg_first(const gk_model *m, const gk_tq *t, gk_mode *md, double T1, double T2, double gw,
                      double gv, const double *y, double *ys, double *f0, double *sk)
{
    gk_ph c;
    double *kv = md->fkv, *ev = md->fev, *es = md->fes, *bv = md->fbv;
    double ea = 0.0, fs = 0.0, sa = 0.0, na = 0.0, ce;
    int j;
    if (md->fsal && y[0] == md->fth && md->lo == md->flo && md->hi == md->fhi) {
        for (j = 0; j < m->P; ++j)
            if (seg_damped(m, md, j)) ea += ev[j];
    } else {
        double cc = seg_cell(m, md, y[0], &c);
        for (j = 0; j < m->P; ++j) {
            slot_tables(m, t, &c, j, seg_sel(m, md, j, cc, &c), &kv[j], &ev[j], &es[j], &bv[j]);
            if (seg_damped(m, md, j)) ea += ev[j];
        }
    }
    md->fsal = 0;
    ce = m->c_Ns_per_m * ea;
    ys[0] = y[0];
    ys[1] = y[1] - gw * ce;
    ys[2] = y[2];
    ys[3] = y[3] - gv * ce;
    ea = 0.0;
    for (j = 0; j < m->P; ++j) seg_pair_terms(m, md, j, kv[j], ev[j], es[j], bv[j], ys[2], &fs, &ea, &sa, &na);
    seg_accel(m, T1, T2, gw, gv, ys[1], ys[3], fs, ea, sa, na, f0, sk);
}

/* the state yt = (theta1, omega1, x, v) of the shifted state y1 (seg_true) and 1 when no pair
 * guard is negative there (pairs_hold_seg), with one table lookup per pair for both (kept in
 * md->fkv.. for seg_first, theta1 and the segment in md->fth, flo, fhi) */
static int seg_end(const gk_model *m, const gk_tq *t, gk_mode *md, double gw, double gv, const double *y1,
                   double *yt)
{
    gk_ph c;
    double *kv = md->fkv, *ev = md->fev, *es = md->fes, *bv = md->fbv;
    double ea = 0.0, ce;
    int j, q;
    double cc = seg_cell(m, md, y1[0], &c);
    md->fth = y1[0];
    md->flo = md->lo;
    md->fhi = md->hi;
    for (j = 0; j < m->P; ++j) {
        slot_tables(m, t, &c, j, seg_sel(m, md, j, cc, &c), &kv[j], &ev[j], &es[j], &bv[j]);
        if (seg_damped(m, md, j)) ea += ev[j];
    }
    ce = m->c_Ns_per_m * ea;
    yt[0] = y1[0];
    yt[1] = y1[1] + gw * ce;
    yt[2] = y1[2];
    yt[3] = y1[3] + gv * ce;
    for (j = 0; j < m->P; ++j)
        for (q = 0; q < 3; ++q)
            if (pair_guard(q, kv[j], ev[j], es[j], bv[j], yt[2], yt[3], yt[1], m->c_Ns_per_m, m->damping_model,
                           md->reg[j], md->sub[j]) < 0.0)
                return 0;
    return 1;
}

/* one substep of rk4_seg (integrators._seg_substep) */
static void seg_substep(const gk_model *m, const gk_tq *t, gk_mode *md, double T1, double T2, double *y, double h)
{
    double rem = h, ys[4], f0[4], y1[4], yt1[4], f1[4], gw, gv, sk;
    int nev = 0, n_guard = 2 + 3 * m->P, q;
    gw = m->seg_gw;
    gv = m->seg_gv;
    for (;;) {
        double best = 2.0, cn;
        int best_gi = -1, have_f1 = 0, gi, any_neg;
        md->cl = floor(md->lo);   /* the segment is fixed until the next pass */
        md->ch = ceil(md->hi) - 1.0;
        cn = floor(y[0] * m->inv_dphi);
        if (cn + 1.0 > md->lo && cn < md->hi && cn != md->nd) {
            md->nd = cn;
            cell_nodes(md, m->n_phi);
            zone_sel(m, md);
        }
        seg_first(m, t, md, T1, T2, gw, gv, y, ys, f0, &sk);
        if (nev < GK_KINK_MAX_EVENTS) {
            double tau = node_time(y[0], y[1], f0[1] + gw * (sk * y[1]), rem, md->lo, md->hi, m->dphi_rad);
            if (tau > 0.0) {
                rk4_seg(m, t, md, T1, T2, gw, gv, ys, f0, tau, y1);
                if (seg_end(m, t, md, gw, gv, y1, yt1)) {
                    seg_cross(m, md, y[1] > 0.0, 1);
                    for (q = 0; q < 4; ++q) y[q] = yt1[q];
                    rem = rem - tau;
                    nev += 1;
                    cell_nodes(md, m->n_phi);
                    zone_sel(m, md);
                    mode_sync(m, t, md, y, 0);
                    if (!(rem > 0.0)) break;
                    continue;
                }
            }
        }
        rk4_seg(m, t, md, T1, T2, gw, gv, ys, f0, rem, y1);
        any_neg = !seg_end(m, t, md, gw, gv, y1, yt1);
        if (nev >= GK_KINK_MAX_EVENTS) {
            for (q = 0; q < 4; ++q) y[q] = yt1[q];
            mode_from_state(m, t, md, y, 1);
            break;
        }
        if ((yt1[0] - md->lo * m->dphi_rad < 0.0) || (md->hi * m->dphi_rad - yt1[0] < 0.0)) any_neg = 1;
        if (!any_neg) {
            for (q = 0; q < 4; ++q) y[q] = yt1[q];
            md->fsal = 1;   /* the next substep starts at the end of seg_end's lookup */
            break;
        }
        for (gi = 0; gi < n_guard; ++gi) {
            double g, s;
            if (gi < 2) {
                g = guard_seg(m, t, md, gi, y1, gw, gv);
            } else { /* guard_seg at y1 from seg_end's lookup (the same cell and values) */
                int j = (gi - 2) / 3;
                g = pair_guard((gi - 2) - 3 * j, md->fkv[j], md->fev[j], md->fes[j], md->fbv[j], yt1[2], yt1[3],
                               yt1[1], m->c_Ns_per_m, m->damping_model, md->reg[j], md->sub[j]);
            }
            if (!(g < 0.0)) continue;
            if (!have_f1) {
                seg_rhs(m, t, md, T1, T2, gw, gv, y1, f1, &sk);
                have_f1 = 1;
            }
            s = guard_root(m, t, md, gi, g, ys, f0, y1, f1, rem, 1, gw, gv);
            if (s < best) {
                best = s;
                best_gi = gi;
            }
        }
        if (best_gi < 0) {
            for (q = 0; q < 4; ++q) y[q] = yt1[q];
            break;
        }
        if (best >= 1.0) {
            for (q = 0; q < 4; ++q) y[q] = yt1[q];
            rem = 0.0;
        } else if (best > 0.0) {
            double tau = best * rem, ye[4];
            rk4_seg(m, t, md, T1, T2, gw, gv, ys, f0, tau, ye);
            seg_true(m, t, md, gw, gv, ye);
            for (q = 0; q < 4; ++q) y[q] = ye[q];
            rem = rem - tau;
        }
        nev += 1;
        if (best_gi < 2) {
            seg_cross(m, md, best_gi == 1, 1);
            cell_nodes(md, m->n_phi);
            zone_sel(m, md);
            mode_sync(m, t, md, y, 0);
        } else {
            int j = (best_gi - 2) / 3;
            double kv = 0.0, ev = 0.0, es = 0.0, bv = 0.0;
            if (md->reg[j] == 0 && m->damping_model == GK_DAMPING_ELASTOBACKLASH) {
                gk_ph c;
                double cc = seg_cell(m, md, y[0], &c);
                slot_tables(m, t, &c, j, seg_sel(m, md, j, cc, &c), &kv, &ev, &es, &bv);
            }
            switch_pair(m, md, j, (best_gi - 2) - 3 * j, kv, ev, es, bv, y);
        }
        if (!(rem > 0.0)) break;
    }
}

/* ------------------------------------------------------------ public API */

int gk_initialize(const gk_model *m, gk_state *s, double theta1_0_rad,
                  double omega1_0_rad_s, double T1_Nm)
{
    gk_tq t;
    gk_ph c = GK_PH_NONE;
    double Fm, S = 0.0, lo = 0.0, hi = 0.0;
    int j, it, any = 0;
    if (m == NULL || s == NULL) return GK_ERR_MODEL;
    if (!isfinite(theta1_0_rad) || !isfinite(omega1_0_rad_s) || !isfinite(T1_Nm))
        return GK_ERR_INPUT;
    t = torque_bracket(m, T1_Nm);
    phi_cell(m, theta1_0_rad, &c);
    Fm = T1_Nm / m->Rb1_m;
    for (j = 0; j < m->P; ++j) {
        double k, e, b;
        slot_tables(m, &t, &c, j, -1, &k, &e, NULL, &b);
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
            slot_tables(m, &t, &c, j, -1, &k, &e, NULL, &b);
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
    gk_ph c = GK_PH_NONE;
    double F, km;
    int j, P;
    if (m == NULL || s == NULL || out == NULL) return GK_ERR_MODEL;
    if (!isfinite(T1_Nm)) return GK_ERR_INPUT;
    P = m->P;
    t = torque_bracket(m, T1_Nm);
    F = mesh_force(m, &t, &c, s->theta1_rad, s->omega1_rad_s, s->x_m, s->v_m_s,
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
    gk_ph c = GK_PH_NONE;
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
    if (m->integrator == GK_INTEGRATOR_RK4_KINK || m->integrator == GK_INTEGRATOR_RK4_NODE) {
        gk_mode md;
        int node = (m->integrator == GK_INTEGRATOR_RK4_NODE);
        if (m->P > GK_KINK_MAX_SLOTS) return GK_ERR_PARAM;
        mode_from_state(m, &t, &md, y, node);
        for (i = 0; i < nsub; ++i) kink_substep(m, &t, &md, T1_Nm, T2_Nm, y, h, node);
        nsub = 0;
    } else if (m->integrator == GK_INTEGRATOR_RK4_SEG) {
        gk_mode md;
        if (m->P > GK_KINK_MAX_SLOTS) return GK_ERR_PARAM;
        mode_from_state(m, &t, &md, y, 1);
        md.fsal = 0;
        for (i = 0; i < nsub; ++i) seg_substep(m, &t, &md, T1_Nm, T2_Nm, y, h);
        nsub = 0;
    }
    for (i = 0; i < nsub; ++i) {
        deriv(m, &t, &c, T1_Nm, T2_Nm, y, k1);
        axpy4(y, 0.5 * h, k1, yt);
        deriv(m, &t, &c, T1_Nm, T2_Nm, yt, k2);
        axpy4(y, 0.5 * h, k2, yt);
        deriv(m, &t, &c, T1_Nm, T2_Nm, yt, k3);
        axpy4(y, h, k3, yt);
        deriv(m, &t, &c, T1_Nm, T2_Nm, yt, k4);
        rk4_update(y, h, k1, k2, k3, k4);
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

/* ------------------------------------------------------------ verified envelope */
int gk_sizeof_envelope(void) { return (int)sizeof(gk_envelope); }

int gk_envelope_init(gk_envelope *e, int kind)
{
    int q;
    if (e == NULL || kind < GK_ENV_VERIFIED || kind > GK_ENV_NOT_VERIFIED) return GK_ERR_PARAM;
    for (q = 0; q < GK_ENV_N; ++q) {
        e->lo[q] = 0.0;
        e->hi[q] = 0.0;
        e->active[q] = 0;
        e->warned[q] = 0;
    }
    e->kind = kind;
    return GK_OK;
}

int gk_envelope_set(gk_envelope *e, int q, double lo_SI, double hi_SI)
{
    if (e == NULL || q < 0 || q >= GK_ENV_N) return GK_ERR_PARAM;
    if (!(isfinite(lo_SI) && isfinite(hi_SI) && lo_SI <= hi_SI)) {
        e->active[q] = 0;
        return GK_ERR_PARAM;
    }
    e->lo[q] = lo_SI;
    e->hi[q] = hi_SI;
    e->active[q] = 1;
    return GK_OK;
}

void gk_envelope_rearm(gk_envelope *e)
{
    int q;
    if (e == NULL) return;
    for (q = 0; q < GK_ENV_N; ++q) e->warned[q] = 0;
}

int gk_envelope_check(gk_envelope *e, int q, const char *name, double value, double t_s, char *msg, int cap)
{
    static const char *const what[3] = {
        "the envelope over which this FMU's accuracy was verified (fidelity plan)",
        "the envelope over which this FMU's accuracy was estimated (as-written estimate, not verified)",
        "the range this FMU was built for (its tables' range; accuracy not verified)"};
    static const char *const quantity[GK_ENV_N] = {"pinion torque", "pinion speed", "temperature"};
    static const char *const unit[GK_ENV_N] = {"N.m", "rad/s", "degC"};
    double lo, hi;
    if (e == NULL || q < 0 || q >= GK_ENV_N || !e->active[q] || e->warned[q] || isnan(value)) return 0;
    lo = e->lo[q];
    hi = e->hi[q];
    if (q == GK_ENV_PINION_SPEED) {
        lo -= GK_ENV_SPEED_MARGIN * fabs(lo);
        hi += GK_ENV_SPEED_MARGIN * fabs(hi);
    }
    if (value >= lo && value <= hi) return 0;
    e->warned[q] = 1;
    if (msg == NULL || cap <= 0) return 1;
    if (q == GK_ENV_PINION_SPEED) {
        const double rpm = 30.0 / 3.14159265358979323846;
        snprintf(msg, (size_t)cap,
                 "%s = %.9g rad/s (%.9g rpm) at t = %.9g s is outside %s: pinion speed [%.9g, %.9g] rad/s "
                 "([%.9g, %.9g] rpm; compared with a %g percent margin for the torsional vibration); the FMU keeps "
                 "running, its accuracy there is not known (one warning per input; resources/envelope.json)",
                 name ? name : "pinion_speed", value, value * rpm, t_s, what[e->kind], e->lo[q], e->hi[q],
                 e->lo[q] * rpm, e->hi[q] * rpm, 100.0 * GK_ENV_SPEED_MARGIN);
    } else {
        snprintf(msg, (size_t)cap,
                 "%s = %.9g %s at t = %.9g s is outside %s: %s [%.9g, %.9g] %s; the FMU keeps running, its "
                 "accuracy there is not known (one warning per input; resources/envelope.json)",
                 name ? name : quantity[q], value, unit[q], t_s, what[e->kind], quantity[q], e->lo[q], e->hi[q],
                 unit[q]);
    }
    return 1;
}
