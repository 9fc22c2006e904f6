/*
 * gf_model.h -- the model contract of the standalone gearfmu runtime, shaped as the
 * Modelica Reference-FMUs' include/model.h: the instance both sides share, what a model
 * provides (gm_*), and the one way a model reaches back (gf_log).
 *
 *   fmi_common.c   the generic FMI plumbing (fmi_common.h): the state-machine check of every
 *                  call, get/set over the variable table, the FMU state box.  It calls the
 *                  model through the gm_* functions below only, and knows no gears;
 *   gear_model.c   the gear model: it reads the resources at instantiation (the configuration,
 *                  tables.bin and its SHA-256), fills the variable table, hands the values to
 *                  ../kernel/gkfmu.c (the parameter and input checks, the initial state, one
 *                  communication step, the outputs and the warnings, with their messages: the
 *                  functions the pythonfmu runtime calls too) and writes the FMU state snapshot.
 *                  It knows no FMI function and calls nothing of the plumbing; its messages go
 *                  through gf_log to the logger the FMI layer put into the instance;
 *   fmi2_gear.c, fmi3_gear.c  the FMI 2.0 and 3.0 layers over both.
 *
 * A second model implements this contract: ../runtime/pyshim.c, the Python slave of the pythonfmu
 * runtime under the same fmi2_gear.c and fmi_common.c (docs/fmu.md "The binary").  A check of the
 * FMI calls themselves (call order, value references, causality and variability, ranges, the
 * time of a step) written in the layers or the plumbing applies to both runtimes; one written in
 * gear_model.c applies to the standalone runtime only.
 *
 * Status codes (GF_OK .. GF_FATAL) have the numbering of both fmi2Status and fmi3Status
 * (OK 0, Warning 1, Discard 2, Error 3, Fatal 4), so a layer casts.
 */
#ifndef GF_MODEL_H
#define GF_MODEL_H

#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>

/* The storage class of the functions the plumbing (fmi_common.h) and the model (gm_*) share:
 * empty when the files are compiled one by one; static in the one translation unit of the FMU
 * (fmi2_all.c, fmi3_all.c), where only the fmi2* / fmi3* functions have external linkage. */
#ifndef GF_API
#define GF_API
#endif

#define GF_MAX_NAME 128

enum { GF_OK = 0, GF_WARNING = 1, GF_DISCARD = 2, GF_ERROR_STATUS = 3, GF_FATAL = 4 };
enum { GF_PARAMETER = 0, GF_INPUT = 1, GF_OUTPUT = 2, GF_OTHER = 3 };
enum { GF_FIXED = 0, GF_TUNABLE = 1, GF_CONTINUOUS = 2, GF_OTHER_VAR = 3 };
/* The states both FMI versions pass through here, one bit each so that a set of states is a mask:
 * Co-Simulation (FMI 2.0 section 4.2.4; FMI 3.0 section 4.2, with no configuration, event or
 * intermediate-update mode: no structural parameters, no clocks, no events in a step) and Model
 * Exchange (FMI 2.0 section 3.2.3, FMI 3.0 section 3.2: event mode and continuous-time mode).  A
 * discarded doStep leaves the state unchanged (nothing was integrated), so the instance stays in
 * GF_STEP_MODE and may step again.  An instance is of one interface (gf_inst.fmu_type), so a
 * Co-Simulation instance never reaches the two Model Exchange modes and the other way round. */
enum { GF_INSTANTIATED = 1, GF_INIT_MODE = 2, GF_STEP_MODE = 4, GF_TERMINATED = 8, GF_ERROR = 16,
       GF_EVENT_MODE = 32, GF_CONT_MODE = 64 };
#define GF_ANY_STATE (GF_INSTANTIATED | GF_INIT_MODE | GF_STEP_MODE | GF_TERMINATED | GF_ERROR | GF_EVENT_MODE | \
                      GF_CONT_MODE)
#define GF_LAST_STATE GF_CONT_MODE
/* the interfaces (gf_inst.fmu_type, gf_inst.offers) */
enum { GF_COSIMULATION = 1, GF_MODEL_EXCHANGE = 2 };

/* one variable of the table (resources/gearfmu_standalone.txt) */
typedef struct {
    int causality;
    int variability;
    int is_integer;
    int out_index;        /* position in the model's output vector, -1 if none */
    int array_len;        /* name[1]: elements name[1..n] follow (n); a scalar: 1; name[k>1]: 0 */
    double start, min, max;
    int has_start, has_min, has_max;
    char name[GF_MAX_NAME];
} gf_var;

typedef struct gf_inst gf_inst;
/* the FMI layer's adapter from one message to its host's logger */
typedef void (*gf_log_fn)(gf_inst *c, int status, const char *category, const char *msg);
/* what the model keeps beside the variable table (gear_model.c) */
typedef struct gm_data gm_data;

/* What a model that offers Model Exchange provides (FMI 2.0 section 3.2, FMI 3.0 section 3.2), as a
 * table of functions the model puts into the instance (gf_inst.me) at instantiation.  A model that
 * does not offer it (the Python slave of the pythonfmu runtime; a model before it implements them)
 * leaves gf_inst.me NULL, and the FMI layer refuses to instantiate it for Model Exchange with
 * gf_inst.me_refusal (or a general reason).  The state vector, derivatives and indicators have
 * gf_inst.n_states and gf_inst.n_indicators values; fn is the FMI function, for messages.
 * Statuses: GF_OK, or GF_DISCARD / GF_ERROR_STATUS with the reason logged. */
typedef struct gf_me_model {
    /* the continuous states (in initialization mode: the initial ones from the values set) and
     * their nominal values (> 0) */
    int (*states)(gf_inst *c, const char *fn, double x[]);
    int (*nominals)(gf_inst *c, const char *fn, double x[]);
    /* new continuous states from the host (continuous-time mode); the outputs follow them */
    int (*set_states)(gf_inst *c, const char *fn, const double x[]);
    /* the derivatives and the event indicators at the time, states and inputs set, the mode held */
    int (*derivatives)(gf_inst *c, const char *fn, double dx[]);
    int (*indicators)(gf_inst *c, const char *fn, double z[]);
    /* event mode: the discrete states (the mode) anew from the continuous ones; *again = 1 asks the
     * host for another update (never, here), *values_changed = 1 when it changed the continuous states */
    int (*event_update)(gf_inst *c, const char *fn, int *again, int *values_changed);
    /* the host accepted an integrator step (fmi2CompletedIntegratorStep); *enter_event = 1 asks for
     * an event */
    int (*completed_step)(gf_inst *c, const char *fn, int *enter_event);
} gf_me_model;

struct gf_inst {
    /* set by the FMI layer (gf_new) */
    gf_log_fn log;
    void *host_env;            /* componentEnvironment / instanceEnvironment */
    void (*host_logger)(void); /* the host's callback, cast back by the layer's gf_log_fn */
    char instance_name[GF_MAX_NAME];
    int logging_on;
    int fmi_version;           /* 2 or 3: the names in messages (state names, types) */
    const char *never_why;     /* the reason a call allowed in no state is refused */
    /* the FMI state, the time and whether a value changed since the outputs were computed
     * (initialization mode), kept by the plumbing and the model */
    int mode;                  /* one GF_* state bit */
    int dirty;
    double time;
    /* the interface the host instantiated (GF_COSIMULATION or GF_MODEL_EXCHANGE, set by the FMI
     * layer before gm_instantiate) and the ones this FMU offers (a mask, set by the model; 0: only
     * Co-Simulation) */
    int fmu_type;
    int offers;
    /* Model Exchange (set by the model; me NULL: not offered, me_refusal says why if not NULL) */
    const gf_me_model *me;
    const char *me_refusal;
    size_t n_states, n_indicators;
    /* the variable table and the outputs, filled by the model (gm_instantiate) */
    int n_vars;
    gf_var *vars;
    double *values;            /* current value of every variable (Integer ones held exactly) */
    double *out;               /* the model's outputs, gf_var.out_index of the output variables */
    int n_out;
    gm_data *data;
};

/* A message to the host (printf format), when logging is on or the status is not OK: the
 * model's one way back, through the logger the FMI layer set in the instance. */
static inline void gf_log(gf_inst *c, int status, const char *category, const char *fmt, ...)
{
    char msg[1024];
    va_list ap;
    if (c == NULL || c->log == NULL || c->host_logger == NULL) return;
    if (status == GF_OK && !c->logging_on) return;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    c->log(c, status, category, msg);
}

/* ------------------------------------------- what the model provides (gear_model.c) */
/* Read the resources in folder res_dir (ending in '/' or '\\'), check token (the GUID /
 * instantiation token), fill the variable table and the outputs, set up the model and its
 * start values (gm_reset); NULL on success, else a message in err. */
GF_API const char *gm_instantiate(gf_inst *c, const char *res_dir, const char *token, char *err, size_t errcap);
/* free what gm_instantiate allocated (the instance itself stays) */
GF_API void gm_free(gf_inst *c);
/* back to the start values, state instantiated, time 0 */
GF_API void gm_reset(gf_inst *c);
/* compute the initial state if the values changed since (logs why not); 1 on success */
GF_API int gm_exit_init(gf_inst *c);
/* in initialization mode (and, for Model Exchange, in event and continuous-time mode) bring the
 * outputs up to date when one of vr[] is an output and a value changed (logs why not) */
GF_API int gm_refresh_outputs(gf_inst *c, const char *fn, const unsigned int vr[], size_t nvr);
/* one communication step: GF_OK or GF_DISCARD (state unchanged, logged) */
GF_API int gm_do_step(gf_inst *c, double t, double H);
/* the FMU state snapshot (flat bytes, no pointers) */
GF_API size_t gm_snap_size(const gf_inst *c);
GF_API void gm_snap_write(const gf_inst *c, unsigned char *p);
GF_API int gm_snap_read(gf_inst *c, const unsigned char *p, size_t size, const char *fn);
/* 1 if the bytes carry this FMU's snapshot header (magic, version, tables) */
GF_API int gm_snap_is_ours(const gf_inst *c, const unsigned char *p, size_t size);

#endif /* GF_MODEL_H */
