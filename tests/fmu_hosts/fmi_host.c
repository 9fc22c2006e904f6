/*
 * fmi_host.c -- a minimal FMI 2.0 Co-Simulation master in plain C, used by
 * tests/fmu_hosts/test_standalone.py to run the standalone gearfmu FMU with no Python in
 * the process (Modelica Association, FMI 2.0 standard, section 4.2: the
 * calling sequence instantiate -> setupExperiment -> enter/exit
 * initialization -> doStep... -> terminate -> freeInstance).
 *
 * usage: fmi_host <unzipped FMU dir> <modelIdentifier> <guid> <stop_time_s> <step_s>
 *                 <output vrs, comma separated> [--state-check] [--resource-uri=URI] [vr=value ...]
 *
 * Prints "time,<vr>,<vr>..." then one CSV row per communication point
 * (%.17g).  With --state-check it also saves the FMU state at the middle
 * of the run, serializes and de-serializes it, runs to the end, restores it,
 * runs the second half again and prints "state-check ok" if both halves agree
 * bit for bit.  Exit code 0 only if every FMI call returned fmi2OK.
 *
 * The binary loaded is binaries/<platform>/<id>.<ext> for the platform this
 * host is compiled for: linux64 (x86_64 Linux), aarch64-linux, win64 (.dll,
 * LoadLibraryW; <unzipped FMU dir> is a Windows path, e.g. Z:/tmp/fmu under
 * Wine), darwin64 (.dylib).  Paths are UTF-8 (on Windows the arguments are read
 * as UTF-16 from the command line and the DLL is loaded by its UTF-16 path, with
 * the long-path prefix \\?\ from 250 characters on).  The resource location is
 * file://<dir>/resources with every byte outside RFC 3986's unreserved set and
 * '/' ':' percent-encoded (UTF-8), or the URI given by --resource-uri.
 */
#ifdef _WIN32
#define __USE_MINGW_ANSI_STDIO 1 /* correctly rounded %.17g with any C runtime */
#include <windows.h>
#include <shellapi.h>
#define FMU_BIN "win64"
#define FMU_EXT ".dll"
typedef HMODULE lib_t;
#define LIB_SYM(lib, name) ((void *)GetProcAddress((lib), (name)))
#else
#include <dlfcn.h>
#if defined(__APPLE__)
#define FMU_BIN "darwin64"
#define FMU_EXT ".dylib"
#elif defined(__aarch64__)
#define FMU_BIN "aarch64-linux"
#define FMU_EXT ".so"
#else
#define FMU_BIN "linux64"
#define FMU_EXT ".so"
#endif
typedef void *lib_t;
#define LIB_SYM(lib, name) dlsym((lib), (name))
#endif
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...)
{
    va_list ap;
    (void)env;
    fprintf(stderr, "[%s %d %s] ", name ? name : "?", (int)status, category ? category : "?");
    va_start(ap, message);
    vfprintf(stderr, message, ap);
    va_end(ap);
    fputc('\n', stderr);
}

#define LOAD(T, name)                                                         \
    T name = (T)LIB_SYM(lib, #name);                                            \
    if (name == NULL) {                                                       \
        fprintf(stderr, "missing symbol %s\n", #name);                        \
        return 2;                                                             \
    }

/* dir + "/resources" as a file URI, percent-encoded (RFC 3986 section 2.1; RFC 8089) */
static void resource_uri(const char *dir, char *uri, size_t cap)
{
    static const char hex[] = "0123456789ABCDEF";
    const unsigned char *p = (const unsigned char *)dir;
    size_t n = (size_t)snprintf(uri, cap, "file://%s", dir[0] == '/' ? "" : "/");
    for (; *p != '\0' && n + 4 < cap; ++p) {
        int c = *p == '\\' ? '/' : *p;
        if ((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || strchr("-._~/:", c)) {
            uri[n++] = (char)c;
        } else {
            uri[n++] = '%';
            uri[n++] = hex[c >> 4];
            uri[n++] = hex[c & 15];
        }
    }
    snprintf(uri + n, cap - n, "/resources");
}

#define CHECK(call)                                                           \
    do {                                                                      \
        fmi2Status st_ = (call);                                              \
        if (st_ != fmi2OK) {                                                  \
            fprintf(stderr, "%s returned %d\n", #call, (int)st_);             \
            return 3;                                                         \
        }                                                                     \
    } while (0)

int main(int argc, char **argv)
{
    char path[4096], uri[12400];
    lib_t lib;
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2Component c;
    fmi2ValueReference outs[256];
    int nout = 0, i, k, nsteps, state_check = 0, argi;
    double stop, step, *rows;
    char *p;

#ifdef _WIN32
    {   /* the arguments as UTF-16 (argv is in the ANSI code page), kept as UTF-8 */
        int wargc, a;
        LPWSTR *wargv = CommandLineToArgvW(GetCommandLineW(), &wargc);
        if (wargv == NULL) return 1;
        argv = (char **)calloc((size_t)wargc + 1, sizeof(char *));
        for (a = 0; a < wargc; ++a) {
            int len = WideCharToMultiByte(CP_UTF8, 0, wargv[a], -1, NULL, 0, NULL, NULL);
            argv[a] = (char *)malloc((size_t)len);
            WideCharToMultiByte(CP_UTF8, 0, wargv[a], -1, argv[a], len, NULL, NULL);
        }
        argc = wargc;
        LocalFree(wargv);
    }
#endif
    if (argc < 7) {
        fprintf(stderr, "usage: %s dir id guid stop step vrs [--state-check] [vr=value ...]\n", argv[0]);
        return 1;
    }
    snprintf(path, sizeof path, "%s/binaries/" FMU_BIN "/%s" FMU_EXT, argv[1], argv[2]);
    resource_uri(argv[1], uri, sizeof uri);
    for (argi = 7; argi < argc; ++argi)
        if (strncmp(argv[argi], "--resource-uri=", 15) == 0) snprintf(uri, sizeof uri, "%s", argv[argi] + 15);
#ifdef _WIN32
    for (p = path; *p != '\0'; ++p)
        if (*p == '/') *p = '\\';
#endif
    stop = atof(argv[4]);
    step = atof(argv[5]);
    for (p = argv[6]; *p != '\0' && nout < 256;) {
        outs[nout++] = (fmi2ValueReference)strtoul(p, &p, 10);
        if (*p == ',') p++;
    }
#ifdef _WIN32
    {   /* the UTF-16 path, with the long-path prefix when it is long */
        wchar_t wpath[4200];
        int off = (strlen(path) >= 250 && path[1] == ':') ? 4 : 0;
        wcscpy(wpath, L"\\\\?\\");
        if (MultiByteToWideChar(CP_UTF8, 0, path, -1, wpath + off, 4000) == 0) return 2;
        lib = LoadLibraryW(wpath);
    }
    if (lib == NULL) {
        fprintf(stderr, "LoadLibrary %s: error %lu\n", path, (unsigned long)GetLastError());
        return 2;
    }
#else
    lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (lib == NULL) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        return 2;
    }
#endif
    {
        LOAD(fmi2InstantiateTYPE *, fmi2Instantiate)
        LOAD(fmi2FreeInstanceTYPE *, fmi2FreeInstance)
        LOAD(fmi2SetupExperimentTYPE *, fmi2SetupExperiment)
        LOAD(fmi2EnterInitializationModeTYPE *, fmi2EnterInitializationMode)
        LOAD(fmi2ExitInitializationModeTYPE *, fmi2ExitInitializationMode)
        LOAD(fmi2TerminateTYPE *, fmi2Terminate)
        LOAD(fmi2SetRealTYPE *, fmi2SetReal)
        LOAD(fmi2GetRealTYPE *, fmi2GetReal)
        LOAD(fmi2DoStepTYPE *, fmi2DoStep)
        LOAD(fmi2GetFMUstateTYPE *, fmi2GetFMUstate)
        LOAD(fmi2SetFMUstateTYPE *, fmi2SetFMUstate)
        LOAD(fmi2FreeFMUstateTYPE *, fmi2FreeFMUstate)
        LOAD(fmi2SerializedFMUstateSizeTYPE *, fmi2SerializedFMUstateSize)
        LOAD(fmi2SerializeFMUstateTYPE *, fmi2SerializeFMUstate)
        LOAD(fmi2DeSerializeFMUstateTYPE *, fmi2DeSerializeFMUstate)

        c = fmi2Instantiate("host", fmi2CoSimulation, argv[3], uri, &cb, fmi2False, fmi2False);
        if (c == NULL) {
            fprintf(stderr, "fmi2Instantiate failed\n");
            return 4;
        }
        CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2True, stop));
        CHECK(fmi2EnterInitializationMode(c));
        for (argi = 7; argi < argc; ++argi) {
            if (strcmp(argv[argi], "--state-check") == 0) {
                state_check = 1;
            } else if (strncmp(argv[argi], "--resource-uri=", 15) == 0) {
                continue;
            } else {
                fmi2ValueReference vr = (fmi2ValueReference)strtoul(argv[argi], &p, 10);
                fmi2Real v;
                if (*p != '=') return 1;
                v = atof(p + 1);
                CHECK(fmi2SetReal(c, &vr, 1, &v));
            }
        }
        CHECK(fmi2ExitInitializationMode(c));
        nsteps = (int)(stop / step + 0.5);
        rows = (double *)calloc((size_t)(nsteps + 1) * (size_t)nout, sizeof(double));
        if (rows == NULL) return 5;
        CHECK(fmi2GetReal(c, outs, (size_t)nout, rows));
        {
            fmi2FMUstate saved = NULL, restored = NULL;
            int mid = nsteps / 2;
            for (k = 1; k <= nsteps; ++k) {
                if (state_check && k - 1 == mid) CHECK(fmi2GetFMUstate(c, &saved));
                CHECK(fmi2DoStep(c, (k - 1) * step, step, fmi2True));
                CHECK(fmi2GetReal(c, outs, (size_t)nout, rows + (size_t)k * nout));
            }
            if (state_check) {
                size_t size = 0;
                fmi2Byte *bytes;
                double *again = (double *)calloc((size_t)nout, sizeof(double));
                CHECK(fmi2SerializedFMUstateSize(c, saved, &size));
                bytes = (fmi2Byte *)malloc(size);
                CHECK(fmi2SerializeFMUstate(c, saved, bytes, size));
                CHECK(fmi2FreeFMUstate(c, &saved));
                CHECK(fmi2DeSerializeFMUstate(c, bytes, size, &restored));
                free(bytes);
                CHECK(fmi2SetFMUstate(c, restored));
                for (k = mid + 1; k <= nsteps; ++k) {
                    CHECK(fmi2DoStep(c, (k - 1) * step, step, fmi2True));
                    CHECK(fmi2GetReal(c, outs, (size_t)nout, again));
                    if (memcmp(again, rows + (size_t)k * nout, sizeof(double) * (size_t)nout) != 0) {
                        fprintf(stderr, "state-check: step %d differs after restoring the state\n", k);
                        return 6;
                    }
                }
                CHECK(fmi2FreeFMUstate(c, &restored));
                free(again);
            }
        }
        CHECK(fmi2Terminate(c));
        fmi2FreeInstance(c);
    }
    printf("time");
    for (i = 0; i < nout; ++i) printf(",%u", outs[i]);
    printf("\n");
    for (k = 0; k <= nsteps; ++k) {
        printf("%.17g", k * step);
        for (i = 0; i < nout; ++i) printf(",%.17g", rows[(size_t)k * nout + i]);
        printf("\n");
    }
    if (state_check) printf("state-check ok\n");
    free(rows);
#ifdef _WIN32
    FreeLibrary(lib);
#else
    dlclose(lib);
#endif
    return 0;
}
