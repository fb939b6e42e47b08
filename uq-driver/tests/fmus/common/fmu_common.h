/*
 * The FMI layer shared by railuq's C test FMUs (uq-driver/tests/fmus/): FMI 2.0 Co-Simulation
 * only. It knows no model: each model (one folder beside this one) provides a `ModelInfo` named
 * MODEL with its GUID, a table of its variables and four hooks. This layer owns
 *   - the state machine: which call is legal in which phase is one bitmask per function, checked
 *     once; every fmi2Error moves the instance to PHASE_ERROR, fmi2Fatal to PHASE_FATAL;
 *   - get/set by the variable table, with the FMI rules for who may be set when (fixed parameters
 *     before the end of initialization, tunable parameters and inputs also between steps,
 *     outputs never);
 *   - FMU state get/set/serialize (a copy of time + the model's data);
 *   - the resource folder: the fmuResourceLocation URI decoded to a file system path;
 *   - logging: warnings and errors always, the rest when logging is on.
 *
 * Written for the test suite, never shipped. C99 + POSIX.
 */
#ifndef FMU_COMMON_H
#define FMU_COMMON_H

#include <stddef.h>

#include "fmi2Functions.h"

/* Bytes of a String variable's storage, the terminating NUL included. Longer values are refused
 * with fmi2Error. */
#define STRING_CAPACITY 1024

/* Relative tolerance when comparing communication points and event times. */
#define TIME_TOLERANCE 1e-9

typedef enum { TYPE_REAL, TYPE_INTEGER, TYPE_BOOLEAN, TYPE_STRING } VarType;

/* Causality and variability as far as setting is concerned. Enumerations are TYPE_INTEGER. */
typedef enum {
    KIND_FIXED_PARAMETER,   /* settable before fmi2ExitInitializationMode only */
    KIND_TUNABLE_PARAMETER, /* settable also between steps */
    KIND_INPUT,             /* settable also between steps */
    KIND_OUTPUT,            /* never settable */
    KIND_INDEPENDENT        /* time: never settable, read from the instance */
} VarKind;

/* One row of a model's variable table: the storage of the value is at `offset` in the model's
 * data struct (double for Real, fmi2Integer for Integer and Enumeration, fmi2Boolean for Boolean,
 * char[STRING_CAPACITY] for String). Integer values outside [min, max] are refused when
 * has_range is set. */
typedef struct {
    const char *name;
    VarType type;
    fmi2ValueReference vr;
    VarKind kind;
    size_t offset;
    int has_range;
    fmi2Integer min;
    fmi2Integer max;
} Variable;

typedef enum {
    PHASE_INSTANTIATED = 1 << 0,
    PHASE_INITIALIZATION = 1 << 1,
    PHASE_STEP_COMPLETE = 1 << 2,
    PHASE_STEP_FAILED = 1 << 3, /* fmi2DoStep returned fmi2Discard */
    PHASE_TERMINATED = 1 << 4,
    PHASE_ERROR = 1 << 5,
    PHASE_FATAL = 1 << 6
} Phase;

typedef struct Instance Instance;

typedef struct {
    const char *guid;
    const Variable *variables;
    size_t n_variables;
    size_t data_size;
    /* The start values of every variable, as in modelDescription.xml. */
    void (*set_defaults)(void *data);
    /* Outputs that follow directly from parameters and inputs; called after every successful
     * set and at the start of initialization. Must not fail. */
    void (*calculate)(Instance *inst);
    /* End of initialization: check the parameters, read files, compute the outputs. */
    fmi2Status (*initialize)(Instance *inst);
    /* Advance from inst->time by h > 0 (the communication point has been checked). Sets
     * inst->time to the time reached. fmi2Discard with inst->terminated set ends the
     * simulation (the FMU asks the importer to stop). */
    fmi2Status (*step)(Instance *inst, double h);
    /* fmi2Reset, before the start values are restored (NULL: nothing): a status above
     * fmi2Warning is returned as is and nothing is reset. */
    fmi2Status (*reset)(Instance *inst);
} ModelInfo;

/* Provided by the model. */
extern const ModelInfo MODEL;

/* The definition of MODEL in a model whose GUID, VARIABLES, Data and hooks set_defaults,
 * calculate, initialize and step have these names; `reset` is its reset hook (or NULL). */
#define DEFINE_MODEL(reset)                                                                   \
    const ModelInfo MODEL = {GUID,         VARIABLES, sizeof VARIABLES / sizeof VARIABLES[0], \
                             sizeof(Data), set_defaults, calculate, initialize, step, reset}

struct Instance {
    fmi2CallbackFunctions cb;
    char *name;
    /* File system path of the FMU's resources folder (no trailing slash), or NULL when the
     * importer gave no usable file URI. */
    char *resource_dir;
    int logging_on;
    Phase phase;
    double start_time;
    double stop_time; /* +inf when the importer set none */
    /* Saved and restored with the FMU state: */
    double time;
    fmi2Boolean terminated; /* the FMU ended the simulation (fmi2GetBooleanStatus) */
    void *data;             /* MODEL.data_size bytes */
};

/* Logs through the importer's logger as logger(env, name, status, category, "%s", message).
 * Messages with a status other than fmi2OK always, the others only when logging is on. */
void fmu_log(Instance *inst, fmi2Status status, const char *category, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

#define LOG_ERROR(inst, ...) fmu_log((inst), fmi2Error, "logStatusError", __VA_ARGS__)
#define LOG_WARNING(inst, ...) fmu_log((inst), fmi2Warning, "logStatusWarning", __VA_ARGS__)
#define LOG_INFO(inst, ...) fmu_log((inst), fmi2OK, "logAll", __VA_ARGS__)

/* `relative` resolved against the resources folder, or copied when absolute, into out (capacity
 * bytes). Returns 0 on success, -1 (logged) when there is no resources folder or the path does
 * not fit. */
int fmu_resource_path(Instance *inst, const char *relative, char *out, size_t capacity);

/* |a - b| within TIME_TOLERANCE relative to max(1, |a|, |b|). */
int fmu_time_close(double a, double b);

#endif
