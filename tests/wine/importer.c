/* A minimal FMI 2.0 Co-Simulation importer for Windows, built with mingw-w64 and run under
 * Wine by tests/python/test_win64_wine.py against the win64 DLL of a railuq FMU.
 *
 *   importer.exe DLL GUID RESOURCE_URI run STOP DT SETS GETS
 *       SETS: "vr=value,..." set before initialization ("-": none); a Real by default,
 *             "i:vr=value" an Integer, "s:vr=text" a String (text without commas);
 *       GETS: "vr,..." Reals read after initialization and after every step.
 *       Prints one CSV line per communication point t_i = i * DT: t_i, then each GETS value,
 *       all with 17 significant digits.
 *   importer.exe DLL GUID RESOURCE_URI wrong-state FIXED_VR
 *       Calls made in the wrong state (or with a wrong GUID); prints "check value" lines.
 *
 * Every mode first resolves all 34 fmi2 functions with GetProcAddress (exit 2 if one is
 * missing) and prints fmi2GetVersion and fmi2GetTypesPlatform. Log messages go to stderr. */
#include <windows.h>

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2FunctionTypes.h"

#define FUNCTIONS(X)                                                                          \
    X(GetTypesPlatform) X(GetVersion) X(SetDebugLogging) X(Instantiate) X(FreeInstance)       \
    X(SetupExperiment) X(EnterInitializationMode) X(ExitInitializationMode) X(Terminate)      \
    X(Reset) X(GetReal) X(GetInteger) X(GetBoolean) X(GetString) X(SetReal) X(SetInteger)     \
    X(SetBoolean) X(SetString) X(GetFMUstate) X(SetFMUstate) X(FreeFMUstate)                  \
    X(SerializedFMUstateSize) X(SerializeFMUstate) X(DeSerializeFMUstate)                     \
    X(GetDirectionalDerivative) X(SetRealInputDerivatives) X(GetRealOutputDerivatives)        \
    X(DoStep) X(CancelStep) X(GetStatus) X(GetRealStatus) X(GetIntegerStatus)                 \
    X(GetBooleanStatus) X(GetStringStatus)

#define DECLARE(name) static fmi2##name##TYPE *fmi2##name;
FUNCTIONS(DECLARE)

#define MAX_VARS 256

static int errors_logged = 0;

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    char buf[2048];
    va_list ap;
    (void)env;
    va_start(ap, message);
    vsnprintf(buf, sizeof buf, message, ap);
    va_end(ap);
    if (status == fmi2Error || status == fmi2Fatal) errors_logged++;
    fprintf(stderr, "[%s] %s (status %d): %s\n", category ? category : "?",
            instance ? instance : "?", (int)status, buf);
}

static const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

static int load(const char *dll) {
    HMODULE h = LoadLibraryA(dll);
    int missing = 0;
    if (!h) {
        fprintf(stderr, "LoadLibrary(%s) failed: error %lu\n", dll, GetLastError());
        return 0;
    }
#define RESOLVE(name)                                                                         \
    fmi2##name = (fmi2##name##TYPE *)(void *)GetProcAddress(h, "fmi2" #name);                \
    if (!fmi2##name) {                                                                        \
        fprintf(stderr, "missing export: fmi2" #name "\n");                                   \
        missing++;                                                                            \
    }
    FUNCTIONS(RESOLVE)
    printf("exports-missing %d\n", missing);
    return missing == 0;
}

/* One value to set before initialization. */
typedef struct {
    char type; /* 'r', 'i' or 's' */
    fmi2ValueReference vr;
    fmi2Real real;
    fmi2Integer integer;
    const char *string;
} Setting;

/* Parses SETS (see above) in place; returns the count, or -1. */
static int parse_sets(char *s, Setting out[]) {
    int n = 0;
    char *item;
    if (strcmp(s, "-") == 0) return 0;
    for (item = strtok(s, ","); item; item = strtok(NULL, ",")) {
        Setting *x = &out[n];
        char *end, *value;
        if (n == MAX_VARS) return -1;
        x->type = 'r';
        if ((item[0] == 'i' || item[0] == 's') && item[1] == ':') {
            x->type = item[0];
            item += 2;
        }
        x->vr = (fmi2ValueReference)strtoul(item, &end, 10);
        if (end == item || *end != '=') return -1;
        value = end + 1;
        if (x->type == 'r') x->real = strtod(value, &end);
        if (x->type == 'i') x->integer = (fmi2Integer)strtol(value, &end, 10);
        if (x->type == 's') x->string = value;
        else if (end == value || *end) return -1;
        n++;
    }
    return n;
}

/* Parses "a,b,c" (value references); returns the count, or -1. */
static int parse_refs(const char *s, fmi2ValueReference vr[]) {
    int n = 0;
    while (*s) {
        char *end;
        if (n == MAX_VARS) return -1;
        vr[n] = (fmi2ValueReference)strtoul(s, &end, 10);
        if (end == s) return -1;
        s = end;
        n++;
        if (*s == ',') s++;
        else if (*s) return -1;
    }
    return n;
}

static fmi2Status apply(fmi2Component c, const Setting *x) {
    switch (x->type) {
    case 'i': return fmi2SetInteger(c, &x->vr, 1, &x->integer);
    case 's': return fmi2SetString(c, &x->vr, 1, &x->string);
    default: return fmi2SetReal(c, &x->vr, 1, &x->real);
    }
}

#define CHECK(call)                                                                           \
    do {                                                                                      \
        fmi2Status st_ = (call);                                                              \
        if (st_ != fmi2OK) {                                                                  \
            fprintf(stderr, "%s returned %d\n", #call, (int)st_);                            \
            return 1;                                                                         \
        }                                                                                     \
    } while (0)

static int run(const char *guid, const char *uri, int argc, char **argv) {
    Setting sets[MAX_VARS];
    fmi2ValueReference get_vr[MAX_VARS];
    fmi2Real got[MAX_VARS];
    double stop, dt;
    long n, i;
    int nset, nget, k;
    fmi2Component c;
    if (argc != 4) return 2;
    stop = strtod(argv[0], NULL);
    dt = strtod(argv[1], NULL);
    nset = parse_sets(argv[2], sets);
    nget = parse_refs(argv[3], get_vr);
    if (!(dt > 0) || !(stop > 0) || nset < 0 || nget <= 0) return 2;
    n = lround(stop / dt);

    c = fmi2Instantiate("wine", fmi2CoSimulation, guid, uri, &callbacks, fmi2False, fmi2False);
    if (!c) {
        fprintf(stderr, "fmi2Instantiate returned NULL\n");
        return 1;
    }
    for (k = 0; k < nset; k++) CHECK(apply(c, &sets[k]));
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2True, stop));
    CHECK(fmi2EnterInitializationMode(c));
    CHECK(fmi2ExitInitializationMode(c));
    for (i = 0; i <= n; i++) {
        double t = (double)i * dt;
        CHECK(fmi2GetReal(c, get_vr, (size_t)nget, got));
        printf("%.17g", t);
        for (k = 0; k < nget; k++) printf(",%.17g", got[k]);
        printf("\n");
        if (i < n) CHECK(fmi2DoStep(c, t, dt, fmi2True));
    }
    CHECK(fmi2Terminate(c));
    fmi2FreeInstance(c);
    return 0;
}

static int wrong_state(const char *guid, const char *uri, int argc, char **argv) {
    fmi2ValueReference fixed;
    fmi2Real value = 1.0;
    fmi2Component c;
    int before;
    if (argc != 1) return 2;
    fixed = (fmi2ValueReference)strtoul(argv[0], NULL, 10);

    c = fmi2Instantiate("wrong-guid", fmi2CoSimulation, "{not-the-guid}", uri, &callbacks,
                        fmi2False, fmi2False);
    printf("instantiate-wrong-guid %s\n", c ? "instance" : "null");
    if (c) fmi2FreeInstance(c);

    /* fmi2DoStep before initialization. */
    c = fmi2Instantiate("early-step", fmi2CoSimulation, guid, uri, &callbacks, fmi2False,
                        fmi2False);
    if (!c) return 1;
    before = errors_logged;
    printf("do-step-before-initialization %d\n", (int)fmi2DoStep(c, 0.0, 0.01, fmi2True));
    printf("errors-logged %d\n", errors_logged - before);
    fmi2FreeInstance(c);

    /* A fixed parameter set after initialization. */
    c = fmi2Instantiate("late-set", fmi2CoSimulation, guid, uri, &callbacks, fmi2False,
                        fmi2False);
    if (!c) return 1;
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK(fmi2EnterInitializationMode(c));
    CHECK(fmi2ExitInitializationMode(c));
    printf("set-fixed-after-initialization %d\n", (int)fmi2SetReal(c, &fixed, 1, &value));
    fmi2FreeInstance(c);
    return 0;
}

int main(int argc, char **argv) {
    if (argc < 5) {
        fprintf(stderr, "usage: importer.exe DLL GUID RESOURCE_URI run|wrong-state ...\n");
        return 2;
    }
    setvbuf(stdout, NULL, _IOFBF, 1 << 16);
    if (!load(argv[1])) return 2;
    printf("version %s\ntypes-platform %s\n", fmi2GetVersion(), fmi2GetTypesPlatform());
    if (strcmp(argv[4], "run") == 0) return run(argv[2], argv[3], argc - 5, argv + 5);
    if (strcmp(argv[4], "wrong-state") == 0)
        return wrong_state(argv[2], argv[3], argc - 5, argv + 5);
    return 2;
}
