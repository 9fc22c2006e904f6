/*
 * gkfmu.h -- the FMU behaviour both gearfmu runtimes share, in C99 over the kernel
 * (gearkernel.h): the pythonfmu slave (gearfmu/fmu/runtime/gearfmu_slave.py, through
 * ctypes) and the standalone C runtime (gearfmu/fmu/standalone/gear_model.c) call these
 * functions, so both check the parameters and inputs, apply damping and temperature,
 * take the communication step and word their messages in one place (docs/fmu.md).
 *
 * The caller owns a gkf_fmu (gkf_sizeof bytes) next to its gk_model, gk_state and
 * gk_envelope, declares the variables it has (gkf_declare: name and min/max of the
 * model description), hands the current values over (gkf_set_values) and calls
 * gkf_initialize or gkf_do_step.  Those never log: they queue their messages with a
 * level (the fmi2Status / fmi3Status numbering); the runtime passes each one to its
 * host's logger (gkf_n_messages, gkf_message, gkf_message_level).
 *
 * Rules as in gearkernel.h: no global or static mutable data, no allocation, never abort.
 */
#ifndef GKFMU_H
#define GKFMU_H

#include "gearkernel.h"

#ifdef __cplusplus
extern "C" {
#endif

#define GKF_ABI_VERSION 2  /* 2: Model Exchange (gkf_me_inputs, gkf_me_speed) */

/* the variables this layer reads, by slot (docs/fmu.md "Variables") */
#define GKF_DAMPING_RATIO 0
#define GKF_PINION_SPEED_START 1
#define GKF_PINION_ANGLE_START 2
#define GKF_MAX_STEP 3
#define GKF_DAMPING_MODEL 4
#define GKF_INTEGRATOR 5      /* optional */
#define GKF_PINION_TORQUE 6
#define GKF_GEAR_TORQUE 7
#define GKF_TEMPERATURE 8     /* bulk_, oil_ or gearbox_temperature; only with a temperature axis */
#define GKF_N 9

/* message levels (fmi2Status and fmi3Status share the numbering) */
#define GKF_WARNING 1
#define GKF_DISCARD 2
#define GKF_ERROR 3

#define GKF_MAX_MESSAGES 12
#define GKF_MESSAGE_LEN 720
#define GKF_NAME_LEN 64

typedef struct gkf_fmu {
    gk_model *model;          /* borrowed (gk_init and gk_set_temperature_axis done) */
    gk_envelope *envelope;    /* borrowed, NULL: no envelope check */
    double value[GKF_N];      /* the values handed over last (gkf_set_values) */
    double min[GKF_N], max[GKF_N];
    int has_min[GKF_N], has_max[GKF_N], present[GKF_N];
    char name[GKF_N][GKF_NAME_LEN];
    int zeta_valid;           /* 1: zeta_applied is the damping ratio in the model */
    double zeta_applied;
    int warned_range;         /* 1: the torque-axis warning was given (until the torque is back inside) */
    int n_messages;
    int level[GKF_MAX_MESSAGES];
    char message[GKF_MAX_MESSAGES][GKF_MESSAGE_LEN];
} gkf_fmu;

GK_API int gkf_abi_version(void);
GK_API int gkf_sizeof(void);

/* The words of a kernel status code (GK_ERR_*). */
GK_API const char *gkf_kernel_error(int status);

/* Empty layer over model m (and envelope env, may be NULL): nothing declared, nothing applied. */
GK_API int gkf_init(gkf_fmu *f, gk_model *m, gk_envelope *env);

/* Declare the variable of `slot`: its name (< GKF_NAME_LEN characters) and min/max. */
GK_API int gkf_declare(gkf_fmu *f, int slot, const char *name, int has_min, double min, int has_max, double max);

/* The current values, GKF_N of them in slot order (undeclared slots are ignored). */
GK_API int gkf_set_values(gkf_fmu *f, const double *values);

/* Nothing applied, no torque-axis warning given (instantiation, reset). */
GK_API void gkf_reset(gkf_fmu *f);

/* The initial state from the values (docs/model.md): parameter and input checks, integrator,
 * temperature, damping, gk_initialize and gk_outputs into out, the torque-axis and envelope
 * warnings.  1 on success; 0 with the reasons queued (GKF_ERROR). */
GK_API int gkf_initialize(gkf_fmu *f, gk_state *s, double t_s, double *out);

/* One communication step from t_s of length H_s with the values: input and step checks,
 * temperature, damping, gk_do_step (outputs into out), the warnings.  1 on success; 0 with
 * the reasons queued (GKF_DISCARD, GKF_ERROR for a damping ratio refused) and s unchanged. */
GK_API int gkf_do_step(gkf_fmu *f, gk_state *s, double t_s, double H_s, double *out);

/* Model Exchange (docs/model.md "Model Exchange"): before the host's solver evaluates the model with
 * new values, the input checks of gkf_do_step (a bad torque or temperature: GKF_DISCARD, "...; not
 * evaluated"), the temperature and damping applied and the torque-axis and envelope warnings.  1 on
 * success; 0 with the reasons queued. */
GK_API int gkf_me_inputs(gkf_fmu *f, double t_s);
/* the envelope check of the pinion speed of state s at t_s (after an accepted integrator step and
 * at events): its warning queued, nothing refused */
GK_API void gkf_me_speed(gkf_fmu *f, const gk_state *s, double t_s);

/* After an FMU state was restored (values handed over first): the integrator (when
 * `integrator` and declared), the damping ratio zeta applied when zeta_valid, and the
 * torque-axis warning flag.  GK_OK or the kernel's status (nothing queued). */
GK_API int gkf_restore(gkf_fmu *f, int integrator, int zeta_valid, double zeta, int warned_range);

GK_API int gkf_zeta_valid(const gkf_fmu *f);
GK_API double gkf_zeta_applied(const gkf_fmu *f);
GK_API int gkf_warned_range(const gkf_fmu *f);

/* The messages the last gkf_initialize / gkf_do_step queued, in order. */
GK_API int gkf_n_messages(const gkf_fmu *f);
GK_API int gkf_message_level(const gkf_fmu *f, int i);
GK_API const char *gkf_message(const gkf_fmu *f, int i);

#ifdef __cplusplus
}
#endif
#endif /* GKFMU_H */
