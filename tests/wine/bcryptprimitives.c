/* Test-only stand-in for Windows' bcryptprimitives.dll, which Debian 12's Wine 8.0 lacks.
 * Rust's standard library for Windows imports ProcessPrng from it (to seed HashMap keys; the
 * FMU never calls it, but the loader needs the import resolved). Every Windows that Rust's
 * x86_64-pc-windows-gnu target supports (10 and later) ships the real one. Built with
 * mingw-w64 beside the test importer, so only the Wine test ever loads it. */
#include <windows.h>

/* RtlGenRandom, exported by advapi32 as SystemFunction036. */
BOOLEAN WINAPI SystemFunction036(PVOID buffer, ULONG length);

__declspec(dllexport) BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T length) {
    while (length > 0) {
        ULONG n = length > 0x10000000 ? 0x10000000 : (ULONG)length;
        if (!SystemFunction036(data, n)) return FALSE;
        data += n;
        length -= n;
    }
    return TRUE;
}
