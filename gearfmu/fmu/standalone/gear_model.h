/*
 * gear_model.h -- what the two FMI layers of the standalone gearfmu runtime
 * (fmi2_gear.c: FMI 2.0 Co-Simulation, fmi3_gear.c: FMI 3.0 Co-Simulation)
 * share, split the way the Modelica Reference-FMUs split fmi2Functions.c /
 * fmi3Functions.c from model.c:
 *
 *   gear_model.c   the gear glue, one definition for both FMI versions:
 *                  the resources the FMU reads at instantiation (the
 *                  configuration, tables.bin and its SHA-256), the values
 *                  handed to ../kernel/gkfmu.c (the parameter and input checks,
 *                  the initial state, one communication step, the outputs and
 *                  the warnings, with their messages: the functions the
 *                  pythonfmu runtime calls too), and the FMU state snapshot;
 *   fmi_common.c   the generic FMI plumbing: logging, the state-machine check
 *                  of every call against a per-version table of allowed
 *                  states, get/set dispatch over the variable table, the FMU
 *                  state box (get/set/free/serialize/deserialize).
 *
 * Status codes (GF_OK .. GF_FATAL) have the numbering of both fmi2Status and
 * fmi3Status (OK 0, Warning 1, Discard 2, Error 3, Fatal 4), so a layer casts.
 */
#ifndef GEAR_MODEL_H
#define GEAR_MODEL_H

#include <stddef.h>
#include <stdint.h>

#include "gearkernel.h"
#include "gkfmu.h"

#define GF_MAX_NAME 128

enum { GF_OK = 0, GF_WARNING = 1, GF_DISCARD = 2, GF_ERROR_STATUS = 3, GF_FATAL = 4 };
enum { GF_PARAMETER = 0, GF_INPUT = 1, GF_OUTPUT = 2, GF_OTHER = 3 };
enum { GF_FIXED = 0, GF_TUNABLE = 1, GF_CONTINUOUS = 2, GF_OTHER_VAR = 3 };
/* The Co-Simulation states both FMI versions pass through here (FMI 2.0
 * section 4.2.4; FMI 3.0 section 4.2, with no configuration, event or
 * intermediate-update mode: this FMU has no structural parameters, no events,
 * no clocks), one bit each so that a set of states is a mask.  A discarded
 * doStep leaves the state unchanged (nothing was integrated), so the instance
 * stays in GF_STEP_MODE and may step again. */
enum { GF_INSTANTIATED = 1, GF_INIT_MODE = 2, GF_STEP_MODE = 4, GF_TERMINATED = 8, GF_ERROR = 16 };
#define GF_ANY_STATE (GF_INSTANTIATED | GF_INIT_MODE | GF_STEP_MODE | GF_TERMINATED | GF_ERROR)
#define GF_GETTERS (GF_INIT_MODE | GF_STEP_MODE | GF_TERMINATED | GF_ERROR)
#define GF_SETTERS (GF_INSTANTIATED | GF_INIT_MODE | GF_STEP_MODE)

typedef struct {
    int causality;
    int variability;
    int is_integer;
    int out_index;        /* position in the kernel output vector, -1 if none */
    int array_len;        /* name[1]: elements name[1..n] follow (n); a scalar: 1; name[k>1]: 0 */
    double start, min, max;
    int has_start, has_min, has_max;
    char name[GF_MAX_NAME];
} gf_var;

typedef struct gf_inst gf_inst;
/* the layer's adapter from one message to its host's logger */
typedef void (*gf_log_fn)(gf_inst *c, int status, const char *category, const char *msg);

/* one call of an FMI function: its name and the mask of states it may be called in
 * (0: never; the layer's message says why) */
typedef struct {
    const char *name;
    int allowed;
} gf_call;

struct gf_inst {
    /* plumbing: set by the FMI layer */
    gf_log_fn log;
    void *host_env;           /* componentEnvironment / instanceEnvironment */
    void (*host_logger)(void); /* the host's callback, cast back by the layer's gf_log_fn */
    char instance_name[GF_MAX_NAME];
    int logging_on;
    int fmi_version;          /* 2 or 3: the names in messages (state names, types) */
    int mode;                 /* one GF_* state bit */
    const char *never_why;    /* the reason a call allowed in no state is refused */
    /* the variable table (resources/gearfmu_standalone.txt) */
    int n_vars;
    gf_var *vars;
    double *values;       /* current value of every variable (Integer ones held exactly) */
    /* gear glue */
    unsigned char *blob;  /* tables.bin */
    double *arr_torque, *arr_k, *arr_e, *arr_b, *arr_temp;
    double *cuts;         /* contact-zone cuts (gk_zone_cuts), NULL: none */
    gk_model *model;
    gk_state state;
    double *out;
    int n_out;
    int P;
    int vr_T1, vr_T2, vr_zeta, vr_w0, vr_th0, vr_hmax, vr_dm, vr_integrator;
    int vr_temp;          /* temperature input (bulk_, oil_ or gearbox_temperature), -1 without a temperature axis */
    int initialized;
    int dirty;            /* a value changed since the outputs were last computed (initialization mode) */
    double time;
    uint64_t tables_tag;
    gk_envelope env;      /* the verified envelope (docs/fmu.md "Verified envelope"), one warning per input */
    gkf_fmu *fmu;         /* the checks, steps and messages both runtimes share (gkfmu.h) */
    int slot_vr[GKF_N];   /* value reference of each GKF_* slot, -1 if none */
};

/* ------------------------------------------------ plumbing (fmi_common.c) */
void gf_log(gf_inst *c, int status, const char *category, const char *fmt, ...);
/* 1 if calls[fn] may be called now, else logs why and returns 0 (the caller returns Error) */
int gf_allowed(gf_inst *c, const gf_call *call);
/* gf_allowed with its allowed case inline: every FMI call passes here */
static inline int gf_may_call(gf_inst *c, const gf_call *call)
{
    return (c != NULL && (c->mode & call->allowed) != 0) || gf_allowed(c, call);
}
/* a new instance with its logger (NULL when out of memory) */
gf_inst *gf_new(int fmi_version, const char *instance_name, int logging_on, gf_log_fn log, void *host_env,
               void (*host_logger)(void), const char *never_why);
/* instantiation failed: log msg (fn: the instantiate function), free, return NULL */
gf_inst *gf_instantiate_error(gf_inst *c, const char *fn, const char *msg);
int gf_null_args(gf_inst *c, const char *fn, size_t nvr, const void *vr, const void *value);
/* get/set over the variable table: nvr value references of type Integer (integer[] given) or Real (real[]); with
 * arrays (FMI 3) a reference names a whole array (its first element) and brings array_len values;
 * n_values: the length of value[] (checked when arrays is set).  time_vr >= 0: that reference is the
 * independent variable time (get only).  Returns GF_OK or GF_ERROR_STATUS (logged). */
int gf_get_values(gf_inst *c, const char *fn, const unsigned int vr[], size_t nvr, int arrays, long time_vr,
                  double real[], int integer[], size_t n_values);
int gf_set_values(gf_inst *c, const char *fn, const unsigned int vr[], size_t nvr, int arrays, long time_vr,
                  const double real[], const int integer[], size_t n_values);
int gf_no_variables_of(gf_inst *c, const char *fn, const char *type, size_t nvr);
/* the FMU state box (one flat block of gf_snap_size bytes behind a size header) */
int gf_get_state(gf_inst *c, const char *fn, void **state);
int gf_set_state(gf_inst *c, const char *fn, void *state);
void gf_free_state(void **state);
int gf_state_size(gf_inst *c, const char *fn, void *state, size_t *size);
int gf_serialize_state(gf_inst *c, const char *fn, void *state, unsigned char *buf, size_t size);
int gf_deserialize_state(gf_inst *c, const char *fn, const unsigned char *buf, size_t size, void **state);

/* ---------------------------------------------- gear glue (gear_model.c) */
/* file:// URI (FMI 2 resource location) -> local folder path ending in '/'; 0 if not a file URI */
int gm_uri_to_dir(const char *uri, char *out, size_t cap);
/* read the resources in folder res_dir (ending in '/' or '\\'), check token (the GUID /
 * instantiation token), set up the kernel; NULL on success, else a message in err */
const char *gm_instantiate(gf_inst *c, const char *res_dir, const char *token, char *err, size_t errcap);
void gm_free(gf_inst *c);
/* back to the start values, state instantiated */
void gm_reset(gf_inst *c);
/* initialization mode: outputs follow the values set */
void gm_enter_init(gf_inst *c);
/* compute the initial state if the values changed (logs why not); 1 on success */
int gm_exit_init(gf_inst *c);
/* in initialization mode, bring the outputs up to date when one of vr[] is an output */
int gm_refresh_outputs(gf_inst *c, const char *fn, const unsigned int vr[], size_t nvr);
/* the current value of variable i (an output: the kernel's output vector), inline for the getters */
static inline double gm_value(const gf_inst *c, int i)
{
    const gf_var *v = &c->vars[i];
    return v->causality == GF_OUTPUT ? c->out[v->out_index] : c->values[i];
}
int gm_settable(gf_inst *c, const char *fn, int i);
/* one communication step: GF_OK or GF_DISCARD (state unchanged, logged) */
int gm_do_step(gf_inst *c, double t, double H);
int gm_as_int(double x);
/* the FMU state snapshot (flat bytes, no pointers) */
size_t gm_snap_size(const gf_inst *c);
void gm_snap_write(const gf_inst *c, unsigned char *p);
int gm_snap_read(gf_inst *c, const unsigned char *p, size_t size, const char *fn);
/* 1 if the bytes carry this FMU's snapshot header (magic, version, tables) */
int gm_snap_is_ours(const gf_inst *c, const unsigned char *p, size_t size);

#endif
