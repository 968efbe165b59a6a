/* FMI 3.0 co-simulation glue of the test fixtures (Burst3, Sum3): written for the master's
 * tests, it implements the calls a fixed-step importer makes and refuses the rest.
 *
 * States: Instantiated -> (Configuration Mode <-> Instantiated) -> Initialization Mode ->
 * Step Mode -> Terminated.  Structural parameters can be set in Configuration Mode only,
 * parameters in Instantiated and Initialization Mode, inputs in those and Step Mode.
 * Every refused call logs its reason and returns fmi3Error.  Event mode, clocks,
 * intermediate update, FMU states and derivatives are not provided.
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixture3.h"

typedef enum { S_INSTANTIATED, S_CONFIGURATION, S_INITIALIZATION, S_STEP, S_TERMINATED } State;

typedef struct {
    State state;
    fmi3Boolean logging;
    fmi3InstanceEnvironment environment;
    fmi3LogMessageCallback log;
    char name[64];
    void *model;
} Instance;

static fmi3Status fail(Instance *c, const char *format, ...)
{
    if (c != NULL && c->logging && c->log != NULL) {
        char text[256];
        va_list args;
        va_start(args, format);
        vsnprintf(text, sizeof text, format, args);
        va_end(args);
        c->log(c->environment, fmi3Error, "logStatusError", text);
    }
    return fmi3Error;
}

static const VarInfo *find(fmi3ValueReference vr)
{
    for (size_t i = 0; i < MODEL_VARIABLE_COUNT; i++)
        if (MODEL_VARIABLES[i].vr == vr) return &MODEL_VARIABLES[i];
    return NULL;
}

static size_t type_size(VarType type)
{
    switch (type) {
    case T_FLOAT32: return sizeof(fmi3Float32);
    case T_FLOAT64: return sizeof(fmi3Float64);
    case T_STRING: return sizeof(fmi3String);
    case T_INT32: return sizeof(fmi3Int32);
    case T_UINT64: return sizeof(fmi3UInt64);
    default: return sizeof(fmi3Boolean);
    }
}

static size_t elements(const Instance *c, const VarInfo *v)
{
    size_t rows = v->dim == 0 ? 1 : v->dim > 0 ? (size_t)v->dim : model_dim(c->model);
    return v->columns > 0 ? rows * (size_t)v->columns : rows;
}

static int settable(State state, VarRole role)
{
    switch (role) {
    case R_STRUCTURAL: return state == S_CONFIGURATION;
    case R_PARAMETER: return state == S_INSTANTIATED || state == S_INITIALIZATION;
    case R_INPUT: return state == S_INSTANTIATED || state == S_INITIALIZATION || state == S_STEP;
    default: return 0;
    }
}

static int gettable(State state, VarRole role)
{
    return state == S_INITIALIZATION || state == S_STEP || state == S_TERMINATED
           || (role == R_STRUCTURAL && state == S_CONFIGURATION);
}

/* Copy nValues values of variables vrs between values and the model, in order. */
static fmi3Status transfer(Instance *c, const char *call, VarType type, const fmi3ValueReference vrs[],
                           size_t nvr, void *values, size_t nValues, int set)
{
    size_t size = type_size(type), done = 0;
    if (c == NULL) return fmi3Error;
    if (nvr > 0 && (vrs == NULL || values == NULL)) return fail(c, "%s: null array", call);
    for (size_t i = 0; i < nvr; i++) {
        const VarInfo *v = find(vrs[i]);
        if (v == NULL || v->type != type)
            return fail(c, "%s: no variable of this type has value reference %u", call, vrs[i]);
        if (set ? !settable(c->state, v->role) : !gettable(c->state, v->role))
            return fail(c, "%s: value reference %u cannot be %s in this state", call, vrs[i],
                        set ? "set" : "read");
        size_t count = elements(c, v);
        if (done + count > nValues)
            return fail(c, "%s: nValues %zu is too small for the variables' values", call, nValues);
        char *field = (char *)c->model + v->offset;
        char *outside = (char *)values + done * size;
        if (type == T_STRING) { /* scalar: a pointer outside, a buffer in the model */
            if (!set) {
                ((fmi3String *)values)[done] = field;
            } else {
                fmi3String text = ((const fmi3String *)values)[done];
                if (text == NULL || strlen(text) >= FIXTURE_STRING_MAX)
                    return fail(c, "%s: value reference %u takes a string of at most %d bytes", call,
                                vrs[i], FIXTURE_STRING_MAX - 1);
                memcpy(field, text, strlen(text) + 1);
            }
        } else if (!set) {
            memcpy(outside, field, count * size);
        } else if (v->role == R_STRUCTURAL) {
            char previous[sizeof(fmi3UInt64)];
            memcpy(previous, field, size);
            memcpy(field, outside, size);
            const char *reason = model_check(c->model);
            if (reason != NULL) {
                memcpy(field, previous, size);
                return fail(c, "%s: %s", call, reason);
            }
        } else {
            memcpy(field, outside, count * size);
        }
        done += count;
    }
    if (done != nValues)
        return fail(c, "%s: nValues is %zu but the variables hold %zu values", call, nValues, done);
    return fmi3OK;
}

static fmi3Status none_of_type(Instance *c, const char *call, size_t nvr)
{
    return nvr == 0 ? fmi3OK : fail(c, "%s: the FMU has no variable of this type", call);
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[])
{
    Instance *c = instance;
    (void)nCategories;
    (void)categories;
    if (c == NULL) return fmi3Error;
    c->logging = loggingOn;
    return fmi3OK;
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible,
                                         fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
                                         fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate)
{
    Instance probe = {S_INSTANTIATED, loggingOn, instanceEnvironment, logMessage, "", NULL};
    (void)resourcePath;
    (void)visible;
    (void)requiredIntermediateVariables;
    (void)intermediateUpdate;
    if (instantiationToken == NULL || strcmp(instantiationToken, MODEL_TOKEN) != 0) {
        fail(&probe, "instantiation token does not match the model description");
        return NULL;
    }
    if (eventModeUsed || earlyReturnAllowed || nRequiredIntermediateVariables > 0) {
        fail(&probe, "event mode, early return and intermediate update are not provided");
        return NULL;
    }
    Instance *c = calloc(1, sizeof *c);
    void *model = calloc(1, model_size());
    if (c == NULL || model == NULL) {
        free(c);
        free(model);
        fail(&probe, "out of memory");
        return NULL;
    }
    *c = probe;
    c->model = model;
    snprintf(c->name, sizeof c->name, "%s", instanceName != NULL ? instanceName : "");
    model_defaults(c->model);
    return c;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage)
{
    Instance probe = {S_INSTANTIATED, loggingOn, instanceEnvironment, logMessage, "", NULL};
    (void)instanceName;
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    fail(&probe, "Model Exchange is not provided");
    return NULL;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible,
                                               fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage,
                                               fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption)
{
    Instance probe = {S_INSTANTIATED, loggingOn, instanceEnvironment, logMessage, "", NULL};
    (void)instanceName;
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)clockUpdate;
    (void)lockPreemption;
    (void)unlockPreemption;
    fail(&probe, "Scheduled Execution is not provided");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance)
{
    Instance *c = instance;
    if (c == NULL) return;
    free(c->model);
    free(c);
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance)
{
    Instance *c = instance;
    if (c == NULL) return fmi3Error;
    if (c->state != S_INSTANTIATED) return fail(c, "fmi3EnterConfigurationMode: not in Instantiated");
    c->state = S_CONFIGURATION;
    return fmi3OK;
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance)
{
    Instance *c = instance;
    if (c == NULL) return fmi3Error;
    if (c->state != S_CONFIGURATION) return fail(c, "fmi3ExitConfigurationMode: not in Configuration Mode");
    c->state = S_INSTANTIATED;
    return fmi3OK;
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    Instance *c = instance;
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (c == NULL) return fmi3Error;
    if (c->state != S_INSTANTIATED) return fail(c, "fmi3EnterInitializationMode: not in Instantiated");
    const char *reason = model_check(c->model);
    if (reason != NULL) return fail(c, "fmi3EnterInitializationMode: %s", reason);
    c->state = S_INITIALIZATION;
    model_start(c->model, startTime);
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    Instance *c = instance;
    if (c == NULL) return fmi3Error;
    if (c->state != S_INITIALIZATION) return fail(c, "fmi3ExitInitializationMode: not in Initialization Mode");
    c->state = S_STEP;
    return fmi3OK;
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime)
{
    Instance *c = instance;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (c == NULL) return fmi3Error;
    if (c->state != S_STEP) return fail(c, "fmi3DoStep: not in Step Mode");
    if (!(communicationStepSize > 0.0)) return fail(c, "fmi3DoStep: the step must be positive");
    if (eventHandlingNeeded == NULL || terminateSimulation == NULL || earlyReturn == NULL
        || lastSuccessfulTime == NULL)
        return fail(c, "fmi3DoStep: null output argument");
    *terminateSimulation = model_step(c->model, currentCommunicationPoint, communicationStepSize)
                           ? fmi3True : fmi3False;
    *eventHandlingNeeded = fmi3False;
    *earlyReturn = fmi3False;
    *lastSuccessfulTime = currentCommunicationPoint + communicationStepSize;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance)
{
    Instance *c = instance;
    if (c == NULL) return fmi3Error;
    if (c->state != S_STEP && c->state != S_INITIALIZATION) return fail(c, "fmi3Terminate: not running");
    c->state = S_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance)
{
    Instance *c = instance;
    if (c == NULL) return fmi3Error;
    memset(c->model, 0, model_size());
    model_defaults(c->model);
    c->state = S_INSTANTIATED;
    return fmi3OK;
}

#define SUPPORTED(Type, ctype, tag)                                                                \
    fmi3Status fmi3Get##Type(fmi3Instance instance, const fmi3ValueReference valueReferences[],   \
                             size_t nValueReferences, ctype values[], size_t nValues)            \
    {                                                                                              \
        return transfer(instance, "fmi3Get" #Type, tag, valueReferences, nValueReferences, values, \
                        nValues, 0);                                                               \
    }                                                                                              \
    fmi3Status fmi3Set##Type(fmi3Instance instance, const fmi3ValueReference valueReferences[],   \
                             size_t nValueReferences, const ctype values[], size_t nValues)      \
    {                                                                                              \
        return transfer(instance, "fmi3Set" #Type, tag, valueReferences, nValueReferences,         \
                        (void *)values, nValues, 1);                                               \
    }

SUPPORTED(Float64, fmi3Float64, T_FLOAT64)
SUPPORTED(Int32, fmi3Int32, T_INT32)
SUPPORTED(UInt64, fmi3UInt64, T_UINT64)
SUPPORTED(Boolean, fmi3Boolean, T_BOOLEAN)
SUPPORTED(Float32, fmi3Float32, T_FLOAT32)
SUPPORTED(String, fmi3String, T_STRING)

#define ABSENT(Type, ctype)                                                                        \
    fmi3Status fmi3Get##Type(fmi3Instance instance, const fmi3ValueReference valueReferences[],   \
                             size_t nValueReferences, ctype values[], size_t nValues)            \
    {                                                                                              \
        (void)valueReferences;                                                                     \
        (void)values;                                                                              \
        (void)nValues;                                                                             \
        return none_of_type(instance, "fmi3Get" #Type, nValueReferences);                          \
    }                                                                                              \
    fmi3Status fmi3Set##Type(fmi3Instance instance, const fmi3ValueReference valueReferences[],   \
                             size_t nValueReferences, const ctype values[], size_t nValues)      \
    {                                                                                              \
        (void)valueReferences;                                                                     \
        (void)values;                                                                              \
        (void)nValues;                                                                             \
        return none_of_type(instance, "fmi3Set" #Type, nValueReferences);                          \
    }

ABSENT(Int8, fmi3Int8)
ABSENT(UInt8, fmi3UInt8)
ABSENT(Int16, fmi3Int16)
ABSENT(UInt16, fmi3UInt16)
ABSENT(UInt32, fmi3UInt32)
ABSENT(Int64, fmi3Int64)

/* The calls below belong to features this FMU does not provide: each refuses. */
#pragma GCC diagnostic ignored "-Wunused-parameter"
#define REFUSE(name) { return fail(instance, #name ": not provided by this FMU"); }

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, size_t valueSizes[], fmi3Binary values[],
                         size_t nValues) REFUSE(fmi3GetBinary)
fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, const size_t valueSizes[],
                         const fmi3Binary values[], size_t nValues) REFUSE(fmi3SetBinary)
fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Clock values[]) REFUSE(fmi3GetClock)
fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Clock values[]) REFUSE(fmi3SetClock)
fmi3Status fmi3EnterEventMode(fmi3Instance instance) REFUSE(fmi3EnterEventMode)
fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference,
                                               size_t *nDependencies) REFUSE(fmi3GetNumberOfVariableDependencies)
fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[], fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[],
                                       size_t nDependencies) REFUSE(fmi3GetVariableDependencies)
fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) REFUSE(fmi3GetFMUState)
fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) REFUSE(fmi3SetFMUState)
fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) REFUSE(fmi3FreeFMUState)
fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState,
                                      size_t *size) REFUSE(fmi3SerializedFMUStateSize)
fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                 size_t size) REFUSE(fmi3SerializeFMUState)
fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState) REFUSE(fmi3DeserializeFMUState)
fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns,
                                        const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[],
                                        size_t nSensitivity) REFUSE(fmi3GetDirectionalDerivative)
fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns,
                                    const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[],
                                    size_t nSensitivity) REFUSE(fmi3GetAdjointDerivative)
fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[]) REFUSE(fmi3GetIntervalDecimal)
fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[]) REFUSE(fmi3GetIntervalFraction)
fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, fmi3Float64 shifts[]) REFUSE(fmi3GetShiftDecimal)
fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, fmi3UInt64 counters[],
                                fmi3UInt64 resolutions[]) REFUSE(fmi3GetShiftFraction)
fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, const fmi3Float64 intervals[]) REFUSE(fmi3SetIntervalDecimal)
fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[]) REFUSE(fmi3SetIntervalFraction)
fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, const fmi3Float64 shifts[]) REFUSE(fmi3SetShiftDecimal)
fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, const fmi3UInt64 counters[],
                                const fmi3UInt64 resolutions[]) REFUSE(fmi3SetShiftFraction)
fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) REFUSE(fmi3EvaluateDiscreteStates)
fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime) REFUSE(fmi3UpdateDiscreteStates)
fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) REFUSE(fmi3EnterContinuousTimeMode)
fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode,
                                       fmi3Boolean *terminateSimulation) REFUSE(fmi3CompletedIntegratorStep)
fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) REFUSE(fmi3SetTime)
fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) REFUSE(fmi3SetContinuousStates)
fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates) REFUSE(fmi3GetContinuousStateDerivatives)
fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[],
                                  size_t nEventIndicators) REFUSE(fmi3GetEventIndicators)
fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) REFUSE(fmi3GetContinuousStates)
fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates) REFUSE(fmi3GetNominalsOfContinuousStates)
fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance,
                                          size_t *nEventIndicators) REFUSE(fmi3GetNumberOfEventIndicators)
fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance,
                                           size_t *nContinuousStates) REFUSE(fmi3GetNumberOfContinuousStates)
fmi3Status fmi3EnterStepMode(fmi3Instance instance) REFUSE(fmi3EnterStepMode)
fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues) REFUSE(fmi3GetOutputDerivatives)
fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) REFUSE(fmi3ActivateModelPartition)
