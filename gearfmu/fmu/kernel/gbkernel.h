/*
 * gbkernel.h -- the gearbox model of docs/gearbox.md in C99: several gear-pair stages (meshes)
 * and elastic shafts joining rigid bodies, one torsional system.
 *
 * Every mesh is a pair model of gearkernel.h (gk_model: its tables, contact-zone cuts, node
 * flags, damping and force law), looked up, loaded and event-located per mesh by the pair's own
 * pieces (gk_pair.h); the gearbox adds the bodies, the shafts and the sums over them in the
 * order of docs/gearbox.md "Kernel data", the same arithmetic as the numba gearbox solver
 * (gearfmu/gearbox/kernels.py), so that the two agree bit for bit.
 *
 * State y (2n values, n bodies): psi, omega (the motor body's angle and speed), then
 * (u_i, du_i) of bodies 1 .. n-1, the deviations from the kinematic positions g_i psi.
 *
 * Rules as in gearkernel.h: no global or static mutable data (the model, the work and the
 * state are structs the caller owns), no allocation, never abort: every entry point returns a
 * status code (GK_OK or a GK_ERR_* of gearkernel.h).  SI units throughout.
 */
#ifndef GBKERNEL_H
#define GBKERNEL_H

#include "gearkernel.h"

#ifdef __cplusplus
extern "C" {
#endif

#define GB_ABI_VERSION 2  /* 2: Model Exchange (gb_me_*) */

/* sizes of the fixed arrays (a gearbox beyond them is refused by gb_init / gb_add_*) */
#define GB_MAX_BODIES 64
#define GB_MAX_MESHES 16
#define GB_MAX_SHAFTS 64
#define GB_MAX_STATE (2 * GB_MAX_BODIES)

/* integrators (docs/gearbox.md "Integrators"): the pair's codes; rk4_seg runs as rk4_node between its
 * stops, every evaluation in the cell of its own angle, the true velocities integrated */
#define GB_INTEGRATOR_RK4 GK_INTEGRATOR_RK4
#define GB_INTEGRATOR_RK4_KINK GK_INTEGRATOR_RK4_KINK
#define GB_INTEGRATOR_RK4_NODE GK_INTEGRATOR_RK4_NODE
#define GB_INTEGRATOR_RK4_SEG GK_INTEGRATOR_RK4_SEG

typedef struct gb_mesh {
    gk_model *pair;   /* the stage's pair model (borrowed; gk_init done, cuts and damping set) */
    int p, q;         /* pinion body, gear body */
    double g_p;       /* kinematic ratio of the pinion body */
    int on_path;      /* 1: on the power path, its torque row follows T_ref/g_p; 0: the row of 0 N*m */
} gb_mesh;

typedef struct gb_model {
    int n;                          /* bodies (>= 2) */
    int n_mesh, n_shaft, n_edge;
    int load_body;
    int motor_input, load_input;    /* which ends are torque inputs (an end that is not takes 0) */
    int integrator;                 /* GB_INTEGRATOR_* */
    double inv_I[GB_MAX_BODIES];    /* 1/I_i (1/(kg*m^2)) */
    double g[GB_MAX_BODIES];        /* kinematic ratios, g[0] = 1 */
    gb_mesh mesh[GB_MAX_MESHES];
    int shaft_a[GB_MAX_SHAFTS], shaft_b[GB_MAX_SHAFTS];    /* upstream, downstream body */
    double shaft_k[GB_MAX_SHAFTS], shaft_c[GB_MAX_SHAFTS];  /* N*m/rad, N*m*s/rad */
    int shaft_on_path[GB_MAX_SHAFTS];                       /* 1: carries the static torque T_ref/g_a */
    /* the tree walked from body 0 (static state): kind 0 shaft, 1 mesh; its index; up, down body */
    int edge_kind[GB_MAX_MESHES + GB_MAX_SHAFTS], edge_index[GB_MAX_MESHES + GB_MAX_SHAFTS];
    int edge_up[GB_MAX_MESHES + GB_MAX_SHAFTS], edge_down[GB_MAX_MESHES + GB_MAX_SHAFTS];
} gb_model;

typedef struct gb_state {
    double y[GB_MAX_STATE];         /* psi, omega, u_1, du_1, ... (2n used) */
} gb_state;

/* the work of a step (gb_kernel.c; caller-owned, gb_sizeof_work bytes, no meaning between calls) */
typedef struct gb_work gb_work;

GK_API int gb_abi_version(void);
GK_API int gb_sizeof_model(void);
GK_API int gb_sizeof_work(void);
/* the events located by the last gb_do_step (rk4_kink, rk4_node) */
GK_API long gb_events(const gb_work *w);

/* An empty gearbox of n bodies with 1/I (inv_I[n], finite > 0) and kinematic ratios g[n] (finite
 * > 0, g[0] = 1), the load body and which ends are torque inputs; integrator rk4. */
GK_API int gb_init(gb_model *gb, int n, const double *inv_I, const double *g, int load_body, int motor_input,
                   int load_input);
/* mesh of pinion body p and gear body q on the pair model `pair` (borrowed), pinion ratio g_p = g[p] */
GK_API int gb_add_mesh(gb_model *gb, gk_model *pair, int p, int q, int on_path);
/* elastic shaft from upstream body a to downstream body b (k > 0, c >= 0); on_path: on the power path */
GK_API int gb_add_shaft(gb_model *gb, int a, int b, double k_Nm_per_rad, double c_Nms_per_rad, int on_path);
/* the next link of the tree walked from body 0 (kind 0 shaft, 1 mesh; its index) */
GK_API int gb_add_edge(gb_model *gb, int kind, int index, int up, int down);
/* GB_INTEGRATOR_*; GK_ERR_PARAM for another code or a mesh of more than GK_KINK_MAX_SLOTS slots */
GK_API int gb_set_integrator(gb_model *gb, int integrator);

/* The motor-side torque the stages transmit (N*m): T_motor when the motor is a torque input,
 * else T_load * g_load (docs/gearbox.md "Model"). */
GK_API double gb_reference_torque(const gb_model *gb, double T_motor_Nm, double T_load_Nm);
/* The static pinion torque of mesh m at the reference torque: T_ref/g_p on the power path, else 0. */
GK_API double gb_stage_torque(const gb_model *gb, int m, double T_ref_Nm);

/* The quasi-static initial state (docs/gearbox.md "Initial state") under T_ref at motor angle
 * psi0 and speed omega0.  GK_ERR_NOCONTACT with *bad_mesh = the mesh that has no pair in contact. */
GK_API int gb_initialize(const gb_model *gb, gb_state *s, double psi0_rad, double omega0_rad_s, double T_ref_Nm,
                         int *bad_mesh);

/* The right-hand side dy = f(t, y) with the inputs held (docs/gearbox.md "Model"; the plain lookup,
 * every mesh in its own table cell): the form a Model Exchange host integrates.  The model is
 * autonomous, t_s is not read. */
GK_API int gb_derivatives(const gb_model *gb, gb_work *w, double t_s, const double *y, double T_motor_Nm,
                          double T_load_Nm, double *dy);

/* One communication step of length H with the inputs held: n = max(1, ceil(H/h_max*(1 - 1e-12)))
 * substeps of the integrator; outputs into out (may be NULL).  On an error the state is left
 * unchanged (GK_ERR_NONFINITE: the state turned non-finite). */
GK_API int gb_do_step(const gb_model *gb, gb_work *w, gb_state *s, double T_motor_Nm, double T_load_Nm,
                      double H_s, double h_max_s, double *out);

/* The outputs at state s (the torque rows of the inputs): gb_n_outputs values, laid out as
 * gb_output_offset says. */
GK_API int gb_outputs(const gb_model *gb, const gb_state *s, double T_motor_Nm, double T_load_Nm, double *out);

/* Model Exchange (docs/model.md "Model Exchange"; the pair's gk_me_* for every mesh): the host
 * integrates y; every mesh's mode is held between events (gb_me) and decided anew from the state at
 * each (gb_me_update: at the state and a moment ahead); the derivatives, indicators and outputs are
 * those with the modes held.  The indicators: every mesh's gk_me_indicators one after another
 * (gb_me_n_indicators of them).  GK_ERR_NONFINITE for a non-finite state, GK_ERR_INPUT for a
 * non-finite torque, GK_ERR_PARAM for a bad node_events (GK_ME_NODES_*). */
typedef struct gb_me {
    gk_me mesh[GB_MAX_MESHES];
} gb_me;

GK_API int gb_sizeof_me(void);
GK_API int gb_me_n_indicators(const gb_model *gb, int node_events);
GK_API int gb_me_init(const gb_model *gb, gb_work *w, gb_me *me, const double *y, double T_motor_Nm,
                      double T_load_Nm, int node_events);
GK_API int gb_me_update(const gb_model *gb, gb_work *w, gb_me *me, const double *y, double T_motor_Nm,
                        double T_load_Nm, int *changed);
GK_API int gb_me_derivatives(const gb_model *gb, gb_work *w, const gb_me *me, const double *y, double T_motor_Nm,
                             double T_load_Nm, double *dy);
GK_API int gb_me_indicators(const gb_model *gb, gb_work *w, const gb_me *me, const double *y, double T_motor_Nm,
                            double T_load_Nm, double *z);
/* gb_outputs with the modes held (gb_n_outputs values) */
GK_API int gb_me_outputs(const gb_model *gb, gb_work *w, const gb_me *me, const double *y, double T_motor_Nm,
                         double T_load_Nm, double *out);

/* Output layout: body i: [2i] angle (rad), [2i + 1] speed (rad/s); mesh m from gb_mesh_offset(m):
 * x (m), v (m/s), mesh force (N), stiffness in contact (N/m), P pair forces (N), P load sharings (1);
 * shaft s at gb_shaft_offset + s: torque (N*m, positive driving away from the motor). */
#define GB_OUT_DTE 0
#define GB_OUT_DTE_RATE 1
#define GB_OUT_MESH_FORCE 2
#define GB_OUT_MESH_STIFFNESS 3
#define GB_OUT_PAIR_FORCE 4
GK_API int gb_mesh_offset(const gb_model *gb, int m);
GK_API int gb_shaft_offset(const gb_model *gb);
GK_API int gb_n_outputs(const gb_model *gb);

#ifdef __cplusplus
}
#endif
#endif /* GBKERNEL_H */
