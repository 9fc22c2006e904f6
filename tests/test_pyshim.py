"""The pythonfmu runtime's FMU never takes its host down (docs/fmu.md "The binary").

Hosts: tests/fmi_host.c (one FMU, plain C), tests/fmi_threads_host.c (several
FMUs instantiated at the same moment from several threads, plain C),
LATE_HOST below (a second FMU instantiated while the first one's interpreter
is still starting, plain C), and a Python interpreter without numpy driving the binary through ctypes.  Every
run is a fresh process; the reference is the FMI 2.0 contract (section 2.1.5:
fmi2Instantiate returns NULL when it cannot instantiate, and reports why
through the logger) and the process exit code (a crash is a signal, negative
in ``subprocess``).
"""
import os
import shutil
import subprocess
import sys
import textwrap
import zipfile
from pathlib import Path

import fmpy
import pytest

from gearfmu.fmu.pythonfmu_build import build_fmu
from gearfmu.fmu.standalone_build import fmi2_header_dir
from test_fmu import make_tables

HERE = os.path.dirname(os.path.abspath(__file__))
RUNS = 20
REFUSED = "the pythonfmu runtime needs"


def _clean_env():
    """The environment of a C/C++ master that knows nothing of Python."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("LD_PRELOAD", "PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV", "LD_LIBRARY_PATH")}
    return env


def _cc(src, exe, *libs):
    cc = shutil.which("gcc") or shutil.which("cc")
    subprocess.run([cc, "-std=c99", "-O1", "-Wall", f"-I{fmi2_header_dir()}", "-o", str(exe), str(src), *libs],
                   check=True, capture_output=True, text=True)
    return exe


@pytest.fixture(scope="module")
def two(tmp_path_factory):
    """Two different pythonfmu gear FMUs (small synthetic tables), unzipped, and the C hosts."""
    d = tmp_path_factory.mktemp("pyshim")
    out = {}
    for key, kw in (("a", {}), ("b", {"P": 3, "eps": 2.4, "e_amp": -1e-6, "b": 0.0})):
        fmu = build_fmu(make_tables(**kw), d / f"{key}.fmu", model_name=f"pair{key}", stop_time_s=0.002,
                        output_interval_s=1e-4, max_step_s=1e-5)
        md = fmpy.read_model_description(str(fmu))
        unzip = d / key
        zipfile.ZipFile(fmu).extractall(unzip)
        vrs = {v.name: v.valueReference for v in md.modelVariables}
        out[key] = {"fmu": fmu, "dir": unzip, "id": md.coSimulation.modelIdentifier, "guid": md.guid,
                    "vr": vrs["mesh_force"]}
    out["host"] = _cc(os.path.join(HERE, "fmi_host.c"), d / "fmi_host", "-ldl")
    out["threads"] = _cc(os.path.join(HERE, "fmi_threads_host.c"), d / "fmi_threads_host", "-ldl", "-lpthread")
    return out


def _batches(cmds, env, width=4):
    """Run the commands as fresh processes, ``width`` at a time; return (rc, stdout, stderr)."""
    res = []
    for i in range(0, len(cmds), width):
        procs = [subprocess.Popen(c, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
                 for c in cmds[i:i + width]]
        for p in procs:
            o, e = p.communicate(timeout=300)
            res.append((p.returncode, o, e))
    return res


def _host_cmd(two, f, stop="0.002"):
    return [str(two["host"]), str(f["dir"]), f["id"], f["guid"], stop, "1e-4", str(f["vr"])]


def test_c_host_without_python_loads_and_runs(two):
    """20 fresh C-host processes, no LD_PRELOAD, no PYTHONPATH: the binary loads
    every time, and each run completes (exit 0) or is refused at instantiation
    with the logged reason -- never a load failure, never a crash."""
    res = _batches([_host_cmd(two, two["a"])] * RUNS, _clean_env())
    bad = [(rc, e[-400:]) for rc, o, e in res if not (rc == 0 or (rc == 4 and REFUSED in e))]
    assert bad == [], bad
    finals = {o.strip().splitlines()[-1] for rc, o, e in res if rc == 0}
    assert len(finals) <= 1  # the completed runs agree


def test_c_host_refusal_names_what_is_missing(two, tmp_path):
    """No libpython to be found (recorded path and soname point nowhere): the C
    host gets NULL from fmi2Instantiate and the logged reason names the shared
    library and how to provide it."""
    d = tmp_path / "nopy"
    shutil.copytree(two["a"]["dir"], d)
    cfg = d / "resources" / "gearfmu_pyshim.txt"
    lines = [ln for ln in cfg.read_text().splitlines() if not ln.startswith(("libpython", "python_executable"))]
    cfg.write_text("\n".join(lines + ["libpython=/nonexistent/libpython3.99.so.1.0",
                                      "libpython_soname=libpython3.99.so.1.0"]) + "\n")
    f = dict(two["a"], dir=d)
    rc, o, e = _batches([_host_cmd(two, f)], _clean_env())[0]
    assert rc == 4, (rc, e[-600:])
    assert REFUSED in e and "shared library" in e and "LD_LIBRARY_PATH" in e and "--runtime standalone" in e


def test_gone_environment_is_named_not_a_module(two, tmp_path):
    """The virtual environment the FMU was built in is deleted (its interpreter, recorded at build
    time, is gone): the C host gets NULL from fmi2Instantiate, exit status 4, and the logged reason
    names that environment by a description without a path (Python and numpy versions) and the
    remedies -- not a module of whatever other Python the search would find (before:
    "... needs the Python module 'ctypes' ... (No module named '_struct')")."""
    d = tmp_path / "gone"
    shutil.copytree(two["a"]["dir"], d)
    cfg = d / "resources" / "gearfmu_pyshim.txt"
    env_line = next(ln for ln in cfg.read_text().splitlines() if ln.startswith("environment="))
    assert "/" not in env_line and f"Python {sys.version.split()[0]} with numpy" in env_line
    venv = tmp_path / "deleted_venv"
    lines = [ln for ln in cfg.read_text().splitlines() if not ln.startswith("python_executable")]
    cfg.write_text("\n".join(lines + [f"python_executable={venv}/bin/python"]) + "\n")
    env = dict(_clean_env(), PATH="/usr/bin:/bin")  # the search would find the system's Python
    rc, o, e = _batches([_host_cmd(two, dict(two["a"], dir=d))], env)[0]
    assert rc == 4, (rc, e[-600:])
    line = next(ln for ln in e.splitlines() if "fmi2Instantiate" in ln)
    assert f"the Python environment this FMU was built with ({env_line[len('environment='):]}) is gone" in line
    assert "--runtime standalone" in line and "module" not in line and str(tmp_path) not in line


FATAL_HOST = textwrap.dedent("""
    import sys
    import fmpy
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import FMU2Slave
    sys.path.insert(0, sys.argv[3])
    from test_standalone import _callbacks
    log = []
    md = fmpy.read_model_description(sys.argv[1] + "/modelDescription.xml")
    s = FMU2Slave(guid=md.guid, unzipDirectory=sys.argv[1], modelIdentifier=sys.argv[2], instanceName="fatal")
    s.instantiate(callbacks=_callbacks(log), loggingOn=True)
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    def status(f, *a):
        try:
            f(*a)
            return 0
        except FMICallException as exc:
            return exc.status
    print("STEP", status(s.doStep, 0.0, 1e-4), flush=True)
    print("AGAIN", status(s.doStep, 0.0, 1e-4), flush=True)
    print("GET", status(s.getReal, [7]), flush=True)
    print("RESET", status(s.reset), flush=True)
    print("EXIT", status(s.enterInitializationMode), flush=True)
    s.freeInstance()
    for st, m in log:
        print("LOG", st, m.replace(chr(10), " "), flush=True)
    print("END", flush=True)
""")


def test_a_fatal_slave_is_never_called_again(two, tmp_path):
    """A slave whose do_step raises (pythonfmu's wrapper then returns fmi2Fatal and releases the
    slave, keeping its pointers): the step returns fmi2Fatal with the exception logged; the
    instance is in the error state, its slave is not called again (a step is refused as an
    illegal call sequence, a reset cannot bring it back), gets are served, fmi2FreeInstance
    leaves the released slave alone, and the host exits 0."""
    d = tmp_path / "fatal"
    shutil.copytree(two["a"]["dir"], d)
    slave = d / "resources" / f"{two['a']['id']}.py"
    text = slave.read_text()
    head = "    def do_step(self, current_time, step_size):\n"
    assert text.count(head) == 1
    slave.write_text(text.replace(head, head + "        raise RuntimeError('slave broken on purpose')\n"))
    script = tmp_path / "host.py"
    script.write_text(FATAL_HOST)
    p = subprocess.run([sys.executable, str(script), str(d), two["a"]["id"], HERE], capture_output=True, text=True,
                       timeout=300)
    assert p.returncode == 0 and "END" in p.stdout, (p.returncode, p.stdout[-600:], p.stderr[-600:])
    got = dict(line.split() for line in p.stdout.splitlines() if line.split()[0] in ("STEP", "AGAIN", "GET",
                                                                                       "RESET", "EXIT"))
    assert got == {"STEP": "4", "AGAIN": "3", "GET": "0", "RESET": "0", "EXIT": "3"}
    logs = [line for line in p.stdout.splitlines() if line.startswith("LOG ")]
    assert any("slave broken on purpose" in line for line in logs)
    assert any("fmi2DoStep: illegal call sequence: not allowed in state error" in line for line in logs)
    assert any("fmi2Reset: the Python slave of this instance ended with fmi2Fatal" in line for line in logs)


def _libpython():
    import sysconfig

    return os.path.join(sysconfig.get_config_var("LIBDIR"), sysconfig.get_config_var("INSTSONAME"))


@pytest.mark.parametrize("preload", [True, False], ids=["libpython-preloaded", "no-preload"])
def test_two_fmus_instantiated_at_once_from_two_threads(two, preload):
    """20 fresh processes of a C host that instantiates two different gear FMUs
    at the same moment from two threads, with libpython loaded but Python not
    started (LD_PRELOAD) or not loaded at all: every run exits 0 and gives what
    the FMU gives alone in the C host."""
    env = _clean_env()
    if preload:
        env["LD_PRELOAD"] = _libpython()
    a, b = two["a"], two["b"]
    # both FMUs have the same mesh_force value reference (same spec order)
    assert a["vr"] == b["vr"]
    cmd = [str(two["threads"]), "20", "1e-4", str(a["vr"]),
           str(a["dir"]), a["id"], a["guid"], str(b["dir"]), b["id"], b["guid"]]
    res = _batches([cmd] * RUNS, env)
    assert [rc for rc, _, _ in res] == [0] * RUNS, [(rc, e[-300:]) for rc, _, e in res if rc != 0]
    finals = {o for _, o, _ in res}
    assert len(finals) == 1
    alone = {}
    for k, key in enumerate(("a", "b")):
        rc, o, e = _batches([_host_cmd(two, two[key])], env)[0]
        assert rc == 0, e[-400:]
        alone[k] = float(o.strip().splitlines()[-1].split(",")[1])
    got = dict((int(x.split()[0]), float(x.split()[1])) for x in finals.pop().strip().splitlines())
    assert got == alone


CTYPES_HOST = textwrap.dedent("""
    import ctypes, sys
    lib = ctypes.CDLL(sys.argv[1])
    LOGGER = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                              ctypes.c_char_p, ctypes.c_char_p)   # x86-64: the first vararg
    @LOGGER
    def logger(env, name, status, category, fmt, arg):
        print("LOG", status, (fmt or b"").decode(), (arg or b"").decode() if fmt == b"%s" else "", flush=True)
    class CB(ctypes.Structure):
        _fields_ = [("logger", LOGGER), ("allocate", ctypes.c_void_p), ("free", ctypes.c_void_p),
                    ("step_finished", ctypes.c_void_p), ("env", ctypes.c_void_p)]
    libc = ctypes.CDLL(None)
    cb = CB(logger, ctypes.cast(libc.calloc, ctypes.c_void_p), ctypes.cast(libc.free, ctypes.c_void_p), None, None)
    lib.fmi2Instantiate.restype = ctypes.c_void_p
    lib.fmi2Instantiate.argtypes = [ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p,
                                    ctypes.POINTER(CB), ctypes.c_int, ctypes.c_int]
    c = lib.fmi2Instantiate(b"nonumpy", 1, sys.argv[2].encode(), sys.argv[3].encode(), ctypes.byref(cb), 0, 1)
    print("INSTANCE", "NULL" if not c else "ok", flush=True)
""")


def test_python_host_without_numpy_is_refused_cleanly(two, tmp_path):
    """A Python interpreter without numpy (a venv of the base interpreter)
    loads the binary and calls fmi2Instantiate: NULL and a logged message naming
    numpy, exit code 0 -- no crash."""
    venv = tmp_path / "venv"
    base = getattr(sys, "_base_executable", sys.executable)
    subprocess.run([base, "-m", "venv", "--without-pip", str(venv)], check=True, capture_output=True)
    py = venv / "bin" / "python"
    env = _clean_env()
    probe = subprocess.run([str(py), "-c", "import numpy"], capture_output=True, text=True, env=env)
    assert probe.returncode != 0, "the venv must lack numpy"
    script = tmp_path / "host.py"
    script.write_text(CTYPES_HOST)
    f = two["a"]
    rc, o, e = _batches([[str(py), str(script), str(f["dir"] / "binaries" / "linux64" / f"{f['id']}.so"),
                          f["guid"], f"file://{f['dir']}/resources"]], env)[0]
    assert rc == 0, (rc, o[-400:], e[-400:])
    assert "INSTANCE NULL" in o
    assert REFUSED in o and "'numpy'" in o and "install it" in o  # what is missing, how to provide it


LATE_HOST = textwrap.dedent(r"""
    /* Two FMUs, one thread each: the first instantiates at once; the second waits until
     * Py_IsInitialized() says 1 -- the interpreter the first one started is up, though it
     * may still be importing site -- and only then instantiates.  Exit 0 iff both instances
     * are created. */
    #define _GNU_SOURCE
    #include <dlfcn.h>
    #include <pthread.h>
    #include <stdarg.h>
    #include <stdio.h>
    #include <stdlib.h>
    #include <unistd.h>
    #include "fmi2Functions.h"

    static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                       fmi2String message, ...)
    {
        va_list ap;
        (void)env; (void)category;
        fprintf(stderr, "[%s %d] ", name ? name : "?", (int)status);
        va_start(ap, message);
        vfprintf(stderr, message, ap);
        va_end(ap);
        fputc('\n', stderr);
    }

    typedef struct { const char *dir, *id, *guid; void *lib; int late, ok; } job;

    static void *run(void *arg)
    {
        job *j = (job *)arg;
        char uri[4200];
        fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
        fmi2InstantiateTYPE *inst = (fmi2InstantiateTYPE *)dlsym(j->lib, "fmi2Instantiate");
        fmi2FreeInstanceTYPE *fr = (fmi2FreeInstanceTYPE *)dlsym(j->lib, "fmi2FreeInstance");
        fmi2Component c;
        if (j->late) {
            int (*up)(void) = NULL;
            while (up == NULL || !up()) {
                usleep(200);
                if (up == NULL) *(void **)(&up) = dlsym(RTLD_DEFAULT, "Py_IsInitialized");
            }
        }
        snprintf(uri, sizeof uri, "file://%s/resources", j->dir);
        c = inst(j->id, fmi2CoSimulation, j->guid, uri, &cb, fmi2False, fmi2False);
        j->ok = c != NULL;
        if (c != NULL) fr(c);
        return NULL;
    }

    int main(int argc, char **argv)
    {
        job jobs[2];
        pthread_t t[2];
        char path[4200];
        int i;
        if (argc != 7) return 1;
        for (i = 0; i < 2; ++i) {
            jobs[i] = (job){argv[1 + 3 * i], argv[2 + 3 * i], argv[3 + 3 * i], NULL, i, 0};
            snprintf(path, sizeof path, "%s/binaries/linux64/%s.so", jobs[i].dir, jobs[i].id);
            if ((jobs[i].lib = dlopen(path, RTLD_NOW | RTLD_LOCAL)) == NULL) return 2;
        }
        for (i = 0; i < 2; ++i) pthread_create(&t[i], NULL, run, &jobs[i]);
        for (i = 0; i < 2; ++i) pthread_join(t[i], NULL);
        return jobs[0].ok && jobs[1].ok ? 0 : 4;
    }
""")


def test_fmu_started_while_another_fmus_python_imports_site(two, tmp_path):
    """Py_IsInitialized() turns 1 before the interpreter imports site (which puts
    site-packages, and numpy with it, on sys.path).  A second FMU instantiated in
    that window must wait for the first FMU's start to finish, not import numpy
    from a half-started interpreter.  The window is widened on purpose: the FMUs
    run a venv of the base interpreter whose site-packages first sleeps in a
    .pth file and then adds this environment's site-packages.  Reference: the
    FMI 2.0 contract (fmi2Instantiate of a healthy FMU returns an instance);
    3 fresh processes, every one must create both instances."""
    import sysconfig

    venv = tmp_path / "venv"
    base = getattr(sys, "_base_executable", sys.executable)
    subprocess.run([base, "-m", "venv", "--without-pip", str(venv)], check=True, capture_output=True)
    py = venv / "bin" / "python"
    site_dir = subprocess.run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                              check=True, capture_output=True, text=True).stdout.strip()
    (Path(site_dir) / "00_slow.pth").write_text("import time; time.sleep(1.0)\n")
    (Path(site_dir) / "zz_env.pth").write_text(
        f"import site; site.addsitedir({sysconfig.get_paths()['purelib']!r})\n")
    args = []
    for key in ("a", "b"):
        d = tmp_path / key
        shutil.copytree(two[key]["dir"], d)
        cfg = d / "resources" / "gearfmu_pyshim.txt"
        lines = [ln for ln in cfg.read_text().splitlines() if not ln.startswith("python_executable")]
        cfg.write_text("\n".join(lines + [f"python_executable={py}"]) + "\n")
        args += [str(d), two[key]["id"], two[key]["guid"]]
    (tmp_path / "late_host.c").write_text(LATE_HOST)
    host = _cc(tmp_path / "late_host.c", tmp_path / "late_host", "-ldl", "-lpthread")
    res = _batches([[str(host), *args]] * 3, _clean_env(), width=1)
    assert [rc for rc, _, _ in res] == [0] * 3, [(rc, e[-600:]) for rc, _, e in res if rc != 0]
