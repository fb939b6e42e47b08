/*
 * The 34 functions of FMI 2.0 Co-Simulation over a model described by `MODEL` (fmu_common.h).
 * Unsupported functions (directional derivatives, input/output derivatives, cancelling a step)
 * log and return fmi2Error. Every fmi2Error moves the instance to PHASE_ERROR, where only the
 * getters, fmi2Reset, fmi2SetDebugLogging, the FMU state functions and fmi2FreeInstance remain
 * legal; fmi2Fatal leaves only fmi2FreeInstance.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "fmu_common.h"

/* ------------------------------------------------------------------------------------------ */
/* Which call is legal in which phase (FMI 2.0 standard, section 4.2.4, without the states
 * that need asynchronous steps). */

#define ALL_BUT_FATAL                                                                     \
    (PHASE_INSTANTIATED | PHASE_INITIALIZATION | PHASE_STEP_COMPLETE | PHASE_STEP_FAILED | \
     PHASE_TERMINATED | PHASE_ERROR)
#define MASK_SetDebugLogging ALL_BUT_FATAL
#define MASK_SetupExperiment PHASE_INSTANTIATED
#define MASK_EnterInitializationMode PHASE_INSTANTIATED
#define MASK_ExitInitializationMode PHASE_INITIALIZATION
#define MASK_Terminate (PHASE_STEP_COMPLETE | PHASE_STEP_FAILED)
#define MASK_Reset ALL_BUT_FATAL
#define MASK_Get \
    (PHASE_INITIALIZATION | PHASE_STEP_COMPLETE | PHASE_STEP_FAILED | PHASE_TERMINATED | PHASE_ERROR)
#define MASK_Set (PHASE_INSTANTIATED | PHASE_INITIALIZATION | PHASE_STEP_COMPLETE)
#define MASK_State ALL_BUT_FATAL
#define MASK_GetDirectionalDerivative MASK_Get
#define MASK_SetRealInputDerivatives MASK_Set
#define MASK_GetRealOutputDerivatives \
    (PHASE_STEP_COMPLETE | PHASE_STEP_FAILED | PHASE_TERMINATED | PHASE_ERROR)
#define MASK_DoStep PHASE_STEP_COMPLETE
#define MASK_CancelStep 0 /* only after fmi2Pending, which this layer never returns */
#define MASK_GetStatus (PHASE_STEP_COMPLETE | PHASE_STEP_FAILED | PHASE_TERMINATED)

static const char *phase_name(Phase phase) {
    switch (phase) {
    case PHASE_INSTANTIATED: return "instantiated";
    case PHASE_INITIALIZATION: return "initialization mode";
    case PHASE_STEP_COMPLETE: return "step complete";
    case PHASE_STEP_FAILED: return "step failed (the FMU ended the simulation)";
    case PHASE_TERMINATED: return "terminated";
    case PHASE_ERROR: return "error";
    case PHASE_FATAL: return "fatal";
    }
    return "?";
}

/* The status a function returns, with the phase change it implies. */
static fmi2Status finish(Instance *inst, fmi2Status status) {
    if (status == fmi2Error) inst->phase = PHASE_ERROR;
    if (status == fmi2Fatal) inst->phase = PHASE_FATAL;
    return status;
}

/* Declares `inst` and returns fmi2Error from the calling function when c is NULL or the call is
 * illegal in the current phase. */
#define BEGIN(function)                                                                    \
    Instance *inst = (Instance *)c;                                                        \
    if (inst == NULL) return fmi2Error;                                                    \
    if (!(inst->phase & (MASK_##function))) {                                              \
        LOG_ERROR(inst, "fmi2%s: illegal call in phase '%s'", #function,                   \
                  phase_name(inst->phase));                                                \
        return inst->phase == PHASE_FATAL ? fmi2Fatal : finish(inst, fmi2Error);           \
    }

#define REQUIRE_NOT_NULL(function, pointer)                                                \
    if ((pointer) == NULL) {                                                               \
        LOG_ERROR(inst, "fmi2%s: argument '%s' must not be NULL", #function, #pointer);   \
        return finish(inst, fmi2Error);                                                    \
    }

/* ------------------------------------------------------------------------------------------ */
/* Logging, time, resources. */

static void emit(const fmi2CallbackFunctions *cb, const char *name, fmi2Status status,
                 const char *category, const char *format, va_list args) {
    char message[4096];
    vsnprintf(message, sizeof message, format, args);
    cb->logger(cb->componentEnvironment, name, status, category, "%s", message);
}

void fmu_log(Instance *inst, fmi2Status status, const char *category, const char *format, ...) {
    va_list args;
    if (inst == NULL) return;
    if (!inst->logging_on && status == fmi2OK) return;
    va_start(args, format);
    emit(&inst->cb, inst->name, status, category, format, args);
    va_end(args);
}

/* Logs an error before an instance exists. */
static void log_instantiate_error(const fmi2CallbackFunctions *cb, const char *name,
                                  const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static void log_instantiate_error(const fmi2CallbackFunctions *cb, const char *name,
                                  const char *format, ...) {
    va_list args;
    va_start(args, format);
    emit(cb, name ? name : "?", fmi2Error, "logStatusError", format, args);
    va_end(args);
}

int fmu_time_close(double a, double b) {
    double scale = fabs(a) > fabs(b) ? fabs(a) : fabs(b);
    if (scale < 1.0) scale = 1.0;
    return fabs(a - b) <= TIME_TOLERANCE * scale;
}

static int hex_value(char ch) {
    if (ch >= '0' && ch <= '9') return ch - '0';
    if (ch >= 'a' && ch <= 'f') return ch - 'a' + 10;
    if (ch >= 'A' && ch <= 'F') return ch - 'A' + 10;
    return -1;
}

/* The path of a file URI: file:///p, file://localhost/p and file:/p, percent-decoded, without a
 * trailing slash. NULL when the URI is not a local file URI. */
static char *decode_file_uri(const fmi2CallbackFunctions *cb, const char *uri) {
    const char *p;
    char *path;
    size_t n = 0;
    if (uri == NULL || strncmp(uri, "file:", 5) != 0) return NULL;
    p = uri + 5;
    if (strncmp(p, "//", 2) == 0) {
        p += 2;
        if (strncmp(p, "localhost", 9) == 0) p += 9;
    }
    if (*p != '/') return NULL;
    path = (char *)cb->allocateMemory(strlen(p) + 1, 1);
    if (path == NULL) return NULL;
    while (*p != '\0') {
        if (p[0] == '%' && hex_value(p[1]) >= 0 && hex_value(p[2]) >= 0) {
            path[n++] = (char)(hex_value(p[1]) * 16 + hex_value(p[2]));
            p += 3;
        } else {
            path[n++] = *p++;
        }
    }
    while (n > 1 && path[n - 1] == '/') n--;
    path[n] = '\0';
    return path;
}

int fmu_resource_path(Instance *inst, const char *relative, char *out, size_t capacity) {
    int written;
    if (relative[0] == '/') {
        written = snprintf(out, capacity, "%s", relative);
    } else if (inst->resource_dir == NULL) {
        LOG_ERROR(inst, "cannot resolve '%s': the importer gave no file URI for the resources",
                  relative);
        return -1;
    } else {
        written = snprintf(out, capacity, "%s/%s", inst->resource_dir, relative);
    }
    if (written < 0 || (size_t)written >= capacity) {
        LOG_ERROR(inst, "the path of '%s' is too long", relative);
        return -1;
    }
    return 0;
}

/* ------------------------------------------------------------------------------------------ */
/* Instances. */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

static void reset_values(Instance *inst) {
    inst->phase = PHASE_INSTANTIATED;
    inst->start_time = 0.0;
    inst->stop_time = INFINITY;
    inst->time = 0.0;
    inst->terminated = fmi2False;
    MODEL.set_defaults(inst->data);
    MODEL.calculate(inst);
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn) {
    Instance *inst;
    (void)visible;
    if (functions == NULL || functions->logger == NULL) return NULL;
    if (functions->allocateMemory == NULL || functions->freeMemory == NULL) {
        log_instantiate_error(functions, instanceName,
                              "allocateMemory and freeMemory callbacks are required");
        return NULL;
    }
    if (instanceName == NULL || instanceName[0] == '\0') {
        log_instantiate_error(functions, instanceName, "missing instance name");
        return NULL;
    }
    if (fmuType != fmi2CoSimulation) {
        log_instantiate_error(functions, instanceName,
                              "only Co-Simulation is supported (fmuType = %d)", (int)fmuType);
        return NULL;
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, MODEL.guid) != 0) {
        log_instantiate_error(functions, instanceName, "wrong GUID %s, expected %s",
                              fmuGUID ? fmuGUID : "(null)", MODEL.guid);
        return NULL;
    }
    inst = (Instance *)functions->allocateMemory(1, sizeof(Instance));
    if (inst == NULL) return NULL;
    inst->cb = *functions;
    inst->logging_on = loggingOn != fmi2False;
    inst->name = (char *)functions->allocateMemory(strlen(instanceName) + 1, 1);
    inst->data = functions->allocateMemory(1, MODEL.data_size);
    if (inst->name == NULL || inst->data == NULL) {
        functions->freeMemory(inst->name);
        functions->freeMemory(inst->data);
        functions->freeMemory(inst);
        return NULL;
    }
    strcpy(inst->name, instanceName);
    inst->resource_dir = decode_file_uri(functions, fmuResourceLocation);
    reset_values(inst);
    LOG_INFO(inst, "instantiated; resources at %s",
             inst->resource_dir ? inst->resource_dir : "(none)");
    return inst;
}

void fmi2FreeInstance(fmi2Component c) {
    Instance *inst = (Instance *)c;
    fmi2CallbackFreeMemory free_memory;
    if (inst == NULL) return;
    free_memory = inst->cb.freeMemory;
    free_memory(inst->resource_dir);
    free_memory(inst->data);
    free_memory(inst->name);
    free_memory(inst);
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    BEGIN(SetDebugLogging)
    (void)nCategories;
    (void)categories;
    inst->logging_on = loggingOn != fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined,
                               fmi2Real stopTime) {
    BEGIN(SetupExperiment)
    (void)toleranceDefined;
    (void)tolerance;
    if (!isfinite(startTime) || (stopTimeDefined && !(stopTime >= startTime))) {
        LOG_ERROR(inst, "fmi2SetupExperiment: bad start time %g or stop time %g", startTime,
                  stopTime);
        return finish(inst, fmi2Error);
    }
    inst->start_time = startTime;
    inst->time = startTime;
    inst->stop_time = stopTimeDefined ? stopTime : INFINITY;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    BEGIN(EnterInitializationMode)
    inst->phase = PHASE_INITIALIZATION;
    MODEL.calculate(inst);
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    fmi2Status status;
    BEGIN(ExitInitializationMode)
    MODEL.calculate(inst);
    status = MODEL.initialize(inst);
    if (status <= fmi2Warning) inst->phase = PHASE_STEP_COMPLETE;
    return finish(inst, status);
}

fmi2Status fmi2Terminate(fmi2Component c) {
    BEGIN(Terminate)
    inst->phase = PHASE_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    fmi2Status status;
    BEGIN(Reset)
    status = MODEL.reset != NULL ? MODEL.reset(inst) : fmi2OK;
    if (status > fmi2Warning) return finish(inst, status);
    reset_values(inst);
    return status;
}

/* ------------------------------------------------------------------------------------------ */
/* Getting and setting by the variable table. */

static const Variable *find_variable(VarType type, fmi2ValueReference vr) {
    size_t i;
    for (i = 0; i < MODEL.n_variables; i++) {
        if (MODEL.variables[i].type == type && MODEL.variables[i].vr == vr) {
            return &MODEL.variables[i];
        }
    }
    return NULL;
}

static const char *const TYPE_NAMES[] = {"Real", "Integer", "Boolean", "String"};

static fmi2Status get_values(Instance *inst, VarType type, const fmi2ValueReference vr[],
                             size_t nvr, void *values) {
    size_t i;
    for (i = 0; i < nvr; i++) {
        const Variable *var = find_variable(type, vr[i]);
        const char *field;
        if (var == NULL) {
            LOG_ERROR(inst, "fmi2Get%s: no %s variable has value reference %u", TYPE_NAMES[type],
                      TYPE_NAMES[type], (unsigned)vr[i]);
            return finish(inst, fmi2Error);
        }
        field = (const char *)inst->data + var->offset;
        switch (type) {
        case TYPE_REAL:
            ((fmi2Real *)values)[i] =
                var->kind == KIND_INDEPENDENT ? inst->time : *(const double *)field;
            break;
        case TYPE_INTEGER: ((fmi2Integer *)values)[i] = *(const fmi2Integer *)field; break;
        case TYPE_BOOLEAN: ((fmi2Boolean *)values)[i] = *(const fmi2Boolean *)field; break;
        case TYPE_STRING: ((fmi2String *)values)[i] = field; break;
        }
    }
    return fmi2OK;
}

/* Whether `var` may be set now; logs why not. */
static int settable(Instance *inst, const Variable *var) {
    switch (var->kind) {
    case KIND_OUTPUT:
    case KIND_INDEPENDENT:
        LOG_ERROR(inst, "fmi2Set%s: '%s' is an %s and cannot be set", TYPE_NAMES[var->type],
                  var->name, var->kind == KIND_OUTPUT ? "output" : "independent variable");
        return 0;
    case KIND_FIXED_PARAMETER:
        if (inst->phase != PHASE_INSTANTIATED && inst->phase != PHASE_INITIALIZATION) {
            LOG_ERROR(inst, "fmi2Set%s: '%s' is a fixed parameter and cannot be set after "
                            "initialization",
                      TYPE_NAMES[var->type], var->name);
            return 0;
        }
        return 1;
    case KIND_TUNABLE_PARAMETER:
    case KIND_INPUT: return 1;
    }
    return 0;
}

/* Sets one value; logs and returns fmi2Error when it is refused. */
static fmi2Status set_value(Instance *inst, const Variable *var, const void *values, size_t i) {
    char *field = (char *)inst->data + var->offset;
    if (!settable(inst, var)) return fmi2Error;
    switch (var->type) {
    case TYPE_REAL: *(double *)field = ((const fmi2Real *)values)[i]; break;
    case TYPE_INTEGER: {
        fmi2Integer v = ((const fmi2Integer *)values)[i];
        if (var->has_range && (v < var->min || v > var->max)) {
            LOG_ERROR(inst, "fmi2SetInteger: %s = %d is outside [%d, %d]", var->name, (int)v,
                      (int)var->min, (int)var->max);
            return fmi2Error;
        }
        *(fmi2Integer *)field = v;
        break;
    }
    case TYPE_BOOLEAN:
        *(fmi2Boolean *)field = ((const fmi2Boolean *)values)[i] != fmi2False;
        break;
    case TYPE_STRING: {
        fmi2String v = ((const fmi2String *)values)[i];
        if (v == NULL) {
            LOG_ERROR(inst, "fmi2SetString: NULL value for '%s'", var->name);
            return fmi2Error;
        }
        if (strlen(v) >= STRING_CAPACITY) {
            LOG_ERROR(inst, "fmi2SetString: the value of '%s' has %zu bytes, at most %d allowed",
                      var->name, strlen(v), STRING_CAPACITY - 1);
            return fmi2Error;
        }
        strcpy(field, v);
        break;
    }
    }
    return fmi2OK;
}

static fmi2Status set_values(Instance *inst, VarType type, const fmi2ValueReference vr[],
                             size_t nvr, const void *values) {
    size_t i;
    for (i = 0; i < nvr; i++) {
        const Variable *var = find_variable(type, vr[i]);
        if (var == NULL) {
            LOG_ERROR(inst, "fmi2Set%s: no %s variable has value reference %u", TYPE_NAMES[type],
                      TYPE_NAMES[type], (unsigned)vr[i]);
            return finish(inst, fmi2Error);
        }
        if (set_value(inst, var, values, i) != fmi2OK) return finish(inst, fmi2Error);
    }
    MODEL.calculate(inst);
    return fmi2OK;
}

#define GETTER(Type, TYPE, CType)                                                           \
    fmi2Status fmi2Get##Type(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,    \
                             CType value[]) {                                               \
        BEGIN(Get)                                                                          \
        if (nvr == 0) return fmi2OK;                                                        \
        REQUIRE_NOT_NULL(Get##Type, vr)                                                     \
        REQUIRE_NOT_NULL(Get##Type, value)                                                  \
        return get_values(inst, TYPE, vr, nvr, value);                                      \
    }

#define SETTER(Type, TYPE, CType)                                                           \
    fmi2Status fmi2Set##Type(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,    \
                             const CType value[]) {                                         \
        BEGIN(Set)                                                                          \
        if (nvr == 0) return fmi2OK;                                                        \
        REQUIRE_NOT_NULL(Set##Type, vr)                                                     \
        REQUIRE_NOT_NULL(Set##Type, value)                                                  \
        return set_values(inst, TYPE, vr, nvr, value);                                      \
    }

GETTER(Real, TYPE_REAL, fmi2Real)
GETTER(Integer, TYPE_INTEGER, fmi2Integer)
GETTER(Boolean, TYPE_BOOLEAN, fmi2Boolean)
GETTER(String, TYPE_STRING, fmi2String)
SETTER(Real, TYPE_REAL, fmi2Real)
SETTER(Integer, TYPE_INTEGER, fmi2Integer)
SETTER(Boolean, TYPE_BOOLEAN, fmi2Boolean)
SETTER(String, TYPE_STRING, fmi2String)

/* ------------------------------------------------------------------------------------------ */
/* FMU state: a header and a copy of the model's data, also as the serialized bytes. */

#define STATE_MAGIC 0x55514653u /* "UQFS" */

typedef struct {
    unsigned magic;
    unsigned data_size;
    Phase phase;
    fmi2Boolean terminated;
    double time;
} StateHeader;

static size_t state_size(void) { return sizeof(StateHeader) + MODEL.data_size; }

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    StateHeader header;
    char *bytes;
    BEGIN(State)
    REQUIRE_NOT_NULL(GetFMUstate, FMUstate)
    bytes = (char *)(*FMUstate != NULL ? *FMUstate : inst->cb.allocateMemory(1, state_size()));
    if (bytes == NULL) {
        LOG_ERROR(inst, "fmi2GetFMUstate: out of memory");
        return finish(inst, fmi2Error);
    }
    header.magic = STATE_MAGIC;
    header.data_size = (unsigned)MODEL.data_size;
    header.phase = inst->phase;
    header.terminated = inst->terminated;
    header.time = inst->time;
    memcpy(bytes, &header, sizeof header);
    memcpy(bytes + sizeof header, inst->data, MODEL.data_size);
    *FMUstate = bytes;
    return fmi2OK;
}

/* Whether `bytes` hold a state of this model; logs why not. */
static int valid_state(Instance *inst, const char *function, const void *bytes) {
    StateHeader header;
    memcpy(&header, bytes, sizeof header);
    if (header.magic != STATE_MAGIC || header.data_size != MODEL.data_size ||
        (header.phase & ALL_BUT_FATAL) == 0) {
        LOG_ERROR(inst, "%s: not an FMU state of this model", function);
        return 0;
    }
    return 1;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    StateHeader header;
    BEGIN(State)
    REQUIRE_NOT_NULL(SetFMUstate, FMUstate)
    if (!valid_state(inst, "fmi2SetFMUstate", FMUstate)) return finish(inst, fmi2Error);
    memcpy(&header, FMUstate, sizeof header);
    inst->phase = header.phase;
    inst->terminated = header.terminated;
    inst->time = header.time;
    memcpy(inst->data, (const char *)FMUstate + sizeof header, MODEL.data_size);
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    BEGIN(State)
    REQUIRE_NOT_NULL(FreeFMUstate, FMUstate)
    inst->cb.freeMemory(*FMUstate);
    *FMUstate = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size) {
    BEGIN(State)
    (void)FMUstate;
    REQUIRE_NOT_NULL(SerializedFMUstateSize, size)
    *size = state_size();
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate,
                                 fmi2Byte serializedState[], size_t size) {
    BEGIN(State)
    REQUIRE_NOT_NULL(SerializeFMUstate, FMUstate)
    REQUIRE_NOT_NULL(SerializeFMUstate, serializedState)
    if (size != state_size()) {
        LOG_ERROR(inst, "fmi2SerializeFMUstate: buffer of %zu bytes, need %zu", size,
                  state_size());
        return finish(inst, fmi2Error);
    }
    memcpy(serializedState, FMUstate, size);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate) {
    char *bytes;
    BEGIN(State)
    REQUIRE_NOT_NULL(DeSerializeFMUstate, serializedState)
    REQUIRE_NOT_NULL(DeSerializeFMUstate, FMUstate)
    if (size != state_size()) {
        LOG_ERROR(inst, "fmi2DeSerializeFMUstate: %zu bytes, expected %zu", size, state_size());
        return finish(inst, fmi2Error);
    }
    if (!valid_state(inst, "fmi2DeSerializeFMUstate", serializedState)) {
        return finish(inst, fmi2Error);
    }
    bytes = (char *)(*FMUstate != NULL ? *FMUstate : inst->cb.allocateMemory(1, size));
    if (bytes == NULL) {
        LOG_ERROR(inst, "fmi2DeSerializeFMUstate: out of memory");
        return finish(inst, fmi2Error);
    }
    memcpy(bytes, serializedState, size);
    *FMUstate = bytes;
    return fmi2OK;
}

/* ------------------------------------------------------------------------------------------ */
/* Unsupported. */

static fmi2Status unsupported(Instance *inst, const char *function) {
    LOG_ERROR(inst, "%s is not supported by this FMU", function);
    return finish(inst, fmi2Error);
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[]) {
    BEGIN(GetDirectionalDerivative)
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    return unsupported(inst, "fmi2GetDirectionalDerivative");
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    BEGIN(SetRealInputDerivatives)
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return unsupported(inst, "fmi2SetRealInputDerivatives (canInterpolateInputs is false)");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    BEGIN(GetRealOutputDerivatives)
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return unsupported(inst, "fmi2GetRealOutputDerivatives (maxOutputDerivativeOrder is 0)");
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    BEGIN(CancelStep)
    return unsupported(inst, "fmi2CancelStep");
}

/* ------------------------------------------------------------------------------------------ */
/* Stepping and the status of the last step. */

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    fmi2Status status;
    double end;
    BEGIN(DoStep)
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!fmu_time_close(currentCommunicationPoint, inst->time)) {
        LOG_ERROR(inst, "fmi2DoStep: communication point %.17g, but the FMU is at t = %.17g",
                  currentCommunicationPoint, inst->time);
        return finish(inst, fmi2Error);
    }
    if (!(communicationStepSize > 0.0) || !isfinite(communicationStepSize)) {
        LOG_ERROR(inst, "fmi2DoStep: the step size must be positive and finite, got %g",
                  communicationStepSize);
        return finish(inst, fmi2Error);
    }
    end = currentCommunicationPoint + communicationStepSize;
    if (end > inst->stop_time && !fmu_time_close(end, inst->stop_time)) {
        LOG_ERROR(inst, "fmi2DoStep: a step to t = %.17g goes beyond the stop time %.17g", end,
                  inst->stop_time);
        return finish(inst, fmi2Error);
    }
    inst->time = currentCommunicationPoint;
    status = MODEL.step(inst, communicationStepSize);
    if (status == fmi2Discard) inst->phase = PHASE_STEP_FAILED;
    return finish(inst, status);
}

static fmi2Status status_unavailable(Instance *inst, const char *function, fmi2StatusKind s) {
    LOG_WARNING(inst, "%s: status kind %d is not available from this FMU", function, (int)s);
    return fmi2Discard;
}

/* fmi2Get<Kind>Status of a type `Type` for which this FMU has no status kind. */
#define NO_STATUS(Kind, Type)                                                                 \
    fmi2Status fmi2Get##Kind##Status(fmi2Component c, const fmi2StatusKind s, Type *value) {  \
        BEGIN(GetStatus)                                                                      \
        (void)value;                                                                          \
        return status_unavailable(inst, "fmi2Get" #Kind "Status", s);                         \
    }

NO_STATUS(, fmi2Status)
NO_STATUS(Integer, fmi2Integer)
NO_STATUS(String, fmi2String)

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    BEGIN(GetStatus)
    REQUIRE_NOT_NULL(GetRealStatus, value)
    if (s != fmi2LastSuccessfulTime) return status_unavailable(inst, "fmi2GetRealStatus", s);
    *value = inst->time;
    return fmi2OK;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    BEGIN(GetStatus)
    REQUIRE_NOT_NULL(GetBooleanStatus, value)
    if (s != fmi2Terminated) return status_unavailable(inst, "fmi2GetBooleanStatus", s);
    *value = inst->terminated;
    return fmi2OK;
}
