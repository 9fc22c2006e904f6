/*
 * fmi_common.h -- the generic FMI plumbing of the standalone gearfmu runtime (fmi_common.c)
 * that its FMI 2.0 layer (fmi2_gear.c) and FMI 3.0 layer (fmi3_gear.c) share, split the way
 * the Modelica Reference-FMUs split fmi2Functions.c / fmi3Functions.c and cosimulation.c from
 * model.c: the instance, the logging, the state-machine check of every call, get/set over the
 * variable table and the FMU state box.  The model behind it is reached through the contract
 * of gf_model.h only.
 */
#ifndef FMI_COMMON_H
#define FMI_COMMON_H

#include <stddef.h>

#include "gf_model.h"

#define GF_GETTERS (GF_INIT_MODE | GF_STEP_MODE | GF_EVENT_MODE | GF_CONT_MODE | GF_TERMINATED | GF_ERROR)
/* a set in continuous-time mode reaches continuous inputs only, in event mode also tunable parameters
 * (FMI 2.0 section 3.2.3, FMI 3.0 section 3.2.2; settable() in fmi_common.c) */
#define GF_SETTERS (GF_INSTANTIATED | GF_INIT_MODE | GF_STEP_MODE | GF_EVENT_MODE | GF_CONT_MODE)

/* one call of an FMI function: its name and the mask of states it may be called in
 * (0: never; the layer's message says why) */
typedef struct {
    const char *name;
    int allowed;
} gf_call;

/* 1 if call may be called now, else logs why and returns 0 (the caller returns Error) */
GF_API int gf_allowed(gf_inst *c, const gf_call *call);
/* gf_allowed with its allowed case inline: every FMI call passes here */
static inline int gf_may_call(gf_inst *c, const gf_call *call)
{
    return (c != NULL && (c->mode & call->allowed) != 0) || gf_allowed(c, call);
}
/* a new instance with its logger (NULL when out of memory) */
GF_API gf_inst *gf_new(int fmi_version, const char *instance_name, int logging_on, gf_log_fn log, void *host_env,
                void (*host_logger)(void), const char *never_why);
/* free the instance and what its model allocated */
GF_API void gf_free(gf_inst *c);
/* instantiation failed: log msg (fn: the instantiate function), free, return NULL */
GF_API gf_inst *gf_instantiate_error(gf_inst *c, const char *fn, const char *msg);
/* file:// URI (FMI 2 resource location) -> local folder path ending in '/'; 0 if not a file URI */
GF_API int gf_uri_to_dir(const char *uri, char *out, size_t cap);
/* initialization mode: from here on the outputs follow the values set */
GF_API void gf_enter_init(gf_inst *c);
GF_API int gf_null_args(gf_inst *c, const char *fn, size_t nvr, const void *vr, const void *value);
/* get/set over the variable table: nvr value references of type Integer (integer[] given) or Real (real[]); with
 * arrays (FMI 3) a reference names a whole array (its first element) and brings array_len values;
 * n_values: the length of value[] (checked when arrays is set).  time_vr >= 0: that reference is the
 * independent variable time (get only).  Returns GF_OK or GF_ERROR_STATUS (logged). */
GF_API int gf_get_values(gf_inst *c, const char *fn, const unsigned int vr[], size_t nvr, int arrays, long time_vr,
                  double real[], int integer[], size_t n_values);
GF_API int gf_set_values(gf_inst *c, const char *fn, const unsigned int vr[], size_t nvr, int arrays, long time_vr,
                  const double real[], const int integer[], size_t n_values);
GF_API int gf_no_variables_of(gf_inst *c, const char *fn, const char *type, size_t nvr);
/* 1 if t is the time the FMU has reached (to round-off; then it becomes the FMU's time), else logs
 * why, puts the instance into state error and returns 0 (the caller returns Error) */
GF_API int gf_check_step_time(gf_inst *c, const char *fn, double t, double H);
/* the interface asked for at instantiation is one this FMU offers (Model Exchange: the model
 * provides gf_inst.me); else the reason, for gf_instantiate_error */
GF_API const char *gf_offered(gf_inst *c);
/* Model Exchange (gf_model.h gf_me_model): the size of the host's array checked against the model's
 * (nx states or nz indicators), then the model's function; GF_OK or GF_ERROR_STATUS / GF_DISCARD
 * with the reason logged */
GF_API int gf_me_states(gf_inst *c, const char *fn, double x[], size_t nx);
GF_API int gf_me_nominals(gf_inst *c, const char *fn, double x[], size_t nx);
GF_API int gf_me_set_states(gf_inst *c, const char *fn, const double x[], size_t nx);
GF_API int gf_me_derivatives(gf_inst *c, const char *fn, double dx[], size_t nx);
GF_API int gf_me_indicators(gf_inst *c, const char *fn, double z[], size_t nz);
GF_API int gf_me_event_update(gf_inst *c, const char *fn, int *again, int *values_changed);
GF_API int gf_me_completed_step(gf_inst *c, const char *fn, int *enter_event);
/* the FMU state box (one flat block of gm_snap_size bytes behind a size header) */
GF_API int gf_get_state(gf_inst *c, const char *fn, void **state);
GF_API int gf_set_state(gf_inst *c, const char *fn, void *state);
GF_API void gf_free_state(void **state);
GF_API int gf_state_size(gf_inst *c, const char *fn, void *state, size_t *size);
GF_API int gf_serialize_state(gf_inst *c, const char *fn, void *state, unsigned char *buf, size_t size);
GF_API int gf_deserialize_state(gf_inst *c, const char *fn, const unsigned char *buf, size_t size, void **state);

#endif /* FMI_COMMON_H */
