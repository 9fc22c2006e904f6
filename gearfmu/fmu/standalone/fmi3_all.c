/*
 * fmi3_all.c -- the FMI 3.0 FMU in one translation unit: the file a build compiles (the
 * FMU's sources/buildDescription.xml).  It includes the FMI layer, the plumbing,
 * the gear model and the kernel, in the way the FMI standard suggests for source-code FMUs ("one
 * C source file that includes all other needed C files", FMI 2.0.5 section 2.3) and the Modelica
 * Reference-FMUs ship theirs (all.c).
 *
 * Every function but the fmi3* ones is static here (GF_API, GK_API: gf_model.h, gearkernel.h),
 * so the unit exports the FMI functions only, and the sources of several FMUs link into one
 * program: compile each FMU's fmi3_all.c with FMI3_FUNCTION_PREFIX=<modelIdentifier>_ and the
 * standard's unmodified fmi3Functions.h (FMI 3.0 section 2.2.2; docs/standalone.md "Source code").
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
#include "gear_model.c"
#include "gf_resources.c"
#include "gkfmu.c"
#include "gearkernel.c"
#include "gk_model.c"
#include "gk_stops.c"
#include "gk_zones.c"
#include "gk_temperature.c"
#include "gk_envelope.c"
