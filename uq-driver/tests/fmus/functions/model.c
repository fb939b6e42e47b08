/*
 * Functions: analytic UQ benchmarks as an FMI 2.0 Co-Simulation FMU (see ../README.md for the
 * formulas, the reference values and the hash of the two-level test).
 *
 * The Integer parameter `function` selects
 *   1 Ishigami      y = sin x1 + a sin^2 x2 + b x3^4 sin x1
 *   2 borehole      y = 2 pi Tu (Hu - Hl) / ( ln(r/rw) (1 + 2 L Tu / (ln(r/rw) rw^2 Kw) + Tu/Tl) )
 *                   (water flow through a borehole, m^3/yr)
 *   3 g-function    y = prod_{i=1..8} (|4 x_i - 2| + a_i) / (1 + a_i)
 *   4 two-level     y = f_x + sigma_h h_seed, f_x = x1 + x2^2, h_seed = a standard normal
 *                   obtained by hashing the Integer parameter `seed` (SplitMix64 + Box-Muller)
 *   5 linear        y = x1 + x2 + ... + x8 (closed-form tails for normal inputs)
 *   6 sum of squares y = x1^2 + x2^2 + ... + x8^2 (a chi-square for standard normal inputs)
 *   7 product       y = x1 x2 ... x8 (lognormal inputs: ln y is normal, closed-form tails)
 *   8 g-function 20 y = prod_{i=1..20} (|4 x_i - 2| + a_i) / (1 + a_i) (twenty inputs)
 * y is computed once at the end of initialization; the time-varying output is
 * y_t = y (1 + t). f_x and h_seed are outputs too (for the other functions f_x = y, h_seed = 0).
 * One fmi2DoStep is an addition and a multiplication.
 */
#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "fmu_common.h"

#define PI 3.14159265358979323846
#define GUID "{d6f1c9a4-5b3e-4f1a-8c2d-railuq-test-functions}"

enum { ISHIGAMI = 1, BOREHOLE = 2, G_FUNCTION = 3, TWO_LEVEL = 4, LINEAR = 5, SQUARES = 6,
       PRODUCT = 7, G_FUNCTION_20 = 8 };

typedef struct {
    fmi2Integer function;
    double x[20];
    double a, b;                            /* Ishigami */
    double rw, r, Tu, Hu, Tl, Hl, L, Kw;    /* borehole */
    double g_a[20];                         /* g-function coefficients a1..a20 */
    fmi2Integer seed;                       /* two-level */
    double sigma_h;
    double y, y_t, f_x, h_seed;             /* outputs */
} Data;

#define REAL_PARAMETER(name, vr, field) \
    {name, TYPE_REAL, vr, KIND_FIXED_PARAMETER, offsetof(Data, field), 0, 0, 0}
#define REAL_OUTPUT(name, vr, field) \
    {name, TYPE_REAL, vr, KIND_OUTPUT, offsetof(Data, field), 0, 0, 0}

/* Value references: Real 0..55, Integer 0..1 (as in modelDescription.xml). */
static const Variable VARIABLES[] = {
    {"time", TYPE_REAL, 0, KIND_INDEPENDENT, 0, 0, 0, 0},
    REAL_OUTPUT("y", 1, y),
    REAL_OUTPUT("y_t", 2, y_t),
    REAL_OUTPUT("f_x", 3, f_x),
    REAL_OUTPUT("h_seed", 4, h_seed),
    REAL_PARAMETER("x1", 5, x[0]),
    REAL_PARAMETER("x2", 6, x[1]),
    REAL_PARAMETER("x3", 7, x[2]),
    REAL_PARAMETER("x4", 8, x[3]),
    REAL_PARAMETER("x5", 9, x[4]),
    REAL_PARAMETER("x6", 10, x[5]),
    REAL_PARAMETER("x7", 11, x[6]),
    REAL_PARAMETER("x8", 12, x[7]),
    REAL_PARAMETER("a", 13, a),
    REAL_PARAMETER("b", 14, b),
    REAL_PARAMETER("rw", 15, rw),
    REAL_PARAMETER("r", 16, r),
    REAL_PARAMETER("Tu", 17, Tu),
    REAL_PARAMETER("Hu", 18, Hu),
    REAL_PARAMETER("Tl", 19, Tl),
    REAL_PARAMETER("Hl", 20, Hl),
    REAL_PARAMETER("L", 21, L),
    REAL_PARAMETER("Kw", 22, Kw),
    REAL_PARAMETER("a1", 23, g_a[0]),
    REAL_PARAMETER("a2", 24, g_a[1]),
    REAL_PARAMETER("a3", 25, g_a[2]),
    REAL_PARAMETER("a4", 26, g_a[3]),
    REAL_PARAMETER("a5", 27, g_a[4]),
    REAL_PARAMETER("a6", 28, g_a[5]),
    REAL_PARAMETER("a7", 29, g_a[6]),
    REAL_PARAMETER("a8", 30, g_a[7]),
    REAL_PARAMETER("sigma_h", 31, sigma_h),
    REAL_PARAMETER("x9", 32, x[8]),
    REAL_PARAMETER("x10", 33, x[9]),
    REAL_PARAMETER("x11", 34, x[10]),
    REAL_PARAMETER("x12", 35, x[11]),
    REAL_PARAMETER("x13", 36, x[12]),
    REAL_PARAMETER("x14", 37, x[13]),
    REAL_PARAMETER("x15", 38, x[14]),
    REAL_PARAMETER("x16", 39, x[15]),
    REAL_PARAMETER("x17", 40, x[16]),
    REAL_PARAMETER("x18", 41, x[17]),
    REAL_PARAMETER("x19", 42, x[18]),
    REAL_PARAMETER("x20", 43, x[19]),
    REAL_PARAMETER("a9", 44, g_a[8]),
    REAL_PARAMETER("a10", 45, g_a[9]),
    REAL_PARAMETER("a11", 46, g_a[10]),
    REAL_PARAMETER("a12", 47, g_a[11]),
    REAL_PARAMETER("a13", 48, g_a[12]),
    REAL_PARAMETER("a14", 49, g_a[13]),
    REAL_PARAMETER("a15", 50, g_a[14]),
    REAL_PARAMETER("a16", 51, g_a[15]),
    REAL_PARAMETER("a17", 52, g_a[16]),
    REAL_PARAMETER("a18", 53, g_a[17]),
    REAL_PARAMETER("a19", 54, g_a[18]),
    REAL_PARAMETER("a20", 55, g_a[19]),
    {"function", TYPE_INTEGER, 0, KIND_FIXED_PARAMETER, offsetof(Data, function), 1, ISHIGAMI,
     G_FUNCTION_20},
    {"seed", TYPE_INTEGER, 1, KIND_FIXED_PARAMETER, offsetof(Data, seed), 0, 0, 0},
};

static void set_defaults(void *data) {
    static const double g_a[8] = {0.0, 1.0, 4.5, 9.0, 99.0, 99.0, 99.0, 99.0};
    Data *d = (Data *)data;
    int i;
    d->function = ISHIGAMI;
    for (i = 0; i < 20; i++) {
        d->x[i] = 0.0;
        d->g_a[i] = i < 8 ? g_a[i] : 99.0;
    }
    d->a = 7.0;
    d->b = 0.1;
    /* The borehole inputs at the middle of their usual ranges. */
    d->rw = 0.1;
    d->r = 25050.0;
    d->Tu = 89335.0;
    d->Hu = 1050.0;
    d->Tl = 89.55;
    d->Hl = 760.0;
    d->L = 1400.0;
    d->Kw = 10950.0;
    d->seed = 0;
    d->sigma_h = 1.0;
}

static double ishigami(const Data *d) {
    const double s1 = sin(d->x[0]), s2 = sin(d->x[1]), x3 = d->x[2];
    return s1 + d->a * s2 * s2 + d->b * x3 * x3 * x3 * x3 * s1;
}

static double borehole(const Data *d) {
    const double log_ratio = log(d->r / d->rw);
    const double denominator =
        log_ratio * (1.0 + 2.0 * d->L * d->Tu / (log_ratio * d->rw * d->rw * d->Kw) + d->Tu / d->Tl);
    return 2.0 * PI * d->Tu * (d->Hu - d->Hl) / denominator;
}

static double g_function(const Data *d, int inputs) {
    double y = 1.0;
    int i;
    for (i = 0; i < inputs; i++) y *= (fabs(4.0 * d->x[i] - 2.0) + d->g_a[i]) / (1.0 + d->g_a[i]);
    return y;
}

/* SplitMix64 (Steele, Lea & Flood 2014): the state advances by the golden gamma, the output is
 * the state mixed. */
static uint64_t splitmix64_next(uint64_t *state) {
    uint64_t z = (*state += UINT64_C(0x9E3779B97F4A7C15));
    z = (z ^ (z >> 30)) * UINT64_C(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94D049BB133111EB);
    return z ^ (z >> 31);
}

/* A standard normal from the seed: state = seed as a 64-bit two's complement integer,
 * u1 = ((z1 >> 11) + 0.5) / 2^53 in (0, 1), u2 = (z2 >> 11) / 2^53 in [0, 1) from the first two
 * SplitMix64 outputs z1, z2, then Box-Muller: sqrt(-2 ln u1) cos(2 pi u2). */
static double hashed_normal(fmi2Integer seed) {
    uint64_t state = (uint64_t)(int64_t)seed;
    const double u1 = ((double)(splitmix64_next(&state) >> 11) + 0.5) * 0x1.0p-53;
    const double u2 = (double)(splitmix64_next(&state) >> 11) * 0x1.0p-53;
    return sqrt(-2.0 * log(u1)) * cos(2.0 * PI * u2);
}

static void calculate(Instance *inst) {
    Data *d = (Data *)inst->data;
    d->h_seed = 0.0;
    switch (d->function) {
    case ISHIGAMI: d->f_x = ishigami(d); break;
    case BOREHOLE: d->f_x = borehole(d); break;
    case G_FUNCTION: d->f_x = g_function(d, 8); break;
    case G_FUNCTION_20: d->f_x = g_function(d, 20); break;
    case TWO_LEVEL:
        d->f_x = d->x[0] + d->x[1] * d->x[1];
        d->h_seed = hashed_normal(d->seed);
        break;
    case LINEAR:
    case SQUARES: {
        int i;
        d->f_x = 0.0;
        for (i = 0; i < 8; i++) d->f_x += d->function == LINEAR ? d->x[i] : d->x[i] * d->x[i];
        break;
    }
    case PRODUCT: {
        int i;
        d->f_x = 1.0;
        for (i = 0; i < 8; i++) d->f_x *= d->x[i];
        break;
    }
    default: d->f_x = NAN; break;
    }
    d->y = d->f_x + d->sigma_h * d->h_seed;
    d->y_t = d->y * (1.0 + inst->time);
}

static fmi2Status initialize(Instance *inst) {
    const Data *d = (const Data *)inst->data;
    int i;
    if (d->function == BOREHOLE && !(d->rw > 0.0 && d->r > d->rw && d->Tl > 0.0 && d->Kw > 0.0)) {
        LOG_ERROR(inst, "borehole: needs 0 < rw < r, Tl > 0 and Kw > 0 (rw = %g, r = %g, "
                        "Tl = %g, Kw = %g)",
                  d->rw, d->r, d->Tl, d->Kw);
        return fmi2Error;
    }
    if (d->function == G_FUNCTION || d->function == G_FUNCTION_20) {
        for (i = 0; i < (d->function == G_FUNCTION ? 8 : 20); i++) {
            if (!(d->g_a[i] >= 0.0)) {
                LOG_ERROR(inst, "g-function: a%d = %g, the coefficients must be >= 0", i + 1,
                          d->g_a[i]);
                return fmi2Error;
            }
        }
    }
    if (!isfinite(d->y)) {
        LOG_ERROR(inst, "function %d gives y = %g for these parameters", (int)d->function, d->y);
        return fmi2Error;
    }
    LOG_INFO(inst, "function %d: y = %.17g", (int)d->function, d->y);
    return fmi2OK;
}

static fmi2Status step(Instance *inst, double h) {
    Data *d = (Data *)inst->data;
    inst->time += h;
    d->y_t = d->y * (1.0 + inst->time);
    return fmi2OK;
}

DEFINE_MODEL(NULL);
