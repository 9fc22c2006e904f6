/*
 * stage_model.h -- the data of the stage model (stage_model.c: one stage of a gearbox with the shafts
 * that end at its flanges, for an SSP of stage FMUs, docs/gearbox.md "The SSP of stage FMUs") beside
 * the gearbox model's (gearbox_model.h), and the gearbox model's functions under the names the stage
 * model calls them by.  The plumbing (fmi_common.c) does not include this header: it reaches the model
 * through the contract of gf_model.h only.
 */
#ifndef STAGE_MODEL_H
#define STAGE_MODEL_H

#include "gearbox_model.h"

#define ST_MAX_FLANGES 2

/* A flange: a body of the stage's gearbox whose motion is the neighbouring FMU's (its speed an input,
 * its angle integrated from that speed), moved at constant speed over a communication step; the
 * shaft that ends there and the output of the torque that shaft transmits. */
typedef struct {
    int n;
    int body[ST_MAX_FLANGES];         /* the flange body */
    int shaft[ST_MAX_FLANGES];        /* the elastic shaft ending at it */
    int vr_speed[ST_MAX_FLANGES];     /* input: the flange's speed (rad/s) */
    int out_torque[ST_MAX_FLANGES];   /* output index: the torque the shaft transmits, predicted */
    double theta[ST_MAX_FLANGES];     /* the flange's angle at the last communication point (rad) */
    double omega[ST_MAX_FLANGES];     /* the speed received there (rad/s) */
    double h_prev;                    /* the step that followed it (s; 0: none yet) */
    int vr_first_start;               /* parameter: 1 = the first step holds the port inputs at their starts */
    int vr_order;                     /* parameter: the flange's motion over a step, 1 linear, 2 quadratic */
    int n_port;
    int vr_port[2];                   /* the torque inputs that come from neighbouring FMUs */
} st_flanges;

/* what the stage model keeps: the gearbox model's data first (the gearbox model's functions see
 * c->data as their gm_data), then the flanges */
typedef struct {
    gm_data gb;
    st_flanges fl;
} st_data;

/* the gearbox model (gearbox_model.c), included by stage_model.c under these names */
GF_API const char *gbm_instantiate(gf_inst *c, const char *res_dir, const char *token, char *err, size_t errcap);
GF_API void gbm_free(gf_inst *c);
GF_API void gbm_reset(gf_inst *c);
GF_API int gbm_exit_init(gf_inst *c);
GF_API int gbm_refresh_outputs(gf_inst *c, const char *fn, const unsigned int vr[], size_t nvr);
GF_API int gbm_do_step(gf_inst *c, double t, double H);
GF_API size_t gbm_snap_size(const gf_inst *c);
GF_API void gbm_snap_write(const gf_inst *c, unsigned char *p);
GF_API int gbm_snap_read(gf_inst *c, const unsigned char *p, size_t size, const char *fn);
GF_API int gbm_snap_is_ours(const gf_inst *c, const unsigned char *p, size_t size);

#endif /* STAGE_MODEL_H */
