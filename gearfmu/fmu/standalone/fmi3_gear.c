/*
 * fmi3_gear.c -- FMI 3.0 Co-Simulation and Model Exchange layer of the standalone gearfmu
 * runtime (docs/standalone.md "FMI 3.0"): the fmi3* functions and their table
 * of allowed states over the same plumbing (fmi_common.h) and gear model
 * (gf_model.h) as the FMI 2.0 layer (fmi2_gear.c), so both FMUs compute the
 * same numbers from the same calls.
 *
 * Standard: Modelica Association, "Functional Mock-up Interface Specification",
 * version 3.0 (sections 2.3 common API, 3 Model Exchange, 4 Co-Simulation).  The FMI headers are
 * the standard's own (fmi3Functions.h, fmi3FunctionTypes.h,
 * fmi3PlatformTypes.h), shipped beside this file in the FMU's sources/.
 *
 * Variables: the value references of the FMI 2 FMU; the per-slot elements
 * pair_force[1..P] and load_sharing[1..P] are the arrays pair_force and
 * load_sharing, addressed by the reference of element 1 (a get brings all P
 * values); the independent variable time has the reference n_vars.  Only
 * Float64 and Int32 variables exist; every other type's get/set is an error
 * unless it names no variable.  This FMU has no clocks, structural parameters or
 * intermediate updates, and its Co-Simulation no event mode: the functions of those
 * are refused.  Model Exchange (when the FMU offers it) has the event and
 * continuous-time modes of FMI 3.0 section 3.2.
 */
#include <math.h>

#include "fmi3Functions.h"
#include "fmi_common.h"

typedef enum {
    F_SetDebugLogging, F_EnterInitializationMode, F_ExitInitializationMode, F_EnterEventMode,
    F_Terminate, F_Reset,
    F_GetFloat64, F_GetInt32, F_GetOther, F_SetFloat64, F_SetInt32, F_SetOther,
    F_GetNumberOfVariableDependencies, F_GetVariableDependencies,
    F_GetFMUState, F_SetFMUState, F_FreeFMUState, F_SerializedFMUStateSize, F_SerializeFMUState,
    F_DeserializeFMUState, F_GetDirectionalDerivative, F_GetAdjointDerivative,
    F_EnterConfigurationMode, F_ExitConfigurationMode, F_Clocks, F_EvaluateDiscreteStates,
    F_UpdateDiscreteStates, F_EnterStepMode, F_GetOutputDerivatives, F_DoStep,
    F_ActivateModelPartition,
    F_EnterContinuousTimeMode, F_CompletedIntegratorStep, F_SetTime, F_SetContinuousStates,
    F_GetContinuousStateDerivatives, F_GetEventIndicators, F_GetContinuousStates, F_GetNominalsOfContinuousStates,
    F_GetNumberOfEventIndicators, F_GetNumberOfContinuousStates,
    F_COUNT
} gf_fn;

/* Which fmi3 function may be called in which state (FMI 3.0 sections 3.2 and 4.2, the
 * Model Exchange and Co-Simulation state machines, with the states this FMU has: Instantiated,
 * InitializationMode, EventMode and ContinuousTimeMode (Model Exchange), StepMode (Co-Simulation),
 * Terminated and the error state; as the Modelica Reference-FMUs' masks); 0: never. */
static const gf_call GF_CALLS[F_COUNT] = {
    {"fmi3SetDebugLogging", GF_ANY_STATE},
    {"fmi3EnterInitializationMode", GF_INSTANTIATED},
    {"fmi3ExitInitializationMode", GF_INIT_MODE},
    {"fmi3EnterEventMode", GF_EVENT_MODE | GF_CONT_MODE},
    {"fmi3Terminate", GF_STEP_MODE | GF_EVENT_MODE | GF_CONT_MODE},
    {"fmi3Reset", GF_ANY_STATE},
    {"fmi3GetFloat64", GF_GETTERS},
    {"fmi3GetInt32", GF_GETTERS},
    {"fmi3Get (Float32, Int8..UInt64 but Int32, Boolean, String, Binary)", GF_GETTERS},
    {"fmi3SetFloat64", GF_SETTERS},
    {"fmi3SetInt32", GF_SETTERS},
    {"fmi3Set (Float32, Int8..UInt64 but Int32, Boolean, String, Binary)", GF_SETTERS},
    {"fmi3GetNumberOfVariableDependencies", GF_GETTERS},
    {"fmi3GetVariableDependencies", GF_GETTERS},
    {"fmi3GetFMUState", GF_ANY_STATE},
    {"fmi3SetFMUState", GF_ANY_STATE},
    {"fmi3FreeFMUState", GF_ANY_STATE},
    {"fmi3SerializedFMUStateSize", GF_ANY_STATE},
    {"fmi3SerializeFMUState", GF_ANY_STATE},
    {"fmi3DeserializeFMUState", GF_ANY_STATE},
    {"fmi3GetDirectionalDerivative", GF_GETTERS},
    {"fmi3GetAdjointDerivative", GF_GETTERS},
    {"fmi3EnterConfigurationMode", 0},
    {"fmi3ExitConfigurationMode", 0},
    {"fmi3 clock, interval and shift functions", 0},
    {"fmi3EvaluateDiscreteStates", 0},
    {"fmi3UpdateDiscreteStates", GF_EVENT_MODE},
    {"fmi3EnterStepMode", 0},
    {"fmi3GetOutputDerivatives", GF_STEP_MODE | GF_TERMINATED | GF_ERROR},
    {"fmi3DoStep", GF_STEP_MODE},
    {"fmi3ActivateModelPartition", 0},
    {"fmi3EnterContinuousTimeMode", GF_EVENT_MODE},
    {"fmi3CompletedIntegratorStep", GF_CONT_MODE},
    {"fmi3SetTime", GF_EVENT_MODE | GF_CONT_MODE},
    {"fmi3SetContinuousStates", GF_CONT_MODE},
    {"fmi3GetContinuousStateDerivatives", GF_INIT_MODE | GF_EVENT_MODE | GF_CONT_MODE | GF_TERMINATED | GF_ERROR},
    {"fmi3GetEventIndicators", GF_INIT_MODE | GF_EVENT_MODE | GF_CONT_MODE | GF_TERMINATED | GF_ERROR},
    {"fmi3GetContinuousStates", GF_INIT_MODE | GF_EVENT_MODE | GF_CONT_MODE | GF_TERMINATED | GF_ERROR},
    {"fmi3GetNominalsOfContinuousStates", GF_INIT_MODE | GF_EVENT_MODE | GF_CONT_MODE | GF_TERMINATED | GF_ERROR},
    {"fmi3GetNumberOfEventIndicators", GF_ANY_STATE},
    {"fmi3GetNumberOfContinuousStates", GF_ANY_STATE},
};

#define GF_GUARD(inst, fn)                                                     \
    gf_inst *c = (gf_inst *)(inst);                                            \
    if (!gf_may_call(c, &GF_CALLS[fn])) return fmi3Error
/* a function this FMU never offers: the guard logs why */
#define GF_NEVER(fn) return (gf_allowed((gf_inst *)instance, &GF_CALLS[fn]), fmi3Error)

static void log_fmi3(gf_inst *c, int status, const char *category, const char *msg)
{
    ((fmi3LogMessageCallback)c->host_logger)(c->host_env, (fmi3Status)status, category, msg);
}

static long time_vr(const gf_inst *c) { return (long)c->n_vars; }

/* ---------------------------------------------------------- FMI: common */
FMI3_Export const char *fmi3GetVersion(void) { return fmi3Version; }

FMI3_Export fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                                           const fmi3String categories[])
{
    GF_GUARD(instance, F_SetDebugLogging);
    (void)nCategories; (void)categories;
    c->logging_on = loggingOn ? 1 : 0;
    return fmi3OK;
}

#define GF_NEVER_WHY "no state: this FMU has no clocks, structural parameters or intermediate updates, and " \
                     "its Co-Simulation no event mode"

static gf_inst *refuse(const char *fn, fmi3String instanceName, fmi3Boolean loggingOn,
                       fmi3InstanceEnvironment env, fmi3LogMessageCallback logMessage, const char *why)
{
    gf_inst *c = gf_new(3, instanceName, loggingOn, log_fmi3, env, (void (*)(void))logMessage, GF_NEVER_WHY);
    return c == NULL ? NULL : gf_instantiate_error(c, fn, why);
}

/* a new instance of type fmu_type: the model instantiated from resourcePath, the interface offered */
static fmi3Instance instantiate(const char *fn, int fmu_type, fmi3String instanceName, fmi3String instantiationToken,
                                fmi3String resourcePath, fmi3Boolean loggingOn, fmi3InstanceEnvironment env,
                                fmi3LogMessageCallback logMessage, const char *refusal)
{
    char err[700];
    const char *e;
    gf_inst *c = gf_new(3, instanceName, loggingOn, log_fmi3, env, (void (*)(void))logMessage, GF_NEVER_WHY);
    if (c == NULL) return NULL;
    c->fmu_type = fmu_type;
    if (refusal != NULL) return gf_instantiate_error(c, fn, refusal);
    if (resourcePath == NULL) return gf_instantiate_error(c, fn, "resourcePath is NULL");
    e = gm_instantiate(c, resourcePath, instantiationToken, err, sizeof err);
    if (e == NULL) e = gf_offered(c);
    if (e != NULL) return gf_instantiate_error(c, fn, e);
    return (fmi3Instance)c;
}

FMI3_Export fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                                      fmi3String resourcePath, fmi3Boolean visible,
                                                      fmi3Boolean loggingOn, fmi3InstanceEnvironment env,
                                                      fmi3LogMessageCallback logMessage)
{
    (void)visible;
    return instantiate("fmi3InstantiateModelExchange", GF_MODEL_EXCHANGE, instanceName, instantiationToken,
                       resourcePath, loggingOn, env, logMessage, NULL);
}

FMI3_Export fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath, fmi3Boolean visible,
    fmi3Boolean loggingOn, fmi3InstanceEnvironment env, fmi3LogMessageCallback logMessage,
    fmi3ClockUpdateCallback clockUpdate, fmi3LockPreemptionCallback lockPreemption,
    fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)instantiationToken; (void)resourcePath; (void)visible; (void)clockUpdate; (void)lockPreemption;
    (void)unlockPreemption;
    return refuse("fmi3InstantiateScheduledExecution", instanceName, loggingOn, env, logMessage,
                  "only Co-Simulation is supported");
}

FMI3_Export fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath, fmi3Boolean visible,
    fmi3Boolean loggingOn, fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
    const fmi3ValueReference requiredIntermediateVariables[], size_t nRequiredIntermediateVariables,
    fmi3InstanceEnvironment env, fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate)
{
    (void)visible; (void)earlyReturnAllowed; (void)requiredIntermediateVariables; (void)intermediateUpdate;
    return instantiate("fmi3InstantiateCoSimulation", GF_COSIMULATION, instanceName, instantiationToken, resourcePath,
                       loggingOn, env, logMessage,
                       eventModeUsed ? "eventModeUsed: this FMU has no event mode in Co-Simulation (hasEventMode=false)"
                       : nRequiredIntermediateVariables > 0
                       ? "requiredIntermediateVariables: this FMU provides no intermediate update" : NULL);
}

FMI3_Export void fmi3FreeInstance(fmi3Instance instance) { gf_free((gf_inst *)instance); }

FMI3_Export fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                                   fmi3Float64 tolerance, fmi3Float64 startTime,
                                                   fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    GF_GUARD(instance, F_EnterInitializationMode);
    (void)toleranceDefined; (void)tolerance; (void)stopTimeDefined; (void)stopTime;
    if (!isfinite(startTime)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "fmi3EnterInitializationMode: startTime not finite");
        return fmi3Error;
    }
    c->time = startTime;
    gf_enter_init(c);
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    GF_GUARD(instance, F_ExitInitializationMode);
    if (!gm_exit_init(c)) {
        c->mode = GF_ERROR;
        gf_log(c, GF_ERROR_STATUS, "logStatusError",
               "fmi3ExitInitializationMode: no initial state from the values set (reasons above); "
               "the instance is in state error (fmi3Reset or fmi3FreeInstance)");
        return fmi3Error;
    }
    c->mode = c->fmu_type == GF_MODEL_EXCHANGE ? GF_EVENT_MODE : GF_STEP_MODE;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3EnterEventMode(fmi3Instance instance)
{
    GF_GUARD(instance, F_EnterEventMode);
    c->mode = GF_EVENT_MODE;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3Terminate(fmi3Instance instance)
{
    GF_GUARD(instance, F_Terminate);
    c->mode = GF_TERMINATED;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3Reset(fmi3Instance instance)
{
    GF_GUARD(instance, F_Reset);
    gm_reset(c);
    return fmi3OK;
}

/* ------------------------------------------------------- FMI: get / set */
FMI3_Export fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                      fmi3Float64 values[], size_t nValues)
{
    GF_GUARD(instance, F_GetFloat64);
    return (fmi3Status)gf_get_values(c, "fmi3GetFloat64", vr, nvr, 1, time_vr(c), values, NULL, nValues);
}

FMI3_Export fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                    fmi3Int32 values[], size_t nValues)
{
    GF_GUARD(instance, F_GetInt32);
    return (fmi3Status)gf_get_values(c, "fmi3GetInt32", vr, nvr, 1, time_vr(c), NULL, (int *)values, nValues);
}

FMI3_Export fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                      const fmi3Float64 values[], size_t nValues)
{
    GF_GUARD(instance, F_SetFloat64);
    return (fmi3Status)gf_set_values(c, "fmi3SetFloat64", vr, nvr, 1, time_vr(c), values, NULL, nValues);
}

FMI3_Export fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                    const fmi3Int32 values[], size_t nValues)
{
    GF_GUARD(instance, F_SetInt32);
    return (fmi3Status)gf_set_values(c, "fmi3SetInt32", vr, nvr, 1, time_vr(c), NULL, (const int *)values, nValues);
}

/* the types this FMU has no variable of */
#define GF_NONE(NAME, FN, TYPE, LABEL)                                                                    \
    FMI3_Export fmi3Status NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,         \
                                TYPE values[], size_t nValues)                                            \
    {                                                                                                     \
        GF_GUARD(instance, FN);                                                                           \
        (void)vr; (void)values; (void)nValues;                                                            \
        return (fmi3Status)gf_no_variables_of(c, #NAME, LABEL, nvr);                                      \
    }
GF_NONE(fmi3GetFloat32, F_GetOther, fmi3Float32, "Float32")
GF_NONE(fmi3GetInt8, F_GetOther, fmi3Int8, "Int8")
GF_NONE(fmi3GetUInt8, F_GetOther, fmi3UInt8, "UInt8")
GF_NONE(fmi3GetInt16, F_GetOther, fmi3Int16, "Int16")
GF_NONE(fmi3GetUInt16, F_GetOther, fmi3UInt16, "UInt16")
GF_NONE(fmi3GetUInt32, F_GetOther, fmi3UInt32, "UInt32")
GF_NONE(fmi3GetInt64, F_GetOther, fmi3Int64, "Int64")
GF_NONE(fmi3GetUInt64, F_GetOther, fmi3UInt64, "UInt64")
GF_NONE(fmi3GetBoolean, F_GetOther, fmi3Boolean, "Boolean")
GF_NONE(fmi3GetString, F_GetOther, fmi3String, "String")
GF_NONE(fmi3SetFloat32, F_SetOther, const fmi3Float32, "Float32")
GF_NONE(fmi3SetInt8, F_SetOther, const fmi3Int8, "Int8")
GF_NONE(fmi3SetUInt8, F_SetOther, const fmi3UInt8, "UInt8")
GF_NONE(fmi3SetInt16, F_SetOther, const fmi3Int16, "Int16")
GF_NONE(fmi3SetUInt16, F_SetOther, const fmi3UInt16, "UInt16")
GF_NONE(fmi3SetUInt32, F_SetOther, const fmi3UInt32, "UInt32")
GF_NONE(fmi3SetInt64, F_SetOther, const fmi3Int64, "Int64")
GF_NONE(fmi3SetUInt64, F_SetOther, const fmi3UInt64, "UInt64")
GF_NONE(fmi3SetBoolean, F_SetOther, const fmi3Boolean, "Boolean")
GF_NONE(fmi3SetString, F_SetOther, const fmi3String, "String")

FMI3_Export fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                     size_t valueSizes[], fmi3Binary values[], size_t nValues)
{
    GF_GUARD(instance, F_GetOther);
    (void)vr; (void)valueSizes; (void)values; (void)nValues;
    return (fmi3Status)gf_no_variables_of(c, "fmi3GetBinary", "Binary", nvr);
}

FMI3_Export fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                     const size_t valueSizes[], const fmi3Binary values[], size_t nValues)
{
    GF_GUARD(instance, F_SetOther);
    (void)vr; (void)valueSizes; (void)values; (void)nValues;
    return (fmi3Status)gf_no_variables_of(c, "fmi3SetBinary", "Binary", nvr);
}

FMI3_Export fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                    fmi3Clock values[])
{
    (void)vr; (void)nvr; (void)values;
    GF_NEVER(F_Clocks);
}

FMI3_Export fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                    const fmi3Clock values[])
{
    (void)vr; (void)nvr; (void)values;
    GF_NEVER(F_Clocks);
}

FMI3_Export fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference vr,
                                                           size_t *nDependencies)
{
    GF_GUARD(instance, F_GetNumberOfVariableDependencies);
    (void)vr; (void)nDependencies;
    gf_log(c, GF_ERROR_STATUS, "logStatusError", "fmi3GetNumberOfVariableDependencies: not provided");
    return fmi3Error;
}

FMI3_Export fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                                   size_t elementIndicesOfDependent[],
                                                   fmi3ValueReference independents[],
                                                   size_t elementIndicesOfIndependents[],
                                                   fmi3DependencyKind dependencyKinds[], size_t nDependencies)
{
    GF_GUARD(instance, F_GetVariableDependencies);
    (void)dependent; (void)elementIndicesOfDependent; (void)independents; (void)elementIndicesOfIndependents;
    (void)dependencyKinds; (void)nDependencies;
    gf_log(c, GF_ERROR_STATUS, "logStatusError", "fmi3GetVariableDependencies: not provided");
    return fmi3Error;
}

/* ------------------------------------------------------ FMI: FMU state */
FMI3_Export fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    GF_GUARD(instance, F_GetFMUState);
    return (fmi3Status)gf_get_state(c, "fmi3GetFMUState", FMUState);
}

FMI3_Export fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState)
{
    GF_GUARD(instance, F_SetFMUState);
    return (fmi3Status)gf_set_state(c, "fmi3SetFMUState", FMUState);
}

FMI3_Export fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    GF_GUARD(instance, F_FreeFMUState);
    (void)c;
    gf_free_state(FMUState);
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size)
{
    GF_GUARD(instance, F_SerializedFMUStateSize);
    return (fmi3Status)gf_state_size(c, "fmi3SerializedFMUStateSize", FMUState, size);
}

FMI3_Export fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                             size_t size)
{
    GF_GUARD(instance, F_SerializeFMUState);
    return (fmi3Status)gf_serialize_state(c, "fmi3SerializeFMUState", FMUState, serializedState, size);
}

FMI3_Export fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                               fmi3FMUState *FMUState)
{
    GF_GUARD(instance, F_DeserializeFMUState);
    return (fmi3Status)gf_deserialize_state(c, "fmi3DeserializeFMUState", serializedState, size, FMUState);
}

/* ----------------------------------------------------- FMI: derivatives */
#define GF_NO_DERIVATIVE(NAME, FN)                                                                         \
    FMI3_Export fmi3Status NAME(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns, \
                                const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], \
                                size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity)              \
    {                                                                                                      \
        GF_GUARD(instance, FN);                                                                            \
        (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed;             \
        (void)sensitivity; (void)nSensitivity;                                                             \
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: not provided", #NAME);                           \
        return fmi3Error;                                                                                  \
    }
GF_NO_DERIVATIVE(fmi3GetDirectionalDerivative, F_GetDirectionalDerivative)
GF_NO_DERIVATIVE(fmi3GetAdjointDerivative, F_GetAdjointDerivative)

/* ------------------------------------- FMI: what this FMU never offers */
FMI3_Export fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) { GF_NEVER(F_EnterConfigurationMode); }
FMI3_Export fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) { GF_NEVER(F_ExitConfigurationMode); }

FMI3_Export fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                              fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[])
{
    (void)vr; (void)nvr; (void)intervals; (void)qualifiers;
    GF_NEVER(F_Clocks);
}

FMI3_Export fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                               fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                               fmi3IntervalQualifier qualifiers[])
{
    (void)vr; (void)nvr; (void)counters; (void)resolutions; (void)qualifiers;
    GF_NEVER(F_Clocks);
}

FMI3_Export fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                           fmi3Float64 shifts[])
{
    (void)vr; (void)nvr; (void)shifts;
    GF_NEVER(F_Clocks);
}

FMI3_Export fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                            fmi3UInt64 counters[], fmi3UInt64 resolutions[])
{
    (void)vr; (void)nvr; (void)counters; (void)resolutions;
    GF_NEVER(F_Clocks);
}

FMI3_Export fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                              const fmi3Float64 intervals[])
{
    (void)vr; (void)nvr; (void)intervals;
    GF_NEVER(F_Clocks);
}

FMI3_Export fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                               const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
{
    (void)vr; (void)nvr; (void)counters; (void)resolutions;
    GF_NEVER(F_Clocks);
}

FMI3_Export fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                           const fmi3Float64 shifts[])
{
    (void)vr; (void)nvr; (void)shifts;
    GF_NEVER(F_Clocks);
}

FMI3_Export fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                            const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
{
    (void)vr; (void)nvr; (void)counters; (void)resolutions;
    GF_NEVER(F_Clocks);
}

FMI3_Export fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) { GF_NEVER(F_EvaluateDiscreteStates); }

/* the mode anew from the continuous states (gf_model.h event_update): one pass always suffices, the
 * continuous states keep their values, no time event */
FMI3_Export fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                                fmi3Boolean *terminateSimulation,
                                                fmi3Boolean *nominalsOfContinuousStatesChanged,
                                                fmi3Boolean *valuesOfContinuousStatesChanged,
                                                fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime)
{
    int again, changed, st;
    GF_GUARD(instance, F_UpdateDiscreteStates);
    if (discreteStatesNeedUpdate == NULL || terminateSimulation == NULL || nominalsOfContinuousStatesChanged == NULL ||
        valuesOfContinuousStatesChanged == NULL || nextEventTimeDefined == NULL || nextEventTime == NULL) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "fmi3UpdateDiscreteStates: an output argument is NULL");
        return fmi3Error;
    }
    st = gf_me_event_update(c, "fmi3UpdateDiscreteStates", &again, &changed);
    *discreteStatesNeedUpdate = again ? fmi3True : fmi3False;
    *terminateSimulation = fmi3False;
    *nominalsOfContinuousStatesChanged = fmi3False;
    *valuesOfContinuousStatesChanged = changed ? fmi3True : fmi3False;
    *nextEventTimeDefined = fmi3False;
    *nextEventTime = 0.0;
    return (fmi3Status)st;
}

FMI3_Export fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance)
{
    GF_GUARD(instance, F_EnterContinuousTimeMode);
    c->mode = GF_CONT_MODE;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                                   fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation)
{
    int ev, st;
    GF_GUARD(instance, F_CompletedIntegratorStep);
    (void)noSetFMUStatePriorToCurrentPoint;
    if (enterEventMode == NULL || terminateSimulation == NULL) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "fmi3CompletedIntegratorStep: enterEventMode or "
               "terminateSimulation is NULL");
        return fmi3Error;
    }
    st = gf_me_completed_step(c, "fmi3CompletedIntegratorStep", &ev);
    *enterEventMode = ev ? fmi3True : fmi3False;
    *terminateSimulation = fmi3False;
    return (fmi3Status)st;
}

FMI3_Export fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time)
{
    GF_GUARD(instance, F_SetTime);
    if (!isfinite(time)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "fmi3SetTime: time = %.17g is not finite", time);
        return fmi3Error;
    }
    c->time = time;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 x[], size_t n)
{
    GF_GUARD(instance, F_SetContinuousStates);
    return (fmi3Status)gf_me_set_states(c, "fmi3SetContinuousStates", x, n);
}

FMI3_Export fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[], size_t n)
{
    GF_GUARD(instance, F_GetContinuousStateDerivatives);
    return (fmi3Status)gf_me_derivatives(c, "fmi3GetContinuousStateDerivatives", derivatives, n);
}

FMI3_Export fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t n)
{
    GF_GUARD(instance, F_GetEventIndicators);
    return (fmi3Status)gf_me_indicators(c, "fmi3GetEventIndicators", eventIndicators, n);
}

FMI3_Export fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 x[], size_t n)
{
    GF_GUARD(instance, F_GetContinuousStates);
    return (fmi3Status)gf_me_states(c, "fmi3GetContinuousStates", x, n);
}

FMI3_Export fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 x[], size_t n)
{
    GF_GUARD(instance, F_GetNominalsOfContinuousStates);
    return (fmi3Status)gf_me_nominals(c, "fmi3GetNominalsOfContinuousStates", x, n);
}

/* the counts of Model Exchange (0 for an FMU without it) */
FMI3_Export fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *n)
{
    GF_GUARD(instance, F_GetNumberOfEventIndicators);
    if (n == NULL) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "fmi3GetNumberOfEventIndicators: nEventIndicators is NULL");
        return fmi3Error;
    }
    *n = c->me != NULL ? c->n_indicators : 0;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *n)
{
    GF_GUARD(instance, F_GetNumberOfContinuousStates);
    if (n == NULL) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "fmi3GetNumberOfContinuousStates: nContinuousStates is NULL");
        return fmi3Error;
    }
    *n = c->me != NULL ? c->n_states : 0;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3EnterStepMode(fmi3Instance instance) { GF_NEVER(F_EnterStepMode); }

FMI3_Export fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                                  fmi3Float64 activationTime)
{
    (void)clockReference; (void)activationTime;
    GF_NEVER(F_ActivateModelPartition);
}

/* ------------------------------------------------- FMI: Co-Simulation */
FMI3_Export fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                                const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues)
{
    GF_GUARD(instance, F_GetOutputDerivatives);
    (void)vr; (void)orders; (void)values; (void)nValues;
    if (nvr == 0) return fmi3OK;
    gf_log(c, GF_ERROR_STATUS, "logStatusError", "fmi3GetOutputDerivatives: maxOutputDerivativeOrder is 0");
    return fmi3Error;
}

/* one communication step (the model's gm_do_step, as fmi2DoStep); synchronous: never an event,
 * never early, lastSuccessfulTime = the time reached (the start of the step when discarded) */
FMI3_Export fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                                  fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                  fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                                  fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime)
{
    fmi3Status st;
    GF_GUARD(instance, F_DoStep);
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!gf_check_step_time(c, "fmi3DoStep", currentCommunicationPoint, communicationStepSize)) {
        if (lastSuccessfulTime != NULL) *lastSuccessfulTime = c->time;
        return fmi3Error;
    }
    st = (fmi3Status)gm_do_step(c, currentCommunicationPoint, communicationStepSize);
    if (eventHandlingNeeded != NULL) *eventHandlingNeeded = fmi3False;
    if (terminateSimulation != NULL) *terminateSimulation = fmi3False;
    if (earlyReturn != NULL) *earlyReturn = fmi3False;
    if (lastSuccessfulTime != NULL) *lastSuccessfulTime = c->time;
    return st;
}
