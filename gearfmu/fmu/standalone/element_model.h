/*
 * element_model.h -- the data of the torsional element model (element_model.c: a rigid body or an
 * elastic shaft of an SSP of stage FMUs, docs/gearbox.md "The SSP of stage FMUs") beside the
 * instance's variable table.  The plumbing (fmi_common.c) does not include this header: it reaches
 * the model through the contract of gf_model.h only.
 */
#ifndef ELEMENT_MODEL_H
#define ELEMENT_MODEL_H

#include "gf_model.h"

enum { EL_BODY = 0, EL_SHAFT = 1 };
#define EL_MAX_TORQUES 8

/* output vector: a body's angle and speed, a shaft's predicted torque and twist */
enum { EL_OUT_ANGLE = 0, EL_OUT_SPEED = 1, EL_BODY_OUTPUTS = 2 };
enum { EL_OUT_TORQUE = 0, EL_OUT_TWIST = 1, EL_SHAFT_OUTPUTS = 2 };

/* the state: a body's angle and speed; a shaft's twist at the last communication point, the relative
 * speed received there and the length of the step that followed it (0: none yet) */
typedef struct {
    double theta, omega;
    double x, v, h_prev;   /* h_prev: a body's too (0: no step since the initial state) */
} el_state;

/* what the element model keeps (gf_model.h gm_data) */
struct gm_data {
    int kind;
    el_state state;
    int initialized;
    /* the value references it reads (-1: none) */
    int vr_inertia, vr_angle0, vr_speed0;
    int vr_k, vr_c, vr_x0, vr_speed_a, vr_speed_b;
    int vr_first_start;   /* parameter: 1 = the first step holds the port inputs at their start values */
    int n_torque;
    int vr_torque[EL_MAX_TORQUES];
    double torque_sign[EL_MAX_TORQUES];
    int torque_port[EL_MAX_TORQUES];   /* 1: the torque comes from a neighbouring FMU (a port) */
};

#endif /* ELEMENT_MODEL_H */
