/*
 * gearkernel.c -- C99 implementation of docs/model.md (the contract shared
 * with the numba native solver gearfmu/dynamics/native.py).
 *
 * Physics: Xu et al. (Appl. Sci. 2022) eq 1-6: per tooth-pair slot j
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
 * The kernel's other files (gk_internal.h says which holds what): the per-mesh pieces of the
 * model (gk_pair.h: the mesh force, the force law and guards with the mode held, the mode
 * decisions, the root finder; shared with the gearbox kernel), the table lookup (gk_lookup.h,
 * inlined here), the model and its setters (gk_model.c), the stops of the event integrators
 * (gk_stops.c), the contact-zone cuts (gk_zones.c), the temperature axis (gk_temperature.c) and
 * the verified envelope (gk_envelope.c).  This file is the hot path: RK4, the right-hand sides
 * with the contact mode held, the rk4_seg pieces, the one event-location loop of rk4_kink,
 * rk4_node and rk4_seg, and the public step functions.
 *
 * No globals, no allocation, no abort: every function returns a status.
 */
#include "gk_pair.h"

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

/* --------------------------------------------------------------- rk4_seg
 * docs/model.md "rk4_seg": rk4_node's held segments, stops and event location, the
 * segments running from contact-zone edge to edge (node_flagged), every evaluation
 * reading the tables in the cell of its own theta1 clamped to the segment, and the RK4
 * steps taken in the shifted state (theta1, Omega, x, V) = (theta1, omega1 - g_w*C, x,
 * v - g_v*C), C = c*sum e_j over the damped pairs.  Same arithmetic as _seg_substep and
 * friends in gearfmu/dynamics/integrators.py and model_rhs.py. */

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
 * docs/model.md "Model Exchange": the host integrates [theta1, omega1, x, v]; the per-mesh pieces
 * (the mode held between events and decided anew at each, the force and the indicators with it
 * held) are gk_pair.h's, shared with the gearbox kernel; here the pair's equations of motion. */

static int me_check(const gk_model *m, const gk_me *me, const gk_state *s)
{
    if (m == NULL || me == NULL || s == NULL) return GK_ERR_MODEL;
    if (m->P > GK_KINK_MAX_SLOTS) return GK_ERR_PARAM;
    if (!isfinite(s->theta1_rad) || !isfinite(s->omega1_rad_s) || !isfinite(s->x_m) || !isfinite(s->v_m_s))
        return GK_ERR_NONFINITE;
    return GK_OK;
}

/* the state as the per-mesh pieces take it */
GK_INLINE void me_y(const gk_state *s, double *y)
{
    y[0] = s->theta1_rad;
    y[1] = s->omega1_rad_s;
    y[2] = s->x_m;
    y[3] = s->v_m_s;
}

int gk_me_n_indicators(const gk_model *m, int node_events)
{
    if (m == NULL) return 0;
    return me_n_indicators(m, node_events);
}

static void me_rhs(const gk_model *m, const double *y, double F, double T1, double T2, double *dx)
{
    double Rb1 = m->Rb1_m, Rb2 = m->Rb2_m;
    dx[0] = y[1];
    dx[1] = (T1 - Rb1 * F) * m->inv_I1;
    dx[2] = y[3];
    dx[3] = Rb1 * (T1 - Rb1 * F) * m->inv_I1 - Rb2 * (Rb2 * F - T2) * m->inv_I2;
}

/* The mode anew at an event (docs/model.md "Model Exchange"): decided at the state, then again at the
 * state a moment ahead, y + delta*f(y) with f in the mode decided first and delta = 1e-9 of the
 * natural period 2 pi sqrt(m_e/k_mean) (the choice of gearfmu.dynamics.reference), so that a guard
 * the host's root finder left at zero, or a hair short of it, takes the side it moves to. */
int gk_me_update(const gk_model *m, gk_me *me, const gk_state *s, double T1_Nm, double T2_Nm, int *changed)
{
    gk_tq t;
    gk_me old;
    double y[4], dx[4], ahead[4], delta;
    int q, st = me_check(m, me, s), finite = 1;
    if (st != GK_OK) return st;
    if (!isfinite(T1_Nm) || !isfinite(T2_Nm)) return GK_ERR_INPUT;
    old = *me;
    me_y(s, y);
    t = torque_bracket(m, T1_Nm);
    me_decide(m, me, &t, y);
    me_rhs(m, y, me_force(m, me, &t, y, NULL, NULL), T1_Nm, T2_Nm, dx);
    delta = me_ahead_time(m);
    for (q = 0; q < 4; ++q) {
        ahead[q] = y[q] + delta * dx[q];
        finite &= isfinite(ahead[q]) != 0;
    }
    if (finite) me_decide(m, me, &t, ahead);
    if (changed != NULL) *changed = me_differs(m, me, &old);
    return GK_OK;
}

int gk_me_init(const gk_model *m, gk_me *me, const gk_state *s, double T1_Nm, double T2_Nm, int node_events)
{
    if (me == NULL) return GK_ERR_MODEL;
    if (!me_clear(me, node_events)) return GK_ERR_PARAM;
    return gk_me_update(m, me, s, T1_Nm, T2_Nm, NULL);
}

int gk_me_derivatives(const gk_model *m, const gk_me *me, const gk_state *s, double T1_Nm, double T2_Nm,
                      double *dx)
{
    gk_tq t;
    double y[4];
    int st = me_check(m, me, s);
    if (st != GK_OK) return st;
    if (dx == NULL) return GK_ERR_MODEL;
    if (!isfinite(T1_Nm) || !isfinite(T2_Nm)) return GK_ERR_INPUT;
    me_y(s, y);
    t = torque_bracket(m, T1_Nm);
    me_rhs(m, y, me_force(m, me, &t, y, NULL, NULL), T1_Nm, T2_Nm, dx);
    return GK_OK;
}

int gk_me_indicators(const gk_model *m, const gk_me *me, const gk_state *s, double T1_Nm, double *z)
{
    gk_tq t;
    double all[4 * GK_KINK_MAX_SLOTS + 2], y[4];
    int st = me_check(m, me, s);
    if (st != GK_OK) return st;
    if (z == NULL) return GK_ERR_MODEL;
    if (!isfinite(T1_Nm)) return GK_ERR_INPUT;
    me_y(s, y);
    t = torque_bracket(m, T1_Nm);
    me_all_indicators(m, me, &t, y, all);
    me_pack_indicators(m, me, all, z);
    return GK_OK;
}

int gk_me_outputs(const gk_model *m, const gk_me *me, const gk_state *s, double T1_Nm, double T2_Nm, double *out,
                  double *me_out)
{
    gk_tq t;
    double F, km, y[4];
    int j, P, st = me_check(m, me, s);
    if (st != GK_OK) return st;
    if (out == NULL) return GK_ERR_MODEL;
    if (!isfinite(T1_Nm) || !isfinite(T2_Nm)) return GK_ERR_INPUT;
    P = m->P;
    me_y(s, y);
    t = torque_bracket(m, T1_Nm);
    F = me_force(m, me, &t, y, out + GK_OUT_PAIR_FORCE, &km);
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
        me_rhs(m, y, F, T1_Nm, T2_Nm, me_out + GK_ME_OUT_DERIVATIVES);
        me_all_indicators(m, me, &t, y, me_out + GK_ME_OUT_INDICATORS);
    }
    return GK_OK;
}
