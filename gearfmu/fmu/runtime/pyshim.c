/*
 * pyshim.c -- the FMI 2.0 binary of a gearfmu FMU built with the pythonfmu
 * runtime (docs/fmu.md "The binary: a loader in front of pythonfmu's wrapper").
 *
 * pythonfmu's FMI wrapper needs the Python interpreter's symbols when it is
 * loaded, starts the interpreter behind a lock of its own (one per FMU, since
 * every FMU carries its own copy of the wrapper) and crashes on any failure
 * of the slave's import.  This library has no link-time dependency on Python:
 * it exports the fmi2* functions, and on the first fmi2Instantiate
 *
 *  1. finds libpython: already in the process (dlsym(RTLD_DEFAULT,
 *     "Py_IsInitialized")), else the path recorded at build time in
 *     resources/gearfmu_pyshim.txt, else its soname through the loader; it is
 *     loaded RTLD_GLOBAL so that the wrapper's Python symbols resolve;
 *  2. starts the interpreter if nobody has, under a process-wide lock shared
 *     by every gearfmu FMU in the process: flock() on a per-process lock file
 *     (each FMU's copy of this library opens the file itself; flock locks of
 *     separate open file descriptions conflict even within one process); the
 *     lock is taken even when the interpreter reports itself initialized, since
 *     that flag is set before site-packages is on sys.path;
 *  3. imports the modules the slave needs from outside the FMU (ctypes,
 *     numpy) and refuses to instantiate, with a message through the host's
 *     logger, if one is missing;
 *  4. loads pythonfmu's wrapper, shipped beside this library under another
 *     name, and forwards every fmi2 call to it;
 *  5. registers an exit handler that releases the wrapper's interpreter state
 *     before the wrapper's own static destructor runs (the order pythonfmu's
 *     library gets wrong at process exit).
 *
 * Any failure returns NULL from fmi2Instantiate with a logged message; no
 * failure path reaches the wrapper.  Linux only (dlopen, flock).
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>
#include <wchar.h>

#include "fmi2Functions.h"

#define CONFIG_FILE "gearfmu_pyshim.txt"
#define EXPORT __attribute__((visibility("default")))

/* ---- the part of the Python C API used here (stable ABI, resolved with dlsym) ---- */
typedef void PyObj;
static struct {
    int (*IsInitialized)(void);
    void (*InitializeEx)(int);
    void *(*EvalSaveThread)(void);
    int (*GILStateEnsure)(void);
    void (*GILStateRelease)(int);
    PyObj *(*ImportModule)(const char *);
    void (*ErrFetch)(PyObj **, PyObj **, PyObj **);
    PyObj *(*ObjectStr)(PyObj *);
    const char *(*UnicodeAsUTF8)(PyObj *);
    void (*DecRef)(PyObj *);
    const char *(*GetVersion)(void);
    void (*SetProgramName)(const wchar_t *);        /* absent from Python 3.13 on */
    wchar_t *(*DecodeLocale)(const char *, size_t *);
} py;

/* ---- the wrapper's functions ---- */
#define FMI2_FORWARDED(X)                                                                         \
    X(SetDebugLogging) X(Instantiate) X(FreeInstance) X(SetupExperiment) X(EnterInitializationMode) \
    X(ExitInitializationMode) X(Terminate) X(Reset) X(GetReal) X(GetInteger) X(GetBoolean)          \
    X(GetString) X(SetReal) X(SetInteger) X(SetBoolean) X(SetString) X(GetFMUstate)                \
    X(SetFMUstate) X(FreeFMUstate) X(SerializedFMUstateSize) X(SerializeFMUstate)                   \
    X(DeSerializeFMUstate) X(GetDirectionalDerivative) X(SetRealInputDerivatives)                   \
    X(GetRealOutputDerivatives) X(DoStep) X(CancelStep) X(GetStatus) X(GetRealStatus)               \
    X(GetIntegerStatus) X(GetBooleanStatus) X(GetStringStatus)

#define FIELD(n) fmi2##n##TYPE *n;
static struct {
    FMI2_FORWARDED(FIELD)
    void (*finalize)(void);
} W;
static int loaded = 0;
static pthread_mutex_t load_mutex = PTHREAD_MUTEX_INITIALIZER;

typedef struct {
    char python_version[32], libpython[PATH_MAX], libpython_soname[128], python_executable[PATH_MAX],
        wrapper[256];
} shim_config;

static void fail(char *err, size_t n, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void fail(char *err, size_t n, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, n, fmt, ap);
    va_end(ap);
}

static int read_config(const char *path, shim_config *cfg, char *err, size_t n)
{
    char line[PATH_MAX + 64];
    FILE *f = fopen(path, "r");
    memset(cfg, 0, sizeof *cfg);
    if (f == NULL) {
        fail(err, n, "cannot read %s (%s); the FMU is incomplete, rebuild it", path, strerror(errno));
        return -1;
    }
    while (fgets(line, sizeof line, f) != NULL) {
        char *eq = strchr(line, '='), *end;
        if (eq == NULL) continue;
        *eq++ = '\0';
        end = eq + strcspn(eq, "\r\n");
        *end = '\0';
#define KEY(k)                                                                  \
    if (strcmp(line, #k) == 0) snprintf(cfg->k, sizeof cfg->k, "%s", eq);
        KEY(python_version) KEY(libpython) KEY(libpython_soname) KEY(python_executable) KEY(wrapper)
#undef KEY
    }
    fclose(f);
    if (cfg->wrapper[0] == '\0' || strchr(cfg->wrapper, '/') != NULL) {
        fail(err, n, "%s: no valid 'wrapper' entry; the FMU is incomplete, rebuild it", path);
        return -1;
    }
    return 0;
}

/* 1. libpython: already loaded, else the recorded path, else the soname.  *h is the
 * handle to resolve the Python API from (RTLD_DEFAULT, which is NULL on glibc, when the
 * process already has it). */
static int find_libpython(const shim_config *cfg, void **h, char *err, size_t n)
{
    const char *e1 = "", *e2 = "";
    char m1[512] = "", m2[512] = "";
    *h = RTLD_DEFAULT;
    if (dlsym(RTLD_DEFAULT, "Py_IsInitialized") != NULL) return 0;
    if (cfg->libpython[0] != '\0') {
        if ((*h = dlopen(cfg->libpython, RTLD_NOW | RTLD_GLOBAL)) != NULL) return 0;
        e1 = dlerror();
        snprintf(m1, sizeof m1, "%s", e1 ? e1 : "?");
    }
    if (cfg->libpython_soname[0] != '\0') {
        if ((*h = dlopen(cfg->libpython_soname, RTLD_NOW | RTLD_GLOBAL)) != NULL) return 0;
        e2 = dlerror();
        snprintf(m2, sizeof m2, "%s", e2 ? e2 : "?");
    }
    fail(err, n,
         "the pythonfmu runtime needs Python %s's shared library: it is not loaded in this process, "
         "not at the path recorded at build time (%s) and not found by the dynamic loader (%s); "
         "install Python %s with its shared library (or add its directory to LD_LIBRARY_PATH), "
         "or rebuild the FMU with --runtime standalone (no Python needed)",
         cfg->python_version, m1[0] ? m1 : "none recorded", m2[0] ? m2 : "no soname recorded",
         cfg->python_version);
    return -1;
}

static int bind_python(void *h, char *err, size_t n)
{
#define SYM(field, name)                                                             \
    *(void **)(&py.field) = dlsym(h, name);                                          \
    if (py.field == NULL) {                                                          \
        fail(err, n, "the Python library in this process lacks %s", name);           \
        return -1;                                                                   \
    }
    SYM(IsInitialized, "Py_IsInitialized")
    SYM(InitializeEx, "Py_InitializeEx")
    SYM(EvalSaveThread, "PyEval_SaveThread")
    SYM(GILStateEnsure, "PyGILState_Ensure")
    SYM(GILStateRelease, "PyGILState_Release")
    SYM(ImportModule, "PyImport_ImportModule")
    SYM(ErrFetch, "PyErr_Fetch")
    SYM(ObjectStr, "PyObject_Str")
    SYM(UnicodeAsUTF8, "PyUnicode_AsUTF8")
    SYM(DecRef, "Py_DecRef")
    SYM(GetVersion, "Py_GetVersion")
#undef SYM
    *(void **)(&py.SetProgramName) = dlsym(h, "Py_SetProgramName");
    *(void **)(&py.DecodeLocale) = dlsym(h, "Py_DecodeLocale");
    return 0;
}

/* 2. The process-wide guard: flock() on a lock file named after this process. */
static int process_lock(char *path, size_t n)
{
    const char *dir = getenv("XDG_RUNTIME_DIR");
    struct stat st;
    int fd;
    if (dir == NULL || dir[0] == '\0' || stat(dir, &st) != 0 || !S_ISDIR(st.st_mode)) dir = getenv("TMPDIR");
    if (dir == NULL || dir[0] == '\0') dir = "/tmp";
    snprintf(path, n, "%s/gearfmu-pyinit-%lu-%ld.lock", dir, (unsigned long)getuid(), (long)getpid());
    fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0600);
    if (fd < 0) return -1;
    while (flock(fd, LOCK_EX) != 0) {
        if (errno != EINTR) {
            close(fd);
            return -1;
        }
    }
    return fd;
}

static int start_interpreter(const shim_config *cfg, char *err, size_t n)
{
    char lock_path[PATH_MAX];
    int fd, ok;
    /* Always through the lock, even when Py_IsInitialized() already says 1: CPython sets
     * that flag before it imports site (which puts site-packages, numpy's home, on
     * sys.path), so another FMU's start may still be under way; the lock is held until
     * that start has returned. */
    fd = process_lock(lock_path, sizeof lock_path);
    if (fd < 0) {
        if (py.IsInitialized()) return 0; /* started by the host itself, which needs no lock file */
        fail(err, n, "cannot open or lock %s (%s): the Python interpreter is not started without the "
                     "lock that keeps several FMUs from starting it at once", lock_path, strerror(errno));
        return -1;
    }
    if (!py.IsInitialized()) {
        /* the Python environment the FMU was built with (its site-packages hold numpy) */
        if (py.SetProgramName != NULL && py.DecodeLocale != NULL && cfg->python_executable[0] != '\0' &&
            access(cfg->python_executable, X_OK) == 0) {
            static wchar_t *program = NULL; /* must outlive the interpreter */
            if (program == NULL) program = py.DecodeLocale(cfg->python_executable, NULL);
            if (program != NULL) py.SetProgramName(program);
        }
        py.InitializeEx(0); /* 0: no Python signal handlers in the host */
        if (py.IsInitialized()) py.EvalSaveThread(); /* release the GIL; never finalized */
    }
    ok = py.IsInitialized();
    unlink(lock_path); /* after the interpreter is up: a later opener finds it initialized */
    flock(fd, LOCK_UN);
    close(fd);
    if (!ok) {
        fail(err, n, "Python %s failed to start", cfg->python_version);
        return -1;
    }
    return 0;
}

/* 3. The modules the slave imports from outside the FMU. */
static int check_modules(char *err, size_t n)
{
    static const char *const needed[] = {"ctypes", "numpy"};
    size_t i;
    int rc = 0, g = py.GILStateEnsure();
    for (i = 0; i < sizeof needed / sizeof needed[0] && rc == 0; ++i) {
        PyObj *m = py.ImportModule(needed[i]);
        if (m != NULL) {
            py.DecRef(m);
        } else {
            PyObj *t = NULL, *v = NULL, *tb = NULL, *s = NULL;
            const char *why = NULL;
            py.ErrFetch(&t, &v, &tb);
            if (v != NULL) s = py.ObjectStr(v);
            if (s != NULL) why = py.UnicodeAsUTF8(s);
            const char *ver = py.GetVersion();
            fail(err, n,
                 "the pythonfmu runtime needs the Python module '%s', which cannot be imported in the "
                 "Python %.*s running in this process (%s): install it into that Python, or "
                 "rebuild the FMU with --runtime standalone (no Python needed)",
                 needed[i], (int)strcspn(ver, " "), ver, why ? why : "import failed");
            if (s != NULL) py.DecRef(s);
            if (t != NULL) py.DecRef(t);
            if (v != NULL) py.DecRef(v);
            if (tb != NULL) py.DecRef(tb);
            rc = -1;
        }
    }
    py.GILStateRelease(g);
    return rc;
}

/* 5. Release the wrapper's shared_ptr<PyState> through its own finalizer before
 * the wrapper's static destructor runs: exit handlers run in reverse order of
 * registration, and this one is registered after the wrapper was loaded. */
static void release_wrapper_state(void)
{
    if (W.finalize != NULL) W.finalize();
}

static int load(char *err, size_t n)
{
    Dl_info info;
    char bindir[PATH_MAX], path[PATH_MAX + 300], *slash;
    shim_config cfg;
    void *h, *lib;
    if (dladdr((void *)&load, &info) == 0 || info.dli_fname == NULL) {
        fail(err, n, "cannot locate the FMU's binary (dladdr failed)");
        return -1;
    }
    snprintf(bindir, sizeof bindir, "%s", info.dli_fname);
    slash = strrchr(bindir, '/');
    if (slash == NULL) snprintf(bindir, sizeof bindir, ".");
    else *slash = '\0';
    snprintf(path, sizeof path, "%s/../../resources/" CONFIG_FILE, bindir);
    if (read_config(path, &cfg, err, n) != 0) return -1;
    if (find_libpython(&cfg, &h, err, n) != 0) return -1;
    if (bind_python(h, err, n) != 0) return -1;
    if (start_interpreter(&cfg, err, n) != 0) return -1;
    if (check_modules(err, n) != 0) return -1;
    snprintf(path, sizeof path, "%s/%s", bindir, cfg.wrapper);
    lib = dlopen(path, RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
    if (lib == NULL) {
        const char *e = dlerror();
        fail(err, n, "cannot load pythonfmu's wrapper %s: %s", path, e ? e : "?");
        return -1;
    }
#define BIND(name)                                                                   \
    *(void **)(&W.name) = dlsym(lib, "fmi2" #name);                                  \
    if (W.name == NULL) {                                                            \
        fail(err, n, "pythonfmu's wrapper %s lacks fmi2" #name, path);               \
        return -1;                                                                   \
    }
    FMI2_FORWARDED(BIND)
#undef BIND
    *(void **)(&W.finalize) = dlsym(lib, "finalizePythonInterpreter");
    if (W.finalize != NULL) atexit(release_wrapper_state);
    return 0;
}

/* ---- exported FMI 2.0 functions ---- */

EXPORT const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
EXPORT const char *fmi2GetVersion(void) { return fmi2Version; }

EXPORT fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                                     fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                                     fmi2Boolean visible, fmi2Boolean loggingOn)
{
    char err[2048] = "";
    int ok;
    pthread_mutex_lock(&load_mutex);
    ok = loaded || load(err, sizeof err) == 0;
    if (ok) loaded = 1;
    pthread_mutex_unlock(&load_mutex);
    if (!ok) {
        if (functions != NULL && functions->logger != NULL)
            functions->logger(functions->componentEnvironment, instanceName ? instanceName : "?", fmi2Error,
                              "logStatusError", "%s", err);
        return NULL;
    }
    return W.Instantiate(instanceName, fmuType, fmuGUID, fmuResourceLocation, functions, visible, loggingOn);
}

/* A component exists only after a successful fmi2Instantiate, so W is bound whenever c is
 * a component; a call without one is refused instead of reaching a NULL pointer. */
#define READY(c) (loaded && (c) != NULL)

EXPORT void fmi2FreeInstance(fmi2Component c)
{
    if (READY(c)) W.FreeInstance(c);
}

#define FWD(name, params, args)                                                      \
    EXPORT fmi2Status fmi2##name params                                              \
    {                                                                                \
        if (!READY(c)) return fmi2Error;                                             \
        return W.name args;                                                          \
    }

FWD(SetDebugLogging, (fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cat[]), (c, on, n, cat))
FWD(SetupExperiment, (fmi2Component c, fmi2Boolean td, fmi2Real tol, fmi2Real t0, fmi2Boolean sd, fmi2Real t1),
    (c, td, tol, t0, sd, t1))
FWD(EnterInitializationMode, (fmi2Component c), (c))
FWD(ExitInitializationMode, (fmi2Component c), (c))
FWD(Terminate, (fmi2Component c), (c))
FWD(Reset, (fmi2Component c), (c))
FWD(GetReal, (fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[]), (c, vr, n, v))
FWD(GetInteger, (fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[]), (c, vr, n, v))
FWD(GetBoolean, (fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[]), (c, vr, n, v))
FWD(GetString, (fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[]), (c, vr, n, v))
FWD(SetReal, (fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real v[]), (c, vr, n, v))
FWD(SetInteger, (fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer v[]), (c, vr, n, v))
FWD(SetBoolean, (fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean v[]), (c, vr, n, v))
FWD(SetString, (fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String v[]), (c, vr, n, v))
FWD(GetFMUstate, (fmi2Component c, fmi2FMUstate *s), (c, s))
FWD(SetFMUstate, (fmi2Component c, fmi2FMUstate s), (c, s))
FWD(FreeFMUstate, (fmi2Component c, fmi2FMUstate *s), (c, s))
FWD(SerializedFMUstateSize, (fmi2Component c, fmi2FMUstate s, size_t *size), (c, s, size))
FWD(SerializeFMUstate, (fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t size), (c, s, b, size))
FWD(DeSerializeFMUstate, (fmi2Component c, const fmi2Byte b[], size_t size, fmi2FMUstate *s), (c, b, size, s))
FWD(GetDirectionalDerivative,
    (fmi2Component c, const fmi2ValueReference u[], size_t nu, const fmi2ValueReference z[], size_t nz,
     const fmi2Real dv[], fmi2Real dz[]),
    (c, u, nu, z, nz, dv, dz))
FWD(SetRealInputDerivatives,
    (fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer order[], const fmi2Real v[]),
    (c, vr, n, order, v))
FWD(GetRealOutputDerivatives,
    (fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer order[], fmi2Real v[]),
    (c, vr, n, order, v))
FWD(DoStep, (fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior), (c, t, h, noSetPrior))
FWD(CancelStep, (fmi2Component c), (c))
FWD(GetStatus, (fmi2Component c, const fmi2StatusKind s, fmi2Status *v), (c, s, v))
FWD(GetRealStatus, (fmi2Component c, const fmi2StatusKind s, fmi2Real *v), (c, s, v))
FWD(GetIntegerStatus, (fmi2Component c, const fmi2StatusKind s, fmi2Integer *v), (c, s, v))
FWD(GetBooleanStatus, (fmi2Component c, const fmi2StatusKind s, fmi2Boolean *v), (c, s, v))
FWD(GetStringStatus, (fmi2Component c, const fmi2StatusKind s, fmi2String *v), (c, s, v))
