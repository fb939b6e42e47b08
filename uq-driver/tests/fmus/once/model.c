/*
 * Once: an FMU that keeps its state in the library's globals and so declares
 * canBeInstantiatedOnlyOncePerProcess="true" (see ../README.md).
 *
 * y = x t is integrated step by step in a global (y += x h), and the instance that last
 * initialized is remembered in a global: a step of any other instance of the same loaded copy
 * of the library fails with fmi2Error ("another instance of this library ..."), so an importer
 * that runs two instances on one copy is caught instead of giving wrong numbers. Two copies of
 * the library (loaded from two files) have globals of their own and run side by side.
 * `step_delay` (s, default 0) makes each step sleep that long, so that runs overlap in time.
 * `log_bytes` > 0 (default 0): every step logs a warning of that many bytes, starting with a
 * terminal colour escape; with x > `fail_above` (default 1e300) that step then fails
 * (fmi2Error) after logging such a message as an error.
 */
#define _POSIX_C_SOURCE 199309L
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmu_common.h"

#define GUID "{3b9e6f0c-1d2a-4c5e-9f80-railuq-test-once}"

typedef struct {
    double x;
    double step_delay;
    double log_bytes;
    double fail_above;
    double y; /* output: a copy of the global integral */
} Data;

/* The global state: one per loaded copy of the library. */
static double g_integral;
static const Instance *g_owner;

static const Variable VARIABLES[] = {
    {"time", TYPE_REAL, 0, KIND_INDEPENDENT, 0, 0, 0, 0},
    {"x", TYPE_REAL, 1, KIND_FIXED_PARAMETER, offsetof(Data, x), 0, 0, 0},
    {"y", TYPE_REAL, 2, KIND_OUTPUT, offsetof(Data, y), 0, 0, 0},
    {"step_delay", TYPE_REAL, 3, KIND_FIXED_PARAMETER, offsetof(Data, step_delay), 0, 0, 0},
    {"log_bytes", TYPE_REAL, 4, KIND_FIXED_PARAMETER, offsetof(Data, log_bytes), 0, 0, 0},
    {"fail_above", TYPE_REAL, 5, KIND_FIXED_PARAMETER, offsetof(Data, fail_above), 0, 0, 0},
};

static void set_defaults(void *data) {
    Data *d = (Data *)data;
    d->x = 1.0;
    d->step_delay = 0.0;
    d->log_bytes = 0.0;
    d->fail_above = 1e300;
    d->y = 0.0;
}

static void calculate(Instance *inst) { (void)inst; }

static fmi2Status initialize(Instance *inst) {
    Data *d = (Data *)inst->data;
    g_owner = inst;
    g_integral = d->x * inst->time;
    d->y = g_integral;
    return fmi2OK;
}

static fmi2Status step(Instance *inst, double h) {
    Data *d = (Data *)inst->data;
    if (g_owner != inst) {
        LOG_ERROR(inst, "another instance of this library was initialized since this one: "
                        "its global state is lost (canBeInstantiatedOnlyOncePerProcess)");
        return fmi2Error;
    }
    if (d->step_delay > 0.0) {
        struct timespec t;
        t.tv_sec = (time_t)d->step_delay;
        t.tv_nsec = (long)((d->step_delay - (double)t.tv_sec) * 1e9);
        nanosleep(&t, NULL);
    }
    if (d->log_bytes > 0.0 && d->log_bytes < 1e9) {
        size_t n = (size_t)d->log_bytes;
        char *text = (char *)malloc(n + 1);
        int fail = d->x > d->fail_above;
        if (text != NULL) {
            memset(text, 'w', n);
            memcpy(text, "\x1b[31m", n < 5 ? n : 5);
            text[n] = '\0';
            /* The logger itself: fmu_log would cut the text at 4 KiB. */
            inst->cb.logger(inst->cb.componentEnvironment, inst->name,
                            fail ? fmi2Error : fmi2Warning, "logStatusWarning", "%s", text);
            free(text);
        }
        if (fail) {
            return fmi2Error;
        }
    }
    g_integral += d->x * h;
    inst->time += h;
    d->y = g_integral;
    return fmi2OK;
}

DEFINE_MODEL(NULL);
