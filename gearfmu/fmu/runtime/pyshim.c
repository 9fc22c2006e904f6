/*
 * pyshim.c -- the FMI 2.0 binary of a gearfmu FMU built with the pythonfmu
 * runtime (docs/fmu.md "The binary: the standalone FMI layer over the Python slave").
 *
 * The binary is the standalone runtime's FMI 2.0 layer (../standalone/fmi2_gear.c) and
 * plumbing (../standalone/fmi_common.c) -- the table of allowed calls, the checks of every
 * get/set, the statuses and the messages -- over a model (the contract ../standalone/gf_model.h)
 * that is the Python slave of this FMU, reached through pythonfmu's FMI wrapper.  So both
 * runtimes give one FMI behaviour: the same state machine, refusals, statuses and words, and
 * the same logging rule (a message whose status is not OK reaches the host whether or not
 * logging is on).  This file is that model, and the loader that makes the wrapper loadable.
 *
 * The loader.  pythonfmu's FMI wrapper needs the Python interpreter's symbols when it is
 * loaded, starts the interpreter behind a lock of its own (one per FMU, since every FMU
 * carries its own copy of the wrapper) and crashes on any failure of the slave's import.
 * This library has no link-time dependency on Python; on the first fmi2Instantiate it
 *
 *  1. finds libpython: already in the process (dlsym(RTLD_DEFAULT,
 *     "Py_IsInitialized")), else that of the Python it chooses to start: the
 *     executable $GEARFMU_PYTHON names (its library beside it, <prefix>/lib, or
 *     for a virtual environment the lib folder of its pyvenv.cfg's home), else
 *     the one recorded for this FMU's record id (resources/gearfmu_pyshim.txt:
 *     python_record) in gearfmu's cache folder, <cache>/pythons/<id>.txt, written
 *     when the FMU was built; else its soname through the loader.  The FMU holds
 *     no path: the record lives on the machine that built it.  It is loaded
 *     RTLD_GLOBAL so that the wrapper's Python symbols resolve;
 *  2. starts the interpreter if nobody has, under a process-wide lock shared
 *     by every gearfmu FMU in the process: flock() on a per-process lock file
 *     (each FMU's copy of this library opens the file itself; flock locks of
 *     separate open file descriptions conflict even within one process); the
 *     lock is taken even when the interpreter reports itself initialized, since
 *     that flag is set before site-packages is on sys.path; the program name is
 *     the chosen executable, so the interpreter gets its environment (numpy);
 *  3. imports the modules the slave needs from outside the FMU (ctypes,
 *     numpy) and refuses to instantiate, with a message through the host's
 *     logger, if one is missing.  When the recorded environment is gone, or
 *     libpython is not in the process and no Python is named (no record, no
 *     $GEARFMU_PYTHON), nothing is loaded and no interpreter is started: the
 *     message names the build's environment by its path-free description and
 *     says what to do ($GEARFMU_PYTHON, or the standalone runtime);
 *  4. loads pythonfmu's wrapper, shipped beside this library under another
 *     name, and binds its functions;
 *  5. registers an exit handler that releases the wrapper's interpreter state
 *     before the wrapper's own static destructor runs (the order pythonfmu's
 *     library gets wrong at process exit).
 *
 * The model (gm_* below).  The plumbing keeps the variable table, the values and the
 * outputs; the model hands the values to the slave before the calls that use them (the
 * initial state, a step), takes the outputs back after them, and turns what the slave says
 * into the contract's answers: the wrapper's fmi2Discard from do_step, and a message the slave
 * logged with status fmi2Error during a call (its reason for refusing: no initial state, a
 * refused FMU state).  The wrapper is given this file's logger with its logging always on;
 * every message goes through gf_log, which applies the plumbing's rule.
 *
 * Any failure of the loader returns NULL from fmi2Instantiate with a logged message; no
 * failure path reaches the wrapper.  Linux only (dlopen, flock).
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <pwd.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>
#include <wchar.h>

#include "fmi2Functions.h"
#include "gf_model.h"

#define CONFIG_FILE "gearfmu_pyshim.txt"
/* the records of the Pythons FMUs were built with, in gearfmu's cache folder, and their first line;
 * the variable naming a Python to start instead (gearfmu/fmu/pythonfmu_build.py: PYTHON_RECORDS,
 * PYTHON_RECORD_FORMAT, PYTHON_OVERRIDE_VARIABLE) */
#define RECORD_DIR "pythons"
#define RECORD_FORMAT "format=gearfmu-python-record 1"
#define OVERRIDE_VARIABLE "GEARFMU_PYTHON"
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
    char python_version[32], libpython_soname[128], record_id[64], wrapper[256], environment[256];
} shim_config;

/* The Python the loader starts when the process has none: the one GEARFMU_PYTHON names, else the
 * one recorded for this FMU's record id in gearfmu's cache (written when the FMU was built). */
enum { PY_UNCHOSEN, PY_OVERRIDE, PY_RECORD };
typedef struct {
    int source;
    char executable[PATH_MAX], libpython[PATH_MAX], record[PATH_MAX];
} py_choice;

/* where the interpreter of this process comes from (the words of the loader's messages) */
enum { ENV_HOST, ENV_CHOSEN, ENV_UNKNOWN };
static int env_origin = ENV_HOST;

#define REMEDY "rebuild the FMU with --runtime standalone (no Python needed)"

static void fail(char *err, size_t n, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void fail(char *err, size_t n, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, n, fmt, ap);
    va_end(ap);
}

/* key=value lines; "" for a key that is absent */
static int read_config(const char *path, shim_config *cfg, char *err, size_t n)
{
    char line[PATH_MAX + 64];
    FILE *f = fopen(path, "r");
    memset(cfg, 0, sizeof *cfg);
    if (f == NULL) {
        fail(err, n, "cannot read resources/" CONFIG_FILE " (%s); the FMU is incomplete, rebuild it", strerror(errno));
        return -1;
    }
    while (fgets(line, sizeof line, f) != NULL) {
        char *eq = strchr(line, '='), *end;
        if (eq == NULL) continue;
        *eq++ = '\0';
        end = eq + strcspn(eq, "\r\n");
        *end = '\0';
#define KEY(k, name)                                                            \
    if (strcmp(line, name) == 0) snprintf(cfg->k, sizeof cfg->k, "%s", eq);
        KEY(python_version, "python_version") KEY(libpython_soname, "libpython_soname")
        KEY(record_id, "python_record") KEY(wrapper, "wrapper") KEY(environment, "environment")
#undef KEY
    }
    fclose(f);
    if (cfg->wrapper[0] == '\0' || strchr(cfg->wrapper, '/') != NULL || strlen(cfg->record_id) != 16 ||
        strspn(cfg->record_id, "0123456789abcdef") != 16) {
        fail(err, n, "resources/" CONFIG_FILE ": no valid 'wrapper' and 'python_record' entries; the FMU is "
                     "incomplete, rebuild it");
        return -1;
    }
    return 0;
}

/* gearfmu's cache folder, the rule of gearfmu/common/cache.py: $GEARFMU_CACHE_DIR, else
 * $XDG_CACHE_HOME/gearfmu, else <home>/.cache/gearfmu (home: $HOME, else the user database) */
static int cache_root(char *out, size_t n)
{
    const char *r = getenv("GEARFMU_CACHE_DIR");
    struct passwd pw, *found = NULL;
    char buf[4096];
    if (r != NULL && r[0] != '\0') return snprintf(out, n, "%s", r) < (int)n ? 0 : -1;
    r = getenv("XDG_CACHE_HOME");
    if (r != NULL && r[0] != '\0') return snprintf(out, n, "%s/gearfmu", r) < (int)n ? 0 : -1;
    r = getenv("HOME");
    if (r == NULL || r[0] == '\0') {
        if (getpwuid_r(getuid(), &pw, buf, sizeof buf, &found) != 0 || found == NULL || found->pw_dir == NULL) return -1;
        r = found->pw_dir;
    }
    return snprintf(out, n, "%s/.cache/gearfmu", r) < (int)n ? 0 : -1;
}

static int is_executable_file(const char *path)
{
    struct stat st;
    return path[0] != '\0' && stat(path, &st) == 0 && S_ISREG(st.st_mode) && access(path, X_OK) == 0;
}

/* the Python to start: 0 (pc filled), 1 nothing known (err says so), -1 refused (err says why) */
static int choose_python(const shim_config *cfg, py_choice *pc, char *err, size_t n)
{
    const char *o = getenv(OVERRIDE_VARIABLE);
    char root[PATH_MAX], line[PATH_MAX + 64];
    FILE *f;
    int first = 1, ok = 0;
    memset(pc, 0, sizeof *pc);
    if (o != NULL && o[0] != '\0') {
        if (!is_executable_file(o) || snprintf(pc->executable, sizeof pc->executable, "%s", o) >= (int)sizeof pc->executable) {
            fail(err, n, OVERRIDE_VARIABLE " names %.200s, which is not an executable file: set it to the executable of "
                         "a Python %s with numpy (python -c \"import sys; print(sys.executable)\"), or " REMEDY,
                 o, cfg->python_version);
            return -1;
        }
        pc->source = PY_OVERRIDE;
        return 0;
    }
    if (cache_root(root, sizeof root) != 0 ||
        snprintf(pc->record, sizeof pc->record, "%s/" RECORD_DIR "/%s.txt", root, cfg->record_id) >= (int)sizeof pc->record) {
        fail(err, n, "the Python this FMU was built with (%s) cannot be looked up: no home folder and no "
                     "GEARFMU_CACHE_DIR; set " OVERRIDE_VARIABLE " to the executable of a Python %s with numpy, or " REMEDY,
             cfg->environment, cfg->python_version);
        return -1;
    }
    if ((f = fopen(pc->record, "r")) == NULL) {
        int e = errno;
        fail(err, n, "the Python this FMU was built with (%s) is not recorded on this machine (%.200s: %s); set "
                     OVERRIDE_VARIABLE " to the executable of a Python %s with numpy, or " REMEDY,
             cfg->environment, pc->record, strerror(e), cfg->python_version);
        return e == ENOENT ? 1 : -1;
    }
    while (fgets(line, sizeof line, f) != NULL) {
        char *eq;
        line[strcspn(line, "\r\n")] = '\0';
        if (first) {
            ok = strcmp(line, RECORD_FORMAT) == 0;
            first = 0;
            if (!ok) break;
            continue;
        }
        if ((eq = strchr(line, '=')) == NULL) continue;
        *eq++ = '\0';
        if (strcmp(line, "python_executable") == 0) snprintf(pc->executable, sizeof pc->executable, "%s", eq);
        else if (strcmp(line, "libpython") == 0) snprintf(pc->libpython, sizeof pc->libpython, "%s", eq);
    }
    fclose(f);
    if (!ok || pc->executable[0] == '\0') {
        fail(err, n, "%.200s is not a record of a Python written by gearfmu (first line '" RECORD_FORMAT "', then "
                     "python_executable=...); set " OVERRIDE_VARIABLE " to the executable of a Python %s with numpy, or "
                     REMEDY, pc->record, cfg->python_version);
        return -1;
    }
    if (!is_executable_file(pc->executable)) {
        /* no other Python in its place: whichever the search would find may lack numpy, or even its
         * own standard library, and a Python that cannot start aborts the process */
        fail(err, n, "the Python environment this FMU was built with (%s) is gone: its interpreter is no longer "
                     "where the FMU was built, and no other Python is started in its place; recreate that "
                     "environment, set " OVERRIDE_VARIABLE " to the executable of a Python %s with numpy, or " REMEDY,
             cfg->environment[0] ? cfg->environment : cfg->python_version, cfg->python_version);
        return -1;
    }
    pc->source = PY_RECORD;
    return 0;
}

/* dlopen(path) into *h; on failure the loader's reason is appended to why */
static int try_open(const char *path, void **h, char *why, size_t n)
{
    const char *e;
    size_t used = strlen(why);
    if ((*h = dlopen(path, RTLD_NOW | RTLD_GLOBAL)) != NULL) return 1;
    e = dlerror();
    if (used + 1 < n) snprintf(why + used, n - used, "%s%.150s", used ? "; " : "", e ? e : path);
    return 0;
}

/* 1. libpython: already loaded (the Python to start, if any, is chosen under the lock), else the
 * chosen Python's: recorded, or beside the executable GEARFMU_PYTHON names (<prefix>/lib, and for
 * a virtual environment the lib folder of its pyvenv.cfg's home), else its soname.  *h is the
 * handle to resolve the Python API from (RTLD_DEFAULT, which is NULL on glibc, when the process
 * already has it). */
static int find_libpython(const shim_config *cfg, py_choice *pc, void **h, char *err, size_t n)
{
    char why[512] = "", dir[PATH_MAX], cand[PATH_MAX + 160], line[PATH_MAX + 16], *slash;
    const char *where;
    int k;
    *h = RTLD_DEFAULT;
    pc->source = PY_UNCHOSEN;
    if (dlsym(RTLD_DEFAULT, "Py_IsInitialized") != NULL) return 0;
    if (choose_python(cfg, pc, err, n) != 0) return -1;
    if (pc->source == PY_RECORD) {
        where = "at the path recorded at build time";
        if (pc->libpython[0] != '\0' && try_open(pc->libpython, h, why, sizeof why)) return 0;
    } else {
        where = "beside " OVERRIDE_VARIABLE;
        for (k = 0; k < 3; ++k) {
            FILE *f;
            if (k == 2) { /* the executable's real folder (a link into a Python installation) */
                if (realpath(pc->executable, dir) == NULL) break;
            } else {
                snprintf(dir, sizeof dir, "%s", pc->executable);
            }
            if ((slash = strrchr(dir, '/')) == NULL) continue;
            *slash = '\0';
            if (k == 1) { /* a virtual environment: <venv>/pyvenv.cfg "home = <python's bin folder>" */
                snprintf(cand, sizeof cand, "%s/../pyvenv.cfg", dir);
                if ((f = fopen(cand, "r")) == NULL) continue;
                dir[0] = '\0';
                while (fgets(line, sizeof line, f) != NULL) {
                    char *v = line + strspn(line, " \t");
                    if (strncmp(v, "home", 4) != 0) continue;
                    v += 4 + strspn(v + 4, " \t");
                    if (*v != '=') continue;
                    v += 1 + strspn(v + 1, " \t");
                    v[strcspn(v, "\r\n")] = '\0';
                    while (*v != '\0' && strchr(" \t", v[strlen(v) - 1]) != NULL) v[strlen(v) - 1] = '\0';
                    snprintf(dir, sizeof dir, "%s", v);
                }
                fclose(f);
                if (dir[0] == '\0') continue;
            }
            snprintf(cand, sizeof cand, "%s/../lib/%s", dir, cfg->libpython_soname);
            if (access(cand, R_OK) == 0 && try_open(cand, h, why, sizeof why)) return 0;
        }
    }
    if (cfg->libpython_soname[0] != '\0' && try_open(cfg->libpython_soname, h, why, sizeof why)) return 0;
    fail(err, n,
         "the pythonfmu runtime needs Python %s's shared library: it is not loaded in this process, not found %s "
         "nor by the dynamic loader (%s); install Python %s with its shared library (or add its directory to "
         "LD_LIBRARY_PATH), or " REMEDY,
         cfg->python_version, where, why[0] ? why : "nothing to load", cfg->python_version);
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

static int start_interpreter(const shim_config *cfg, py_choice *pc, char *err, size_t n)
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
        /* the Python environment to start (its site-packages hold numpy): chosen already when this
         * loader loaded libpython, else now (libpython was in the process, Python not started) */
        int rc = pc->source == PY_UNCHOSEN ? choose_python(cfg, pc, err, n) : 0;
        if (rc < 0) {
            /* the lock file stays: a loader waiting on it may start the interpreter next */
            flock(fd, LOCK_UN);
            close(fd);
            return -1;
        }
        env_origin = rc == 0 ? ENV_CHOSEN : ENV_UNKNOWN; /* unknown: the library's own default Python */
        if (py.SetProgramName != NULL && py.DecodeLocale != NULL && env_origin == ENV_CHOSEN) {
            static wchar_t *program = NULL; /* must outlive the interpreter */
            if (program == NULL) program = py.DecodeLocale(pc->executable, NULL);
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

/* 3. The modules the slave imports from outside the FMU.  When this loader started the
 * interpreter without knowing which environment to start (libpython was in the process, and
 * neither GEARFMU_PYTHON nor a record names a Python), a failed import says so: that is the
 * cause, whatever module fails first. */
static int check_modules(const shim_config *cfg, const py_choice *pc, char *err, size_t n)
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
            int vlen = (int)strcspn(ver, " ");
            if (env_origin == ENV_UNKNOWN)
                fail(err, n,
                     "the Python this FMU was built with (%s) is not recorded on this machine: the Python %.*s "
                     "loaded in this process, started in its place, cannot import '%s' (%.120s); set "
                     OVERRIDE_VARIABLE " to the executable of a Python %s with numpy, or " REMEDY,
                     cfg->environment[0] ? cfg->environment : "not recorded", vlen, ver, needed[i],
                     why ? why : "import failed", cfg->python_version);
            else if (env_origin == ENV_CHOSEN && pc->source == PY_OVERRIDE)
                fail(err, n,
                     "the pythonfmu runtime needs the Python module '%s', which cannot be imported in the "
                     "Python %.*s that " OVERRIDE_VARIABLE " names (%.120s): install it into that Python, or " REMEDY,
                     needed[i], vlen, ver, why ? why : "import failed");
            else
                fail(err, n,
                     "the pythonfmu runtime needs the Python module '%s', which cannot be imported in the "
                     "Python %.*s running in this process (%.120s): install it into that Python, or " REMEDY,
                     needed[i], vlen, ver, why ? why : "import failed");
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
    static py_choice pc; /* three paths: off the host thread's stack (load runs under load_mutex) */
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
    if (find_libpython(&cfg, &pc, &h, err, n) != 0) return -1;
    if (bind_python(h, err, n) != 0) return -1;
    if (start_interpreter(&cfg, &pc, err, n) != 0) return -1;
    if (check_modules(&cfg, &pc, err, n) != 0) return -1;
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


/* ====================================================================================== */
/* The model of the contract gf_model.h: the Python slave behind pythonfmu's wrapper.     */
/* ====================================================================================== */

#define SNAP_MAGIC 0x50464d55u /* "UMFP" */
#define SNAP_VERSION 1u

struct gm_data {
    fmi2Component w;          /* the wrapper's instance (NULL: none) */
    fmi2CallbackFunctions cb; /* given to the wrapper, which keeps a pointer to it */
    int worst;                /* the worst status the slave logged during the current call */
    int capture;              /* instantiation: keep the wrapper's messages in `said` instead of logging them */
    char said[512];
    int dead;                 /* the wrapper returned fmi2Fatal: its instance is never touched again */
    int fresh;                /* the slave is as constructed (nothing handed to it since) */
    int py_mode;              /* the FMI state the slave has seen: GF_INSTANTIATED, GF_INIT_MODE, GF_STEP_MODE */
    int initialized;          /* the initial state was computed from the current values */
    unsigned int *vr_real, *vr_int, *vr_out;
    double *buf;              /* one value per variable: the values handed over, the outputs taken back */
    int *ibuf;
    int n_real, n_int, n_outvars;
    size_t py_state_size;     /* bytes of the slave's serialized state (0: not asked yet) */
    uint64_t tag;             /* FNV-1a of the GUID: a snapshot fits this FMU only */
};

/* The FMU state: this header, the values, the outputs, the slave's serialized state (it holds
 * the kernel state; its own checksum and fingerprint), all under one FNV-1a 64 checksum. */
typedef struct {
    uint32_t magic, version, n_vars, n_out;
    uint64_t tag, py_size, check;
    int32_t mode, dirty, initialized, py_mode;
    double time;
} snap_header;

static uint64_t fnv1a(uint64_t h, const unsigned char *p, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
    return h;
}

/* the slave's messages: through gf_log (the plumbing's logging rule), the worst status kept */
static void py_logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                      fmi2String message, ...)
{
    static const char *const by_status[5] = {"logAll", "logStatusWarning", "logStatusDiscard", "logStatusError",
                                             "logStatusFatal"};
    gf_inst *c = (gf_inst *)env;
    int st = (int)status;
    (void)name;
    if (c == NULL || c->data == NULL) return;
    if (st < GF_OK || st > GF_FATAL) st = GF_ERROR_STATUS;
    if (st > c->data->worst) c->data->worst = st;
    if (c->data->capture) { /* the wrapper's text "Fatal py exception encountered: <where>\n<repr>": the repr */
        const char *nl = message != NULL ? strchr(message, '\n') : NULL;
        if (st >= GF_ERROR_STATUS) snprintf(c->data->said, sizeof c->data->said, "%s", nl ? nl + 1 : message);
        return;
    }
    /* the wrapper passes the text as the format: it is logged as text */
    gf_log(c, st, category != NULL && category[0] != '\0' ? category : by_status[st], "%s",
           message != NULL ? message : "");
}

/* before a call of the wrapper: 0 (logged) if the slave is gone */
static int begin(gf_inst *c, const char *fn)
{
    if (c->data->dead || c->data->w == NULL) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError",
               "%s: the Python slave of this instance ended with fmi2Fatal (reason above); only fmi2FreeInstance "
               "may follow", fn);
        return 0;
    }
    c->data->worst = GF_OK;
    return 1;
}

/* after a call of the wrapper: the worse of its status and what the slave logged */
static int end(gf_inst *c, fmi2Status st)
{
    if (st == fmi2Fatal) {
        c->data->dead = 1;
        c->mode = GF_ERROR;
    }
    return (int)st > c->data->worst ? (int)st : c->data->worst;
}

static int as_int(double x) { return (x >= -2147483647.0 && x <= 2147483647.0) ? (int)x : -1; }

/* the values of the plumbing to the slave (when one changed since they were last handed over) */
static int hand_over(gf_inst *c, const char *fn)
{
    gm_data *d = c->data;
    int i, st;
    if (!c->dirty && !d->fresh) return GF_OK;
    if (!begin(c, fn)) return GF_ERROR_STATUS;
    d->fresh = 0;
    for (i = 0; i < d->n_real; ++i) d->buf[i] = c->values[d->vr_real[i]];
    for (i = 0; i < d->n_int; ++i) d->ibuf[i] = as_int(c->values[d->vr_int[i]]);
    st = end(c, W.SetReal(d->w, d->vr_real, (size_t)d->n_real, d->buf));
    if (st < GF_ERROR_STATUS && d->n_int > 0) st = end(c, W.SetInteger(d->w, d->vr_int, (size_t)d->n_int, d->ibuf));
    return st;
}

/* the slave's outputs to the plumbing; the status of the call */
static int take_outputs(gf_inst *c, const char *fn)
{
    gm_data *d = c->data;
    int i, st;
    if (!begin(c, fn)) return GF_ERROR_STATUS;
    st = end(c, W.GetReal(d->w, d->vr_out, (size_t)d->n_outvars, d->buf));
    if (st < GF_ERROR_STATUS)
        for (i = 0; i < d->n_outvars; ++i) c->out[c->vars[d->vr_out[i]].out_index] = d->buf[i];
    return st;
}

/* the slave in initialization mode (it computes its outputs there from the values handed over) */
static int slave_in_init(gf_inst *c, const char *fn)
{
    gm_data *d = c->data;
    int st;
    if (d->py_mode != GF_INSTANTIATED) return GF_OK;
    if (!begin(c, fn)) return GF_ERROR_STATUS;
    d->fresh = 0;
    st = end(c, W.SetupExperiment(d->w, fmi2False, 0.0, c->time, fmi2False, 0.0));
    if (st < GF_ERROR_STATUS) st = end(c, W.EnterInitializationMode(d->w));
    if (st < GF_ERROR_STATUS) d->py_mode = GF_INIT_MODE;
    return st;
}

/* ---- the variable table: n_vars= and var= lines of resources/gearfmu_pyshim.txt, the format of
 * the standalone runtime's (vr|causality|variability|type|output_index|start|min|max|name) ---- */
static int num(const char *s, double *v)
{
    char *e;
    if (*s == '\0') return 0;
    *v = strtod(s, &e);
    return *e == '\0';
}

static int read_var(gf_inst *c, char *val, int expect)
{
    char *f[9], *q = val;
    int k = 0;
    long vr, oi;
    gf_var *v;
    f[k++] = q;
    for (; *q != '\0'; ++q)
        if (*q == '|') {
            if (k == 9) return 0;
            *q = '\0';
            f[k++] = q + 1;
        }
    if (k != 9) return 0;
    vr = strtol(f[0], &q, 10);
    if (*q != '\0' || vr != expect || vr >= c->n_vars) return 0;
    v = &c->vars[vr];
    v->causality = strcmp(f[1], "parameter") == 0 ? GF_PARAMETER : strcmp(f[1], "input") == 0 ? GF_INPUT
                   : strcmp(f[1], "output") == 0 ? GF_OUTPUT : GF_OTHER;
    v->variability = strcmp(f[2], "fixed") == 0 ? GF_FIXED : strcmp(f[2], "tunable") == 0 ? GF_TUNABLE
                     : strcmp(f[2], "continuous") == 0 ? GF_CONTINUOUS : GF_OTHER_VAR;
    if (strcmp(f[3], "Integer") == 0) v->is_integer = 1;
    else if (strcmp(f[3], "Real") == 0) v->is_integer = 0;
    else return 0;
    oi = strtol(f[4], &q, 10);
    if (f[4][0] != '\0' && *q != '\0') return 0;
    v->out_index = f[4][0] == '\0' ? -1 : (int)oi;
    v->has_start = num(f[5], &v->start);
    v->has_min = num(f[6], &v->min);
    v->has_max = num(f[7], &v->max);
    if ((f[5][0] && !v->has_start) || (f[6][0] && !v->has_min) || (f[7][0] && !v->has_max)) return 0;
    if (v->causality == GF_OUTPUT && (v->out_index < 0 || v->out_index >= 100000 || v->is_integer)) return 0;
    snprintf(v->name, sizeof v->name, "%s", f[8]);
    v->array_len = 1;
    return 1;
}

static const char *read_table(gf_inst *c, const char *res_dir, char *guid, size_t guid_cap, char *err, size_t cap)
{
    char path[PATH_MAX + 64], line[4096];
    int seen = 0, i;
    FILE *f;
    snprintf(path, sizeof path, "%s%s", res_dir, CONFIG_FILE);
    if ((f = fopen(path, "r")) == NULL) {
        snprintf(err, cap, "cannot read resources/%s (%s); the FMU is incomplete, rebuild it", CONFIG_FILE,
                 strerror(errno));
        return err;
    }
    guid[0] = '\0';
    while (fgets(line, sizeof line, f) != NULL) {
        char *val = strchr(line, '=');
        if (val == NULL) continue;
        *val++ = '\0';
        val[strcspn(val, "\r\n")] = '\0';
        if (strcmp(line, "guid") == 0) {
            snprintf(guid, guid_cap, "%s", val);
        } else if (strcmp(line, "n_vars") == 0 && c->vars == NULL) {
            long n = strtol(val, NULL, 10);
            if (n < 1 || n > 100000) break;
            c->n_vars = (int)n;
            c->vars = (gf_var *)calloc((size_t)n, sizeof(gf_var));
            c->values = (double *)calloc((size_t)n, sizeof(double));
            if (c->vars == NULL || c->values == NULL) break;
        } else if (strcmp(line, "var") == 0) {
            if (c->vars == NULL || !read_var(c, val, seen)) break;
            seen++;
        }
    }
    fclose(f);
    if (c->vars == NULL || seen != c->n_vars || guid[0] == '\0') {
        snprintf(err, cap, "resources/%s: no valid variable table (guid, n_vars, then var lines of vr 0, 1, ... "
                 "in order); the FMU is incomplete, rebuild it", CONFIG_FILE);
        return err;
    }
    for (i = 0; i < c->n_vars; ++i)
        if (c->vars[i].causality == GF_OUTPUT && c->vars[i].out_index + 1 > c->n_out) c->n_out = c->vars[i].out_index + 1;
    return NULL;
}

const char *gm_instantiate(gf_inst *c, const char *res_dir, const char *token, char *err, size_t errcap)
{
    char guid[128], uri[PATH_MAX + 16];
    const char *e;
    gm_data *d;
    int ok, i;
    c->offers = GF_COSIMULATION;   /* the Python slave steps itself: no Model Exchange (gf_model.h gf_me_model) */
    if (c->fmu_type == GF_MODEL_EXCHANGE)
        return "the pythonfmu runtime offers Co-Simulation only; for Model Exchange build the FMU with "
               "--runtime standalone (docs/standalone.md \"Model Exchange\")";
    pthread_mutex_lock(&load_mutex);
    ok = loaded || load(err, errcap) == 0;
    if (ok) loaded = 1;
    pthread_mutex_unlock(&load_mutex);
    if (!ok) return err;
    d = c->data = (gm_data *)calloc(1, sizeof(gm_data));
    if (d == NULL) return "out of memory";
    if ((e = read_table(c, res_dir, guid, sizeof guid, err, errcap)) != NULL) return e;
    if (token == NULL || strcmp(token, guid) != 0) return "GUID differs from the one this FMU was built with";
    c->out = (double *)calloc((size_t)(c->n_out > 0 ? c->n_out : 1), sizeof(double));
    d->vr_real = (unsigned int *)calloc((size_t)c->n_vars, sizeof(unsigned int));
    d->vr_int = (unsigned int *)calloc((size_t)c->n_vars, sizeof(unsigned int));
    d->vr_out = (unsigned int *)calloc((size_t)c->n_vars, sizeof(unsigned int));
    d->buf = (double *)calloc((size_t)c->n_vars, sizeof(double));
    d->ibuf = (int *)calloc((size_t)c->n_vars, sizeof(int));
    if (c->out == NULL || d->vr_real == NULL || d->vr_int == NULL || d->vr_out == NULL || d->buf == NULL ||
        d->ibuf == NULL)
        return "out of memory";
    for (i = 0; i < c->n_vars; ++i) {
        if (c->vars[i].causality == GF_OUTPUT) d->vr_out[d->n_outvars++] = (unsigned int)i;
        else if (c->vars[i].is_integer) d->vr_int[d->n_int++] = (unsigned int)i;
        else d->vr_real[d->n_real++] = (unsigned int)i;
    }
    d->tag = fnv1a(14695981039346656037ull, (const unsigned char *)guid, strlen(guid));
    d->cb.logger = py_logger;
    d->cb.allocateMemory = calloc;
    d->cb.freeMemory = free;
    d->cb.componentEnvironment = c;
    snprintf(uri, sizeof uri, "file://%s", res_dir);
    d->capture = 1;
    d->w = W.Instantiate(c->instance_name, fmi2CoSimulation, token, uri, &d->cb, fmi2False, fmi2True);
    d->capture = 0;
    if (d->w == NULL) {
        snprintf(err, errcap, "the Python slave refused to start: %s", d->said[0] ? d->said : "no reason given");
        return err;
    }
    d->fresh = 1;
    gm_reset(c);
    gf_log(c, GF_OK, "logAll", "instantiated: %d variables, the Python slave started (tables SHA-256 ok)", c->n_vars);
    return NULL;
}

void gm_free(gf_inst *c)
{
    gm_data *d;
    if (c == NULL) return;
    d = c->data;
    /* after fmi2Fatal the wrapper has released the slave but kept its pointers: its instance is
     * left alone (freeing it would release them again) */
    if (d != NULL && d->w != NULL && !d->dead) W.FreeInstance(d->w);
    if (d != NULL) {
        free(d->vr_real);
        free(d->vr_int);
        free(d->vr_out);
        free(d->buf);
        free(d->ibuf);
        free(d);
    }
    free(c->vars);
    free(c->values);
    free(c->out);
    c->data = NULL;
    c->vars = NULL;
    c->values = c->out = NULL;
    c->n_vars = c->n_out = 0;
}

void gm_reset(gf_inst *c)
{
    gm_data *d = c->data;
    int i;
    for (i = 0; i < c->n_vars; ++i) c->values[i] = c->vars[i].has_start ? c->vars[i].start : 0.0;
    for (i = 0; i < c->n_out; ++i) c->out[i] = 0.0;
    c->dirty = 1;
    c->time = 0.0;
    c->mode = GF_INSTANTIATED;
    d->initialized = 0;
    d->py_mode = GF_INSTANTIATED;
    if (d->dead) { /* no slave to reset: the instance stays in the error state (logged by begin) */
        begin(c, "fmi2Reset");
        c->mode = GF_ERROR;
    } else if (!d->fresh && begin(c, "fmi2Reset")) { /* pythonfmu re-creates the slave */
        if (end(c, W.Reset(d->w)) < GF_ERROR_STATUS) d->fresh = 1;
    }
}

int gm_exit_init(gf_inst *c)
{
    static const char *const fn = "fmi2ExitInitializationMode";
    gm_data *d = c->data;
    if (slave_in_init(c, fn) >= GF_ERROR_STATUS || hand_over(c, fn) >= GF_ERROR_STATUS || !begin(c, fn)) return 0;
    d->fresh = 0;
    /* the slave computes the initial state (or keeps the one its outputs already show); a failure
     * is logged by it with status fmi2Error */
    if (end(c, W.ExitInitializationMode(d->w)) >= GF_ERROR_STATUS) {
        d->initialized = 0;
        return 0;
    }
    d->py_mode = GF_STEP_MODE;
    if (take_outputs(c, fn) >= GF_ERROR_STATUS) return 0;
    d->initialized = 1;
    c->dirty = 0;
    return 1;
}

int gm_refresh_outputs(gf_inst *c, const char *fn, const unsigned int vr[], size_t nvr)
{
    size_t i;
    int want = 0;
    if (c->mode != GF_INIT_MODE || !c->dirty) return 1;
    for (i = 0; i < nvr && !want; ++i) want = (long)vr[i] < (long)c->n_vars && c->vars[vr[i]].causality == GF_OUTPUT;
    if (!want) return 1;
    if (slave_in_init(c, fn) >= GF_ERROR_STATUS || hand_over(c, fn) >= GF_ERROR_STATUS ||
        take_outputs(c, fn) >= GF_ERROR_STATUS) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: the initial outputs cannot be computed from the values set "
               "(reasons above)", fn);
        return 0;
    }
    c->dirty = 0;
    return 1;
}

int gm_do_step(gf_inst *c, double t, double H)
{
    static const char *const fn = "fmi2DoStep";
    gm_data *d = c->data;
    int st;
    if (isfinite(t)) c->time = t;
    if (hand_over(c, fn) >= GF_ERROR_STATUS) return c->data->dead ? GF_FATAL : GF_DISCARD;
    c->dirty = 0;
    if (!begin(c, fn)) return GF_ERROR_STATUS;
    d->fresh = 0;
    st = (int)W.DoStep(d->w, c->time, H, fmi2True);
    if (st == fmi2Fatal) {
        end(c, fmi2Fatal);
        return GF_FATAL;
    }
    if (st != fmi2OK) return GF_DISCARD; /* the slave logged why; state unchanged */
    if (take_outputs(c, fn) >= GF_ERROR_STATUS) return c->data->dead ? GF_FATAL : GF_DISCARD;
    c->time = c->time + H;
    return GF_OK;
}

/* ------------------------------------------------------------ FMU state */
/* the size of the slave's serialized state, asked once */
static size_t py_size(const gf_inst *c, const char *fn)
{
    gf_inst *cc = (gf_inst *)c; /* the slave is asked; the instance's FMI state does not change */
    gm_data *d = c->data;
    fmi2FMUstate s = NULL;
    size_t n = 0;
    if (d->py_state_size > 0 || !begin(cc, fn)) return d->py_state_size;
    if (end(cc, W.GetFMUstate(d->w, &s)) < GF_ERROR_STATUS && s != NULL) {
        if (end(cc, W.SerializedFMUstateSize(d->w, s, &n)) < GF_ERROR_STATUS) d->py_state_size = n;
        if (!d->dead) W.FreeFMUstate(d->w, &s);
    }
    return d->py_state_size;
}

size_t gm_snap_size(const gf_inst *c)
{
    return sizeof(snap_header) + sizeof(double) * ((size_t)c->n_vars + (size_t)c->n_out) + py_size(c, "fmi2GetFMUstate");
}

void gm_snap_write(const gf_inst *c, unsigned char *p)
{
    gm_data *d = c->data;
    snap_header h;
    size_t np = py_size(c, "fmi2GetFMUstate"), n = 0, at = sizeof h + sizeof(double) * ((size_t)c->n_vars + (size_t)c->n_out);
    fmi2FMUstate s = NULL;
    memset(&h, 0, sizeof h);
    h.magic = SNAP_MAGIC;
    h.version = SNAP_VERSION;
    h.n_vars = (uint32_t)c->n_vars;
    h.n_out = (uint32_t)c->n_out;
    h.tag = d->tag;
    h.py_size = np;
    h.mode = c->mode;
    h.dirty = c->dirty;
    h.initialized = d->initialized;
    h.py_mode = d->py_mode;
    h.time = c->time;
    memcpy(p, &h, sizeof h);
    memcpy(p + sizeof h, c->values, sizeof(double) * (size_t)c->n_vars);
    memcpy(p + sizeof h + sizeof(double) * (size_t)c->n_vars, c->out, sizeof(double) * (size_t)c->n_out);
    memset(p + at, 0, np); /* a slave that cannot give its state leaves zeros, which it refuses on restore */
    if (np > 0 && begin((gf_inst *)c, "fmi2GetFMUstate") &&
        end((gf_inst *)c, W.GetFMUstate(d->w, &s)) < GF_ERROR_STATUS && s != NULL) {
        if (end((gf_inst *)c, W.SerializedFMUstateSize(d->w, s, &n)) < GF_ERROR_STATUS && n == np)
            end((gf_inst *)c, W.SerializeFMUstate(d->w, s, (fmi2Byte *)(p + at), n));
        if (!d->dead) W.FreeFMUstate(d->w, &s);
    }
    h.check = fnv1a(14695981039346656037ull, p, sizeof h + (at - sizeof h) + np);
    memcpy(p + offsetof(snap_header, check), &h.check, sizeof h.check);
}

int gm_snap_is_ours(const gf_inst *c, const unsigned char *p, size_t size)
{
    snap_header h;
    uint64_t zero = 0, sum;
    if (size < sizeof h) return 0;
    memcpy(&h, p, sizeof h);
    if (h.magic != SNAP_MAGIC || h.version != SNAP_VERSION || h.tag != c->data->tag ||
        h.n_vars != (uint32_t)c->n_vars || h.n_out != (uint32_t)c->n_out ||
        size != sizeof h + sizeof(double) * ((size_t)c->n_vars + (size_t)c->n_out) + h.py_size)
        return 0;
    sum = fnv1a(14695981039346656037ull, p, offsetof(snap_header, check));
    sum = fnv1a(sum, (const unsigned char *)&zero, sizeof zero);
    sum = fnv1a(sum, p + offsetof(snap_header, check) + sizeof zero, size - offsetof(snap_header, check) - sizeof zero);
    return sum == h.check;
}

int gm_snap_read(gf_inst *c, const unsigned char *p, size_t size, const char *fn)
{
    gm_data *d = c->data;
    snap_header h;
    fmi2FMUstate s = NULL;
    size_t at;
    int st;
    if (!gm_snap_is_ours(c, p, size)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: not a state of this FMU (header mismatch)", fn);
        return 0;
    }
    memcpy(&h, p, sizeof h);
    if ((h.mode & GF_ANY_STATE) == 0 || (h.mode & (h.mode - 1)) != 0 || (h.initialized & ~1) != 0 ||
        (h.dirty & ~1) != 0 || (h.py_mode != GF_INSTANTIATED && h.py_mode != GF_INIT_MODE && h.py_mode != GF_STEP_MODE)) {
        gf_log(c, GF_ERROR_STATUS, "logStatusError", "%s: state has an invalid FMI state %d", fn, (int)h.mode);
        return 0;
    }
    /* the slave first: it checks its part (checksum, fingerprint) and refuses with its reason */
    at = sizeof h + sizeof(double) * ((size_t)c->n_vars + (size_t)c->n_out);
    if (!begin(c, fn)) return 0;
    d->fresh = 0;
    st = end(c, W.DeSerializeFMUstate(d->w, (const fmi2Byte *)(p + at), (size_t)h.py_size, &s));
    if (st < GF_ERROR_STATUS && s != NULL) st = end(c, W.SetFMUstate(d->w, s));
    if (s != NULL && !d->dead) W.FreeFMUstate(d->w, &s);
    if (st >= GF_ERROR_STATUS) return 0;
    c->mode = h.mode;
    c->dirty = h.dirty;
    c->time = h.time;
    d->initialized = h.initialized;
    d->py_mode = h.py_mode;
    memcpy(c->values, p + sizeof h, sizeof(double) * (size_t)c->n_vars);
    memcpy(c->out, p + sizeof h + sizeof(double) * (size_t)c->n_vars, sizeof(double) * (size_t)c->n_out);
    return 1;
}
