/*
 * fmi3_element_all.c -- the FMI 3.0 torsional element FMU (a rigid body or an elastic shaft of an SSP
 * of stage FMUs, docs/gearbox.md "The SSP of stage FMUs") in one translation unit: the same FMI
 * layer (fmi3_gear.c) and plumbing (fmi_common.c) as the pair and the gearbox FMU, over the element
 * model (element_model.c).  Every function but the fmi3* ones is static here (GF_API), so the unit
 * exports the FMI functions only (docs/standalone.md "Source code").
 * The FMI headers are the importer's (they are not part of sources/, as the standard requires).
 */
#if defined(__GNUC__) || defined(__clang__)
#define GF_UNIT_STATIC static __attribute__((unused))
#else
#define GF_UNIT_STATIC static
#endif
#define GF_API GF_UNIT_STATIC

#include "fmi3_gear.c"
#include "fmi_common.c"
#include "element_model.c"
#include "gf_resources.c"
