/*
 * gearbox_model.h -- the data of the gearbox model (gearbox_model.c) beside the instance's
 * variable table: the multi-mesh core (gf_meshes.h) and the gearbox kernel's model, work and
 * state (../kernel/gbkernel.h).  The plumbing
 * (fmi_common.c) does not include this header: it reaches the model through the contract of
 * gf_model.h only; tools that look inside an instance (benchmarks) do.
 */
#ifndef GEARBOX_MODEL_H
#define GEARBOX_MODEL_H

#include <stdint.h>

#include "gbkernel.h"
#include "gearkernel.h"
#include "gf_meshes.h"
#include "gf_model.h"

/* what the gearbox model keeps (gf_model.h gm_data): the shared behaviour's core first (gf_meshes.h:
 * the stages' tables and pair models, the value references, Model Exchange), then the gearbox
 * kernel's model, work, state and Model Exchange modes */
struct gm_data {
    gfm_core core;
    gb_model *gb;
    gb_work *work;
    gb_state state;
    gb_me me;
};

#endif /* GEARBOX_MODEL_H */
