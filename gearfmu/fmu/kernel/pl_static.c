/*
 * pl_static.c -- the quasi-static initial state of the planetary drivetrain kernel (plkernel.h
 * pl_initialize; docs/planetary.md "Initial state"): the port of PlanetaryModel.static_state
 * (gearfmu/planetary/model.py).  q balances the static forces -- the reference torque on the motor
 * DOF and the balancing load on the load DOF, the springs, every mesh's static law at its table angle
 * (per pair k (d - b) on the drive flank, k (d + b) on the back flank, 0 in the backlash, for the pairs
 * in their contact zone; Lin & Parker 1999's mesh springs with Kahraman 1994's multi-mesh sums), the
 * rotating frames' centripetal terms at the start speed -- by Newton's method on the piecewise-linear
 * laws from the state with every pair in its zone pressed on its drive flank (an active-set
 * iteration that ends when the contact state repeats), each linear system solved by dense Gaussian
 * elimination with partial pivoting over the DOFs 1 .. n-1.
 *
 * The lookup of a mesh is the pair's Model Exchange lookup without node events (gk_pair.h me_tables:
 * the plain line of the cell of theta, k = 0 out of the pair's contact zone, the in-zone line of a
 * cell holding a zone edge).  No globals, no allocation, no abort.
 */
#include "pl_internal.h"

/* the DOF vector of a sparse map into v[n] (PlanetaryModel.vector: repeated DOFs add) */
static void pls_vector(int n, int count, const int *dof, const double *coef, double *v)
{
    int i, j;
    for (i = 0; i < n; ++i) v[i] = 0.0;
    for (j = 0; j < count; ++j) v[dof[j]] += coef[j];
}

/* sum_i v[i] q[i] */
static double pls_dot(int n, const double *v, const double *q)
{
    double s = 0.0;
    int i;
    for (i = 0; i < n; ++i) s += v[i] * q[i];
    return s;
}

/* The static law of mesh m at q (model.mesh_law): the force F, the stiffness of the pairs in contact
 * kt, the sum of k over the pairs (ksum) and of k (e + b) (keb); 0 when no pair is in its contact zone. */
static int pls_mesh_law(const pl_model *pl, pl_work *w, int m, double psi0, const double *q, double *F,
                        double *kt, double *ksum, double *keb)
{
    const pl_mesh *me = &pl->mesh[m];
    const gk_model *pm = me->pair;
    double th = me->a_ref * psi0, x, sv;
    gk_me mode;
    gk_ph c = GK_PH_NONE;
    int j, act = 0;
    pls_vector(pl->n, me->na, me->a_dof, me->a_coef, w->vec);
    th = th + pls_dot(pl->n, w->vec, q);
    th = th + me->phase;
    pls_vector(pl->n, me->nx, me->x_dof, me->x_coef, w->vec);
    x = pls_dot(pl->n, w->vec, q);
    me_clear(&mode, GK_ME_NODES_NONE);
    sv = th * pm->inv_dphi;
    if (pm->zone_n_mesh > 0.0)
        for (j = 0; j < pm->P; ++j) me_zone_distance(pm, j, sv, &mode.zin[j]);
    me_cell(pm, &mode, th, &c);
    *F = *kt = *ksum = *keb = 0.0;
    for (j = 0; j < pm->P; ++j) {
        double kv, ev, es, bv, d;
        me_tables(pm, &w->tq[m], &mode, &c, j, &kv, &ev, &es, &bv);
        *ksum += kv;
        *keb += kv * (ev + bv);
        if (!(kv > 0.0)) continue;
        act = 1;
        d = x - ev;
        if (d > bv) {
            *F += kv * (d - bv);
            *kt += kv;
        } else if (d < -bv) {
            *F += kv * (d + bv);
            *kt += kv;
        }
    }
    return act;
}

/* Solve A[free, free] x = b[free] for the DOFs 1 .. n-1 (A row-major n x n, destroyed; b destroyed;
 * x[0] untouched): Gaussian elimination with partial pivoting.  0 when singular. */
static int pls_solve(int n, double *A, double *b, double *x)
{
    int i, j, k;
    for (k = 1; k < n; ++k) {
        int p = k;
        double big = fabs(A[k * n + k]);
        for (i = k + 1; i < n; ++i)
            if (fabs(A[i * n + k]) > big) {
                big = fabs(A[i * n + k]);
                p = i;
            }
        if (!(big > 0.0) || !isfinite(big)) return 0;
        if (p != k) {
            double t;
            for (j = 1; j < n; ++j) {
                t = A[k * n + j];
                A[k * n + j] = A[p * n + j];
                A[p * n + j] = t;
            }
            t = b[k];
            b[k] = b[p];
            b[p] = t;
        }
        for (i = k + 1; i < n; ++i) {
            double f = A[i * n + k] / A[k * n + k];
            if (f == 0.0) continue;
            for (j = k; j < n; ++j) A[i * n + j] -= f * A[k * n + j];
            b[i] -= f * b[k];
        }
    }
    for (i = n - 1; i >= 1; --i) {
        double s = b[i];
        for (j = i + 1; j < n; ++j) s -= A[i * n + j] * x[j];
        x[i] = s / A[i * n + i];
    }
    return 1;
}

/* J += s a a^T with a the x map of mesh m */
static void pls_add_outer(const pl_model *pl, pl_work *w, int m, double s, double *J)
{
    const pl_mesh *me = &pl->mesh[m];
    int n = pl->n, i, j;
    pls_vector(n, me->nx, me->x_dof, me->x_coef, w->vec);
    for (i = 0; i < n; ++i)
        for (j = 0; j < n; ++j) J[i * n + j] += s * (w->vec[i] * w->vec[j]);
}

/* a drive DOF (1/m 0) is not solved for: its row and column of J the identity's, its residual 0, so that
 * it stays at q = 0 (PlanetaryModel.static_state leaves it out) */
static void pls_fix_drives(const pl_model *pl, double *J, double *r)
{
    int n = pl->n, i, j;
    for (i = 1; i < n; ++i) {
        if (pl->inv_m[i] != 0.0) continue;
        for (j = 0; j < n; ++j) J[i * n + j] = J[j * n + i] = 0.0;
        J[i * n + i] = 1.0;
        r[i] = 0.0;
    }
}

int pl_initialize(const pl_model *pl, pl_work *w, pl_state *s, double psi0, double omega0, double T_ref,
                  int *bad_mesh)
{
    return pl_initialize_driven(pl, w, s, psi0, omega0, T_ref, NULL, bad_mesh);
}

int pl_initialize_driven(const pl_model *pl, pl_work *w, pl_state *s, double psi0, double omega0, double T_ref,
                         const double *speed, int *bad_mesh)
{
    int n, i, j, m, it, nn;
    double *J, *Ks, *q;
    if (bad_mesh != NULL) *bad_mesh = -1;
    if (pl == NULL || w == NULL || s == NULL) return GK_ERR_MODEL;
    if (!isfinite(psi0) || !isfinite(omega0) || !isfinite(T_ref)) return GK_ERR_INPUT;
    for (j = 0; speed != NULL && j < pl->n_drive; ++j)
        if (!isfinite(speed[j])) return GK_ERR_INPUT;
    n = pl->n;
    nn = n * n;
    J = w->J;
    Ks = w->Ks;
    q = w->q;
    for (m = 0; m < pl->n_mesh; ++m) {
        const gk_ph none = GK_PH_NONE;
        w->tq[m] = torque_bracket(pl->mesh[m].pair, pl_mesh_torque(pl, m, T_ref));
        w->ph[m] = none;
    }
    for (i = 0; i < n; ++i) {
        w->fext[i] = 0.0;
        w->cen[i] = 0.0;
        w->Kc[i] = 0.0;
        q[i] = 0.0;
    }
    w->fext[0] += T_ref;
    w->fext[pl->load_dof] -= T_ref / pl->g[pl->load_dof];
    for (i = 0; i < nn; ++i) Ks[i] = 0.0;
    for (m = 0; m < pl->n_spring; ++m) {
        const pl_spring *sp = &pl->spring[m];
        pls_vector(n, sp->count, sp->dof, sp->coef, w->vec);
        for (i = 0; i < n; ++i)
            for (j = 0; j < n; ++j) Ks[i * n + j] += sp->k * (w->vec[i] * w->vec[j]);
    }
    /* the frames' centripetal force m Omega^2 (R0 + q_a) on q_a: its q part a negative stiffness */
    for (m = 0; m < pl->n_frame; ++m) {
        const pl_frame *f = &pl->frame[m];
        double W = f->ratio * omega0, W2;
        if (f->drive >= 0 && speed != NULL)   /* a drive turns the frame too (PlanetaryModel.static_state) */
            for (j = 0; j < pl->n_drive; ++j)
                if (pl->drive_dof[j] == f->drive) W += f->drive_ratio * speed[j];
        W2 = W * W;
        w->cen[f->a] += (1.0 / pl->inv_m[f->a]) * W2 * f->R0_m;
        w->Kc[f->a] += (1.0 / pl->inv_m[f->a]) * W2;
        w->Kc[f->b] += (1.0 / pl->inv_m[f->b]) * W2;
    }
    /* start: every pair in its zone on its drive flank, the linear problem of that contact state */
    for (i = 0; i < nn; ++i) J[i] = Ks[i];
    for (i = 0; i < n; ++i) {
        J[i * n + i] -= w->Kc[i];
        w->r[i] = w->fext[i] + w->cen[i];
    }
    for (m = 0; m < pl->n_mesh; ++m) {
        double F, kt, ksum, keb;
        if (!pls_mesh_law(pl, w, m, psi0, q, &F, &kt, &ksum, &keb)) {
            if (bad_mesh != NULL) *bad_mesh = m;
            return GK_ERR_NOCONTACT;
        }
        pls_add_outer(pl, w, m, ksum, J);
        for (i = 0; i < n; ++i) w->r[i] += keb * w->vec[i];
    }
    pls_fix_drives(pl, J, w->r);
    if (!pls_solve(n, J, w->r, q)) return GK_ERR_NOCONTACT;
    for (it = 0;; ++it) {
        double scale, worst = 0.0, kq = 0.0;
        for (i = 0; i < nn; ++i) J[i] = Ks[i];
        for (i = 0; i < n; ++i) {
            double a = 0.0;
            int j;
            J[i * n + i] -= w->Kc[i];
            w->r[i] = w->fext[i] + w->cen[i] + w->Kc[i] * q[i] - pls_dot(n, Ks + i * n, q);
            /* the residual's round-off grows with the largest term summed into it, the springs' k q too */
            for (j = 0; j < n; ++j) a += fabs(Ks[i * n + j]) * fabs(q[j]);
            if (a > kq) kq = a;
        }
        scale = fabs(T_ref) + kq;
        for (m = 0; m < pl->n_mesh; ++m) {
            double F, kt, ksum, keb, amax = 0.0, kj;
            if (!pls_mesh_law(pl, w, m, psi0, q, &F, &kt, &ksum, &keb)) {
                if (bad_mesh != NULL) *bad_mesh = m;
                return GK_ERR_NOCONTACT;
            }
            pls_vector(n, pl->mesh[m].nx, pl->mesh[m].x_dof, pl->mesh[m].x_coef, w->vec);
            for (i = 0; i < n; ++i) {
                w->r[i] -= w->vec[i] * F;
                if (fabs(w->vec[i]) > amax) amax = fabs(w->vec[i]);
            }
            scale += fabs(F) * amax;
            kj = 1e-6 * ksum;
            pls_add_outer(pl, w, m, kt > kj ? kt : kj, J);
        }
        pls_fix_drives(pl, J, w->r);
        for (i = 1; i < n; ++i)
            worst = isfinite(w->r[i]) ? (fabs(w->r[i]) > worst ? fabs(w->r[i]) : worst) : HUGE_VAL;
        if (worst <= PL_STATIC_TOL * (scale > 1e-300 ? scale : 1e-300)) break;
        if (it == PL_STATIC_ITERATIONS - 1) return GK_ERR_NOCONTACT;   /* no equilibrium */
        for (i = 1; i < n; ++i) w->dq[i] = 0.0;
        if (!pls_solve(n, J, w->r, w->dq)) return GK_ERR_NOCONTACT;
        for (i = 1; i < n; ++i) q[i] += w->dq[i];
    }
    s->y[0] = psi0;
    s->y[1] = omega0;
    for (i = 1; i < n; ++i) {
        s->y[2 * i] = q[i];
        s->y[2 * i + 1] = 0.0;
    }
    return speed != NULL ? pl_start_drives(pl, s, speed) : GK_OK;
}
