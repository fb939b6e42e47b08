/*
 * Features: what FMUs from other tools do, in one small FMI 2.0 Co-Simulation FMU (see
 * ../README.md): parameters of every type read back through outputs, inputs of three types, a
 * String parameter naming a file in the resources, an FMU that ends the simulation itself, and
 * chosen ways to misbehave in fmi2DoStep.
 *
 *   int_out = int_param, bool_out = bool_param, enum_out = enum_param (Enumeration Colour),
 *   string_out = string_param, string_len = strlen(string_param)
 *   u_echo = u and u_gain = gain u (direct feedthrough; gain is a tunable parameter), u_integral = integral of u dt with u held over each step
 *   (the left Riemann sum over the communication steps), k_echo = k, flag_echo = flag
 *   file_value = the first number in the file read_file (resolved in resources/ when
 *   relative; read at the end of initialization; 0 when read_file is empty)
 *   stop_at > 0: the step that reaches t = stop_at ends there, returns fmi2Discard, and
 *   fmi2GetBooleanStatus(fmi2Terminated) is true, fmi2GetRealStatus(fmi2LastSuccessfulTime) =
 *   stop_at (as Reference-FMUs' Stair does at t = 9)
 *   misbehave: the first step that reaches t = misbehave_at
 *     1 returns fmi2Error (logged)   2 segfaults        3 calls abort()   4 calls exit(0)
 *     5 blocks forever (sleeps)      6 makes every Real output NaN from then on (fmi2OK)
 *     7 returns fmi2Fatal (logged)   8 returns fmi2Warning (logged) and goes on
 *     9 writes 12 bytes of garbage to file descriptor 3 and goes on
 *     10 starts a helper process that lives 20 s (holding every descriptor), then segfaults
 *     11 raises SIGTERM on itself   12 prints a line to stdout (fd 1) and goes on
 *     13 returns fmi2Error (logged) if gain > file_value: a failure region whose bound is
 *        read from a file, so that it can move between runs of a study
 *   reset_bug: a broken fmi2Reset, as FMUs from other tools have: 1 returns fmi2Error (logged),
 *   2 returns fmi2OK but forgets the start values (every variable keeps its value of the run
 *   before, u_integral included, which then starts where that run ended), 3 returns fmi2Error
 *   (logged) after a run with gain < 1.5 only, 4 returns fmi2Fatal (logged)
 *   quiet: the model's own messages (these misbehaviours, read_file) reach the importer only
 *   with logging on, errors included (as pythonfmu FMUs log)
 *   name_dir: not empty: at the end of initialization gain is written to the file
 *   <name_dir>/<instanceName>.txt, and every step reads file_value back from it (an FMU that
 *   keys its working files on its instance name)
 */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <signal.h>
#include <unistd.h>

#include "fmu_common.h"

#define GUID "{8e2b7f3c-1d4a-4c6e-9f0b-railuq-test-features}"

/* At most this many bytes of read_file are read. */
#define FILE_LIMIT 65536

enum { MISBEHAVE_NONE, MISBEHAVE_ERROR, MISBEHAVE_SEGFAULT, MISBEHAVE_ABORT, MISBEHAVE_EXIT,
       MISBEHAVE_BLOCK, MISBEHAVE_NAN, MISBEHAVE_FATAL, MISBEHAVE_WARNING, MISBEHAVE_FD3,
       MISBEHAVE_CHILD_SEGFAULT, MISBEHAVE_SIGTERM, MISBEHAVE_STDOUT, MISBEHAVE_ABOVE,
       MISBEHAVE_LAST };

typedef struct {
    /* parameters */
    fmi2Integer int_param;
    fmi2Boolean bool_param;
    fmi2Integer enum_param;
    char string_param[STRING_CAPACITY];
    char read_file[STRING_CAPACITY];
    double stop_at;
    fmi2Integer misbehave;
    double misbehave_at;
    double gain; /* tunable */
    /* inputs */
    double u;
    fmi2Integer k;
    fmi2Boolean flag;
    /* outputs */
    fmi2Integer int_out;
    fmi2Boolean bool_out;
    fmi2Integer enum_out;
    char string_out[STRING_CAPACITY];
    fmi2Integer string_len;
    double u_echo;
    double u_gain;
    double u_integral;
    fmi2Integer k_echo;
    fmi2Boolean flag_echo;
    double file_value;
    fmi2Integer reset_bug;
    fmi2Boolean quiet;
    char name_dir[STRING_CAPACITY];
    /* internal */
    fmi2Boolean misbehaved; /* the misbehaviour has happened */
} Data;

/* The model's own messages: with `quiet`, only when logging is on (errors included). */
#define QUIET(inst) (((Data *)(inst)->data)->quiet && !(inst)->logging_on)
#define MODEL_LOG(inst, status, category, ...)                                   \
    do {                                                                          \
        if (!QUIET(inst)) fmu_log((inst), (status), (category), __VA_ARGS__);     \
    } while (0)
#define M_ERROR(inst, ...) MODEL_LOG((inst), fmi2Error, "logStatusError", __VA_ARGS__)
#define M_WARNING(inst, ...) MODEL_LOG((inst), fmi2Warning, "logStatusWarning", __VA_ARGS__)
#define M_INFO(inst, ...) MODEL_LOG((inst), fmi2OK, "logAll", __VA_ARGS__)

#define VAR(name, type, vr, kind, field) {name, type, vr, kind, offsetof(Data, field), 0, 0, 0}

/* Value references (as in modelDescription.xml): each type counts from 0, as many tools do. */
static const Variable VARIABLES[] = {
    {"time", TYPE_REAL, 0, KIND_INDEPENDENT, 0, 0, 0, 0},
    VAR("u", TYPE_REAL, 1, KIND_INPUT, u),
    VAR("u_echo", TYPE_REAL, 2, KIND_OUTPUT, u_echo),
    VAR("u_integral", TYPE_REAL, 3, KIND_OUTPUT, u_integral),
    VAR("file_value", TYPE_REAL, 4, KIND_OUTPUT, file_value),
    VAR("stop_at", TYPE_REAL, 5, KIND_FIXED_PARAMETER, stop_at),
    VAR("misbehave_at", TYPE_REAL, 6, KIND_FIXED_PARAMETER, misbehave_at),
    VAR("gain", TYPE_REAL, 7, KIND_TUNABLE_PARAMETER, gain),
    VAR("u_gain", TYPE_REAL, 8, KIND_OUTPUT, u_gain),
    VAR("int_param", TYPE_INTEGER, 0, KIND_FIXED_PARAMETER, int_param),
    {"enum_param", TYPE_INTEGER, 1, KIND_FIXED_PARAMETER, offsetof(Data, enum_param), 1, 1, 3},
    {"misbehave", TYPE_INTEGER, 2, KIND_FIXED_PARAMETER, offsetof(Data, misbehave), 1, 0,
     MISBEHAVE_LAST - 1},
    VAR("k", TYPE_INTEGER, 3, KIND_INPUT, k),
    VAR("int_out", TYPE_INTEGER, 4, KIND_OUTPUT, int_out),
    VAR("enum_out", TYPE_INTEGER, 5, KIND_OUTPUT, enum_out),
    VAR("string_len", TYPE_INTEGER, 6, KIND_OUTPUT, string_len),
    VAR("k_echo", TYPE_INTEGER, 7, KIND_OUTPUT, k_echo),
    VAR("bool_param", TYPE_BOOLEAN, 0, KIND_FIXED_PARAMETER, bool_param),
    VAR("flag", TYPE_BOOLEAN, 1, KIND_INPUT, flag),
    VAR("bool_out", TYPE_BOOLEAN, 2, KIND_OUTPUT, bool_out),
    VAR("flag_echo", TYPE_BOOLEAN, 3, KIND_OUTPUT, flag_echo),
    VAR("string_param", TYPE_STRING, 0, KIND_FIXED_PARAMETER, string_param),
    VAR("read_file", TYPE_STRING, 1, KIND_FIXED_PARAMETER, read_file),
    VAR("string_out", TYPE_STRING, 2, KIND_OUTPUT, string_out),
    {"reset_bug", TYPE_INTEGER, 8, KIND_FIXED_PARAMETER, offsetof(Data, reset_bug), 1, 0, 4},
    VAR("quiet", TYPE_BOOLEAN, 4, KIND_FIXED_PARAMETER, quiet),
    VAR("name_dir", TYPE_STRING, 3, KIND_FIXED_PARAMETER, name_dir),
};

static void set_defaults(void *data) {
    Data *d = (Data *)data;
    /* reset_bug = 2: fmi2Reset forgets the start values (the data of a new instance is zero). */
    if (d->reset_bug == 2) return;
    memset(d, 0, sizeof *d);
    d->int_param = 3;
    d->bool_param = fmi2False;
    d->enum_param = 2;
    strcpy(d->string_param, "hello");
    strcpy(d->read_file, "value.txt");
    d->stop_at = 0.0;
    d->misbehave = MISBEHAVE_NONE;
    d->misbehave_at = 0.5;
    d->gain = 1.0;
}

static void calculate(Instance *inst) {
    Data *d = (Data *)inst->data;
    d->int_out = d->int_param;
    d->bool_out = d->bool_param;
    d->enum_out = d->enum_param;
    strcpy(d->string_out, d->string_param);
    d->string_len = (fmi2Integer)strlen(d->string_param);
    d->k_echo = d->k;
    d->flag_echo = d->flag;
    if (d->misbehave == MISBEHAVE_NAN && d->misbehaved) {
        d->u_echo = NAN;
        d->u_gain = NAN;
    } else {
        d->u_echo = d->u;
        d->u_gain = d->gain * d->u;
    }
}

/* The first decimal number in `text` (as strtod reads it from a sign, digit or point), skipping
 * lines that start with '#'. Returns 0 when found. */
static int first_number(const char *text, double *value) {
    const char *p = text;
    while (*p != '\0') {
        char *end;
        if (*p == '#' && (p == text || p[-1] == '\n')) {
            while (*p != '\0' && *p != '\n') p++;
            continue;
        }
        if (strchr("+-.0123456789", *p) != NULL) {
            *value = strtod(p, &end);
            if (end != p) return 0;
        }
        p++;
    }
    return -1;
}

static fmi2Status read_value(Instance *inst, const char *name, double *value) {
    char path[2 * STRING_CAPACITY + 64];
    char *text;
    FILE *file;
    size_t n;
    int found;
    if (fmu_resource_path(inst, name, path, sizeof path) != 0) return fmi2Error;
    file = fopen(path, "rb");
    if (file == NULL) {
        M_ERROR(inst, "read_file: cannot open '%s'", path);
        return fmi2Error;
    }
    text = (char *)inst->cb.allocateMemory(FILE_LIMIT + 1, 1);
    if (text == NULL) {
        fclose(file);
        M_ERROR(inst, "read_file: out of memory");
        return fmi2Error;
    }
    n = fread(text, 1, FILE_LIMIT, file);
    fclose(file);
    text[n] = '\0';
    found = first_number(text, value);
    inst->cb.freeMemory(text);
    if (found != 0) {
        M_ERROR(inst, "read_file: no number in the first %d bytes of '%s'", FILE_LIMIT, path);
        return fmi2Error;
    }
    M_INFO(inst, "read_file: %s gives %.17g", path, *value);
    return fmi2OK;
}

/* <name_dir>/<instanceName>.txt into path (capacity bytes); 0 when it fits. */
static int name_file(Instance *inst, char *path, size_t capacity) {
    Data *d = (Data *)inst->data;
    int written = snprintf(path, capacity, "%s/%s.txt", d->name_dir, inst->name);
    if (written < 0 || (size_t)written >= capacity) {
        M_ERROR(inst, "name_dir: the path of the instance's file is too long");
        return -1;
    }
    return 0;
}

/* name_dir: gain written to the instance's file, file_value read back from it. */
static fmi2Status write_name_file(Instance *inst) {
    Data *d = (Data *)inst->data;
    char path[2 * STRING_CAPACITY + 64];
    FILE *file;
    if (name_file(inst, path, sizeof path) != 0) return fmi2Error;
    file = fopen(path, "w");
    if (file == NULL || fprintf(file, "%.17g\n", d->gain) < 0 || fclose(file) != 0) {
        M_ERROR(inst, "name_dir: cannot write '%s'", path);
        return fmi2Error;
    }
    return read_value(inst, path, &d->file_value);
}

static fmi2Status initialize(Instance *inst) {
    Data *d = (Data *)inst->data;
    /* u_integral starts at its start value 0 (set_defaults; kept by reset_bug = 2). */
    d->file_value = 0.0;
    if (d->name_dir[0] != '\0') return write_name_file(inst);
    if (d->read_file[0] != '\0') return read_value(inst, d->read_file, &d->file_value);
    return fmi2OK;
}

static fmi2Status reset(Instance *inst) {
    Data *d = (Data *)inst->data;
    if (d->reset_bug == 1) {
        M_ERROR(inst, "reset_bug = 1: fmi2Reset fails on purpose");
        return fmi2Error;
    }
    if (d->reset_bug == 4) {
        MODEL_LOG(inst, fmi2Fatal, "logStatusFatal", "reset_bug = 4: fmi2Reset fails fatally on purpose");
        return fmi2Fatal;
    }
    if (d->reset_bug == 3 && d->gain < 1.5) {
        M_ERROR(inst, "reset_bug = 3: fmi2Reset fails on purpose after a run with gain %g < 1.5",
                d->gain);
        return fmi2Error;
    }
    return fmi2OK;
}

static void block_forever(void) {
    const struct timespec second = {1, 0};
    for (;;) nanosleep(&second, NULL);
}

/* A null pointer the compiler cannot see through: writing to it is a real segfault. */
static int *volatile null_pointer = NULL;

/* The misbehaviour selected by `misbehave`, at the first step that reaches misbehave_at. */
static fmi2Status misbehave(Instance *inst, double end) {
    Data *d = (Data *)inst->data;
    if (d->misbehave == MISBEHAVE_NONE || d->misbehaved) return fmi2OK;
    if (end < d->misbehave_at && !fmu_time_close(end, d->misbehave_at)) return fmi2OK;
    d->misbehaved = fmi2True;
    switch (d->misbehave) {
    case MISBEHAVE_ERROR:
        M_ERROR(inst, "misbehave = 1: fmi2DoStep fails on purpose at t = %g", end);
        return fmi2Error;
    /* 2..5 first log a warning, the last words an importer can show of the run. */
    case MISBEHAVE_SEGFAULT:
        M_WARNING(inst, "misbehave = 2: segfaulting on purpose at t = %g", end);
        *null_pointer = 1;
        return fmi2Error;
    case MISBEHAVE_ABORT:
        M_WARNING(inst, "misbehave = 3: calling abort() on purpose at t = %g", end);
        abort();
    case MISBEHAVE_EXIT:
        M_WARNING(inst, "misbehave = 4: calling exit(0) on purpose at t = %g", end);
        exit(0);
    case MISBEHAVE_BLOCK:
        M_WARNING(inst, "misbehave = 5: blocking forever on purpose at t = %g", end);
        block_forever();
        return fmi2Error;
    case MISBEHAVE_FATAL:
        MODEL_LOG(inst, fmi2Fatal, "logStatusFatal", "misbehave = 7: fatal error on purpose at t = %g",
                end);
        return fmi2Fatal;
    case MISBEHAVE_WARNING:
        M_WARNING(inst, "misbehave = 8: a warning on purpose at t = %g", end);
        return fmi2Warning;
    case MISBEHAVE_FD3: {
        static const char garbage[12] = "garbage\xff\x01\x02\x03!";
        ssize_t written = write(3, garbage, sizeof garbage);
        (void)written;
        return fmi2OK;
    }
    case MISBEHAVE_CHILD_SEGFAULT:
        M_WARNING(inst, "misbehave = 10: starting a helper, then segfaulting at t = %g", end);
        if (fork() == 0) {
            const struct timespec life = {20, 0};
            nanosleep(&life, NULL);
            _exit(0);
        }
        *null_pointer = 1;
        return fmi2Error;
    case MISBEHAVE_SIGTERM:
        M_WARNING(inst, "misbehave = 11: raising SIGTERM on purpose at t = %g", end);
        raise(SIGTERM);
        return fmi2Error;
    case MISBEHAVE_STDOUT:
        printf("Features: misbehave = 12 prints to stdout at t = %g\n", end);
        fflush(stdout);
        return fmi2OK;
    case MISBEHAVE_ABOVE:
        if (d->gain <= d->file_value) return fmi2OK;
        M_ERROR(inst, "misbehave = 13: gain = %g is above file_value = %g at t = %g", d->gain,
                d->file_value, end);
        return fmi2Error;
    default: return fmi2OK; /* MISBEHAVE_NAN: applied in step() */
    }
}

static fmi2Status step(Instance *inst, double h) {
    Data *d = (Data *)inst->data;
    double end = inst->time + h;
    int stop = d->stop_at > 0.0 && (end >= d->stop_at || fmu_time_close(end, d->stop_at));
    fmi2Status status;
    if (stop) end = d->stop_at > inst->time ? d->stop_at : inst->time;
    status = misbehave(inst, end);
    if (status > fmi2Warning) return status;
    if (d->name_dir[0] != '\0') {
        char path[2 * STRING_CAPACITY + 64];
        if (name_file(inst, path, sizeof path) != 0) return fmi2Error;
        if (read_value(inst, path, &d->file_value) != fmi2OK) return fmi2Error;
    }
    d->u_integral += d->u * (end - inst->time);
    inst->time = end;
    if (d->misbehave == MISBEHAVE_NAN && d->misbehaved) {
        d->u_echo = NAN;
        d->u_gain = NAN;
        d->u_integral = NAN;
        d->file_value = NAN;
    }
    if (stop) {
        inst->terminated = fmi2True;
        M_INFO(inst, "stop_at: the simulation ends at t = %g", end);
        return fmi2Discard;
    }
    return status;
}

DEFINE_MODEL(reset);
