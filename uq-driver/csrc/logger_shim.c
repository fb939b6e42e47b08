/*
 * The fmi2CallbackLogger that uq-driver hands to FMUs.
 *
 * FMI 2.0's logger is a variadic C function, which stable Rust cannot define. This shim formats
 * the message with vsnprintf (sizing it first, so long messages are not truncated) and passes
 * the finished text to a Rust function.
 *
 * componentEnvironment points to a Rust `LogSink` (#[repr(C)]) whose first field is that Rust
 * function, so no global symbol is needed in either direction.
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

typedef void (*uq_driver_sink_fn)(void *env, const char *instance_name, int status,
                                  const char *category, const char *message);

typedef struct {
    uq_driver_sink_fn sink; /* must stay the first field of the Rust LogSink */
} uq_driver_log_env;

void uq_driver_fmi2_logger(void *env, const char *instance_name, int status,
                           const char *category, const char *message, ...) {
    uq_driver_log_env *e = (uq_driver_log_env *)env;
    char small[512];
    char *heap = NULL;
    const char *text = "";
    va_list args;
    va_list again;
    int n;

    if (e == NULL || e->sink == NULL) {
        return;
    }
    if (message != NULL) {
        va_start(args, message);
        va_copy(again, args);
        n = vsnprintf(small, sizeof small, message, args);
        if (n < 0) {
            text = message; /* formatting failed: pass the format string itself */
        } else if ((size_t)n < sizeof small) {
            text = small;
        } else {
            heap = (char *)malloc((size_t)n + 1);
            if (heap != NULL && vsnprintf(heap, (size_t)n + 1, message, again) >= 0) {
                text = heap;
            } else {
                text = small; /* out of memory: keep the truncated text */
            }
        }
        va_end(again);
        va_end(args);
    }
    e->sink(env, instance_name, status, category, text);
    free(heap);
}
