/*
 * fmi2_gear.c -- FMI 2.0 layer of the standalone gearfmu runtime (docs/standalone.md),
 * Co-Simulation and Model Exchange: the fmi2* functions, their table of allowed
 * states, and the adapters to the shared plumbing (fmi_common.h) and the gear
 * model behind the contract gf_model.h, which the FMI 3.0 layer (fmi3_gear.c) uses too.
 *
 * Standard: Modelica Association, "Functional Mock-up Interface for Model
 * Exchange and Co-Simulation", version 2.0 (sections 2.1 common API,
 * 3.2 Model Exchange API, 4.2 Co-Simulation API).  The FMI headers are the standard's own
 * (fmi2Functions.h, fmi2FunctionTypes.h, fmi2TypesPlatform.h), shipped
 * beside this file in the FMU's sources/.  The resources are found through
 * the file:// URI the host gives (fmuResourceLocation).
 */
#include <math.h>
#include <stdio.h>

#include "fmi2Functions.h"
#include "fmi_common.h"

/* FMI 2.0 Co-Simulation states (standard section 4.2.4, figure 2 and the table
 * of allowed calls), GF_* bits of gf_model.h. */
typedef enum {
    F_SetDebugLogging, F_SetupExperiment, F_EnterInitializationMode, F_ExitInitializationMode,
    F_Terminate, F_Reset, F_FreeInstance,
    F_GetReal, F_GetInteger, F_GetBoolean, F_GetString,
    F_SetReal, F_SetInteger, F_SetBoolean, F_SetString,
    F_GetFMUstate, F_SetFMUstate, F_FreeFMUstate, F_SerializedFMUstateSize, F_SerializeFMUstate,
    F_DeSerializeFMUstate, F_GetDirectionalDerivative,
    F_SetRealInputDerivatives, F_GetRealOutputDerivatives, F_DoStep, F_CancelStep,
    F_GetStatus, F_GetRealStatus, F_GetIntegerStatus, F_GetBooleanStatus, F_GetStringStatus,
    F_EnterEventMode, F_NewDiscreteStates, F_EnterContinuousTimeMode, F_CompletedIntegratorStep, F_SetTime,
    F_SetContinuousStates, F_GetDerivatives, F_GetEventIndicators, F_GetContinuousStates,
    F_GetNominalsOfContinuousStates,
    F_COUNT
} gf_fn;

#define GF_STATUS (GF_STEP_MODE | GF_TERMINATED)

/* Which fmi2 function may be called in which state: one table, checked at the
 * entry of every function (FMI 2.0 standard sections 3.2.3 and 4.2.4, the tables of
 * allowed calls for Model Exchange and Co-Simulation; the same scheme as the Modelica
 * Reference-FMUs' fmi2Functions.c); 0: never (stepInProgress does not exist here).  A
 * Co-Simulation instance never is in eventMode or continuousTimeMode, a Model Exchange
 * instance never in stepComplete. */
static const gf_call GF_CALLS[F_COUNT] = {
    {"fmi2SetDebugLogging", GF_ANY_STATE},
    {"fmi2SetupExperiment", GF_INSTANTIATED},
    {"fmi2EnterInitializationMode", GF_INSTANTIATED},
    {"fmi2ExitInitializationMode", GF_INIT_MODE},
    {"fmi2Terminate", GF_STEP_MODE | GF_EVENT_MODE | GF_CONT_MODE},
    {"fmi2Reset", GF_ANY_STATE},
    {"fmi2FreeInstance", GF_ANY_STATE},
    {"fmi2GetReal", GF_GETTERS},
    {"fmi2GetInteger", GF_GETTERS},
    {"fmi2GetBoolean", GF_GETTERS},
    {"fmi2GetString", GF_GETTERS},
    {"fmi2SetReal", GF_SETTERS},
    {"fmi2SetInteger", GF_SETTERS},
    {"fmi2SetBoolean", GF_SETTERS},
    {"fmi2SetString", GF_SETTERS},
    {"fmi2GetFMUstate", GF_ANY_STATE},
    {"fmi2SetFMUstate", GF_ANY_STATE},
    {"fmi2FreeFMUstate", GF_ANY_STATE},
    {"fmi2SerializedFMUstateSize", GF_ANY_STATE},
    {"fmi2SerializeFMUstate", GF_ANY_STATE},
    {"fmi2DeSerializeFMUstate", GF_ANY_STATE},
    {"fmi2GetDirectionalDerivative", GF_GETTERS},
    {"fmi2SetRealInputDerivatives", GF_SETTERS},
    {"fmi2GetRealOutputDerivatives", GF_STEP_MODE | GF_TERMINATED | GF_ERROR},
    {"fmi2DoStep", GF_STEP_MODE},
    {"fmi2CancelStep", 0},
    {"fmi2GetStatus", GF_STATUS},
    {"fmi2GetRealStatus", GF_STATUS},
    {"fmi2GetIntegerStatus", GF_STATUS},
    {"fmi2GetBooleanStatus", GF_STATUS},
    {"fmi2GetStringStatus", GF_STATUS},
    {"fmi2EnterEventMode", GF_EVENT_MODE | GF_CONT_MODE},
    {"fmi2NewDiscreteStates", GF_EVENT_MODE},
    {"fmi2EnterContinuousTimeMode", GF_EVENT_MODE},
    {"fmi2CompletedIntegratorStep", GF_CONT_MODE},
    {"fmi2SetTime", GF_EVENT_MODE | GF_CONT_MODE},
    {"fmi2SetContinuousStates", GF_CONT_MODE},
    {"fmi2GetDerivatives", GF_EVENT_MODE | GF_CONT_MODE | GF_TERMINATED | GF_ERROR},
    {"fmi2GetEventIndicators", GF_INIT_MODE | GF_EVENT_MODE | GF_CONT_MODE | GF_TERMINATED | GF_ERROR},
    {"fmi2GetContinuousStates", GF_INIT_MODE | GF_EVENT_MODE | GF_CONT_MODE | GF_TERMINATED | GF_ERROR},
    {"fmi2GetNominalsOfContinuousStates", GF_INSTANTIATED | GF_EVENT_MODE | GF_CONT_MODE | GF_TERMINATED | GF_ERROR},
};

#define GF_GUARD(comp, fn)                                                     \
    gf_inst *c = (gf_inst *)(comp);                                            \
    if (!gf_may_call(c, &GF_CALLS[fn])) return fmi2Error

/* the FMI 2 logger is variadic (a format); the message is passed as "%s" */
static void log_fmi2(gf_inst *c, int status, const char *category, const char *msg)
{
    ((fmi2CallbackLogger)c->host_logger)(c->host_env, c->instance_name, (fmi2Status)status, category, "%s", msg);
}

/* ---------------------------------------------------------- FMI: common */
FMI2_Export const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
FMI2_Export const char *fmi2GetVersion(void) { return fmi2Version; }

FMI2_Export fmi2Status fmi2SetDebugLogging(fmi2Component comp, fmi2Boolean loggingOn, size_t nCategories,
                                           const fmi2String categories[])
{
    GF_GUARD(comp, F_SetDebugLogging);
    (void)nCategories;
    (void)categories;
    c->logging_on = loggingOn ? 1 : 0;
    return fmi2OK;
}

FMI2_Export fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                                          fmi2String fmuResourceLocation,
                                          const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                                          fmi2Boolean loggingOn)
{
    static const char *const fn = "fmi2Instantiate";
    gf_inst *c;
    char dir[4096], err[700];
    const char *e;
    (void)visible;
    c = gf_new(2, instanceName, loggingOn, log_fmi2, functions ? functions->componentEnvironment : NULL,
               functions ? (void (*)(void))functions->logger : NULL,
               "stepInProgress, which the synchronous fmi2DoStep never enters");
    if (c == NULL) return NULL;
    if (fmuType != fmi2CoSimulation && fmuType != fmi2ModelExchange)
        return gf_instantiate_error(c, fn, "fmuType is neither fmi2ModelExchange nor fmi2CoSimulation");
    c->fmu_type = fmuType == fmi2ModelExchange ? GF_MODEL_EXCHANGE : GF_COSIMULATION;
    if (!gf_uri_to_dir(fmuResourceLocation, dir, sizeof dir)) {
        snprintf(err, sizeof err, "fmuResourceLocation '%.500s' is not a file URI of this machine (file:///path, "
                 "file://localhost/path or file:/path, RFC 8089)", fmuResourceLocation ? fmuResourceLocation : "(null)");
        return gf_instantiate_error(c, fn, err);
    }
    e = gm_instantiate(c, dir, fmuGUID, err, sizeof err);
    if (e == NULL) e = gf_offered(c);
    if (e != NULL) return gf_instantiate_error(c, fn, e);
    return (fmi2Component)c;
}

FMI2_Export void fmi2FreeInstance(fmi2Component comp) { gf_free((gf_inst *)comp); }

FMI2_Export fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                                           fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    GF_GUARD(comp, F_SetupExperiment);
    (void)toleranceDefined; (void)tolerance; (void)stopTimeDefined; (void)stopTime;
    if (!isfinite(startTime)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "fmi2SetupExperiment: startTime not finite");
        return fmi2Error;
    }
    c->time = startTime;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2EnterInitializationMode(fmi2Component comp)
{
    GF_GUARD(comp, F_EnterInitializationMode);
    gf_enter_init(c);
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2ExitInitializationMode(fmi2Component comp)
{
    GF_GUARD(comp, F_ExitInitializationMode);
    if (!gm_exit_init(c)) {
        c->mode = GF_ERROR;
        gf_log(c, GF_ERROR_STATUS, "logStatusError",
               "fmi2ExitInitializationMode: no initial state from the values set (reasons above); "
               "the instance is in state error (fmi2Reset or fmi2FreeInstance)");
        return fmi2Error;
    }
    c->mode = c->fmu_type == GF_MODEL_EXCHANGE ? GF_EVENT_MODE : GF_STEP_MODE;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2Terminate(fmi2Component comp)
{
    GF_GUARD(comp, F_Terminate);
    c->mode = GF_TERMINATED;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2Reset(fmi2Component comp)
{
    GF_GUARD(comp, F_Reset);
    gm_reset(c);
    return fmi2OK;
}

/* ------------------------------------------------------- FMI: get / set */
#define GF_NONE(NAME, FN, TYPE, LABEL)                                                                   \
    FMI2_Export fmi2Status NAME(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, TYPE value[]) \
    {                                                                                                    \
        GF_GUARD(comp, FN);                                                                              \
        (void)vr; (void)value;                                                                           \
        return (fmi2Status)gf_no_variables_of(c, #NAME, LABEL, nvr);                                     \
    }

FMI2_Export fmi2Status fmi2GetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[])
{
    GF_GUARD(comp, F_GetReal);
    return (fmi2Status)gf_get_values(c, "fmi2GetReal", vr, nvr, 0, -1, value, NULL, nvr);
}

FMI2_Export fmi2Status fmi2GetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                                      fmi2Integer value[])
{
    GF_GUARD(comp, F_GetInteger);
    return (fmi2Status)gf_get_values(c, "fmi2GetInteger", vr, nvr, 0, -1, NULL, value, nvr);
}

FMI2_Export fmi2Status fmi2SetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                                   const fmi2Real value[])
{
    GF_GUARD(comp, F_SetReal);
    return (fmi2Status)gf_set_values(c, "fmi2SetReal", vr, nvr, 0, -1, value, NULL, nvr);
}

FMI2_Export fmi2Status fmi2SetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                                      const fmi2Integer value[])
{
    GF_GUARD(comp, F_SetInteger);
    return (fmi2Status)gf_set_values(c, "fmi2SetInteger", vr, nvr, 0, -1, NULL, value, nvr);
}

GF_NONE(fmi2GetBoolean, F_GetBoolean, fmi2Boolean, "Boolean")
GF_NONE(fmi2GetString, F_GetString, fmi2String, "String")
GF_NONE(fmi2SetBoolean, F_SetBoolean, const fmi2Boolean, "Boolean")
GF_NONE(fmi2SetString, F_SetString, const fmi2String, "String")

/* ------------------------------------------------------ FMI: FMU state */
FMI2_Export fmi2Status fmi2GetFMUstate(fmi2Component comp, fmi2FMUstate *FMUstate)
{
    GF_GUARD(comp, F_GetFMUstate);
    return (fmi2Status)gf_get_state(c, "fmi2GetFMUstate", FMUstate);
}

FMI2_Export fmi2Status fmi2SetFMUstate(fmi2Component comp, fmi2FMUstate FMUstate)
{
    GF_GUARD(comp, F_SetFMUstate);
    return (fmi2Status)gf_set_state(c, "fmi2SetFMUstate", FMUstate);
}

FMI2_Export fmi2Status fmi2FreeFMUstate(fmi2Component comp, fmi2FMUstate *FMUstate)
{
    GF_GUARD(comp, F_FreeFMUstate);
    (void)c;
    gf_free_state(FMUstate);
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SerializedFMUstateSize(fmi2Component comp, fmi2FMUstate FMUstate, size_t *size)
{
    GF_GUARD(comp, F_SerializedFMUstateSize);
    return (fmi2Status)gf_state_size(c, "fmi2SerializedFMUstateSize", FMUstate, size);
}

FMI2_Export fmi2Status fmi2SerializeFMUstate(fmi2Component comp, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                             size_t size)
{
    GF_GUARD(comp, F_SerializeFMUstate);
    return (fmi2Status)gf_serialize_state(c, "fmi2SerializeFMUstate", FMUstate, (unsigned char *)serializedState,
                                          size);
}

FMI2_Export fmi2Status fmi2DeSerializeFMUstate(fmi2Component comp, const fmi2Byte serializedState[], size_t size,
                                               fmi2FMUstate *FMUstate)
{
    GF_GUARD(comp, F_DeSerializeFMUstate);
    return (fmi2Status)gf_deserialize_state(c, "fmi2DeSerializeFMUstate", (const unsigned char *)serializedState,
                                            size, FMUstate);
}

FMI2_Export fmi2Status fmi2GetDirectionalDerivative(fmi2Component comp, const fmi2ValueReference vUnknown_ref[],
                                                    size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                                    size_t nKnown, const fmi2Real dvKnown[], fmi2Real dvUnknown[])
{
    GF_GUARD(comp, F_GetDirectionalDerivative);
    (void)vUnknown_ref; (void)nUnknown; (void)vKnown_ref; (void)nKnown; (void)dvKnown; (void)dvUnknown;
    gf_log(c, GF_ERROR_STATUS, "logStatusError", "fmi2GetDirectionalDerivative: not provided");
    return fmi2Error;
}

/* ------------------------------------------------- FMI: Co-Simulation */
FMI2_Export fmi2Status fmi2SetRealInputDerivatives(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                                                   const fmi2Integer order[], const fmi2Real value[])
{
    GF_GUARD(comp, F_SetRealInputDerivatives);
    (void)vr; (void)order; (void)value;
    if (nvr == 0) return fmi2OK;
    gf_log(c, GF_ERROR_STATUS, "logStatusError", "fmi2SetRealInputDerivatives: canInterpolateInputs is false");
    return fmi2Error;
}

FMI2_Export fmi2Status fmi2GetRealOutputDerivatives(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                                                    const fmi2Integer order[], fmi2Real value[])
{
    GF_GUARD(comp, F_GetRealOutputDerivatives);
    (void)vr; (void)order; (void)value;
    if (nvr == 0) return fmi2OK;
    gf_log(c, GF_ERROR_STATUS, "logStatusError", "fmi2GetRealOutputDerivatives: maxOutputDerivativeOrder is 0");
    return fmi2Error;
}

FMI2_Export fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real currentCommunicationPoint,
                                  fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    GF_GUARD(comp, F_DoStep);
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!gf_check_step_time(c, "fmi2DoStep", currentCommunicationPoint, communicationStepSize)) return fmi2Error;
    return (fmi2Status)gm_do_step(c, currentCommunicationPoint, communicationStepSize);
}

FMI2_Export fmi2Status fmi2CancelStep(fmi2Component comp)
{
    gf_allowed((gf_inst *)comp, &GF_CALLS[F_CancelStep]); /* never allowed: logs why */
    return fmi2Error;
}

/* fmi2Get*Status: this FMU's doStep is synchronous (never fmi2Pending), so only
 * fmi2LastSuccessfulTime and fmi2Terminated have an answer; any other kind is
 * fmi2Discard with a log message (FMI 2.0 section 4.2.3). */
static fmi2Status get_status(gf_inst *c, const char *fn, fmi2StatusKind s, void *value, fmi2StatusKind kind)
{
    if (kind != (fmi2StatusKind)-1 && value == NULL) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: value is NULL", fn);
        return fmi2Error;
    }
    if (kind != (fmi2StatusKind)-1 && s == kind) {
        if (kind == fmi2LastSuccessfulTime) *(fmi2Real *)value = c->time;
        else *(fmi2Boolean *)value = fmi2False;
        return fmi2OK;
    }
    gf_log(c, GF_DISCARD, "logStatusDiscard", "%s: status kind %d not provided (fmi2DoStep is synchronous and "
           "never returns fmi2Pending)", fn, (int)s);
    return fmi2Discard;
}

#define GF_STATUS_FN(NAME, FN, TYPE, KIND)                                                 \
    FMI2_Export fmi2Status NAME(fmi2Component comp, const fmi2StatusKind s, TYPE *value)   \
    {                                                                                      \
        GF_GUARD(comp, FN);                                                                \
        return get_status(c, #NAME, s, value, KIND);                                       \
    }

GF_STATUS_FN(fmi2GetStatus, F_GetStatus, fmi2Status, (fmi2StatusKind)-1)
GF_STATUS_FN(fmi2GetRealStatus, F_GetRealStatus, fmi2Real, fmi2LastSuccessfulTime)
GF_STATUS_FN(fmi2GetIntegerStatus, F_GetIntegerStatus, fmi2Integer, (fmi2StatusKind)-1)
GF_STATUS_FN(fmi2GetBooleanStatus, F_GetBooleanStatus, fmi2Boolean, fmi2Terminated)
GF_STATUS_FN(fmi2GetStringStatus, F_GetStringStatus, fmi2String, (fmi2StatusKind)-1)

/* ------------------------------------------------- FMI: Model Exchange */
FMI2_Export fmi2Status fmi2EnterEventMode(fmi2Component comp)
{
    GF_GUARD(comp, F_EnterEventMode);
    c->mode = GF_EVENT_MODE;
    return fmi2OK;
}

/* the mode anew from the continuous states (gf_model.h event_update): one pass always suffices, the
 * continuous states keep their values, no time event */
FMI2_Export fmi2Status fmi2NewDiscreteStates(fmi2Component comp, fmi2EventInfo *eventInfo)
{
    int again, changed, st;
    GF_GUARD(comp, F_NewDiscreteStates);
    if (eventInfo == NULL) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "fmi2NewDiscreteStates: fmi2EventInfo is NULL");
        return fmi2Error;
    }
    st = gf_me_event_update(c, "fmi2NewDiscreteStates", &again, &changed);
    eventInfo->newDiscreteStatesNeeded = again ? fmi2True : fmi2False;
    eventInfo->terminateSimulation = fmi2False;
    eventInfo->nominalsOfContinuousStatesChanged = fmi2False;
    eventInfo->valuesOfContinuousStatesChanged = changed ? fmi2True : fmi2False;
    eventInfo->nextEventTimeDefined = fmi2False;
    eventInfo->nextEventTime = 0.0;
    return (fmi2Status)st;
}

FMI2_Export fmi2Status fmi2EnterContinuousTimeMode(fmi2Component comp)
{
    GF_GUARD(comp, F_EnterContinuousTimeMode);
    c->mode = GF_CONT_MODE;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2CompletedIntegratorStep(fmi2Component comp, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                                   fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation)
{
    int ev, st;
    GF_GUARD(comp, F_CompletedIntegratorStep);
    (void)noSetFMUStatePriorToCurrentPoint;
    if (enterEventMode == NULL || terminateSimulation == NULL) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "fmi2CompletedIntegratorStep: enterEventMode or "
               "terminateSimulation is NULL");
        return fmi2Error;
    }
    st = gf_me_completed_step(c, "fmi2CompletedIntegratorStep", &ev);
    *enterEventMode = ev ? fmi2True : fmi2False;
    *terminateSimulation = fmi2False;
    return (fmi2Status)st;
}

FMI2_Export fmi2Status fmi2SetTime(fmi2Component comp, fmi2Real time)
{
    GF_GUARD(comp, F_SetTime);
    if (!isfinite(time)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "fmi2SetTime: time = %.17g is not finite", time);
        return fmi2Error;
    }
    c->time = time;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetContinuousStates(fmi2Component comp, const fmi2Real x[], size_t nx)
{
    GF_GUARD(comp, F_SetContinuousStates);
    return (fmi2Status)gf_me_set_states(c, "fmi2SetContinuousStates", x, nx);
}

FMI2_Export fmi2Status fmi2GetDerivatives(fmi2Component comp, fmi2Real derivatives[], size_t nx)
{
    GF_GUARD(comp, F_GetDerivatives);
    return (fmi2Status)gf_me_derivatives(c, "fmi2GetDerivatives", derivatives, nx);
}

FMI2_Export fmi2Status fmi2GetEventIndicators(fmi2Component comp, fmi2Real eventIndicators[], size_t ni)
{
    GF_GUARD(comp, F_GetEventIndicators);
    return (fmi2Status)gf_me_indicators(c, "fmi2GetEventIndicators", eventIndicators, ni);
}

FMI2_Export fmi2Status fmi2GetContinuousStates(fmi2Component comp, fmi2Real x[], size_t nx)
{
    GF_GUARD(comp, F_GetContinuousStates);
    return (fmi2Status)gf_me_states(c, "fmi2GetContinuousStates", x, nx);
}

FMI2_Export fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component comp, fmi2Real x_nominal[], size_t nx)
{
    GF_GUARD(comp, F_GetNominalsOfContinuousStates);
    return (fmi2Status)gf_me_nominals(c, "fmi2GetNominalsOfContinuousStates", x_nominal, nx);
}
