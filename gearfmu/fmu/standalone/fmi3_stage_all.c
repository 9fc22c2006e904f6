/*
 * fmi3_stage_all.c -- the FMI 3.0 stage FMU of an SSP of stage FMUs (docs/gearbox.md "The SSP of
 * stage FMUs") in one translation unit: the same FMI layer (fmi3_gear.c) and plumbing (fmi_common.c)
 * as the pair and the gearbox FMU, over the stage model (stage_model.c, which includes the gearbox
 * model gearbox_model.c), the gearbox kernel (gb_kernel.c) and the pair kernel files it uses.  Every
 * function but the fmi3* ones is static here (GF_API, GK_API), so the unit exports the FMI functions
 * only (docs/standalone.md "Source code").  The FMI headers are the importer's (they are not part of
 * sources/, as the standard requires).
 */
#if defined(__GNUC__) || defined(__clang__)
#define GF_UNIT_STATIC static __attribute__((unused))
#else
#define GF_UNIT_STATIC static
#endif
#define GF_API GF_UNIT_STATIC
#define GK_API GF_UNIT_STATIC

#include "fmi3_gear.c"
#include "fmi_common.c"
#include "stage_model.c"
#include "gf_resources.c"
#include "gf_meshes.c"
#include "gb_kernel.c"
#include "gearkernel.c"
#include "gk_model.c"
#include "gk_stops.c"
#include "gk_zones.c"
#include "gk_temperature.c"
#include "gk_envelope.c"
