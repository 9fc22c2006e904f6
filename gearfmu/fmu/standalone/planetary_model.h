/*
 * planetary_model.h -- the data of the planetary model (planetary_model.c) beside the instance's
 * variable table: the multi-mesh core (gf_meshes.h: every mesh's tables and pair model, the value
 * references, Model Exchange) and the planetary kernel's model, work, state and Model Exchange modes
 * (../kernel/plkernel.h).  The plumbing (fmi_common.c) does not include this header: it reaches the
 * model through the contract of gf_model.h only; tools that look inside an instance (benchmarks) do.
 */
#ifndef PLANETARY_MODEL_H
#define PLANETARY_MODEL_H

#include "gearkernel.h"
#include "gf_meshes.h"
#include "gf_model.h"
#include "plkernel.h"

/* what the planetary model keeps (gf_model.h gm_data): the shared behaviour's core first */
struct gm_data {
    gfm_core core;
    pl_model *pl;
    pl_work *work;
    pl_state state;
    pl_me me;
    gf_inst *inst;                 /* the instance (its values: the drives' speed inputs) */
    int drive_vr[PL_MAX_DRIVES];   /* value reference of every drive's speed input (rad/s) */
};

#endif /* PLANETARY_MODEL_H */
