/*
 * fmi2_gearbox_all.c -- the FMI 2.0 gearbox FMU in one translation unit (docs/gearbox.md "The
 * gearbox FMU"): the same FMI layer (fmi2_gear.c) and plumbing (fmi_common.c) as the pair FMU's
 * fmi2_all.c, over the gearbox model (gearbox_model.c) and the gearbox kernel (gb_kernel.c) with
 * the pair kernel files it uses per mesh.  Every function but the fmi2* ones is static here
 * (GF_API, GK_API), so the unit exports the FMI functions only (docs/standalone.md "Source code").
 * The FMI headers are the importer's (they are not part of sources/, as the standard requires).
 */
#if defined(__GNUC__) || defined(__clang__)
#define GF_UNIT_STATIC static __attribute__((unused))
#else
#define GF_UNIT_STATIC static
#endif
#define GF_API GF_UNIT_STATIC
#define GK_API GF_UNIT_STATIC

#include "fmi2_gear.c"
#include "fmi_common.c"
#include "gearbox_model.c"
#include "gf_resources.c"
#include "gf_meshes.c"
#include "gb_kernel.c"
#include "gearkernel.c"
#include "gk_model.c"
#include "gk_stops.c"
#include "gk_zones.c"
#include "gk_temperature.c"
#include "gk_envelope.c"
