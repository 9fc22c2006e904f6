/*
 * fmi3_planetary_all.c -- the FMI 3.0 planetary FMU in one translation unit (docs/planetary.md "The
 * planetary FMU"): the same FMI layer (fmi3_gear.c) and plumbing (fmi_common.c) as the pair and gearbox
 * FMUs, over the planetary model (planetary_model.c, on the multi-mesh behaviour of gf_meshes.c) and the
 * planetary kernel (pl_kernel.c, pl_static.c) with the pair kernel files it uses per mesh.  Every function
 * but the fmi3* ones is static here (GF_API, GK_API), so the unit exports the FMI functions only.
 * The FMI headers are the importer's (they are not part of sources/, as the standard requires).
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
#include "planetary_model.c"
#include "gf_resources.c"
#include "gf_meshes.c"
#include "pl_kernel.c"
#include "pl_static.c"
#include "gearkernel.c"
#include "gk_model.c"
#include "gk_stops.c"
#include "gk_zones.c"
#include "gk_temperature.c"
#include "gk_envelope.c"
