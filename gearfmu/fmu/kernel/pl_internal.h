/*
 * pl_internal.h -- what the files of the planetary kernel share (the public contract is plkernel.h):
 *
 *   pl_kernel.c   the model's setup, the right-hand side, RK4 and the event-aware substep of
 *                 rk4_kink / rk4_node, the step, the outputs and Model Exchange;
 *   pl_static.c   the quasi-static initial state (pl_initialize).
 *
 * Both compute every mesh with the pair's own pieces (gk_pair.h) on the mesh's own gk_model, mapped
 * to its local state (theta, omega, x, v) by pl_mesh_local.  The internal functions are prefixed plk_.
 */
#ifndef PL_INTERNAL_H
#define PL_INTERNAL_H

#include "plkernel.h"
#include "gk_pair.h"

struct pl_work {
    gk_tq tq[PL_MAX_MESHES];                    /* torque rows of the step */
    gk_ph ph[PL_MAX_MESHES];                    /* rk4: the cell carried from one evaluation to the next */
    gk_mode md[PL_MAX_MESHES];                  /* rk4_kink, rk4_node: the mode held */
    double tau[PL_MAX_DOF];                     /* generalised forces Q_i */
    double y[PL_MAX_STATE], f0[PL_MAX_STATE], y1[PL_MAX_STATE], f1[PL_MAX_STATE], yt[PL_MAX_STATE];
    double tmp[PL_MAX_STATE], acc[PL_MAX_STATE], kk[PL_MAX_STATE];
    long events;
    const pl_me *me;                            /* Model Exchange: the modes held (plk_rhs with locked 2) */
    /* the static state (pl_static.c): the Newton matrix, the spring and frame stiffness, the vectors */
    double J[PL_MAX_DOF * PL_MAX_DOF], Ks[PL_MAX_DOF * PL_MAX_DOF];
    double Kc[PL_MAX_DOF], cen[PL_MAX_DOF], fext[PL_MAX_DOF], q[PL_MAX_DOF], r[PL_MAX_DOF], dq[PL_MAX_DOF];
    double vec[PL_MAX_DOF];
};

/* q_i (o = 0) or q_i' (o = 1) of DOF i from the vector v: 0 for DOF 0 (kernels._u) */
GK_INLINE double plk_u(const double *v, int o, int i)
{
    if (i == 0) return 0.0;
    return v[o + 2 * i];
}

/* mesh m's own (theta, omega) of the vector v, a state (off 1.0) or its derivative (off 0.0: the map is
 * linear but for the phase; kernels._angle) */
GK_INLINE void plk_mesh_angle(const pl_mesh *me, const double *v, double off, double *th_out, double *om_out)
{
    double th = me->a_ref * v[0] + off * me->phase, om = me->a_ref * v[1];
    int j;
    if (me->a_has0) {   /* a DOF-0 term adds c * 0.0 (which can turn a -0.0 sum into +0.0) */
        for (j = 0; j < me->na; ++j) {
            int d = me->a_dof[j];
            double c = me->a_coef[j];
            th += c * plk_u(v, 0, d);
            om += c * plk_u(v, 1, d);
        }
    } else {
        for (j = 0; j < me->na; ++j) {
            const double *q = v + me->a_off[j];
            th += me->a_coef[j] * q[0];
            om += me->a_coef[j] * q[1];
        }
    }
    *th_out = th;
    *om_out = om;
}

/* mesh m's own (theta, omega, x, v) of the vector v (kernels._local): (theta, omega) of plk_mesh_angle,
 * (x, v) over the x map without its DOF-0 terms (xh_*).  Leaving those out is exact: each adds
 * c * 0.0 = +-0 to a sum that starts at +0.0 and so is never -0.0, which leaves it unchanged (the
 * springs' sums of plk_rhs alike; their forces on q_0, tau[0], are never read). */
GK_INLINE void plk_mesh_local(const pl_mesh *me, const double *v, double off, double *loc)
{
    double x = 0.0, xv = 0.0;
    int j;
    plk_mesh_angle(me, v, off, &loc[0], &loc[1]);
    for (j = 0; j < me->nxh; ++j) {
        const double *q = v + me->xh_off[j];
        double c = me->xh_coef[j];
        x += c * q[0];
        xv += c * q[1];
    }
    loc[2] = x;
    loc[3] = xv;
}

#endif /* PL_INTERNAL_H */
