/*
 * Dahlquist test equation x' = -k x as an FMI 2.0 Co-Simulation FMU, written in C so that
 * uq-driver's import layer is tested against an FMU it did not produce itself.
 *
 * Each fmi2DoStep applies the exact update x <- x exp(-k h), so x(t) = x0 exp(-k t) for a
 * constant k. All FMI 2.0 Co-Simulation functions are exported; unsupported ones log and
 * return fmi2Error. Errors are always logged, other messages only when logging is on.
 *
 * Variables (see modelDescription.xml):
 *   Real    0 x       output, calculated (= x0 at initialization)
 *   Real    1 k       tunable parameter, 1/s
 *   Real    2 x0      fixed parameter
 *   Real    3 time    independent
 *   Integer 0 steps   output, number of steps taken
 *   Boolean 0 frozen  input: when true, x does not change
 *   String  0 label   fixed parameter
 *
 * Build (GCC or Clang): cc -std=c99 -shared -fPIC -I<FMI 2.0 headers> dahlquist.c -o dahlquist.so -lm
 * -DOMIT_DO_STEP leaves fmi2DoStep out (to test that a missing symbol is reported).
 * dahlquist_live_instances() is a test hook: the number of instances not yet freed.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "fmi2Functions.h"

#define GUID "{6a1c2d9e-3b7f-4e0a-9d51-uq-driver-test}"

enum { VR_X = 0, VR_K = 1, VR_X0 = 2, VR_TIME = 3 };
enum { VR_STEPS = 0 };
enum { VR_FROZEN = 0 };
enum { VR_LABEL = 0 };

typedef enum { Instantiated, InitializationMode, StepMode, Terminated, Failed } Phase;

typedef struct {
    double time;
    double x;
    double k;
    double x0;
    int steps;
    int frozen;
    char label[64];
} Values;

typedef struct {
    fmi2CallbackFunctions cb;
    char *name;
    int logging_on;
    Phase phase;
    Values v;
} Model;

/* Updated atomically: instances may be created and freed on several threads at once. */
static int live_instances = 0;

FMI2_Export int dahlquist_live_instances(void) {
    return __atomic_load_n(&live_instances, __ATOMIC_SEQ_CST);
}

static void set_defaults(Values *v) {
    memset(v, 0, sizeof *v);
    v->k = 1.0;
    v->x0 = 1.0;
    v->x = 1.0;
    strcpy(v->label, "dahlquist");
}

/* The error helpers format with the logger's varargs, as real FMUs do. */
#define LOG_ERROR(m, ...) \
    (m)->cb.logger((m)->cb.componentEnvironment, (m)->name, fmi2Error, "logStatusError", __VA_ARGS__)
#define LOG_INFO(m, ...)                                                                        \
    do {                                                                                        \
        if ((m)->logging_on)                                                                    \
            (m)->cb.logger((m)->cb.componentEnvironment, (m)->name, fmi2OK, "logAll", __VA_ARGS__); \
    } while (0)

static fmi2Status fail(Model *m, fmi2Status status) {
    if (status == fmi2Error || status == fmi2Fatal) m->phase = Failed;
    return status;
}

static fmi2Status unsupported(fmi2Component c, const char *function) {
    Model *m = (Model *)c;
    if (m == NULL) return fmi2Error;
    LOG_ERROR(m, "%s is not supported by this FMU", function);
    return fmi2Error;
}

/* ---------------------------------------------------------------------------------------- */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    Model *m = (Model *)c;
    (void)nCategories;
    (void)categories;
    if (m == NULL) return fmi2Error;
    m->logging_on = loggingOn != 0;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn) {
    Model *m;
    (void)visible;
    if (functions == NULL || functions->logger == NULL || functions->allocateMemory == NULL ||
        functions->freeMemory == NULL) {
        return NULL;
    }
    if (instanceName == NULL || instanceName[0] == '\0') {
        functions->logger(functions->componentEnvironment, "?", fmi2Error, "logStatusError",
                          "missing instance name");
        return NULL;
    }
    if (fmuType != fmi2CoSimulation) {
        functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                          "logStatusError", "only Co-Simulation is supported (fmuType=%d)",
                          (int)fmuType);
        return NULL;
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, GUID) != 0) {
        functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                          "logStatusError", "wrong GUID %s, expected %s",
                          fmuGUID ? fmuGUID : "(null)", GUID);
        return NULL;
    }
    if (fmuResourceLocation == NULL || strncmp(fmuResourceLocation, "file:///", 8) != 0) {
        functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                          "logStatusError", "resource location is not a file:/// URI: %s",
                          fmuResourceLocation ? fmuResourceLocation : "(null)");
        return NULL;
    }
    m = (Model *)functions->allocateMemory(1, sizeof(Model));
    if (m == NULL) return NULL;
    m->name = (char *)functions->allocateMemory(strlen(instanceName) + 1, 1);
    if (m->name == NULL) {
        functions->freeMemory(m);
        return NULL;
    }
    strcpy(m->name, instanceName);
    m->cb = *functions;
    m->logging_on = loggingOn != 0;
    m->phase = Instantiated;
    set_defaults(&m->v);
    __atomic_add_fetch(&live_instances, 1, __ATOMIC_SEQ_CST);
    LOG_INFO(m, "instantiated with resources at %s", fmuResourceLocation);
    return m;
}

void fmi2FreeInstance(fmi2Component c) {
    Model *m = (Model *)c;
    fmi2CallbackFreeMemory free_memory;
    if (m == NULL) return;
    free_memory = m->cb.freeMemory;
    __atomic_sub_fetch(&live_instances, 1, __ATOMIC_SEQ_CST);
    free_memory(m->name);
    free_memory(m);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined,
                               fmi2Real stopTime) {
    Model *m = (Model *)c;
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (m == NULL) return fmi2Error;
    if (m->phase != Instantiated) {
        LOG_ERROR(m, "fmi2SetupExperiment called after instantiation");
        return fail(m, fmi2Error);
    }
    m->v.time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    Model *m = (Model *)c;
    if (m == NULL) return fmi2Error;
    if (m->phase != Instantiated) {
        LOG_ERROR(m, "fmi2EnterInitializationMode called twice");
        return fail(m, fmi2Error);
    }
    m->phase = InitializationMode;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Model *m = (Model *)c;
    if (m == NULL) return fmi2Error;
    if (m->phase != InitializationMode) {
        LOG_ERROR(m, "fmi2ExitInitializationMode called outside initialization mode");
        return fail(m, fmi2Error);
    }
    m->v.x = m->v.x0;
    m->phase = StepMode;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    Model *m = (Model *)c;
    if (m == NULL) return fmi2Error;
    if (m->phase != StepMode) {
        LOG_ERROR(m, "fmi2Terminate called before initialization");
        return fail(m, fmi2Error);
    }
    m->phase = Terminated;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    Model *m = (Model *)c;
    if (m == NULL) return fmi2Error;
    set_defaults(&m->v);
    m->phase = Instantiated;
    return fmi2OK;
}

/* ---------------------------------------------------------------------------------------- */

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[]) {
    Model *m = (Model *)c;
    size_t i;
    if (m == NULL) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        switch (vr[i]) {
        case VR_X: value[i] = m->v.x; break;
        case VR_K: value[i] = m->v.k; break;
        case VR_X0: value[i] = m->v.x0; break;
        case VR_TIME: value[i] = m->v.time; break;
        default:
            LOG_ERROR(m, "fmi2GetReal: unknown value reference %u", vr[i]);
            return fail(m, fmi2Error);
        }
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[]) {
    Model *m = (Model *)c;
    size_t i;
    if (m == NULL) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        if (vr[i] != VR_STEPS) {
            LOG_ERROR(m, "fmi2GetInteger: unknown value reference %u", vr[i]);
            return fail(m, fmi2Error);
        }
        value[i] = m->v.steps;
    }
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[]) {
    Model *m = (Model *)c;
    size_t i;
    if (m == NULL) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        if (vr[i] != VR_FROZEN) {
            LOG_ERROR(m, "fmi2GetBoolean: unknown value reference %u", vr[i]);
            return fail(m, fmi2Error);
        }
        value[i] = m->v.frozen ? fmi2True : fmi2False;
    }
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[]) {
    Model *m = (Model *)c;
    size_t i;
    if (m == NULL) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        if (vr[i] != VR_LABEL) {
            LOG_ERROR(m, "fmi2GetString: unknown value reference %u", vr[i]);
            return fail(m, fmi2Error);
        }
        value[i] = m->v.label;
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[]) {
    Model *m = (Model *)c;
    size_t i;
    if (m == NULL) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        switch (vr[i]) {
        case VR_K: m->v.k = value[i]; break;
        case VR_X0:
            if (m->phase != Instantiated && m->phase != InitializationMode) {
                LOG_ERROR(m, "fmi2SetReal: x0 is a fixed parameter and cannot be set after "
                             "initialization (value %g)", value[i]);
                return fail(m, fmi2Error);
            }
            m->v.x0 = value[i];
            break;
        default:
            LOG_ERROR(m, "fmi2SetReal: unknown or read-only value reference %u", vr[i]);
            return fail(m, fmi2Error);
        }
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[]) {
    Model *m = (Model *)c;
    (void)value;
    if (m == NULL) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    LOG_ERROR(m, "fmi2SetInteger: value reference %u cannot be set", vr[0]);
    return fail(m, fmi2Error);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[]) {
    Model *m = (Model *)c;
    size_t i;
    if (m == NULL) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        if (vr[i] != VR_FROZEN) {
            LOG_ERROR(m, "fmi2SetBoolean: unknown value reference %u", vr[i]);
            return fail(m, fmi2Error);
        }
        m->v.frozen = value[i] != fmi2False;
    }
    return fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[]) {
    Model *m = (Model *)c;
    size_t i;
    if (m == NULL) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        if (vr[i] != VR_LABEL) {
            LOG_ERROR(m, "fmi2SetString: unknown value reference %u", vr[i]);
            return fail(m, fmi2Error);
        }
        if (value[i] == NULL || strlen(value[i]) >= sizeof m->v.label) {
            /* The whole rejected value is logged: exercises long log messages. */
            LOG_ERROR(m, "fmi2SetString: label too long (at most %d bytes): '%s'",
                      (int)sizeof m->v.label - 1, value[i] ? value[i] : "(null)");
            return fmi2Discard;
        }
        if (m->phase != Instantiated && m->phase != InitializationMode) {
            LOG_ERROR(m, "fmi2SetString: label is a fixed parameter");
            return fail(m, fmi2Error);
        }
        strcpy(m->v.label, value[i]);
    }
    return fmi2OK;
}

/* ---------------------------------------------------------------------------------------- */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    Model *m = (Model *)c;
    Values *copy;
    if (m == NULL || state == NULL) return fmi2Error;
    copy = (Values *)(*state != NULL ? *state : m->cb.allocateMemory(1, sizeof(Values)));
    if (copy == NULL) return fail(m, fmi2Error);
    *copy = m->v;
    *state = copy;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    Model *m = (Model *)c;
    if (m == NULL || state == NULL) return fmi2Error;
    m->v = *(const Values *)state;
    if (m->phase == Failed) m->phase = StepMode;
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    Model *m = (Model *)c;
    if (m == NULL || state == NULL) return fmi2Error;
    m->cb.freeMemory(*state);
    *state = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    (void)c;
    (void)state;
    *size = sizeof(Values);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[],
                                 size_t size) {
    Model *m = (Model *)c;
    if (m == NULL || state == NULL) return fmi2Error;
    if (size != sizeof(Values)) {
        LOG_ERROR(m, "fmi2SerializeFMUstate: buffer of %zu bytes, need %zu", size, sizeof(Values));
        return fail(m, fmi2Error);
    }
    memcpy(bytes, state, sizeof(Values));
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size,
                                   fmi2FMUstate *state) {
    Model *m = (Model *)c;
    Values *copy;
    if (m == NULL || state == NULL) return fmi2Error;
    if (size != sizeof(Values)) {
        LOG_ERROR(m, "fmi2DeSerializeFMUstate: %zu bytes, expected %zu", size, sizeof(Values));
        return fail(m, fmi2Error);
    }
    copy = (Values *)(*state != NULL ? *state : m->cb.allocateMemory(1, sizeof(Values)));
    if (copy == NULL) return fail(m, fmi2Error);
    memcpy(copy, bytes, sizeof(Values));
    *state = copy;
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[]) {
    (void)vUnknown_ref; (void)nUnknown; (void)vKnown_ref; (void)nKnown; (void)dvKnown;
    (void)dvUnknown;
    return unsupported(c, "fmi2GetDirectionalDerivative");
}

/* ---------------------------------------------------------------------------------------- */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr; (void)nvr; (void)order; (void)value;
    return unsupported(c, "fmi2SetRealInputDerivatives");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr; (void)nvr; (void)order; (void)value;
    return unsupported(c, "fmi2GetRealOutputDerivatives");
}

#ifndef OMIT_DO_STEP
fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    Model *m = (Model *)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (m == NULL) return fmi2Error;
    if (m->phase != StepMode) {
        LOG_ERROR(m, "fmi2DoStep called before initialization");
        return fail(m, fmi2Error);
    }
    if (!(communicationStepSize > 0.0)) {
        LOG_ERROR(m, "fmi2DoStep: communication step size must be positive, got %g",
                  communicationStepSize);
        return fail(m, fmi2Error);
    }
    if (fabs(currentCommunicationPoint - m->v.time) > 1e-9 * (1.0 + fabs(m->v.time))) {
        LOG_ERROR(m, "fmi2DoStep: communication point %.17g does not match the FMU time %.17g",
                  currentCommunicationPoint, m->v.time);
        return fail(m, fmi2Error);
    }
    if (!m->v.frozen) m->v.x *= exp(-m->v.k * communicationStepSize);
    m->v.time = currentCommunicationPoint + communicationStepSize;
    m->v.steps++;
    LOG_INFO(m, "step %d to t=%g", m->v.steps, m->v.time);
    return fmi2OK;
}
#endif

fmi2Status fmi2CancelStep(fmi2Component c) { return unsupported(c, "fmi2CancelStep"); }

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)s; (void)value;
    return unsupported(c, "fmi2GetStatus");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    Model *m = (Model *)c;
    if (m == NULL) return fmi2Error;
    if (s == fmi2LastSuccessfulTime) {
        *value = m->v.time;
        return fmi2OK;
    }
    return unsupported(c, "fmi2GetRealStatus for this status kind");
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)s; (void)value;
    return unsupported(c, "fmi2GetIntegerStatus");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    Model *m = (Model *)c;
    if (m == NULL) return fmi2Error;
    if (s == fmi2Terminated) {
        *value = fmi2False;
        return fmi2OK;
    }
    return unsupported(c, "fmi2GetBooleanStatus for this status kind");
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)s; (void)value;
    return unsupported(c, "fmi2GetStringStatus");
}
