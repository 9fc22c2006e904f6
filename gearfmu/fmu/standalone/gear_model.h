/*
 * gear_model.h -- the data of the gear model (gear_model.c) beside the instance's variable
 * table: the tables it read, the kernel's model, state and envelope, the FMU layer over them
 * (../kernel/gkfmu.h) and the value references it drives.  The plumbing (fmi_common.c) does
 * not include this header: it reaches the model through the contract of gf_model.h only;
 * tools that look inside an instance (benchmarks/fmu_layers.c) do.
 */
#ifndef GEAR_MODEL_H
#define GEAR_MODEL_H

#include <stdint.h>

#include "gearkernel.h"
#include "gf_model.h"
#include "gkfmu.h"

/* what the gear model keeps (gf_model.h gm_data) */
struct gm_data {
    unsigned char *blob;  /* tables.bin */
    double *arr_torque, *arr_k, *arr_e, *arr_b, *arr_temp;
    double *cuts;         /* contact-zone cuts (gk_zone_cuts), NULL: none */
    gk_model *model;
    gk_state state;
    int P;
    int vr_T1, vr_T2, vr_zeta, vr_w0, vr_th0, vr_hmax, vr_dm, vr_integrator;
    int vr_temp;          /* temperature input (bulk_, oil_ or gearbox_temperature), -1 without a temperature axis */
    int initialized;
    uint64_t tables_tag;
    gk_envelope env;      /* the verified envelope (docs/fmu.md "Verified envelope"), one warning per input */
    gkf_fmu *fmu;         /* the checks, steps and messages both runtimes share (gkfmu.h) */
    int slot_vr[GKF_N];   /* value reference of each GKF_* slot, -1 if none */
    /* Model Exchange (docs/standalone.md "Model Exchange"): offered when the configuration names it;
     * the mode the host's solver holds between events, the node events asked for at build time, the
     * nominal values of the states; me_base: where the outputs of gk_me_outputs start in c->out */
    int me_offered, me_node_events, me_base;
    gk_me me;
    double me_nominal[4];
    double *scratch;      /* gk_n_outputs(P) values: the mode-held outputs a Co-Simulation step does not use */
};

#endif /* GEAR_MODEL_H */
