/*
 * gearkernel.h -- the dynamic model of docs/model.md in C99.
 *
 * A two-inertia torsional spur gear pair indexed by the pinion angle, with P
 * tooth-pair slots whose stiffness k (N/m), meshing error e (m) and half
 * backlash b (m) come from the tables of gearfmu/tables/mesh_tables.py (Xu et al. 2022 eq 1-6).
 *
 * Rules: no global or static mutable data (every bit of state lives in the
 * structs below, owned by the caller), no allocation anywhere, never abort:
 * every entry point returns a status code (GK_OK = 0 on success).
 *
 * Units: SI throughout (rad, rad/s, m, m/s, N, N/m, N*m, kg*m^2, s).
 */
#ifndef GEARKERNEL_H
#define GEARKERNEL_H

#ifdef __cplusplus
extern "C" {
#endif

/* The storage class of every function of the kernel and its FMU layer (gkfmu.h, gk_internal.h).
 * Empty by default: the kernel library of the pythonfmu runtime and the tests export them.  The
 * standalone FMU compiles everything as one translation unit (gearfmu/fmu/standalone/fmi2_all.c,
 * fmi3_all.c), which defines GK_API as static: then no kernel symbol leaves that unit, and the
 * sources of several FMUs link into one program (docs/standalone.md "Source code"). */
#ifndef GK_API
#define GK_API
#endif

#define GK_ABI_VERSION 6  /* 3: verified envelope check (gk_envelope); 4: node kink flags in gk_model;
                             5: contact-zone cuts (gk_zone_cuts, gk_set_zone_cuts, gk_model.zone_cuts);
                             6: Model Exchange (gk_me_*, gk_set_zone_edges, gk_model.zone_*) */

/* status codes */
#define GK_OK 0
#define GK_ERR_MODEL 1      /* bad table dimensions, pointers or scalars */
#define GK_ERR_INPUT 2      /* non-finite torque or initial value */
#define GK_ERR_STEP 3       /* communication step H or h_max not finite and > 0, or too many substeps */
#define GK_ERR_NONFINITE 4  /* the state became non-finite; the state was left unchanged */
#define GK_ERR_NOCONTACT 5  /* no slot has k > 0 at the initial angle: no equilibrium */
#define GK_ERR_PARAM 6      /* damping ratio or damping model out of range */

/* damping models (docs/model.md "Per-pair force") */
#define GK_DAMPING_ELASTOBACKLASH 0
#define GK_DAMPING_CONTACT_ZONE 1

/* integrators (docs/model.md "Integration"): fixed-step classical RK4, RK4 that
 * steps exactly to every table node and contact-mode change (rk4_kink),
 * rk4_kink stopping only at the table nodes where the tables bend, each reached
 * by one step to its predicted crossing time (rk4_node, docs/native.md), and
 * rk4_node stopping only at the contact-zone edges and reading every evaluation's
 * own table cell, in the shifted velocities (rk4_seg, docs/model.md "rk4_seg") */
#define GK_INTEGRATOR_RK4 0
#define GK_INTEGRATOR_RK4_KINK 1
#define GK_INTEGRATOR_RK4_NODE 2
#define GK_INTEGRATOR_RK4_SEG 3
/* the node_kink bits (gk_model.seg_stops) */
#define GK_STOPS_NODE 1
#define GK_STOPS_SEG 2
#define GK_STOPS_E 4
/* rk4_kink: most slots it accepts, and events located per substep before the
 * rest of the substep is taken without detection */
#define GK_KINK_MAX_SLOTS 32
#define GK_KINK_MAX_EVENTS 1000
/* rk4_node stops only at table nodes where the tables bend (docs/native.md
 * "rk4_node"): node i is flagged when in some torque row, temperature slice and
 * slot |(a[i+1] - a[i]) - (a[i] - a[i-1])| > GK_NODE_KINK_TOL*(|a[i-1]| + |a[i]| + |a[i+1]|)
 * for a = k, e or b, or when the contact_zone flag (k > 0 at the cell midpoint) can
 * differ between its two cells.  The flags live in gk_model (computed by gk_init
 * and gk_set_temperature_axis); with more than GK_NODE_FLAGS_MAX nodes every node
 * is flagged. */
#define GK_NODE_KINK_TOL 1e-9
/* rk4_seg stops at the big kinks only (docs/model.md "rk4_seg"): the test above with
 * this threshold (model_rhs.SEG_KINK_TOL), besides the contact_zone-flag changes and
 * the cells holding a contact-zone edge */
#define GK_SEG_KINK_TOL 1e-2
#define GK_NODE_FLAGS_MAX 8192

/* layout of the output vector written by gk_do_step / gk_outputs
 * (length gk_n_outputs(P) = GK_OUT_PAIR_FORCE + 2*P) */
#define GK_OUT_PINION_ANGLE 0   /* rad */
#define GK_OUT_PINION_SPEED 1   /* rad/s */
#define GK_OUT_GEAR_ANGLE 2     /* rad */
#define GK_OUT_GEAR_SPEED 3     /* rad/s */
#define GK_OUT_DTE 4            /* m */
#define GK_OUT_MESH_FORCE 5     /* N */
#define GK_OUT_MESH_STIFFNESS 6 /* N/m */
#define GK_OUT_PAIR_FORCE 7     /* P values, N; then P values load_sharing (1) */

/* upper bound on the substeps of one communication step (guards a hang) */
#define GK_MAX_SUBSTEPS 100000000.0

typedef struct gk_model {
    int P;                 /* slots */
    int n_phi;             /* angle points per period */
    int n_torque;          /* torque rows (>= 1) */
    const double *torque_Nm;        /* [n_torque], strictly ascending */
    const double *k_N_per_m;        /* [n_torque][n_temp][P][n_phi] */
    const double *e_m;              /* [n_torque][n_temp][P][n_phi] */
    const double *backlash_half_m;  /* [P][n_phi] */
    double phi_period_rad;
    double dphi_rad;                /* phi_period_rad / n_phi */
    double inv_dphi;                /* n_phi / phi_period_rad (1/rad): the lookup multiplies by it */
    double Rb1_m, Rb2_m;            /* base radii */
    double I1_kgm2, I2_kgm2;        /* inertias */
    double inv_I1, inv_I2;          /* 1/I1, 1/I2 (the right-hand sides multiply by them) */
    double seg_gw, seg_gv;          /* rk4_seg's gains Rb1/I1, Rb1*(Rb1/I1) + Rb2*(Rb2/I2) */
    double k_mean_N_per_m;
    double m_e_kg;                  /* I1 I2 / (I1 Rb2^2 + I2 Rb1^2) */
    double damping_ratio;           /* zeta (1) */
    double c_Ns_per_m;              /* 2 zeta sqrt(k_mean m_e) */
    int damping_model;              /* GK_DAMPING_* */
    int integrator;                 /* GK_INTEGRATOR_* (gk_init: RK4) */
    /* temperature axis (docs/model.md "Temperature axis"; gk_init: none, n_temp = 1) */
    int n_temp;                     /* temperature slices (>= 1) */
    const double *temperature_C;    /* [n_temp], strictly ascending, degC (NULL when n_temp = 1 without axis) */
    int temp_ia;                    /* selected slice */
    int temp_two;                   /* 1: blend slices temp_ia, temp_ia + 1 with temp_w */
    double temp_w;                  /* (T - axis[ia]) / (axis[ia+1] - axis[ia]) */
    double temperature_now_C;       /* the temperature selected last (degC) */
    unsigned char node_kink[GK_NODE_FLAGS_MAX];  /* bit 0 (rk4_node): the tables bend at node i; bit 1
                                                    (rk4_seg): a big kink, the contact_zone flag can
                                                    change or a zone edge is in a cell of the node;
                                                    bit 2: e bends there */
    int seg_stops;                  /* the node_kink bits that stop rk4_seg: GK_STOPS_SEG (gk_init);
                                       the multi-mesh kernels add GK_STOPS_E (they integrate the true
                                       velocities, so the damping term's jump where e bends is a stop) */
    const double *zone_cuts;        /* [2][P][n_phi] cuts of gk_zone_cuts (borrowed), NULL: plain lookup */
    /* the contact zones themselves (gk_set_zone_edges; Model Exchange's zone indicators): pair n of
     * slot (n mod n_mesh) mod P is in its zone for n*zone_ppm + zone_in <= s < n*zone_ppm + zone_out
     * (s = theta1/dphi, the edges snapped to a node within GK_ZONE_SNAP); zone_n_mesh = 0: none */
    double zone_n_mesh, zone_ppm, zone_in, zone_out;
} gk_model;

typedef struct gk_state {
    double theta1_rad;
    double omega1_rad_s;
    double x_m;     /* dynamic transmission error theta1*Rb1 - theta2*Rb2 */
    double v_m_s;   /* dx/dt */
} gk_state;

/* size of the structs, so that a caller without the header (ctypes) can own them */
GK_API int gk_abi_version(void);
GK_API int gk_sizeof_model(void);
GK_API int gk_sizeof_state(void);
GK_API int gk_n_outputs(int P);

/* Fill *m.  The arrays are borrowed (not copied): they must outlive m.
 * Checks dimensions, finiteness and signs of the scalars; damping_ratio is
 * set to 0 (call gk_set_damping). */
GK_API int gk_init(gk_model *m, int P, int n_phi, int n_torque,
            const double *torque_Nm, const double *k_N_per_m,
            const double *e_m, const double *backlash_half_m,
            double phi_period_rad, double Rb1_m, double Rb2_m,
            double I1_kgm2, double I2_kgm2, double k_mean_N_per_m);

/* Contact-zone edges (docs/model.md "Contact-zone edges", gearfmu/tables/zones.py): every
 * tooth pair is in its contact zone for n*mesh_period + in <= phi < n*mesh_period + out (slot
 * n % P).  gk_zone_cuts writes the sub-cell cuts of the lookup, 2*P*n_phi doubles
 * (lo[P][n_phi], then hi[P][n_phi]; lo < 0: no edge in the cell), into cuts (caller-owned);
 * GK_ERR_PARAM when a zone spans fewer than GK_ZONE_MIN_CELLS cells or the angles are not
 * finite with out > in (then keep the plain lookup), GK_ERR_MODEL for bad dimensions.
 * gk_set_zone_cuts (after gk_init) makes the lookup read them (borrowed; NULL: plain
 * linear interpolation, the default of gk_init); rk4_kink and rk4_node then stop at the cuts. */
#define GK_ZONE_MIN_CELLS 3.0
#define GK_ZONE_SNAP 1e-9   /* an edge within this many cells of a node lies on the node */
GK_API int gk_zone_cuts(int P, int n_phi, double phi_period_rad, double mesh_period_rad,
                 double in_rad, double out_rad, double *cuts);
GK_API int gk_set_zone_cuts(gk_model *m, const double *cuts);
/* The zones themselves for Model Exchange (after gk_init, beside gk_set_zone_cuts with the same
 * angles): the meshes per period and the edges in node units; the same checks as gk_zone_cuts. */
GK_API int gk_set_zone_edges(gk_model *m, double mesh_period_rad, double in_rad, double out_rad);

/* Declare a temperature axis (call after gk_init): k and e are then laid out
 * [n_torque][n_temp][P][n_phi].  temperature_C (degC, borrowed) finite and
 * strictly ascending, n_temp >= 1.  Selects the first slice.  GK_ERR_MODEL otherwise. */
GK_API int gk_set_temperature_axis(gk_model *m, int n_temp, const double *temperature_C);

/* Select the bulk temperature (degC) for the following steps and outputs:
 * docs/model.md "Temperature axis" (node-wise linear blend of the bracketing
 * slices; exactly one slice at a node).  Non-finite or outside
 * [axis[0], axis[n_temp-1]] (no clamping): GK_ERR_INPUT, selection unchanged. */
GK_API int gk_set_temperature(gk_model *m, double temperature_C);

/* zeta >= 0 finite; model GK_DAMPING_ELASTOBACKLASH or GK_DAMPING_CONTACT_ZONE */
GK_API int gk_set_damping(gk_model *m, double damping_ratio, int damping_model);

/* GK_INTEGRATOR_RK4, GK_INTEGRATOR_RK4_KINK, GK_INTEGRATOR_RK4_NODE or GK_INTEGRATOR_RK4_SEG
 * (all but the first need P <= GK_KINK_MAX_SLOTS); GK_ERR_PARAM otherwise. */
GK_API int gk_set_integrator(gk_model *m, int integrator);

/* Initial state of docs/model.md: theta1 = theta1_0, omega1 = omega1_0, v = 0,
 * x by exactly 200 bisections of the quasi-static balance under F_m = T1/Rb1. */
GK_API int gk_initialize(const gk_model *m, gk_state *s, double theta1_0_rad,
                  double omega1_0_rad_s, double T1_Nm);

/* One communication step of length H_s with constant inputs T1, T2:
 * n = max(1, ceil(H/h_max*(1 - 1e-12))) substeps of the model's integrator
 * (classical RK4, or rk4_kink: docs/model.md).  On success
 * writes the outputs (may be NULL) and returns GK_OK; on any error the state
 * is left unchanged and the outputs are not written. */
GK_API int gk_do_step(const gk_model *m, gk_state *s, double T1_Nm, double T2_Nm,
               double H_s, double h_max_s, double *out);

/* Outputs at state s with pinion torque T1 (selects the torque row). */
GK_API int gk_outputs(const gk_model *m, const gk_state *s, double T1_Nm, double *out);

/* Number of substeps gk_do_step takes for (H, h_max); 0 if invalid. */
GK_API double gk_substeps(double H_s, double h_max_s);

/* ------------------------------------------------------------------------
 * Model Exchange (docs/model.md "Model Exchange"): the host's own solver integrates the state
 * [theta1, omega1, x, v] of gk_state.  Between two events the *mode* is held: per pair its contact
 * region, its elastobacklash branch and, with contact-zone edges, whether it is in its contact
 * zone; with node events also the table segment between two flagged nodes.  The right-hand side
 * with the mode held is smooth between the events except at the table nodes (the plain lookup in
 * the cell of theta1: values continuous, kinks and steps of de/dphi there); the event indicators
 * are >= 0 while the mode holds and the mode is decided anew from the state at every event. */
#define GK_ME_NODES_NONE 0      /* no node events: the plain lookup in the cell of theta1 */
#define GK_ME_NODES_KINKS 1     /* events at the nodes rk4_seg stops at (big kinks, GK_SEG_KINK_TOL) */
#define GK_ME_NODES_ALL 2       /* events at every node where the tables bend (rk4_node's nodes) */
/* the extra outputs of gk_me_outputs (gk_me_n_outputs(P) = 7 + 4P values after the gk_n_outputs(P)
 * ones): v, the four derivatives, then every indicator in the order of gk_me_indicators with room
 * for all of them: the three contact guards of every pair, the P zones, the segment's two ends
 * (those the model does not have are 1.0) */
#define GK_ME_OUT_V 0
#define GK_ME_OUT_DERIVATIVES 1
#define GK_ME_OUT_INDICATORS 5

typedef struct gk_me {
    int node_events;                 /* GK_ME_NODES_* */
    int reg[GK_KINK_MAX_SLOTS];      /* contact region: 1 drive, -1 back, 0 separated */
    int sub[GK_KINK_MAX_SLOTS];      /* elastobacklash branch: 0 two (2 fc), 1 sum (fc + fd), 2 zero */
    int zin[GK_KINK_MAX_SLOTS];      /* 1: in the contact zone (contact-zone edges), else k = 0 */
    double seg_lo, seg_hi;           /* node events: the held segment [lo, hi) in global node indices */
} gk_me;

GK_API int gk_sizeof_me(void);
GK_API int gk_me_n_outputs(int P);
/* The number of event indicators: 3 per pair (the contact guards), 1 per pair with contact-zone
 * edges (gk_set_zone_edges), 2 with node events (the held segment's ends). */
GK_API int gk_me_n_indicators(const gk_model *m, int node_events);
/* The mode from the state (at the start and at every event; the inputs T1, T2): decided at the state
 * and again a moment ahead, so that a guard at zero takes the side it moves to; *changed (may be
 * NULL) = 1 when it differs from the mode held before.  GK_ERR_PARAM for more than
 * GK_KINK_MAX_SLOTS slots or a bad node_events, GK_ERR_NONFINITE for a non-finite state. */
GK_API int gk_me_init(const gk_model *m, gk_me *me, const gk_state *s, double T1_Nm, double T2_Nm,
                      int node_events);
GK_API int gk_me_update(const gk_model *m, gk_me *me, const gk_state *s, double T1_Nm, double T2_Nm, int *changed);
/* dx[4] = d/dt [theta1, omega1, x, v] with the mode held; GK_ERR_NONFINITE for a non-finite state */
GK_API int gk_me_derivatives(const gk_model *m, const gk_me *me, const gk_state *s, double T1_Nm, double T2_Nm,
                             double *dx);
/* z[gk_me_n_indicators] (m: guards of forces divided by k_mean, angles times Rb1): per pair the
 * three contact guards (all pairs' first, then second, then third), per pair its zone, then the
 * segment's lower and upper end; >= 0 while the mode holds, 1.0 for a guard the mode does not have */
GK_API int gk_me_indicators(const gk_model *m, const gk_me *me, const gk_state *s, double T1_Nm, double *z);
/* the outputs of gk_outputs with the mode held (out, gk_n_outputs(P) values), then the extra ones
 * (me_out, gk_me_n_outputs(P) values, may be NULL): v, the derivatives and the indicators (GK_ME_OUT_*) */
GK_API int gk_me_outputs(const gk_model *m, const gk_me *me, const gk_state *s, double T1_Nm, double T2_Nm,
                         double *out, double *me_out);

/* ------------------------------------------------------------------------
 * Verified envelope (docs/fmu.md "Verified envelope"): the input ranges over
 * which the FMU's accuracy was verified (or estimated, or -- without a record --
 * the tables' own range).  Both FMU runtimes call gk_envelope_check with every
 * applied input; the first time a quantity is outside its range it returns 1
 * and the one warning message, later calls for that quantity return 0 (one
 * warning per quantity until gk_envelope_rearm).  The model is not touched:
 * the FMU keeps running. */
#define GK_ENV_PINION_TORQUE 0  /* pinion_torque input, N*m */
#define GK_ENV_PINION_SPEED 1   /* pinion speed (the state), rad/s */
#define GK_ENV_TEMPERATURE 2    /* the temperature input, degC */
#define GK_ENV_N 3
/* what the envelope is */
#define GK_ENV_VERIFIED 0       /* verified by the fidelity plan */
#define GK_ENV_ESTIMATED 1      /* the as-written estimate of `gearfmu build` */
#define GK_ENV_NOT_VERIFIED 2   /* no record: the tables' own range, accuracy not assessed */
/* the speed is compared with its range widened by this share of each end: the
 * pinion speed carries the torsional vibration, which the verified runs had too */
#define GK_ENV_SPEED_MARGIN 0.1

typedef struct gk_envelope {
    double lo[GK_ENV_N], hi[GK_ENV_N];  /* range of each quantity (SI as above) */
    int active[GK_ENV_N];               /* 1: the quantity has a range and is checked */
    int warned[GK_ENV_N];               /* 1: its warning was given */
    int kind;                           /* GK_ENV_VERIFIED, _ESTIMATED or _NOT_VERIFIED */
} gk_envelope;

GK_API int gk_sizeof_envelope(void);

/* Empty envelope of the given kind (nothing checked, nothing warned); GK_ERR_PARAM for a bad kind. */
GK_API int gk_envelope_init(gk_envelope *e, int kind);

/* Range of quantity q: finite lo <= hi, else GK_ERR_PARAM (and q stays unchecked). */
GK_API int gk_envelope_set(gk_envelope *e, int q, double lo_SI, double hi_SI);

/* Forget the warnings given (fmi2Reset). */
GK_API void gk_envelope_rearm(gk_envelope *e);

/* Compare `value` (SI) of quantity q, the FMU variable `name`, at time t_s with
 * its range.  Returns 1 the first time it is outside (a NaN is not compared:
 * the runtimes reject it elsewhere) and writes the warning into msg[cap]; else 0. */
GK_API int gk_envelope_check(gk_envelope *e, int q, const char *name, double value, double t_s, char *msg, int cap);

#ifdef __cplusplus
}
#endif
#endif /* GEARKERNEL_H */
