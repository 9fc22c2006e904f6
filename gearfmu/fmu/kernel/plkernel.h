/*
 * plkernel.h -- the planetary drivetrain model of docs/planetary.md in C99: planetary stages
 * (torsional or translational, Lin & Parker 1999; Kahraman 1994) alone or with parallel-axis
 * meshes and shafts, one system of generalised degrees of freedom.
 *
 * Every element is a sparse linear map of the DOFs (the flat data of gearfmu/planetary/kernels.py):
 * a spring couples up to 5 DOFs, a mesh's transmission error x is a map of up to 7 DOFs and its table
 * angle a map of the reference angle psi and up to 2 DOFs, a rotating frame adds the inertial terms
 * of a planet's translations on a turning carrier.  Every mesh is a pair model of gearkernel.h
 * (gk_model: its tables, contact-zone cuts, node flags, damping and force law), looked up, loaded and
 * event-located per mesh by the pair's own pieces (gk_pair.h) as gb_kernel.c does for the gearbox,
 * with the arithmetic of the numba planetary solver, so that the two agree bit for bit.
 *
 * State y (2n values, n DOFs): psi, omega (the motor DOF's angle and speed), then (q_i, q_i') of
 * DOFs 1 .. n-1, the deviations from the rigid motion g_i psi.
 *
 * Rules as in gearkernel.h: no global or static mutable data (the model, the work and the state are
 * structs the caller owns), no allocation, never abort: every entry point returns a status code
 * (GK_OK or a GK_ERR_* of gearkernel.h).  SI units throughout.
 */
#ifndef PLKERNEL_H
#define PLKERNEL_H

#include "gearkernel.h"

#ifdef __cplusplus
extern "C" {
#endif

#define PL_ABI_VERSION 2

/* sizes of the fixed arrays (a drivetrain beyond them is refused by pl_init / pl_add_*) */
#define PL_MAX_DOF 96
#define PL_MAX_STATE (2 * PL_MAX_DOF)
#define PL_MAX_MESHES 32
#define PL_MAX_SPRINGS 160
#define PL_MAX_FRAMES 48
#define PL_MAX_GROUPS 4      /* load-sharing groups (one per planetary stage) */
#define PL_MAX_GROUP 8       /* meshes per group (planets) */
#define PL_MESH_MAX_X 7      /* DOFs of a mesh's transmission-error map */
#define PL_MESH_MAX_A 2      /* DOFs of a mesh's table-angle map */
#define PL_SPRING_MAX 5      /* DOFs of a spring */
#define PL_MAX_DRIVES 4      /* drives of driven members (one per planetary stage) */

/* integrators: the pair's codes; rk4_seg runs as rk4_node between its stops, every evaluation in the
 * cell of its own angle, the true velocities integrated (docs/planetary.md "rk4_seg") */
#define PL_INTEGRATOR_RK4 GK_INTEGRATOR_RK4
#define PL_INTEGRATOR_RK4_KINK GK_INTEGRATOR_RK4_KINK
#define PL_INTEGRATOR_RK4_NODE GK_INTEGRATOR_RK4_NODE
#define PL_INTEGRATOR_RK4_SEG GK_INTEGRATOR_RK4_SEG

/* static state (pl_initialize): Newton steps and residual (of the forces) */
#define PL_STATIC_ITERATIONS 60
#define PL_STATIC_TOL 1e-13

typedef struct pl_mesh {
    gk_model *pair;                         /* the mesh's pair model (borrowed; gk_init done, cuts and damping set) */
    int nx;                                 /* x = sum_j x_coef[j] q[x_dof[j]] (m) */
    int x_dof[PL_MESH_MAX_X];
    double x_coef[PL_MESH_MAX_X];
    int nxh;                                /* the x map without its DOF-0 terms (q_0 is 0): the loops of the step */
    int xh_dof[PL_MESH_MAX_X];
    double xh_coef[PL_MESH_MAX_X];
    int xh_off[PL_MESH_MAX_X];              /* 2 xh_dof[j]: the offset of q in a state vector */
    int na;                                 /* theta = a_ref psi + sum_j a_coef[j] q[a_dof[j]] + phase (rad) */
    int a_dof[PL_MESH_MAX_A];
    double a_coef[PL_MESH_MAX_A];
    int a_off[PL_MESH_MAX_A];               /* 2 a_dof[j] */
    int a_has0;                             /* 1 when the angle map names DOF 0 (its term reads 0, pl_internal.h) */
    double a_ref, phase;
    double torque_per_ref;                  /* static pinion torque of the tables' rows per reference torque */
} pl_mesh;

typedef struct pl_spring {
    int count;                              /* DOFs: stretch r = sum_j coef[j] q[dof[j]] */
    int dof[PL_SPRING_MAX];
    double coef[PL_SPRING_MAX];
    int nh;                                 /* the map without its DOF-0 terms (q_0 is 0): the loops of the step */
    int hdof[PL_SPRING_MAX];
    double hcoef[PL_SPRING_MAX];
    int hoff[PL_SPRING_MAX];                /* 2 hdof[j]: the offset of q in a state vector */
    double k, c;                            /* N/m and N*s/m (N*m/rad and N*m*s/rad for rotations) */
} pl_spring;

typedef struct pl_frame {
    int a, b;                               /* the radial and tangential DOF of a body on a turning frame */
    double R0_m;                            /* its radius */
    double ratio;                           /* the frame's speed over omega */
    int drive;                              /* the drive DOF that turns the frame too, or -1 */
    double drive_ratio;                     /* the frame's speed over that drive's speed */
} pl_frame;

typedef struct pl_group {
    int count;                              /* the stage's sun-planet meshes */
    int mesh[PL_MAX_GROUP];
} pl_group;

typedef struct pl_model {
    int n;                                  /* DOFs (>= 2) */
    int n_mesh, n_spring, n_frame, n_group;
    int load_dof;                           /* the DOF the load torque acts on (0: the motor DOF) */
    int motor_input, load_input;            /* which ends are torque inputs (an end that is not takes 0) */
    int integrator;                         /* PL_INTEGRATOR_* */
    double inv_m[PL_MAX_DOF];               /* 1/m_i (1/kg or 1/(kg*m^2)) */
    double g[PL_MAX_DOF];                   /* kinematic ratios, g[0] = 1 */
    int n_g;                                /* the DOFs i >= 1 with g[i] != 0, in order: the terms of the */
    int g_dof[PL_MAX_DOF];                  /* step's sum of g_i Q_i (a zero term leaves that sum unchanged) */
    pl_mesh mesh[PL_MAX_MESHES];
    pl_spring spring[PL_MAX_SPRINGS];
    pl_frame frame[PL_MAX_FRAMES];
    pl_group group[PL_MAX_GROUPS];
    /* drives of driven members (docs/planetary.md "Driven members"): a DOF of infinite inertia
     * (inv_m 0, g 0) whose speed q' is prescribed; its rigid motion, every DOF's speed per unit drive
     * speed with the motor DOF at rest */
    int n_drive;
    int drive_dof[PL_MAX_DRIVES];
    double drive_mode[PL_MAX_DRIVES][PL_MAX_DOF];
} pl_model;

typedef struct pl_state {
    double y[PL_MAX_STATE];                 /* psi, omega, q_1, q_1', ... (2n used) */
} pl_state;

/* the work of a step and of the static state (pl_kernel.c; caller-owned, pl_sizeof_work bytes, no
 * meaning between calls) */
typedef struct pl_work pl_work;

GK_API int pl_abi_version(void);
GK_API int pl_sizeof_model(void);
GK_API int pl_sizeof_work(void);
GK_API int pl_sizeof_state(void);
/* the events located by the last pl_do_step (rk4_kink, rk4_node) */
GK_API long pl_events(const pl_work *w);

/* An empty drivetrain of n DOFs with 1/m (inv_m[n], finite > 0; or 0 with g 0 for the drive of a
 * driven member, i >= 1, to be declared by pl_add_drive) and kinematic ratios g[n] (finite, g[0] = 1; 0
 * for a translation), the load DOF (0 <= load_dof < n, g[load_dof] != 0) and which ends are torque
 * inputs; integrator rk4. */
GK_API int pl_init(pl_model *pl, int n_dof, const double *inv_m, const double *g, int load_dof, int motor_input,
                   int load_input);
/* a spring over count (1..PL_SPRING_MAX) DOFs with coefficients coef, stiffness k > 0 and damping c >= 0 */
GK_API int pl_add_spring(pl_model *pl, int count, const int *dof, const double *coef, double k, double c);
/* the inertial terms of a body whose DOFs a (radial) and b (tangential) ride on a frame turning at
 * frame_ratio * omega at radius R0 */
GK_API int pl_add_frame(pl_model *pl, int dof_a, int dof_b, double R0_m, double frame_ratio);
/* a mesh on the pair model `pair` (borrowed): x map (nx <= PL_MESH_MAX_X), table-angle map (na <= 2), the angle's
 * psi coefficient and phase, the static pinion torque per reference torque */
GK_API int pl_add_mesh(pl_model *pl, gk_model *pair, int nx, const int *x_dof, const double *x_coef, int na,
                       const int *a_dof, const double *a_coef, double a_ref, double phase_rad,
                       double torque_per_ref);
/* load-sharing factor group: L_j = count * F_j / sum_k F_k over the listed meshes (the stage's
 * sun-planet meshes; Kahraman 1994), NaN when the sum is 0 */
GK_API int pl_add_group(pl_model *pl, int count, const int *mesh);
/* frame `frame` turns with drive DOF drive_dof (declared by pl_add_drive) too: at ratio * omega +
 * drive_ratio * q_drive' (a translational stage whose carrier a drive turns) */
GK_API int pl_set_frame_drive(pl_model *pl, int frame, int drive_dof, double drive_ratio);
/* the drive of a driven member: DOF dof (inv_m 0, g 0) and its rigid motion mode[n] (finite, mode[dof] =
 * 1, mode[0] = 0) */
GK_API int pl_add_drive(pl_model *pl, int dof, const double *mode);
/* the drives' speeds (rad/s, one per drive, finite) into the state: q' of every drive DOF (the start of a
 * communication step); GK_ERR_INPUT for a non-finite speed (state unchanged) */
GK_API int pl_set_drive_speeds(const pl_model *pl, pl_state *s, const double *speed_rad_s);
/* the drives' rigid motion at the start (after pl_initialize): q'_i = sum_j mode_j[i] speed_j for
 * i >= 1; GK_ERR_INPUT for a non-finite speed (state unchanged) */
GK_API int pl_start_drives(const pl_model *pl, pl_state *s, const double *speed_rad_s);
/* pl_initialize with the drives at speed_rad_s (one per drive; NULL: at rest): the frames' centripetal
 * terms at their speed with the drives', then pl_start_drives */
GK_API int pl_initialize_driven(const pl_model *pl, pl_work *w, pl_state *s, double psi0_rad, double omega0_rad_s,
                                double T_ref_Nm, const double *speed_rad_s, int *bad_mesh);
/* PL_INTEGRATOR_*; GK_ERR_PARAM for another code or a mesh of more than GK_KINK_MAX_SLOTS slots */
GK_API int pl_set_integrator(pl_model *pl, int integrator);

/* The motor-side torque (N*m): T_motor when the motor is a torque input, else T_load * g[load_dof]. */
GK_API double pl_reference_torque(const pl_model *pl, double T_motor_Nm, double T_load_Nm);
/* The static pinion torque of mesh m that selects its torque rows: |torque_per_ref * T_ref| (N*m). */
GK_API double pl_mesh_torque(const pl_model *pl, int m, double T_ref_Nm);

/* The quasi-static initial state (docs/planetary.md "Initial state"; PlanetaryModel.static_state):
 * psi = psi0, omega = omega0, q' = 0 and q balancing (a drive DOF stays at q = 0) the static forces (the reference torque and the
 * balancing load, springs, the meshes' static laws at their table angles, the frames' centripetal
 * terms at omega0), Newton's method on the piecewise-linear mesh laws, dense Gaussian elimination with
 * partial pivoting.  GK_ERR_NOCONTACT (no equilibrium) with *bad_mesh = the mesh with no pair in its
 * contact zone, or with *bad_mesh = -1 when Newton's method finds none in PL_STATIC_ITERATIONS steps
 * (or the linear system is singular); GK_ERR_INPUT for a non-finite argument. */
GK_API int pl_initialize(const pl_model *pl, pl_work *w, pl_state *s, double psi0_rad, double omega0_rad_s,
                         double T_ref_Nm, int *bad_mesh);

/* The right-hand side dy = f(t, y) with the inputs held (the plain lookup, every mesh in its own
 * table cell): the form a Model Exchange host integrates.  Autonomous: t_s is not read. */
GK_API int pl_derivatives(const pl_model *pl, pl_work *w, double t_s, const double *y, double T_motor_Nm,
                          double T_load_Nm, double *dy);

/* One communication step of length H with the inputs held: n = max(1, ceil(H/h_max*(1 - 1e-12)))
 * substeps of the integrator; outputs into out (may be NULL).  On an error the state is left
 * unchanged (GK_ERR_NONFINITE: the state turned non-finite). */
GK_API int pl_do_step(const pl_model *pl, pl_work *w, pl_state *s, double T_motor_Nm, double T_load_Nm,
                      double H_s, double h_max_s, double *out);

/* The outputs at state s (the torque rows of the inputs): pl_n_outputs values, laid out as below. */
GK_API int pl_outputs(const pl_model *pl, pl_work *w, const pl_state *s, double T_motor_Nm, double T_load_Nm,
                      double *out);

/* Model Exchange (docs/model.md "Model Exchange"; the pair's gk_me for every mesh), as gb_me_*: every
 * mesh's mode held between the host's events and decided anew from the state at each; the
 * derivatives, indicators and outputs with the modes held; the indicators of every mesh one after
 * another (pl_me_n_indicators of them). */
typedef struct pl_me {
    gk_me mesh[PL_MAX_MESHES];
} pl_me;

GK_API int pl_sizeof_me(void);
GK_API int pl_me_n_indicators(const pl_model *pl, int node_events);
GK_API int pl_me_init(const pl_model *pl, pl_work *w, pl_me *me, const double *y, double T_motor_Nm,
                      double T_load_Nm, int node_events);
GK_API int pl_me_update(const pl_model *pl, pl_work *w, pl_me *me, const double *y, double T_motor_Nm,
                        double T_load_Nm, int *changed);
GK_API int pl_me_derivatives(const pl_model *pl, pl_work *w, const pl_me *me, const double *y, double T_motor_Nm,
                             double T_load_Nm, double *dy);
GK_API int pl_me_indicators(const pl_model *pl, pl_work *w, const pl_me *me, const double *y, double T_motor_Nm,
                            double T_load_Nm, double *z);
/* pl_outputs with the modes held (pl_n_outputs values) */
GK_API int pl_me_outputs(const pl_model *pl, pl_work *w, const pl_me *me, const double *y, double T_motor_Nm,
                         double T_load_Nm, double *out);

/* Output layout: DOF i: [2i] absolute coordinate g_i psi + q_i (rad or m), [2i + 1] its rate; mesh m
 * from pl_mesh_offset(m): x (m), v (m/s), mesh force (N), stiffness in contact (N/m), P pair forces
 * (N), P load sharings (1); spring s at pl_spring_offset() + s: force (N or N*m); group g member j at
 * pl_group_offset(g) + j: load-sharing factor (1). */
#define PL_OUT_DTE 0
#define PL_OUT_DTE_RATE 1
#define PL_OUT_MESH_FORCE 2
#define PL_OUT_MESH_STIFFNESS 3
#define PL_OUT_PAIR_FORCE 4
GK_API int pl_mesh_offset(const pl_model *pl, int m);
GK_API int pl_spring_offset(const pl_model *pl);
GK_API int pl_group_offset(const pl_model *pl, int g);
GK_API int pl_n_outputs(const pl_model *pl);

#ifdef __cplusplus
}
#endif
#endif /* PLKERNEL_H */
