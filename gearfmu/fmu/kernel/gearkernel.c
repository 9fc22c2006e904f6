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
 * The kernel's other files (gk_internal.h says which holds what): the table lookup
 * (gk_lookup.h, inlined here), the model and its setters (gk_model.c), the stops of the event
 * integrators (gk_stops.c), the contact-zone cuts (gk_zones.c), the temperature axis
 * (gk_temperature.c) and the verified envelope (gk_envelope.c).  This file is the hot path:
 * the forces, RK4, the right-hand sides with the contact mode held, the guards, the one
 * event-location loop of rk4_kink, rk4_node and rk4_seg, and the public step functions.
 *
 * No globals, no allocation, no abort: every function returns a status.
 */
#include "gk_lookup.h"

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


/* -------------------------------------------------------- event location
 * One substep of rk4_kink, rk4_node (node) and rk4_seg (seg), the loop written once
 * (integrators._event_substep): per pass the held cell follows theta1 inside the segment
 * (rk4_node, rk4_seg), the first stage is taken at the state (rk4_seg: in the shifted
 * state), the crossing of the segment's end is predicted and stepped to (rk4_node, rk4_seg),
 * else a trial step to the end of the substep is taken and, when a guard is negative at its
 * end, the earliest zero is located on the step's Hermite interpolant, the step retaken to
 * it and the mode switched there.  ``seg`` is a constant of each caller, so every call site
 * compiles to its own integrator; the operations are those of the two loops it replaces. */

/* an RK4 step of length h from ys with first stage f0, the mode held (rk4_seg: of the shifted state) */
GK_INLINE void held_step(const gk_model *m, const gk_tq *t, const gk_mode *md, double T1, double T2, double gw,
                         double gv, const double *ys, const double *f0, double h, double *yn, const int seg)
{
    if (seg) rk4_seg(m, t, md, T1, T2, gw, gv, ys, f0, h, yn);
    else rk4_locked(m, t, md, T1, T2, ys, f0, h, yn);
}

/* the right-hand side at y1, the mode held (rk4_seg: in the shifted state) */
GK_INLINE void held_rhs(const gk_model *m, const gk_tq *t, const gk_mode *md, double T1, double T2, double gw,
                        double gv, const double *y1, double *f1, const int seg)
{
    double sk;
    if (seg) seg_rhs(m, t, md, T1, T2, gw, gv, y1, f1, &sk);
    else deriv_locked(m, t, md, T1, T2, y1, f1);
}

/* guard gi at the end y1 of a trial step (rk4_seg: the shifted state, its state yt1 and the pair
 * values of seg_end's lookup there, the same cell and values as guard_seg) */
GK_INLINE double end_guard(const gk_model *m, const gk_tq *t, const gk_mode *md, int gi, const double *y1,
                           const double *yt1, double gw, double gv, const int seg)
{
    int j;
    if (!seg) return guard_at(m, t, md, gi, y1);
    if (gi < 2) return guard_seg(m, t, md, gi, y1, gw, gv);
    j = (gi - 2) / 3;
    return pair_guard((gi - 2) - 3 * j, md->fkv[j], md->fev[j], md->fes[j], md->fbv[j], yt1[2], yt1[3], yt1[1],
                      m->c_Ns_per_m, m->damping_model, md->reg[j], md->sub[j]);
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

GK_INLINE void event_substep(const gk_model *m, const gk_tq *t, gk_mode *md, double T1, double T2, double *y,
                             double h, int node, const int seg)
{
    double rem = h, ys[4], f0[4], y1[4], yt1[4], f1[4], gw = m->seg_gw, gv = m->seg_gv, sk = 0.0;
    double *yend = seg ? yt1 : y1;   /* the state at the end of the trial step */
    int nev = 0, n_guard = 2 + 3 * m->P, q;
    for (;;) {
        double best = 2.0, fb;
        int best_gi = -1, have_f1 = 0, gi, any_neg, hold;
        if (seg) {   /* the segment is fixed until the next pass */
            md->cl = floor(md->lo);
            md->ch = ceil(md->hi) - 1.0;
        }
        if (node) {   /* the held cell follows theta1 inside the segment */
            double cn = floor(y[0] * m->inv_dphi);
            if (cn + 1.0 > md->lo && cn < md->hi && cn != md->nd) {
                md->nd = cn;
                gki_cell_nodes(md, m->n_phi);
                gki_zone_sel(m, md);
            }
        }
        if (seg) {   /* the shifted state and its first stage, omega1' for the prediction */
            seg_first(m, t, md, T1, T2, gw, gv, y, ys, f0, &sk);
            fb = f0[1] + gw * (sk * y[1]);
        } else {
            for (q = 0; q < 4; ++q) ys[q] = y[q];
            deriv_locked(m, t, md, T1, T2, y, f0);
            fb = f0[1];
        }
        if (node && nev < GK_KINK_MAX_EVENTS) {   /* the segment's end ahead: one step to it */
            double tau = node_time(y[0], y[1], fb, rem, md->lo, md->hi, m->dphi_rad);
            if (tau > 0.0) {
                held_step(m, t, md, T1, T2, gw, gv, ys, f0, tau, y1, seg);
                if (seg ? seg_end(m, t, md, gw, gv, y1, yt1) : pairs_hold(m, t, md, y1)) {
                    gki_seg_cross(m, md, y[1] > 0.0, 1);
                    for (q = 0; q < 4; ++q) y[q] = yend[q];
                    rem = rem - tau;
                    nev += 1;
                    gki_cell_nodes(md, m->n_phi);
                    gki_zone_sel(m, md);
                    mode_sync(m, t, md, y, 0);
                    if (!(rem > 0.0)) break;
                    continue;
                }
            }
        }
        held_step(m, t, md, T1, T2, gw, gv, ys, f0, rem, y1, seg);
        hold = seg ? seg_end(m, t, md, gw, gv, y1, yt1) : 1;
        if (nev >= GK_KINK_MAX_EVENTS) {
            for (q = 0; q < 4; ++q) y[q] = yend[q];
            mode_from_state(m, t, md, y, node);
            break;
        }
        any_neg = (yend[0] - md->lo * m->dphi_rad < 0.0) || (md->hi * m->dphi_rad - yend[0] < 0.0) || !hold ||
                  (!seg && !pairs_hold(m, t, md, y1));
        if (!any_neg) {
            for (q = 0; q < 4; ++q) y[q] = yend[q];
            if (seg) md->fsal = 1;   /* the next substep starts at the end of seg_end's lookup */
            break;
        }
        for (gi = 0; gi < n_guard; ++gi) {
            double g = end_guard(m, t, md, gi, y1, yt1, gw, gv, seg), s;
            if (!(g < 0.0)) continue;
            if (!have_f1) {
                held_rhs(m, t, md, T1, T2, gw, gv, y1, f1, seg);
                have_f1 = 1;
            }
            s = guard_root(m, t, md, gi, g, ys, f0, y1, f1, rem, seg, gw, gv);
            if (s < best) {
                best = s;
                best_gi = gi;
            }
        }
        if (best_gi < 0) {
            for (q = 0; q < 4; ++q) y[q] = yend[q];
            break;
        }
        if (best >= 1.0) {   /* step exactly to the event, then switch the mode */
            for (q = 0; q < 4; ++q) y[q] = yend[q];
            rem = 0.0;
        } else if (best > 0.0) {
            double tau = best * rem, ye[4];
            held_step(m, t, md, T1, T2, gw, gv, ys, f0, tau, ye, seg);
            if (seg) seg_true(m, t, md, gw, gv, ye);
            for (q = 0; q < 4; ++q) y[q] = ye[q];
            rem = rem - tau;
        }
        nev += 1;
        if (best_gi < 2) {
            gki_seg_cross(m, md, best_gi == 1, node);
            gki_cell_nodes(md, m->n_phi);
            gki_zone_sel(m, md);
            mode_sync(m, t, md, y, 0);
        } else {
            int j = (best_gi - 2) / 3;
            double kv = 0.0, ev = 0.0, es = 0.0, bv = 0.0;
            if (md->reg[j] == 0 && m->damping_model == GK_DAMPING_ELASTOBACKLASH)
                held_tables(m, t, md, j, y[0], &kv, &ev, &es, &bv, seg);
            switch_pair(m, md, j, (best_gi - 2) - 3 * j, kv, ev, es, bv, y);
        }
        if (!(rem > 0.0)) break;
    }
}

/* rk4_kink, or rk4_node with node (docs/native.md "rk4_node") */
static void kink_substep(const gk_model *m, const gk_tq *t, gk_mode *md, double T1, double T2, double *y,
                         double h, int node)
{
    event_substep(m, t, md, T1, T2, y, h, node, 0);
}

/* rk4_seg (docs/model.md "rk4_seg") */
static void seg_substep(const gk_model *m, const gk_tq *t, gk_mode *md, double T1, double T2, double *y, double h)
{
    event_substep(m, t, md, T1, T2, y, h, 1, 1);
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
    if (!gki_finite_pos(H_s) || !gki_finite_pos(h_max_s)) return 0.0;
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

/* ---------------------------------------------------------- Model Exchange
 * docs/model.md "Model Exchange": the host integrates [theta1, omega1, x, v]; the mode (per pair
 * region, elastobacklash branch and contact-zone flag; with node events the table segment) is held
 * between events and decided anew from the state at each event.  The lookup is the plain one in the
 * cell of theta1 (with node events: clamped to the held segment, the end cells' lines extended),
 * except that a pair out of its contact zone has k = 0 and a pair in it takes the in-zone line of
 * a cell that holds one of its edges. */

/* x on the nearest node when within GK_ZONE_SNAP cells (gk_zones.c zone_wrap, without the wrap) */
static double me_snap(double x)
{
    double rn = floor(x + 0.5);
    return (fabs(x - rn) <= GK_ZONE_SNAP) ? rn : x;
}

/* Signed distance (node units) from s to the nearest edge of slot j's contact zones: > 0 inside a
 * zone, < 0 outside; *inside = 1 when in <= s < out for one of them.  Global pair n has the zone
 * [q N + snap(mm ppm + in), q N + snap(mm ppm + out)), q = floor(n / n_mesh), mm = n - q n_mesh, and
 * belongs to slot mm mod P (gk_zone_cuts); the pairs within 2P meshes of s are looked at. */
static double me_zone_distance(const gk_model *m, int j, double s, int *inside)
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
static int me_node_stop(const gk_model *m, double n, int node_events)
{
    if (m->n_phi > GK_NODE_FLAGS_MAX) return 1;
    return (m->node_kink[gki_node_index(m->n_phi, n)] & (node_events == GK_ME_NODES_KINKS ? 2 : 1)) != 0;
}

/* the segment [lo, hi) of stops around s: lo the last stop at or below floor(s), hi the first above */
static void me_segment(const gk_model *m, gk_me *me, double s)
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

/* guard q of pair j as pair_guard, in metres: the force guards divided by k_mean (inv_k) */
GK_INLINE double me_guard(int q, double kv, double ev, double es, double bv, double x, double v, double om,
                          double c, int model, int reg, int sub, double inv_k)
{
    double d = x - ev, fc, fd;
    if (reg == 0) {
        if (q == 0) return bv - d;
        if (q == 1) return d + bv;
        return 1.0;
    }
    if (q == 0) return (reg == 1) ? d - bv : -(d + bv);
    if (model != GK_DAMPING_ELASTOBACKLASH) return 1.0;
    fc = kv * ((reg == 1) ? d - bv : d + bv) * inv_k;
    fd = c * (v - es * om) * inv_k;
    if (reg == 1) {
        if (sub == 0) return (q == 1) ? fd - fc : 1.0;
        if (sub == 1) return (q == 1) ? fc - fd : fc + fd;
        return (q == 1) ? -(fc + fd) : 1.0;
    }
    if (sub == 0) return (q == 1) ? fc - fd : 1.0;
    if (sub == 1) return (q == 1) ? fd - fc : -(fc + fd);
    return (q == 1) ? fc + fd : 1.0;
}

static int me_check(const gk_model *m, const gk_me *me, const gk_state *s)
{
    if (m == NULL || me == NULL || s == NULL) return GK_ERR_MODEL;
    if (m->P > GK_KINK_MAX_SLOTS) return GK_ERR_PARAM;
    if (!isfinite(s->theta1_rad) || !isfinite(s->omega1_rad_s) || !isfinite(s->x_m) || !isfinite(s->v_m_s))
        return GK_ERR_NONFINITE;
    return GK_OK;
}

int gk_me_n_indicators(const gk_model *m, int node_events)
{
    if (m == NULL) return 0;
    return 3 * m->P + ((m->zone_n_mesh > 0.0) ? m->P : 0) + ((node_events != GK_ME_NODES_NONE) ? 2 : 0);
}

static double me_force(const gk_model *m, const gk_me *me, const gk_tq *t, const gk_state *s, double *pf,
                       double *kmesh);
static void me_rhs(const gk_model *m, const gk_state *s, double F, double T1, double T2, double *dx);

/* the mode from state s (gk_me_update) */
static void me_decide(const gk_model *m, gk_me *me, const gk_tq *t, const gk_state *s)
{
    gk_ph c = GK_PH_NONE;
    double sv = s->theta1_rad * m->inv_dphi;
    int j;
    if (me->node_events != GK_ME_NODES_NONE) me_segment(m, me, sv);
    if (m->zone_n_mesh > 0.0)
        for (j = 0; j < m->P; ++j) me_zone_distance(m, j, sv, &me->zin[j]);
    me_cell(m, me, s->theta1_rad, &c);
    for (j = 0; j < m->P; ++j) {
        double kv, ev, es, bv, d;
        if (!me_tables(m, t, me, &c, j, &kv, &ev, &es, &bv)) {
            me->reg[j] = 0;
            me->sub[j] = 0;
            continue;
        }
        d = s->x_m - ev;
        me->reg[j] = (d > bv) ? 1 : (d < -bv) ? -1 : 0;
        me->sub[j] = (m->damping_model == GK_DAMPING_ELASTOBACKLASH)
                         ? decide_sub(me->reg[j], kv, ev, es, bv, s->x_m, s->v_m_s, s->omega1_rad_s, m->c_Ns_per_m)
                         : 0;
    }
}

/* The mode anew at an event (docs/model.md "Model Exchange"): decided at the state, then again at the
 * state a moment ahead, y + delta*f(y) with f in the mode decided first and delta = 1e-9 of the
 * natural period 2 pi sqrt(m_e/k_mean) (the choice of gearfmu.dynamics.reference), so that a guard
 * the host's root finder left at zero, or a hair short of it, takes the side it moves to. */
int gk_me_update(const gk_model *m, gk_me *me, const gk_state *s, double T1_Nm, double T2_Nm, int *changed)
{
    gk_tq t;
    gk_me old;
    gk_state ahead;
    double dx[4], delta;
    int j, st = me_check(m, me, s), diff = 0;
    if (st != GK_OK) return st;
    if (!isfinite(T1_Nm) || !isfinite(T2_Nm)) return GK_ERR_INPUT;
    old = *me;
    t = torque_bracket(m, T1_Nm);
    me_decide(m, me, &t, s);
    me_rhs(m, s, me_force(m, me, &t, s, NULL, NULL), T1_Nm, T2_Nm, dx);
    delta = 1e-9 * 6.283185307179586 * sqrt(m->m_e_kg / m->k_mean_N_per_m);
    ahead.theta1_rad = s->theta1_rad + delta * dx[0];
    ahead.omega1_rad_s = s->omega1_rad_s + delta * dx[1];
    ahead.x_m = s->x_m + delta * dx[2];
    ahead.v_m_s = s->v_m_s + delta * dx[3];
    if (isfinite(ahead.theta1_rad) && isfinite(ahead.omega1_rad_s) && isfinite(ahead.x_m) && isfinite(ahead.v_m_s))
        me_decide(m, me, &t, &ahead);
    for (j = 0; j < m->P; ++j)
        diff |= me->reg[j] != old.reg[j] || me->sub[j] != old.sub[j] || me->zin[j] != old.zin[j];
    diff |= me->seg_lo != old.seg_lo || me->seg_hi != old.seg_hi;
    if (changed != NULL) *changed = diff;
    return GK_OK;
}

int gk_me_init(const gk_model *m, gk_me *me, const gk_state *s, double T1_Nm, double T2_Nm, int node_events)
{
    int j;
    if (me == NULL) return GK_ERR_MODEL;
    if (node_events != GK_ME_NODES_NONE && node_events != GK_ME_NODES_KINKS && node_events != GK_ME_NODES_ALL)
        return GK_ERR_PARAM;
    me->node_events = node_events;
    for (j = 0; j < GK_KINK_MAX_SLOTS; ++j) me->reg[j] = me->sub[j] = me->zin[j] = 0;
    me->seg_lo = me->seg_hi = 0.0;
    return gk_me_update(m, me, s, T1_Nm, T2_Nm, NULL);
}

/* the total force with the mode held; per pair (pf) and the stiffness of the pairs in contact */
static double me_force(const gk_model *m, const gk_me *me, const gk_tq *t, const gk_state *s, double *pf,
                       double *kmesh)
{
    gk_ph c = GK_PH_NONE;
    double F = 0.0, ks = 0.0;
    int j;
    me_cell(m, me, s->theta1_rad, &c);
    for (j = 0; j < m->P; ++j) {
        double kv, ev, es, bv, Fj = 0.0;
        int active = me_tables(m, t, me, &c, j, &kv, &ev, &es, &bv);
        if (active) {
            Fj = pair_force_locked(kv, ev, es, bv, s->x_m, s->v_m_s, s->omega1_rad_s, m->c_Ns_per_m,
                                   m->damping_model, me->reg[j], me->sub[j], me_kpos(m, t, me, &c, j, active));
            if (me->reg[j] != 0) ks += kv;
        }
        if (pf != NULL) pf[j] = Fj;
        F += Fj;
    }
    if (kmesh != NULL) *kmesh = ks;
    return F;
}

static void me_rhs(const gk_model *m, const gk_state *s, double F, double T1, double T2, double *dx)
{
    double Rb1 = m->Rb1_m, Rb2 = m->Rb2_m;
    dx[0] = s->omega1_rad_s;
    dx[1] = (T1 - Rb1 * F) * m->inv_I1;
    dx[2] = s->v_m_s;
    dx[3] = Rb1 * (T1 - Rb1 * F) * m->inv_I1 - Rb2 * (Rb2 * F - T2) * m->inv_I2;
}

int gk_me_derivatives(const gk_model *m, const gk_me *me, const gk_state *s, double T1_Nm, double T2_Nm,
                      double *dx)
{
    gk_tq t;
    int st = me_check(m, me, s);
    if (st != GK_OK) return st;
    if (dx == NULL) return GK_ERR_MODEL;
    if (!isfinite(T1_Nm) || !isfinite(T2_Nm)) return GK_ERR_INPUT;
    t = torque_bracket(m, T1_Nm);
    me_rhs(m, s, me_force(m, me, &t, s, NULL, NULL), T1_Nm, T2_Nm, dx);
    return GK_OK;
}

/* every indicator into z with room for all (3P guards, P zones, 2 segment ends; those the model
 * does not have 1.0) */
static void me_all_indicators(const gk_model *m, const gk_me *me, const gk_tq *t, const gk_state *s, double *z)
{
    gk_ph c = GK_PH_NONE;
    double sv = s->theta1_rad * m->inv_dphi, len = m->Rb1_m * m->dphi_rad, inv_k = 1.0 / m->k_mean_N_per_m;
    int j, q, P = m->P;
    me_cell(m, me, s->theta1_rad, &c);
    for (j = 0; j < P; ++j) {
        double kv, ev, es, bv;
        int active = me_tables(m, t, me, &c, j, &kv, &ev, &es, &bv), inside;
        for (q = 0; q < 3; ++q)
            z[q * P + j] = active ? me_guard(q, kv, ev, es, bv, s->x_m, s->v_m_s, s->omega1_rad_s, m->c_Ns_per_m,
                                             m->damping_model, me->reg[j], me->sub[j], inv_k)
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

int gk_me_indicators(const gk_model *m, const gk_me *me, const gk_state *s, double T1_Nm, double *z)
{
    gk_tq t;
    double all[4 * GK_KINK_MAX_SLOTS + 2];
    int st = me_check(m, me, s), P, n = 0, j;
    if (st != GK_OK) return st;
    if (z == NULL) return GK_ERR_MODEL;
    if (!isfinite(T1_Nm)) return GK_ERR_INPUT;
    P = m->P;
    t = torque_bracket(m, T1_Nm);
    me_all_indicators(m, me, &t, s, all);
    for (j = 0; j < 3 * P; ++j) z[n++] = all[j];
    if (m->zone_n_mesh > 0.0)
        for (j = 0; j < P; ++j) z[n++] = all[3 * P + j];
    if (me->node_events != GK_ME_NODES_NONE) {
        z[n++] = all[4 * P];
        z[n++] = all[4 * P + 1];
    }
    return GK_OK;
}

int gk_me_outputs(const gk_model *m, const gk_me *me, const gk_state *s, double T1_Nm, double T2_Nm, double *out,
                  double *me_out)
{
    gk_tq t;
    double F, km;
    int j, P, st = me_check(m, me, s);
    if (st != GK_OK) return st;
    if (out == NULL) return GK_ERR_MODEL;
    if (!isfinite(T1_Nm) || !isfinite(T2_Nm)) return GK_ERR_INPUT;
    P = m->P;
    t = torque_bracket(m, T1_Nm);
    F = me_force(m, me, &t, s, out + GK_OUT_PAIR_FORCE, &km);
    out[GK_OUT_PINION_ANGLE] = s->theta1_rad;
    out[GK_OUT_PINION_SPEED] = s->omega1_rad_s;
    out[GK_OUT_GEAR_ANGLE] = (s->theta1_rad * m->Rb1_m - s->x_m) / m->Rb2_m;
    out[GK_OUT_GEAR_SPEED] = (s->omega1_rad_s * m->Rb1_m - s->v_m_s) / m->Rb2_m;
    out[GK_OUT_DTE] = s->x_m;
    out[GK_OUT_MESH_FORCE] = F;
    out[GK_OUT_MESH_STIFFNESS] = km;
    for (j = 0; j < P; ++j)
        out[GK_OUT_PAIR_FORCE + P + j] = (F != 0.0) ? out[GK_OUT_PAIR_FORCE + j] / F : 0.0;
    if (me_out != NULL) {
        me_out[GK_ME_OUT_V] = s->v_m_s;
        me_rhs(m, s, F, T1_Nm, T2_Nm, me_out + GK_ME_OUT_DERIVATIVES);
        me_all_indicators(m, me, &t, s, me_out + GK_ME_OUT_INDICATORS);
    }
    return GK_OK;
}
