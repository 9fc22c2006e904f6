/*
 * gearbox_model.h -- the data of the gearbox model (gearbox_model.c) beside the instance's
 * variable table: every stage's tables and pair model, the gearbox kernel's model, work and
 * state (../kernel/gbkernel.h) and the value references it drives.  The plumbing
 * (fmi_common.c) does not include this header: it reaches the model through the contract of
 * gf_model.h only; tools that look inside an instance (benchmarks) do.
 */
#ifndef GEARBOX_MODEL_H
#define GEARBOX_MODEL_H

#include <stdint.h>

#include "gbkernel.h"
#include "gearkernel.h"
#include "gf_model.h"

/* what the gearbox model keeps (gf_model.h gm_data) */
struct gm_data {
    int n_stage;
    unsigned char *blob[GB_MAX_MESHES];   /* each stage's tables.bin */
    double *cuts[GB_MAX_MESHES];          /* its contact-zone cuts (gk_zone_cuts), NULL: none */
    gk_model *pair[GB_MAX_MESHES];        /* its pair model */
    char stage_name[GB_MAX_MESHES][GF_MAX_NAME];
    gb_model *gb;
    gb_work *work;
    gb_state state;
    int initialized;
    uint64_t tables_tag;                  /* first 8 bytes of the SHA-256 of the stages' checksums */
    /* the value references it drives (-1: the FMU has no such variable) */
    int vr_motor_torque, vr_load_torque, vr_speed0, vr_angle0, vr_hmax, vr_integrator;
    int vr_zeta[GB_MAX_MESHES], vr_dm[GB_MAX_MESHES];
    double zeta_applied[GB_MAX_MESHES];   /* the damping ratio in each pair model */
    int zeta_valid;                       /* 1: zeta_applied is applied */
    uint32_t warned;                      /* bit m: stage m's torque-axis warning was given */
};

#endif /* GEARBOX_MODEL_H */
