"""The pythonfmu runtime's FMU never takes its host down, and holds no path of the machine that
built it (docs/fmu.md "The binary").

Hosts: tests/fmu_hosts/fmi_host.c (one FMU, plain C), tests/fmu_hosts/fmi_threads_host.c (several
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

from gearfmu.common.cache import cache_dir, cache_root
from gearfmu.fmu.fmudoc import build_machine_paths
from gearfmu.fmu.pythonfmu_build import (PYSHIM_CONFIG, PYSHIM_SOURCE, PYTHON_OVERRIDE_VARIABLE, PYTHON_RECORD_FORMAT,
                                         PYTHON_RECORDS, build_fmu, python_record)
from gearfmu.fmu.standalone_build import fmi2_header_dir
from factories import make_tables

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

HERE = os.path.dirname(os.path.abspath(__file__))
RUNS = 20
REFUSED = "the pythonfmu runtime needs"


def _clean_env():
    """The environment of a C/C++ master that knows nothing of Python."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("LD_PRELOAD", "PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV", "LD_LIBRARY_PATH",
                        PYTHON_OVERRIDE_VARIABLE)}
    return env


def _record_id(unzipped):
    """The id of the build's Python record an unzipped FMU names (resources/gearfmu_pyshim.txt)."""
    lines = (Path(unzipped) / "resources" / PYSHIM_CONFIG).read_text().splitlines()
    return next(ln.split("=", 1)[1] for ln in lines if ln.startswith("python_record="))


def _write_record(root, rid, **fields):
    """A record of a Python under the cache folder ``root`` (the build's own, with ``fields`` replaced)."""
    rec = dict(ln.split("=", 1) for ln in python_record()[1].splitlines()[1:])
    rec.update(fields)
    d = Path(root) / PYTHON_RECORDS
    d.mkdir(parents=True, exist_ok=True)
    (d / f"{rid}.txt").write_text(PYTHON_RECORD_FORMAT + "\n" + "".join(f"{k}={v}\n" for k, v in rec.items()))


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
    """20 fresh C-host processes on the build machine, no LD_PRELOAD, no PYTHONPATH, no
    GEARFMU_PYTHON: the binary loads every time and finds the build's Python through the record
    the build left in gearfmu's cache; every run completes (exit 0) with the same result."""
    res = _batches([_host_cmd(two, two["a"])] * RUNS, _clean_env())
    bad = [(rc, e[-400:]) for rc, o, e in res if rc != 0]
    assert bad == [], bad
    finals = {o.strip().splitlines()[-1] for rc, o, e in res}
    assert len(finals) == 1  # the runs agree


def test_the_build_records_its_python_outside_the_fmu(two):
    """The build's record of its Python: gearfmu's cache folder, pythons/<id>.txt with the id the
    FMU names; plain text (the format line, then key=value lines) naming this Python's executable
    and shared library; written atomically (no part file left beside it)."""
    rid = _record_id(two["a"]["dir"])
    assert rid == _record_id(two["b"]["dir"]) == python_record()[0]  # one record per environment
    path = cache_dir(PYTHON_RECORDS) / f"{rid}.txt"
    lines = path.read_text(encoding="utf-8").splitlines()
    assert lines[0] == PYTHON_RECORD_FORMAT
    rec = dict(ln.split("=", 1) for ln in lines[1:])
    assert rec["python_executable"] == sys.executable and rec["libpython"] == _libpython()
    assert rec["python_version"] == f"{sys.version_info.major}.{sys.version_info.minor}"
    assert "/" not in rec["environment"]
    assert not [p for p in path.parent.iterdir() if p.name.startswith(path.name) and p != path]


def test_loader_constants_agree_with_the_builder():
    """The names the loader (pyshim.c) and the builder share: the FMU's file, the cache folder of
    the records, their first line and the override variable."""
    src = PYSHIM_SOURCE.read_text()
    for name, value in (("CONFIG_FILE", PYSHIM_CONFIG), ("RECORD_DIR", PYTHON_RECORDS),
                        ("RECORD_FORMAT", PYTHON_RECORD_FORMAT), ("OVERRIDE_VARIABLE", PYTHON_OVERRIDE_VARIABLE)):
        assert f'#define {name} "{value}"\n' in src, name


@pytest.mark.parametrize("rule", ["GEARFMU_CACHE_DIR", "XDG_CACHE_HOME", "HOME"])
def test_the_loader_finds_the_record_by_the_cache_folder_rule(two, tmp_path, monkeypatch, rule):
    """The loader looks for the record where gearfmu.common.cache puts its cache: a record placed in
    the folder Python's cache_root() names under each of its three rules ($GEARFMU_CACHE_DIR, else
    $XDG_CACHE_HOME/gearfmu, else ~/.cache/gearfmu) is found by the C host, which runs."""
    env = _clean_env()
    for k in ("GEARFMU_CACHE_DIR", "XDG_CACHE_HOME"):
        env.pop(k, None)
        monkeypatch.delenv(k, raising=False)
    where = {"GEARFMU_CACHE_DIR": tmp_path / "cache", "XDG_CACHE_HOME": tmp_path / "xdg", "HOME": tmp_path / "home"}
    env[rule] = str(where[rule])
    monkeypatch.setenv(rule, str(where[rule]))
    root = cache_root()
    assert str(root).startswith(str(tmp_path))
    _write_record(root, _record_id(two["a"]["dir"]))
    rc, o, e = _batches([_host_cmd(two, two["a"])], env)[0]
    assert rc == 0, (rc, e[-600:])


RETRY_HOST = textwrap.dedent(r"""
    /* One FMU, one process: fmi2Instantiate without a Python to start (must be NULL), then with
     * GEARFMU_PYTHON set to argv[4] (must succeed).  Exit 0 iff the first is refused and the second
     * instantiates. */
    #define _GNU_SOURCE
    #include <dlfcn.h>
    #include <stdarg.h>
    #include <stdio.h>
    #include <stdlib.h>
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

    int main(int argc, char **argv)
    {
        char path[4200], uri[4200];
        void *lib;
        fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
        fmi2Component first, second;
        if (argc != 5) return 1;
        snprintf(path, sizeof path, "%s/binaries/linux64/%s.so", argv[1], argv[2]);
        snprintf(uri, sizeof uri, "file://%s/resources", argv[1]);
        if ((lib = dlopen(path, RTLD_NOW | RTLD_LOCAL)) == NULL) return 2;
        fmi2InstantiateTYPE *inst = (fmi2InstantiateTYPE *)dlsym(lib, "fmi2Instantiate");
        fmi2FreeInstanceTYPE *fr = (fmi2FreeInstanceTYPE *)dlsym(lib, "fmi2FreeInstance");
        first = inst("first", fmi2CoSimulation, argv[3], uri, &cb, fmi2False, fmi2False);
        fprintf(stderr, "FIRST %s\n", first ? "ok" : "NULL");
        setenv("GEARFMU_PYTHON", argv[4], 1);
        second = inst("second", fmi2CoSimulation, argv[3], uri, &cb, fmi2False, fmi2False);
        fprintf(stderr, "SECOND %s\n", second ? "ok" : "NULL");
        if (second != NULL) fr(second);
        return first == NULL && second != NULL ? 0 : 4;
    }
""")


def test_no_record_and_no_override_is_refused_and_the_override_runs(two, tmp_path):
    """The record removed (an empty cache folder) and no GEARFMU_PYTHON, as on a machine the FMU
    was copied to: fmi2Instantiate returns NULL, exit status 4 (no crash), with one logged line
    naming the build's environment by its path-free description and what to do (set
    GEARFMU_PYTHON, or the standalone runtime).  With GEARFMU_PYTHON set to this Python the C
    host runs and gives what it gives with the record.  In one process the refusal is not
    remembered: a second fmi2Instantiate after setting the variable succeeds."""
    empty = tmp_path / "empty-cache"
    empty.mkdir()
    env = dict(_clean_env(), GEARFMU_CACHE_DIR=str(empty), PATH="/usr/bin:/bin")
    f = two["a"]
    rc, o, e = _batches([_host_cmd(two, f)], env)[0]
    assert rc == 4, (rc, e[-600:])
    said = [ln for ln in e.splitlines() if "fmi2Instantiate:" in ln]
    assert len(said) == 1, e[-800:]
    description = next(ln for ln in (f["dir"] / "resources" / PYSHIM_CONFIG).read_text().splitlines()
                       if ln.startswith("environment="))[len("environment="):]
    assert f"the Python this FMU was built with ({description}) is not recorded on this machine" in said[0]
    assert f"set {PYTHON_OVERRIDE_VARIABLE} to the executable of a Python" in said[0]
    assert "--runtime standalone" in said[0]

    rc, o2, e2 = _batches([_host_cmd(two, f)], dict(env, **{PYTHON_OVERRIDE_VARIABLE: sys.executable}))[0]
    assert rc == 0, (rc, e2[-600:])
    rc, o3, e3 = _batches([_host_cmd(two, f)], _clean_env())[0]
    assert rc == 0 and o2 == o3, (rc, e3[-600:])

    (tmp_path / "retry_host.c").write_text(RETRY_HOST)
    host = _cc(tmp_path / "retry_host.c", tmp_path / "retry_host", "-ldl")
    rc, o, e = _batches([[str(host), str(f["dir"]), f["id"], f["guid"], sys.executable]], env)[0]
    assert rc == 0 and "FIRST NULL" in e and "SECOND ok" in e, (rc, e[-800:])


def test_an_unwritable_cache_is_no_failure_of_the_build(two, tmp_path, monkeypatch, capfd):
    """gearfmu's cache folder cannot be written (it is a file): two builds succeed, stderr says once
    that the record could not be written and what that means, and the FMU runs in a Python host
    (fmpy), where libpython is in the process, giving what the FMU built with the record gives."""
    import gearfmu.fmu.pythonfmu_build as pb

    blocker = tmp_path / "not-a-folder"
    blocker.write_text("a file where the cache folder would be\n")
    monkeypatch.setenv("GEARFMU_CACHE_DIR", str(blocker))
    monkeypatch.setattr(pb, "_UNWRITABLE_SAID", False)
    capfd.readouterr()
    fmus = [build_fmu(make_tables(), tmp_path / f"{k}.fmu", model_name="paira", stop_time_s=0.002,
                      output_interval_s=1e-4, max_step_s=1e-5) for k in ("x", "y")]
    err = capfd.readouterr().err
    assert err.count("cannot write the record of this build's Python") == 1, err[-800:]
    assert f"{PYTHON_OVERRIDE_VARIABLE} set to this Python's executable" in err
    runs = [fmpy.simulate_fmu(str(f), stop_time=0.002, output_interval=1e-4, output=["mesh_force"])
            for f in (fmus[0], two["a"]["fmu"])]
    assert len(runs[0]) == len(runs[1]) == 21
    assert runs[0]["mesh_force"].tolist() == runs[1]["mesh_force"].tolist()


def test_an_override_that_is_no_python_is_refused(two, tmp_path):
    """GEARFMU_PYTHON naming no executable file: NULL with the variable, its value and the remedy."""
    env = dict(_clean_env(), **{PYTHON_OVERRIDE_VARIABLE: str(tmp_path / "no" / "python")})
    rc, o, e = _batches([_host_cmd(two, two["a"])], env)[0]
    assert rc == 4, (rc, e[-600:])
    line = next(ln for ln in e.splitlines() if "fmi2Instantiate:" in ln)
    assert f"{PYTHON_OVERRIDE_VARIABLE} names {tmp_path / 'no' / 'python'}, which is not an executable file" in line
    assert "--runtime standalone" in line


def test_no_member_of_the_fmu_names_the_build_machine(two):
    """A pythonfmu FMU is a file to hand on: no member may hold a path of the machine that built
    it -- neither the build's Python (sys.executable, its resolved file, sys.prefix, the base
    prefix, libpython's path) nor the home folder nor the folder the FMU was built in (before:
    resources/gearfmu_pyshim.txt recorded libpython's and the executable's paths)."""
    marks = [sys.executable, os.path.realpath(sys.executable), sys.prefix, sys.base_prefix, _libpython(),
             os.path.expanduser("~"), str(two["a"]["fmu"].parent)]
    for key in ("a", "b"):
        assert build_machine_paths(two[key]["dir"], marks) == []


def test_c_host_refusal_names_what_is_missing(two, tmp_path):
    """No libpython to be found (recorded path and soname point nowhere): the C
    host gets NULL from fmi2Instantiate and the logged reason names the shared
    library and how to provide it."""
    d = tmp_path / "nopy"
    shutil.copytree(two["a"]["dir"], d)
    cfg = d / "resources" / PYSHIM_CONFIG
    lines = [ln for ln in cfg.read_text().splitlines() if not ln.startswith("libpython_soname")]
    cfg.write_text("\n".join(lines + ["libpython_soname=libpython3.99.so.1.0"]) + "\n")
    _write_record(tmp_path / "cache", _record_id(d), libpython="/nonexistent/libpython3.99.so.1.0")
    f = dict(two["a"], dir=d)
    rc, o, e = _batches([_host_cmd(two, f)], dict(_clean_env(), GEARFMU_CACHE_DIR=str(tmp_path / "cache")))[0]
    assert rc == 4, (rc, e[-600:])
    assert REFUSED in e and "shared library" in e and "LD_LIBRARY_PATH" in e and "--runtime standalone" in e


def test_gone_environment_is_named_not_a_module(two, tmp_path):
    """The virtual environment the FMU was built in is deleted (its interpreter, recorded at build
    time, is gone): the C host gets NULL from fmi2Instantiate, exit status 4, and the logged reason
    names that environment by a description without a path (Python and numpy versions) and the
    remedies -- not a module of whatever other Python the search would find (before:
    "... needs the Python module 'ctypes' ... (No module named '_struct')")."""
    cfg = two["a"]["dir"] / "resources" / PYSHIM_CONFIG
    env_line = next(ln for ln in cfg.read_text().splitlines() if ln.startswith("environment="))
    assert "/" not in env_line and f"Python {sys.version.split()[0]} with numpy" in env_line
    venv = tmp_path / "deleted_venv"
    _write_record(tmp_path / "cache", _record_id(two["a"]["dir"]), python_executable=f"{venv}/bin/python")
    # the search would find the system's Python
    env = dict(_clean_env(), PATH="/usr/bin:/bin", GEARFMU_CACHE_DIR=str(tmp_path / "cache"))
    rc, o, e = _batches([_host_cmd(two, two["a"])], env)[0]
    assert rc == 4, (rc, e[-600:])
    line = next(ln for ln in e.splitlines() if "fmi2Instantiate" in ln)
    assert f"the Python environment this FMU was built with ({env_line[len('environment='):]}) is gone" in line
    assert f"set {PYTHON_OVERRIDE_VARIABLE} to the executable" in line
    assert "--runtime standalone" in line and "module" not in line and str(tmp_path) not in line


FATAL_HOST = textwrap.dedent("""
    import sys
    import fmpy
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import FMU2Slave
    sys.path.insert(0, sys.argv[3])  # tests/, for the support package
    from support.fmpy_host import callbacks
    log = []
    md = fmpy.read_model_description(sys.argv[1] + "/modelDescription.xml")
    s = FMU2Slave(guid=md.guid, unzipDirectory=sys.argv[1], modelIdentifier=sys.argv[2], instanceName="fatal")
    s.instantiate(callbacks=callbacks(log), loggingOn=True)
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
    p = subprocess.run([sys.executable, str(script), str(d), two["a"]["id"], os.path.dirname(HERE)], capture_output=True, text=True,
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
    run (GEARFMU_PYTHON) a venv of the base interpreter whose site-packages first sleeps in a
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
        args += [str(two[key]["dir"]), two[key]["id"], two[key]["guid"]]
    (tmp_path / "late_host.c").write_text(LATE_HOST)
    host = _cc(tmp_path / "late_host.c", tmp_path / "late_host", "-ldl", "-lpthread")
    # the slow venv started in place of the build's Python (libpython: the lib folder of its home)
    res = _batches([[str(host), *args]] * 3, dict(_clean_env(), **{PYTHON_OVERRIDE_VARIABLE: str(py)}), width=1)
    assert [rc for rc, _, _ in res] == [0] * 3, [(rc, e[-600:]) for rc, _, e in res if rc != 0]
