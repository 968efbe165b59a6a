/* FMI 2.0 co-simulation in C for one native model (fmus/c/<model>/model.c, interface in model.h).
 * The FMI-version-independent work (instance, logging, values, checks, FMU state blob) is in glue_core.c,
 * shared with the FMI 3.0 glue (fmi3_glue.c); this file maps the fmi2* calls onto it.
 *
 * Contract:
 * - the state machine of FMI 2.0 section 4.2.4: a call out of order returns fmi2Error with a logged
 *   message and puts the instance in the error state, which only fmi2Reset, fmi2FreeInstance or fmi2SetFMUstate
 *   to a state saved earlier (recovery, as FMI 2.0.x allows) leave;
 * - value references and types are checked against the model's variable table; fmi2Set* checks
 *   causality/variability against the current state;
 * - bad input gives fmi2Error with a logged reason, never fmi2Fatal, never a crash;
 * - parameters are checked at fmi2ExitInitializationMode (the model's initialize());
 * - a Real output that is not finite is never returned with fmi2OK (checked after every callback);
 * - the first fmi2DoStep starts at fmi2SetupExperiment's start time (0 without it), each next one where
 *   the previous ended;
 * - messages reach the host's logger: status >= fmi2Discard always, others when debug logging is on for
 *   their category (loggingOn at instantiation switches every category on; fmi2SetDebugLogging changes them).
 * FMU state (canGetAndSetFMUstate, canSerializeFMUstate): a state is one self-describing blob, the same
 * bytes in memory and serialized: header (magic, format version, the model's state version, byte order,
 * GUID, payload size, FNV-1a checksum of the payload) and payload (FMI state, time, every value, the model's
 * plain-bytes state, its work state).  A wrong, truncated or foreign blob is refused with fmi2Error.
 * Memory: fmi2Instantiate allocates the instance; the model allocates in initialize(); after that nothing
 * allocates except the FMU-state calls (fmi2GetFMUstate and fmi2DeSerializeFMUstate allocate the blob,
 * fmi2SetFMUstate may rebuild the model's work from restored parameters).  No globals.
 */
#include "smath.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "glue_core.h"

#define GET_STATES SG_ANY_STATE
#define SET_STATES (S_INSTANTIATED | S_INIT | S_STEP_COMPLETE)
#define REQUIRE SG_REQUIRE

typedef struct {
    sarins_glue core; /* first: a sarins_glue * is a glue2 * */
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment env;
} glue2;

static void emit2(const sarins_glue *g, int status, const char *category, const char *text)
{
    const glue2 *g2 = (const glue2 *)(const void *)g;
    if (g2->logger != NULL)
        g2->logger(g2->env, g->name ? g->name : "", (fmi2Status)status, category, "%s", text);
}

/* ------------------------------------------------------------- instances */

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn)
{
    (void)visible;
    glue2 *g = (glue2 *)(void *)sg_alloc(sizeof(glue2));
    if (g == NULL) {
        if (functions && functions->logger)
            functions->logger(functions->componentEnvironment, instanceName ? instanceName : "", fmi2Error,
                              "logStatusError", "fmi2Instantiate: out of memory");
        return NULL;
    }
    if (functions != NULL) {
        g->logger = functions->logger;
        g->env = functions->componentEnvironment;
    }
    g->core.emit = emit2;
    g->core.prefix = "fmi2";
    g->core.standard = "FMI 2.0 section 4.2.4";
    if (!sg_init(&g->core, instanceName, fmuGUID, loggingOn, "fmi2Instantiate")
        || !sg_set_resources(&g->core, fmuResourceLocation, 1)) {
        sg_free(&g->core);
        return NULL;
    }
    if (fmuType != fmi2CoSimulation) {
        sg_log(&g->core, fmi2Error, "fmi2Instantiate: this FMU supports co-simulation only (fmuType %d)",
               (int)fmuType);
        sg_free(&g->core);
        return NULL;
    }
    return (fmi2Component)g;
}

void fmi2FreeInstance(fmi2Component c)
{
    sg_free((sarins_glue *)c);
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t n, const fmi2String categories[])
{
    return (fmi2Status)sg_set_debug_logging((sarins_glue *)c, loggingOn, n, categories, "fmi2SetDebugLogging");
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2SetupExperiment", S_INSTANTIATED);
    (void)toleranceDefined;
    (void)tolerance;
    if (!isfinite(startTime))
        return (fmi2Status)sg_fail(g, "fmi2SetupExperiment: start time %g is not finite", startTime);
    if (stopTimeDefined && !(stopTime >= startTime))
        return (fmi2Status)sg_fail(g, "fmi2SetupExperiment: stop time %g before start %g", stopTime, startTime);
    g->ctx.start_time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2EnterInitializationMode", S_INSTANTIATED);
    sg_enter_init(g);
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2ExitInitializationMode", S_INIT);
    return (fmi2Status)sg_exit_init(g, "fmi2ExitInitializationMode");
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2Terminate", S_STEP_COMPLETE | S_STEP_FAILED);
    sg_terminate(g);
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2Reset", SG_ANY_STATE);
    sg_reset(g);
    return fmi2OK;
}

/* --------------------------------------------------------- get and set */

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[])
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2GetReal", GET_STATES);
    return (fmi2Status)sg_get_real(g, "fmi2GetReal", vr, nvr, value);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[])
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2GetInteger", GET_STATES);
    return (fmi2Status)sg_get_int(g, "fmi2GetInteger", vr, nvr, value);
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[])
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2GetBoolean", GET_STATES);
    if (!sg_check_args(g, "fmi2GetBoolean", vr, nvr, value, SARINS_BOOLEAN, NULL))
        return fmi2Error;
    for (size_t k = 0; k < nvr; k++)
        value[k] = g->ctx.b[g->by_vr[vr[k]]->slot] ? fmi2True : fmi2False;
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[])
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2GetString", GET_STATES);
    return (fmi2Status)sg_get_string(g, "fmi2GetString", vr, nvr, value);
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[])
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2SetReal", SET_STATES);
    return (fmi2Status)sg_set_real(g, "fmi2SetReal", vr, nvr, value, sg_settable_default);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[])
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2SetInteger", SET_STATES);
    return (fmi2Status)sg_set_int(g, "fmi2SetInteger", vr, nvr, value, sg_settable_default);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[])
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2SetBoolean", SET_STATES);
    if (!sg_check_args(g, "fmi2SetBoolean", vr, nvr, value, SARINS_BOOLEAN, sg_settable_default))
        return fmi2Error;
    for (size_t k = 0; k < nvr; k++) {
        g->ctx.b[g->by_vr[vr[k]]->slot] = value[k] ? 1 : 0;
        g->ctx.set[g->by_vr[vr[k]] - g->table->vars] = 1; /* its row = its vr (native_fmu.py) */
    }
    return fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[])
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2SetString", SET_STATES);
    return (fmi2Status)sg_set_string(g, "fmi2SetString", vr, nvr, value, sg_settable_default);
}

/* ---------------------------------------------------------------- step */

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    sarins_glue *g = (sarins_glue *)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    REQUIRE(g, "fmi2DoStep", S_STEP_COMPLETE);
    return (fmi2Status)sg_do_step(g, t, h, "fmi2DoStep");
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    sarins_glue *g = (sarins_glue *)c;
    if (g == NULL)
        return fmi2Error;
    return (fmi2Status)sg_fail(g, "fmi2CancelStep: no asynchronous step is in progress (this FMU steps "
                               "synchronously)");
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2GetStatus", RUN_STATES);
    (void)s;
    (void)value;
    return fmi2Discard; /* only meaningful for asynchronous steps */
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2GetRealStatus", RUN_STATES);
    if (s == fmi2LastSuccessfulTime && value != NULL) {
        *value = g->have_time ? g->t_next : g->ctx.start_time;
        return fmi2OK;
    }
    return fmi2Discard;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2GetIntegerStatus", RUN_STATES);
    (void)s;
    (void)value;
    return fmi2Discard;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2GetBooleanStatus", RUN_STATES);
    if (s == fmi2Terminated && value != NULL) {
        *value = fmi2False; /* the model never asks to end the simulation */
        return fmi2OK;
    }
    return fmi2Discard;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2GetStringStatus", RUN_STATES);
    (void)s;
    (void)value;
    return fmi2Discard;
}

/* ------------------------------------------------------------ FMU state */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2GetFMUstate", SG_FMU_STATE_STATES);
    return (fmi2Status)sg_get_state(g, FMUstate, "fmi2GetFMUstate");
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2SetFMUstate", SG_FMU_STATE_STATES | S_ERROR /* recovery: FMI 2.0.x, 3.0 */);
    return (fmi2Status)sg_set_state(g, FMUstate, "fmi2SetFMUstate");
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2FreeFMUstate", SG_ANY_STATE);
    return (fmi2Status)sg_free_state(g, FMUstate, "fmi2FreeFMUstate");
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2SerializedFMUstateSize", SG_ANY_STATE);
    return (fmi2Status)sg_state_size(g, FMUstate, size, "fmi2SerializedFMUstateSize");
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2SerializeFMUstate", SG_ANY_STATE);
    return (fmi2Status)sg_serialize(g, FMUstate, (unsigned char *)serializedState, size, "fmi2SerializeFMUstate");
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate)
{
    sarins_glue *g = (sarins_glue *)c;
    REQUIRE(g, "fmi2DeSerializeFMUstate", SG_ANY_STATE);
    return (fmi2Status)sg_deserialize(g, (const unsigned char *)serializedState, size, FMUstate,
                                      "fmi2DeSerializeFMUstate");
}

/* ------------------------------------------- capabilities this FMU lacks */

static fmi2Status unsupported(fmi2Component c, const char *fn, const char *why)
{
    sarins_glue *g = (sarins_glue *)c;
    if (g == NULL)
        return fmi2Error;
    return (fmi2Status)sg_fail(g, "%s: not supported (%s)", fn, why);
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown[], size_t nUnknown,
                                        const fmi2ValueReference vKnown[], size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    (void)vUnknown; (void)nUnknown; (void)vKnown; (void)nKnown; (void)dvKnown; (void)dvUnknown;
    return unsupported(c, "fmi2GetDirectionalDerivative", "providesDirectionalDerivative is false");
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    (void)vr; (void)nvr; (void)order; (void)value;
    return unsupported(c, "fmi2SetRealInputDerivatives", "canInterpolateInputs is false");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[])
{
    (void)vr; (void)nvr; (void)order; (void)value;
    return unsupported(c, "fmi2GetRealOutputDerivatives", "maxOutputDerivativeOrder is 0");
}
