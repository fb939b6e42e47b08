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
 */
#define _POSIX_C_SOURCE 199309L
#include <stddef.h>
#include <time.h>

#include "fmu_common.h"

#define GUID "{3b9e6f0c-1d2a-4c5e-9f80-railuq-test-once}"

typedef struct {
    double x;
    double step_delay;
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
};

static void set_defaults(void *data) {
    Data *d = (Data *)data;
    d->x = 1.0;
    d->step_delay = 0.0;
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
    g_integral += d->x * h;
    inst->time += h;
    d->y = g_integral;
    return fmi2OK;
}

const ModelInfo MODEL = {
    GUID,
    VARIABLES,
    sizeof VARIABLES / sizeof VARIABLES[0],
    sizeof(Data),
    set_defaults,
    calculate,
    initialize,
    step,
};
