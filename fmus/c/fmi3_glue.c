/* FMI 3.0 co-simulation in C for the same native models as fmi2_glue.c (fmus/c/<model>/model.c through
 * model.h); the version-independent work (instance, logging, values, checks, FMU state blob) is shared in
 * glue_core.c.
 *
 * Contract, as in FMI 2.0 (fmi2_glue.c), on the FMI 3.0 co-simulation state machine (section 4.2 of the
 * standard; no Event Mode, no clocks, no intermediate update, no early return):
 *   Instantiated -> (EnterConfigurationMode <-> ExitConfigurationMode) -> EnterInitializationMode
 *   -> ExitInitializationMode -> Step Mode (DoStep ...) -> Terminate; Reset from anywhere.
 * - a call out of order returns fmi3Error with a logged message and puts the instance in the error state,
 *   which only fmi3Reset, fmi3FreeInstance or fmi3SetFMUState to a state saved earlier (recovery) leave;
 * - value references, types and the number of values are checked against the model's table; setters check
 *   causality/variability against the state (Configuration Mode: structural parameters only; there are
 *   none unless the model declares some, so it refuses every set);
 * - the independent variable `time` has the value reference one past the model's last one (the model
 *   description says so); fmi3GetFloat64 of it returns the current communication point;
 * - Integer variables are Int32, Real ones Float64; the other FMI 3.0 types (Float32, Int8 .. UInt64,
 *   Binary, Clock) are not used by the models: their getters and setters return fmi3Error with a logged
 *   reason, as do the Model Exchange, Scheduled Execution, event, clock and derivative functions;
 * - bad input gives fmi3Error with a logged reason, never fmi3Fatal, never a crash; a non-finite Float64
 *   output is never returned with fmi3OK;
 * - a step the model discards (fmi3Discard) leaves the instance where only getters, the FMU-state calls,
 *   fmi3Terminate and fmi3Reset are allowed (as FMI 2.0's stepFailed);
 * - FMU state (canGetAndSetFMUState, canSerializeFMUState): the blob of glue_core.c.
 * Memory: fmi3InstantiateCoSimulation allocates the instance; the model allocates in initialize(); after
 * that nothing allocates except the FMU-state calls.  No globals.
 */
#include "smath.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "glue_core.h"

_Static_assert(sizeof(fmi3Int32) == sizeof(int), "fmi3Int32 must be an int");

#define GET_STATES (S_CONFIG | S_INIT | RUN_STATES | S_RECONFIG | S_ERROR)
#define SET_STATES (S_INSTANTIATED | S_INIT | S_STEP_COMPLETE | S_CONFIG | S_RECONFIG)
#define STANDARD "FMI 3.0 section 4.2, co-simulation state machine"

typedef struct {
    sarins_glue core; /* first: a sarins_glue * is a glue3 * */
    fmi3LogMessageCallback logger;
    fmi3InstanceEnvironment env;
} glue3;

static void emit3(const sarins_glue *g, int status, const char *category, const char *text)
{
    const glue3 *g3 = (const glue3 *)(const void *)g;
    if (g3->logger != NULL)
        g3->logger(g3->env, (fmi3Status)status, category, text);
}

/* FMI 3.0 setting rules (the state machine): structural parameters in Configuration Mode only (tunable ones
 * also in Reconfiguration Mode), nothing else there; otherwise as FMI 2.0. */
static int settable3(const sarins_glue *g, const sarins_var *v)
{
    int structural = v->causality == SARINS_STRUCTURAL_PARAMETER;
    if (g->state == S_CONFIG)
        return structural && v->variability != SARINS_CONSTANT;
    if (g->state == S_RECONFIG)
        return structural && v->variability == SARINS_TUNABLE;
    return !structural && sg_settable_default(g, v);
}

static int has_structural(const sarins_table *t)
{
    for (size_t k = 0; k < t->n_vars; k++)
        if (t->vars[k].causality == SARINS_STRUCTURAL_PARAMETER)
            return 1;
    return 0;
}

/* Integers are Int32 except the structural parameters, which are UInt64 (FMI 3.0 array dimensions). */
static int check_int_kind(sarins_glue *g, const char *fn, const fmi3ValueReference vr[], size_t n, int structural)
{
    for (size_t k = 0; k < n; k++) {
        const sarins_var *v = g->by_vr[vr[k]];
        if ((v->causality == SARINS_STRUCTURAL_PARAMETER) != structural) {
            sg_fail(g, "%s: %s (value reference %u) is a%s", fn, v->name, (unsigned)vr[k],
                    structural ? "n Int32, not a UInt64" : " UInt64 (structural parameter), not an Int32");
            return 0;
        }
    }
    return 1;
}

#define check_count(g, fn, vr, nvr, n_values) sg_check_count((g), (fn), (vr), (nvr), (n_values))

/* ------------------------------------------------------------- instances */

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                         fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate)
{
    (void)visible;
    (void)earlyReturnAllowed; /* never returns early */
    (void)requiredIntermediateVariables;
    (void)intermediateUpdate; /* no intermediate update */
    glue3 *g = (glue3 *)(void *)sg_alloc(sizeof(glue3));
    if (g == NULL) {
        if (logMessage != NULL)
            logMessage(instanceEnvironment, fmi3Error, "logStatusError", "fmi3InstantiateCoSimulation: out of memory");
        return NULL;
    }
    g->logger = logMessage;
    g->env = instanceEnvironment;
    g->core.emit = emit3;
    g->core.prefix = "fmi3";
    g->core.standard = STANDARD;
    if (!sg_init(&g->core, instanceName, instantiationToken, loggingOn, "fmi3InstantiateCoSimulation")
        || !sg_set_resources(&g->core, resourcePath, 0)) {
        sg_free(&g->core);
        return NULL;
    }
    g->core.time_vr = (unsigned)g->core.n_vr; /* one past the model's last value reference */
    g->core.arrays_visible = 1;
    const char *why = eventModeUsed ? "eventModeUsed is true but this FMU has no Event Mode (hasEventMode=false)"
                      : nRequiredIntermediateVariables > 0 ? "intermediate variables are required but this FMU "
                                                             "provides no intermediate update"
                                                           : NULL;
    if (why != NULL) {
        sg_log(&g->core, fmi3Error, "fmi3InstantiateCoSimulation: %s", why);
        sg_free(&g->core);
        return NULL;
    }
    return (fmi3Instance)g;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage)
{
    (void)instantiationToken; (void)resourcePath; (void)visible; (void)loggingOn;
    if (logMessage != NULL)
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "fmi3InstantiateModelExchange: this FMU supports co-simulation only");
    (void)instanceName;
    return NULL;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)instanceName; (void)instantiationToken; (void)resourcePath; (void)visible; (void)loggingOn;
    (void)clockUpdate; (void)lockPreemption; (void)unlockPreemption;
    if (logMessage != NULL)
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "fmi3InstantiateScheduledExecution: this FMU supports co-simulation only");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance)
{
    sg_free((sarins_glue *)instance);
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[])
{
    return (fmi3Status)sg_set_debug_logging((sarins_glue *)instance, loggingOn, nCategories, categories,
                                            "fmi3SetDebugLogging");
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3EnterConfigurationMode", S_INSTANTIATED | S_STEP_COMPLETE);
    if (!has_structural(g->table))
        return (fmi3Status)sg_fail(g, "fmi3EnterConfigurationMode: this FMU has no structural parameters");
    g->state = g->state == S_INSTANTIATED ? S_CONFIG : S_RECONFIG;
    return fmi3OK;
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3ExitConfigurationMode", S_CONFIG | S_RECONFIG);
    if (sg_size_arrays(g, "fmi3ExitConfigurationMode") != SARINS_OK)
        return fmi3Error;
    g->state = g->state == S_CONFIG ? S_INSTANTIATED : S_STEP_COMPLETE;
    return fmi3OK;
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3EnterInitializationMode", S_INSTANTIATED);
    (void)toleranceDefined;
    (void)tolerance;
    if (!isfinite(startTime))
        return (fmi3Status)sg_fail(g, "fmi3EnterInitializationMode: start time %g is not finite", startTime);
    if (stopTimeDefined && !(stopTime >= startTime))
        return (fmi3Status)sg_fail(g, "fmi3EnterInitializationMode: stop time %g before start %g", stopTime,
                                   startTime);
    g->ctx.start_time = startTime;
    sg_enter_init(g);
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3ExitInitializationMode", S_INIT);
    return (fmi3Status)sg_exit_init(g, "fmi3ExitInitializationMode");
}

fmi3Status fmi3Terminate(fmi3Instance instance)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3Terminate", S_STEP_COMPLETE | S_STEP_FAILED);
    sg_terminate(g);
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3Reset", SG_ANY_STATE);
    sg_reset(g);
    return fmi3OK;
}

/* --------------------------------------------------------- get and set */

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, fmi3Float64 values[], size_t nValues)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3GetFloat64", GET_STATES);
    if (!check_count(g, "fmi3GetFloat64", valueReferences, nValueReferences, nValues))
        return fmi3Error;
    return (fmi3Status)sg_get_real(g, "fmi3GetFloat64", valueReferences, nValueReferences, values);
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        fmi3Int32 values[], size_t nValues)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3GetInt32", GET_STATES);
    if (!check_count(g, "fmi3GetInt32", valueReferences, nValueReferences, nValues)
        || !sg_check_args(g, "fmi3GetInt32", valueReferences, nValueReferences, values, SARINS_INTEGER, NULL)
        || !check_int_kind(g, "fmi3GetInt32", valueReferences, nValueReferences, 0))
        return fmi3Error;
    return (fmi3Status)sg_get_int(g, "fmi3GetInt32", valueReferences, nValueReferences, values);
}

fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, fmi3Boolean values[], size_t nValues)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3GetBoolean", GET_STATES);
    if (!check_count(g, "fmi3GetBoolean", valueReferences, nValueReferences, nValues)
        || !sg_check_args(g, "fmi3GetBoolean", valueReferences, nValueReferences, values, SARINS_BOOLEAN, NULL))
        return fmi3Error;
    for (size_t k = 0; k < nValueReferences; k++)
        values[k] = g->ctx.b[g->by_vr[valueReferences[k]]->slot] ? fmi3True : fmi3False;
    return fmi3OK;
}

fmi3Status fmi3GetString(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, fmi3String values[], size_t nValues)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3GetString", GET_STATES);
    if (!check_count(g, "fmi3GetString", valueReferences, nValueReferences, nValues))
        return fmi3Error;
    return (fmi3Status)sg_get_string(g, "fmi3GetString", valueReferences, nValueReferences, values);
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, const fmi3Float64 values[], size_t nValues)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3SetFloat64", SET_STATES);
    if (!check_count(g, "fmi3SetFloat64", valueReferences, nValueReferences, nValues))
        return fmi3Error;
    return (fmi3Status)sg_set_real(g, "fmi3SetFloat64", valueReferences, nValueReferences, values, settable3);
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        const fmi3Int32 values[], size_t nValues)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3SetInt32", SET_STATES);
    if (!check_count(g, "fmi3SetInt32", valueReferences, nValueReferences, nValues)
        || !sg_check_args(g, "fmi3SetInt32", valueReferences, nValueReferences, values, SARINS_INTEGER, NULL)
        || !check_int_kind(g, "fmi3SetInt32", valueReferences, nValueReferences, 0))
        return fmi3Error;
    return (fmi3Status)sg_set_int(g, "fmi3SetInt32", valueReferences, nValueReferences, values, settable3);
}

fmi3Status fmi3GetUInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, fmi3UInt64 values[], size_t nValues)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3GetUInt64", GET_STATES);
    if (!check_count(g, "fmi3GetUInt64", valueReferences, nValueReferences, nValues)
        || !sg_check_args(g, "fmi3GetUInt64", valueReferences, nValueReferences, values, SARINS_INTEGER, NULL)
        || !check_int_kind(g, "fmi3GetUInt64", valueReferences, nValueReferences, 1))
        return fmi3Error;
    for (size_t k = 0; k < nValueReferences; k++)
        values[k] = (fmi3UInt64)g->ctx.i[g->by_vr[valueReferences[k]]->slot];
    return fmi3OK;
}

fmi3Status fmi3SetUInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, const fmi3UInt64 values[], size_t nValues)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3SetUInt64", SET_STATES);
    if (!check_count(g, "fmi3SetUInt64", valueReferences, nValueReferences, nValues)
        || !sg_check_args(g, "fmi3SetUInt64", valueReferences, nValueReferences, values, SARINS_INTEGER, settable3)
        || !check_int_kind(g, "fmi3SetUInt64", valueReferences, nValueReferences, 1))
        return fmi3Error;
    for (size_t k = 0; k < nValueReferences; k++)
        if (values[k] < 1 || values[k] > (fmi3UInt64)g->table->max_dim)
            return (fmi3Status)sg_fail(g, "fmi3SetUInt64: %s = %llu must be in 1 .. %d",
                                       g->by_vr[valueReferences[k]]->name, (unsigned long long)values[k],
                                       g->table->max_dim);
    for (size_t k = 0; k < nValueReferences; k++)
        g->ctx.i[g->by_vr[valueReferences[k]]->slot] = (int)values[k];
    return fmi3OK;
}

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, const fmi3Boolean values[], size_t nValues)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3SetBoolean", SET_STATES);
    if (!check_count(g, "fmi3SetBoolean", valueReferences, nValueReferences, nValues)
        || !sg_check_args(g, "fmi3SetBoolean", valueReferences, nValueReferences, values, SARINS_BOOLEAN, settable3))
        return fmi3Error;
    for (size_t k = 0; k < nValueReferences; k++) {
        g->ctx.b[g->by_vr[valueReferences[k]]->slot] = values[k] ? 1 : 0;
        g->ctx.set[g->by_vr[valueReferences[k]] - g->table->vars] = 1; /* its row = its vr (native_fmu.py) */
    }
    return fmi3OK;
}

fmi3Status fmi3SetString(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, const fmi3String values[], size_t nValues)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3SetString", SET_STATES);
    if (!check_count(g, "fmi3SetString", valueReferences, nValueReferences, nValues))
        return fmi3Error;
    return (fmi3Status)sg_set_string(g, "fmi3SetString", valueReferences, nValueReferences, values, settable3);
}

/* ---------------------------------------------------------------- step */

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn,
                      fmi3Float64 *lastSuccessfulTime)
{
    sarins_glue *g = (sarins_glue *)instance;
    (void)noSetFMUStatePriorToCurrentPoint;
    SG_REQUIRE(g, "fmi3DoStep", S_STEP_COMPLETE);
    if (eventHandlingNeeded == NULL || terminateSimulation == NULL || earlyReturn == NULL
        || lastSuccessfulTime == NULL)
        return (fmi3Status)sg_fail(g, "fmi3DoStep: eventHandlingNeeded, terminateSimulation, earlyReturn and "
                                   "lastSuccessfulTime must not be NULL");
    *eventHandlingNeeded = fmi3False;
    *terminateSimulation = fmi3False;
    *earlyReturn = fmi3False;
    int st = sg_do_step(g, currentCommunicationPoint, communicationStepSize, "fmi3DoStep");
    *lastSuccessfulTime = sg_time(g);
    return (fmi3Status)st;
}

/* ------------------------------------------------------------ FMU state */

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3GetFMUState", SG_FMU_STATE_STATES);
    return (fmi3Status)sg_get_state(g, FMUState, "fmi3GetFMUState");
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3SetFMUState", SG_FMU_STATE_STATES | S_ERROR /* recovery: FMI 2.0.x, 3.0 */);
    return (fmi3Status)sg_set_state(g, FMUState, "fmi3SetFMUState");
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3FreeFMUState", SG_ANY_STATE);
    return (fmi3Status)sg_free_state(g, FMUState, "fmi3FreeFMUState");
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3SerializedFMUStateSize", SG_ANY_STATE);
    return (fmi3Status)sg_state_size(g, FMUState, size, "fmi3SerializedFMUStateSize");
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                 size_t size)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3SerializeFMUState", SG_ANY_STATE);
    return (fmi3Status)sg_serialize(g, FMUState, serializedState, size, "fmi3SerializeFMUState");
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState)
{
    sarins_glue *g = (sarins_glue *)instance;
    SG_REQUIRE(g, "fmi3DeserializeFMUState", SG_ANY_STATE);
    return (fmi3Status)sg_deserialize(g, serializedState, size, FMUState, "fmi3DeserializeFMUState");
}

/* ------------------------------------------- capabilities this FMU lacks */

static fmi3Status unsupported(fmi3Instance instance, const char *fn, const char *why)
{
    sarins_glue *g = (sarins_glue *)instance;
    if (g == NULL)
        return fmi3Error;
    return (fmi3Status)sg_fail(g, "%s: not supported (%s)", fn, why);
}

#define NO_TYPE_GET(T, t)                                                                                    \
    fmi3Status fmi3Get##T(fmi3Instance instance, const fmi3ValueReference valueReferences[],                 \
                          size_t nValueReferences, t values[], size_t nValues)                               \
    {                                                                                                        \
        (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;                          \
        return unsupported(instance, "fmi3Get" #T, "this FMU has no " #T " variables");                      \
    }
#define NO_TYPE_SET(T, t)                                                                                    \
    fmi3Status fmi3Set##T(fmi3Instance instance, const fmi3ValueReference valueReferences[],                 \
                          size_t nValueReferences, const t values[], size_t nValues)                         \
    {                                                                                                        \
        (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues;                          \
        return unsupported(instance, "fmi3Set" #T, "this FMU has no " #T " variables");                      \
    }
#define NO_TYPE(T, t) NO_TYPE_GET(T, t) NO_TYPE_SET(T, t)

NO_TYPE(Float32, fmi3Float32)
NO_TYPE(Int8, fmi3Int8)
NO_TYPE(UInt8, fmi3UInt8)
NO_TYPE(Int16, fmi3Int16)
NO_TYPE(UInt16, fmi3UInt16)
NO_TYPE(UInt32, fmi3UInt32)
NO_TYPE(Int64, fmi3Int64)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues)
{
    (void)valueReferences; (void)nValueReferences; (void)valueSizes; (void)values; (void)nValues;
    return unsupported(instance, "fmi3GetBinary", "this FMU has no Binary variables");
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues)
{
    (void)valueReferences; (void)nValueReferences; (void)valueSizes; (void)values; (void)nValues;
    return unsupported(instance, "fmi3SetBinary", "this FMU has no Binary variables");
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        fmi3Clock values[])
{
    (void)valueReferences; (void)nValueReferences; (void)values;
    return unsupported(instance, "fmi3GetClock", "this FMU has no clocks");
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        const fmi3Clock values[])
{
    (void)valueReferences; (void)nValueReferences; (void)values;
    return unsupported(instance, "fmi3SetClock", "this FMU has no clocks");
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[])
{
    (void)valueReferences; (void)nValueReferences; (void)intervals; (void)qualifiers;
    return unsupported(instance, "fmi3GetIntervalDecimal", "this FMU has no clocks");
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[])
{
    (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions; (void)qualifiers;
    return unsupported(instance, "fmi3GetIntervalFraction", "this FMU has no clocks");
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, fmi3Float64 shifts[])
{
    (void)valueReferences; (void)nValueReferences; (void)shifts;
    return unsupported(instance, "fmi3GetShiftDecimal", "this FMU has no clocks");
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[])
{
    (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions;
    return unsupported(instance, "fmi3GetShiftFraction", "this FMU has no clocks");
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, const fmi3Float64 intervals[])
{
    (void)valueReferences; (void)nValueReferences; (void)intervals;
    return unsupported(instance, "fmi3SetIntervalDecimal", "this FMU has no clocks");
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[])
{
    (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions;
    return unsupported(instance, "fmi3SetIntervalFraction", "this FMU has no clocks");
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, const fmi3Float64 shifts[])
{
    (void)valueReferences; (void)nValueReferences; (void)shifts;
    return unsupported(instance, "fmi3SetShiftDecimal", "this FMU has no clocks");
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
{
    (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions;
    return unsupported(instance, "fmi3SetShiftFraction", "this FMU has no clocks");
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance)
{
    return unsupported(instance, "fmi3EnterEventMode", "hasEventMode is false");
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance)
{
    return unsupported(instance, "fmi3EvaluateDiscreteStates", "this FMU has no Event Mode");
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation, fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged, fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime)
{
    (void)discreteStatesNeedUpdate; (void)terminateSimulation; (void)nominalsOfContinuousStatesChanged;
    (void)valuesOfContinuousStatesChanged; (void)nextEventTimeDefined; (void)nextEventTime;
    return unsupported(instance, "fmi3UpdateDiscreteStates", "this FMU has no Event Mode");
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance)
{
    return unsupported(instance, "fmi3EnterStepMode", "this FMU has no Event Mode");
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference,
                                               size_t *nDependencies)
{
    (void)valueReference; (void)nDependencies;
    return unsupported(instance, "fmi3GetNumberOfVariableDependencies", "providesPerElementDependencies is false");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[], fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[], fmi3DependencyKind dependencyKinds[],
                                       size_t nDependencies)
{
    (void)dependent; (void)elementIndicesOfDependent; (void)independents; (void)elementIndicesOfIndependents;
    (void)dependencyKinds; (void)nDependencies;
    return unsupported(instance, "fmi3GetVariableDependencies", "providesPerElementDependencies is false");
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns,
                                        const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[],
                                        size_t nSensitivity)
{
    (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed; (void)sensitivity;
    (void)nSensitivity;
    return unsupported(instance, "fmi3GetDirectionalDerivative", "providesDirectionalDerivatives is false");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                    const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                    size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity)
{
    (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed; (void)sensitivity;
    (void)nSensitivity;
    return unsupported(instance, "fmi3GetAdjointDerivative", "providesAdjointDerivatives is false");
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues)
{
    (void)valueReferences; (void)nValueReferences; (void)orders; (void)values; (void)nValues;
    return unsupported(instance, "fmi3GetOutputDerivatives", "maxOutputDerivativeOrder is 0");
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime)
{
    (void)clockReference; (void)activationTime;
    return unsupported(instance, "fmi3ActivateModelPartition", "co-simulation only");
}

/* Model Exchange (co-simulation only) */
fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance)
{
    return unsupported(instance, "fmi3EnterContinuousTimeMode", "co-simulation only");
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint; (void)enterEventMode; (void)terminateSimulation;
    return unsupported(instance, "fmi3CompletedIntegratorStep", "co-simulation only");
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time)
{
    (void)time;
    return unsupported(instance, "fmi3SetTime", "co-simulation only");
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    (void)continuousStates; (void)nContinuousStates;
    return unsupported(instance, "fmi3SetContinuousStates", "co-simulation only");
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates)
{
    (void)derivatives; (void)nContinuousStates;
    return unsupported(instance, "fmi3GetContinuousStateDerivatives", "co-simulation only");
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t nEventIndicators)
{
    (void)eventIndicators; (void)nEventIndicators;
    return unsupported(instance, "fmi3GetEventIndicators", "co-simulation only");
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[], size_t nContinuousStates)
{
    (void)continuousStates; (void)nContinuousStates;
    return unsupported(instance, "fmi3GetContinuousStates", "co-simulation only");
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates)
{
    (void)nominals; (void)nContinuousStates;
    return unsupported(instance, "fmi3GetNominalsOfContinuousStates", "co-simulation only");
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators)
{
    (void)nEventIndicators;
    return unsupported(instance, "fmi3GetNumberOfEventIndicators", "co-simulation only");
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates)
{
    (void)nContinuousStates;
    return unsupported(instance, "fmi3GetNumberOfContinuousStates", "co-simulation only");
}
