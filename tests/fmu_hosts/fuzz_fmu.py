"""Fuzz the gearfmu FMU through fmpy's low-level FMI 2.0 API.

Random sequences of FMI calls -- out of order (a third of the draws follow the legal order, so
that the deep states are reached), NaN/inf/huge/negative inputs
and parameters, zero/negative/non-finite/huge communication steps, calls
after terminate, repeated reset, FMU state get/set/free/serialize/deserialize
in any order, corrupted serialized states, invalid value references -- against
one small FMU (two tooth-pair slots, a two-row torque axis so that torque
clamping is exercised).

Each batch of sequences runs in a child process: a host crash (signal or
non-zero exit code, also at interpreter exit) is *counted*, never fatal to
the fuzzer.  Every call that returns a status other than fmi2OK/fmi2Warning
must have logged at least one message during that call (its reason);
``unlogged_refusals`` counts those that did not.

The standalone (all-C) runtime is fuzzed by a C host, tests/fmu_hosts/fmi_fuzz.c,
which runs thousands of sequences per process (no Python per call): random
orders of every fmi2 function of Co-Simulation, the same kinds of values, NULL
arrays, truncated and corrupted serialized states.  It counts, besides crashes
and unlogged refusals, the calls the FMU refused as an illegal call sequence
(its state table) and the sequences that broke the order at least once.

Both runtimes answer through one FMI layer (docs/fmu.md "The binary"); ``--compare`` runs the
same sequences (FMU-state calls left out) on both through fmpy and names the seeds whose
statuses, messages or values differ.

Usage::

    python tests/fmu_hosts/fuzz_fmu.py --sequences 10000 --json [--batch 50] [--seed 0] [--jobs 2]
    python tests/fmu_hosts/fuzz_fmu.py --runtime standalone --sequences 10000 --json [--batch 2500]
    python tests/fmu_hosts/fuzz_fmu.py --runtime pythonfmu --host c --sequences 10000 --json
    python tests/fmu_hosts/fuzz_fmu.py --compare --sequences 2000 --json

prints ``{"sequences", "host_crashes", "fmi_errors", "fmi_fatal", ...}``.
Importable: :func:`run_fuzz` and :func:`run_c_fuzz` (used by tests/fmu_hosts/test_fuzz.py),
:func:`build_fuzz_fmu`.
A sequence is reproducible from its seed: ``--first-seed S --sequences 1``.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import random
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

OK, WARNING, DISCARD, ERROR, FATAL, PENDING = 0, 1, 2, 3, 4, 5

#: values thrown at Real inputs and parameters
NASTY_REALS = [float("nan"), float("inf"), -float("inf"), 1e308, -1e308, 1e-308, 0.0, -0.0, -1.0, 1e6, -1e6, 5e-324]
#: communication step sizes
NASTY_STEPS = [0.0, -1e-4, float("nan"), float("inf"), -float("inf"), 1e6, 1e-300, 5e-324, 1e308]


def build_fuzz_fmu(directory, runtime: str = "pythonfmu", interface: str = "both") -> Path:
    """A small FMU for fuzzing: synthetic rectangular-wave tables (P = 2),
    torque axis [50, 150] N.m, max_step 1e-5 s; ``runtime`` "pythonfmu" or "standalone";
    ``interface``: the standalone FMU's FMI interfaces ("both", "cs" or "me"; pythonfmu: Co-Simulation)."""
    import numpy as np

    from gearfmu.tables.synthetic import rectangular_wave_tables

    if runtime == "standalone":
        from functools import partial

        from gearfmu.fmu.standalone_build import build_standalone_fmu

        build_fmu = partial(build_standalone_fmu, validation=False, interface=interface)
    else:
        from gearfmu.fmu.pythonfmu_build import build_fmu

    t = rectangular_wave_tables(2e8, contact_ratio=1.6, points_per_mesh=32, backlash_half_m=1e-5)
    t = replace(t, torque_Nm=np.array([50.0, 150.0]), k_N_per_m=np.concatenate([t.k_N_per_m, 1.1 * t.k_N_per_m]),
                e_m=np.concatenate([t.e_m, t.e_m]), e_comprehensive_m=None, static_te_m=None,
                provenance={"source": "tests/fmu_hosts/fuzz_fmu.py"})
    return build_fmu(t, Path(directory) / "fuzz.fmu", model_name="fuzz", max_step_s=1e-5, stop_time_s=0.01,
                     output_interval_s=1e-4, pinion_torque_start_Nm=100.0)


# ---------------------------------------------------------------- the child
#: the legal order of FMI 2.0 Co-Simulation calls, which a third of the draws follow
LEGAL_ORDER = ("setup", "enter", "setreal", "exit", "step", "get", "step", "get", "terminate")
#: the operations on FMU states, left out of a traced run (the two runtimes' states differ in layout)
STATE_OPS = ("getstate", "setstate", "freestate", "serialize", "deserialize")


def _child(fmu_path: str, seeds: list[int], trace: bool = False) -> None:
    """Run the sequences ``seeds``; print one JSON line per finished sequence.  ``trace``: leave
    out the FMU-state operations and add ``trace``, the SHA-256 of every call's name, status,
    messages other than fmi2OK ones, and values read (the record two runtimes must agree on)."""
    import hashlib

    import fmpy
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
    from fmpy.fmi2 import fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE
    from fmpy.logging import addLoggerProxy
    from ctypes import byref

    md = fmpy.read_model_description(fmu_path)
    unzip = fmpy.extract(fmu_path)
    reals = [v for v in md.modelVariables if v.type == "Real"]
    writable = [v.valueReference for v in reals if v.causality in ("input", "parameter")]
    outputs = [v.valueReference for v in reals if v.causality == "output"]
    ints = [v.valueReference for v in md.modelVariables if v.type == "Integer"]
    all_real = [v.valueReference for v in reals]
    log = []
    trace_env = bool(os.environ.get("GEARFMU_FUZZ_TRACE"))

    def logger(env, instance, status, category, message):
        log.append((int(status), (category or b"").decode("utf-8", "replace"),
                    (message or b"").decode("utf-8", "replace")))

    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(logger)
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(fmpy.calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(fmpy.free)
    addLoggerProxy(byref(callbacks))  # the message is a printf format (FMI 2.0 section 2.1.5): formatted

    for seed in seeds:
        rng = random.Random(seed)
        counts = {"calls": 0, "ok": 0, "warning": 0, "discard": 0, "error": 0, "fatal": 0,
                  "unlogged_refusals": 0, "logged_errors_on_ok": 0, "unlogged_examples": []}
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                        instanceName=f"fuzz{seed}")
        states, blobs = [], []
        digest = hashlib.sha256()
        t = 0.0
        logging_on = True  # the host may switch logging off (fmi2SetDebugLogging); then refusals are silent

        def call(name, fn, *args):
            del log[:]
            counts["calls"] += 1
            if trace_env:
                print(f"CALL {name}{args!r:.100}", file=sys.stderr, flush=True)
            try:
                r = fn(*args)
                status = OK
            except FMICallException as exc:
                status, r = int(exc.status), None
            key = {OK: "ok", WARNING: "warning", DISCARD: "discard", ERROR: "error", FATAL: "fatal"}.get(status, "error")
            counts[key] += 1
            if trace_env:
                print(f"{name}{args!r:.100} -> {status} {log!r:.300}", file=sys.stderr, flush=True)
            if trace:
                digest.update(repr((name, status, [(s, m) for s, _, m in log if s > OK],
                                    r if name in ("get", "getint", "badvr") else None)).encode())
            if status >= DISCARD and logging_on and not any(s >= WARNING and m for s, _, m in log):
                counts["unlogged_refusals"] += 1
                if len(counts["unlogged_examples"]) < 3:
                    counts["unlogged_examples"].append(f"{name}{args!r:.80}")
            if status == OK and any(s >= ERROR for s, _, _ in log):
                counts["logged_errors_on_ok"] += 1
            return status, r

        try:
            fmu.instantiate(callbacks=callbacks, loggingOn=True)
        except Exception:  # noqa: BLE001 - a refused instantiation is an error, not a crash
            counts["error"] += 1
            print(json.dumps({"seed": seed, **counts}), flush=True)
            continue
        fatal = False
        legal = 0
        for _ in range(rng.randint(5, 40)):
            if rng.random() < 1 / 3:  # a third of the draws: the next call of the legal order (deep states)
                op = LEGAL_ORDER[legal % len(LEGAL_ORDER)]
                legal += 1
            else:
                op = rng.choice(["setup", "enter", "exit", "step", "step", "step", "step", "setreal", "setreal",
                                 "setint", "get", "getint", "getstate", "setstate", "freestate", "serialize",
                                 "deserialize", "terminate", "reset", "badvr", "debug"])
            if trace and op in STATE_OPS:
                continue
            if op == "setup":
                st, _ = call(op, fmu.setupExperiment, None, rng.choice([0.0, t, -1.0, 1e300]))
            elif op == "enter":
                st, _ = call(op, fmu.enterInitializationMode)
            elif op == "exit":
                st, _ = call(op, fmu.exitInitializationMode)
            elif op == "step":
                H = rng.choice(NASTY_STEPS) if rng.random() < 0.3 else rng.choice([1e-5, 1e-4, 3.3e-4, 2e-3])
                st, _ = call(op, fmu.doStep, t, H)
                if st == OK and math.isfinite(H):
                    t += H
            elif op == "setreal":
                vr = rng.choice(writable)
                val = rng.choice(NASTY_REALS) if rng.random() < 0.5 else rng.uniform(-300.0, 300.0)
                st, _ = call(op, fmu.setReal, [vr], [val])
            elif op == "setint":
                st, _ = call(op, fmu.setInteger, [rng.choice(ints)], [rng.choice([0, 1, 2, -1, 2 ** 31 - 1])])
            elif op == "get":
                st, _ = call(op, fmu.getReal, all_real)
            elif op == "getint":
                st, _ = call(op, fmu.getInteger, ints)
            elif op == "getstate":
                st, s = call(op, fmu.getFMUstate)
                if st == OK:
                    states.append(s)
            elif op == "setstate":
                if not states:
                    continue
                st, _ = call(op, fmu.setFMUstate, rng.choice(states))
            elif op == "freestate":
                if not states:
                    continue
                st, _ = call(op, fmu.freeFMUstate, states.pop(rng.randrange(len(states))))
            elif op == "serialize":
                if not states:
                    continue
                st, b = call(op, fmu.serializeFMUstate, rng.choice(states))
                if st == OK:
                    blobs.append(b)
            elif op == "deserialize":
                if blobs and rng.random() < 0.7:
                    b = bytearray(rng.choice(blobs))
                    kind = rng.random()
                    if kind < 0.3 and b:
                        b[rng.randrange(len(b))] ^= 1 << rng.randrange(8)  # one bit flipped
                    elif kind < 0.45:
                        b = b[: rng.randrange(len(b) + 1)]  # truncated
                else:
                    b = bytearray(rng.randbytes(rng.randrange(1, 400)))  # garbage
                st, s = call(op, fmu.deSerializeFMUstate, bytes(b) or b"\0")
                if st == OK:
                    states.append(s)
                    if rng.random() < 0.8:
                        call("setstate", fmu.setFMUstate, s)
            elif op == "terminate":
                st, _ = call(op, fmu.terminate)
            elif op == "reset":
                st, _ = call(op, fmu.reset)
                t = 0.0
            elif op == "badvr":
                if rng.random() < 0.5:
                    st, _ = call(op, fmu.getReal, [10 ** 6])
                else:
                    st, _ = call(op, fmu.setReal, [rng.choice(outputs + [10 ** 6])], [1.0])
            else:
                on = rng.random() < 0.5
                st, _ = call(op, fmu.setDebugLogging, on, [])
                logging_on = on
            if st == FATAL:
                fatal = True  # FMI 2.0: no further call on this instance is allowed
                break
        if not fatal:
            for s in states:
                call("freestate", fmu.freeFMUstate, s)
            try:
                fmu.freeInstance()
            except Exception:  # noqa: BLE001
                counts["error"] += 1
        if trace:
            counts["trace"] = digest.hexdigest()
        print(json.dumps({"seed": seed, **counts}), flush=True)


# --------------------------------------------------------------- the parent
def run_fuzz(fmu_path, sequences: int, *, first_seed: int = 0, batch: int = 50, jobs: int = 2,
             timeout_s: float = 600.0, progress: bool = False, trace: bool = False) -> dict:
    """Run ``sequences`` sequences (seeds first_seed ...) in child processes of
    ``batch`` sequences each, ``jobs`` at a time; return the summary dict.  ``trace``: without
    the FMU-state operations, and the summary's ``traces`` maps each seed to the digest of its
    calls (statuses, messages, values read; :func:`_child`)."""
    pending = [list(range(s, min(s + batch, first_seed + sequences)))
               for s in range(first_seed, first_seed + sequences, batch)]
    totals = {"sequences": 0, "host_crashes": 0, "fmi_errors": 0, "fmi_fatal": 0, "fmi_discards": 0,
              "fmi_warnings": 0, "calls": 0, "unlogged_refusals": 0, "logged_errors_on_ok": 0,
              "crashes": [], "unlogged_examples": [], "traces": {}}
    running = []
    t0 = time.time()
    while pending or running:
        while pending and len(running) < jobs:
            seeds = pending.pop(0)
            p = subprocess.Popen([sys.executable, os.path.abspath(__file__), "--child", str(fmu_path),
                                  ",".join(map(str, seeds))] + (["--trace"] if trace else []),
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            running.append((p, seeds, time.time()))
        time.sleep(0.02)
        for item in list(running):
            p, seeds, started = item
            if p.poll() is None and time.time() - started < timeout_s:
                continue
            if p.poll() is None:
                p.kill()
            out, err = p.communicate()
            running.remove(item)
            done = []
            for line in out.splitlines():
                try:
                    rec = json.loads(line)
                except ValueError:
                    continue
                if not isinstance(rec, dict) or "seed" not in rec:
                    continue
                done.append(rec["seed"])
                if "trace" in rec:
                    totals["traces"][rec["seed"]] = rec["trace"]
                totals["sequences"] += 1
                totals["calls"] += rec["calls"]
                totals["fmi_errors"] += rec["error"]
                totals["fmi_fatal"] += rec["fatal"]
                totals["fmi_discards"] += rec["discard"]
                totals["fmi_warnings"] += rec["warning"]
                totals["unlogged_refusals"] += rec["unlogged_refusals"]
                totals["logged_errors_on_ok"] += rec["logged_errors_on_ok"]
                totals["unlogged_examples"] += rec["unlogged_examples"][: max(0, 5 - len(totals["unlogged_examples"]))]
            if p.returncode != 0:
                totals["host_crashes"] += 1
                left = [s for s in seeds if s not in done]
                where = left[0] if left else "interpreter exit"
                totals["crashes"].append({"seed": where, "returncode": p.returncode, "stderr": err[-300:]})
                if left:  # the crashed sequence counts; the rest of the batch runs again
                    totals["sequences"] += 1
                    if left[1:]:
                        pending.append(left[1:])
            if progress:
                print(f"fuzz: {totals['sequences']}/{sequences} sequences, {totals['host_crashes']} crashes, "
                      f"{time.time() - t0:.0f} s", file=sys.stderr, flush=True)
    totals["wall_s"] = round(time.time() - t0, 2)
    return totals


# ------------------------------------------------------- the C host (standalone)
C_FUZZER = Path(__file__).resolve().parent / "fmi_fuzz.c"


def build_c_fuzzer(directory) -> Path:
    """Compile tests/fmu_hosts/fmi_fuzz.c (the C host) into ``directory``."""
    import shutil

    from gearfmu.fmu.standalone_build import fmi2_header_dir

    cc = shutil.which("gcc") or shutil.which("cc")
    exe = Path(directory) / "fmi_fuzz"
    subprocess.run([cc, "-O2", "-std=c99", f"-I{fmi2_header_dir()}", "-o", str(exe), str(C_FUZZER), "-ldl", "-lm"],
                   check=True, capture_output=True, text=True)
    return exe


def run_c_fuzz(fmu_path, sequences: int, *, first_seed: int = 0, batch: int = 2500, jobs: int = 2,
               timeout_s: float = 600.0, progress: bool = False) -> dict:
    """Run ``sequences`` sequences (seeds first_seed ...) of tests/fmu_hosts/fmi_fuzz.c against a standalone
    FMU, ``batch`` sequences per child process, ``jobs`` processes at a time; a child that dies
    (signal, non-zero exit) is a host crash, and the rest of its batch runs again."""
    import fmpy

    keys = ("sequences", "sequences_breaking_order", "calls", "refused", "unlogged", "illegal_sequence_refusals",
            "bad_status", "discards", "errors", "fatals", "warnings", "instantiate_refused")
    totals = {k: 0 for k in keys}
    totals.update(host_crashes=0, crashes=[], unlogged_examples=[])
    t0 = time.time()
    with tempfile.TemporaryDirectory(prefix="gearfmu_cfuzz_") as d:
        exe = build_c_fuzzer(d)
        md = fmpy.read_model_description(str(fmu_path))
        unzip = fmpy.extract(str(fmu_path), unzipdir=os.path.join(d, "fmu"))
        args = [str(exe), unzip, md.coSimulation.modelIdentifier, md.guid, str(len(md.modelVariables))]
        n_states = len(md.derivatives)   # the Model Exchange state vectors have the FMU's own count
        pending = [(s, min(batch, first_seed + sequences - s)) for s in range(first_seed, first_seed + sequences, batch)]
        running = []
        while pending or running:
            while pending and len(running) < jobs:
                s0, n = pending.pop(0)
                extra = [str(n_states)] if n_states else []
                p = subprocess.Popen(args + [str(s0), str(n)] + extra, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     text=True)
                running.append((p, s0, n, time.time()))
            time.sleep(0.02)
            for item in list(running):
                p, s0, n, started = item
                if p.poll() is None and time.time() - started < timeout_s:
                    continue
                if p.poll() is None:
                    p.kill()
                out, err = p.communicate()
                running.remove(item)
                lines = out.splitlines()
                done = sum(1 for x in lines if x.startswith("done "))
                summary = next((json.loads(x) for x in reversed(lines) if x.startswith("{")), None)
                if p.returncode == 0 and summary is not None:
                    for k in keys:
                        totals[k] += summary[k]
                    if summary["unlogged_example"] and len(totals["unlogged_examples"]) < 5:
                        totals["unlogged_examples"].append(summary["unlogged_example"])
                else:
                    totals["host_crashes"] += 1
                    totals["sequences"] += done + 1  # the finished ones and the crashed one
                    totals["crashes"].append({"seed": s0 + done, "returncode": p.returncode, "stderr": err[-300:]})
                    if done + 1 < n:
                        pending.append((s0 + done + 1, n - done - 1))
                if progress:
                    print(f"c fuzz: {totals['sequences']}/{sequences} sequences, {totals['host_crashes']} crashes, "
                          f"{time.time() - t0:.0f} s", file=sys.stderr, flush=True)
    totals["unlogged_refusals"] = totals.pop("unlogged")
    totals["wall_s"] = round(time.time() - t0, 2)
    return totals


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sequences", type=int, default=1000)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--batch", type=int, help="sequences per child process (default 50; standalone: 2500)")
    ap.add_argument("--jobs", type=int, default=2, help="child processes at a time")
    ap.add_argument("--fmu", help="FMU to fuzz (default: build a small one)")
    ap.add_argument("--runtime", choices=("pythonfmu", "standalone"), default="pythonfmu",
                    help="the FMU's runtime (standalone: fuzzed by the C host unless --host fmpy)")
    ap.add_argument("--host", choices=("fmpy", "c"),
                    help="fmpy's low-level API or the C host tests/fmu_hosts/fmi_fuzz.c (--batch default 2500); "
                         "default: fmpy for pythonfmu, c for standalone")
    ap.add_argument("--compare", action="store_true",
                    help="both runtimes through fmpy, FMU-state calls left out: the seeds whose calls differ")
    ap.add_argument("--json", action="store_true", help="print the summary as JSON")
    ap.add_argument("--child", nargs=2, metavar=("FMU", "SEEDS"), help=argparse.SUPPRESS)
    ap.add_argument("--trace", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.child:
        _child(a.child[0], [int(s) for s in a.child[1].split(",")], trace=a.trace)
        return 0
    host = a.host or ("c" if a.runtime == "standalone" and not a.compare else "fmpy")
    if a.batch is None:
        a.batch = 2500 if host == "c" else 50
    if a.sequences < 1 or a.batch < 1 or a.jobs < 1:
        ap.error("--sequences, --batch and --jobs must be >= 1")
    if a.compare and (a.fmu or host == "c"):
        ap.error("--compare builds both FMUs and fuzzes them through fmpy")
    with tempfile.TemporaryDirectory(prefix="gearfmu_fuzz_") as d:
        if a.compare:
            runs = {rt: run_fuzz(build_fuzz_fmu(Path(d) / rt, rt), a.sequences, first_seed=a.first_seed,
                                 batch=a.batch, jobs=a.jobs, progress=True, trace=True)
                    for rt in ("pythonfmu", "standalone")}
            t_py, t_sa = runs["pythonfmu"].pop("traces"), runs["standalone"].pop("traces")
            res = {"sequences": a.sequences, "compared": len(set(t_py) & set(t_sa)),
                   "differing_seeds": sorted(k for k in t_py if t_sa.get(k) != t_py[k]), **runs}
        elif host == "c":
            fmu = a.fmu or str(build_fuzz_fmu(d, a.runtime))
            res = run_c_fuzz(fmu, a.sequences, first_seed=a.first_seed, batch=a.batch, jobs=a.jobs, progress=True)
        else:
            fmu = a.fmu or str(build_fuzz_fmu(d, a.runtime))
            res = run_fuzz(fmu, a.sequences, first_seed=a.first_seed, batch=a.batch, jobs=a.jobs, progress=True)
            res.pop("traces")
    if a.json:
        print(json.dumps(res))
    else:
        for k, v in res.items():
            print(f"{k}: {v}")
    if a.compare:
        return 0 if not res["differing_seeds"] and all(r["host_crashes"] == 0 for r in runs.values()) else 1
    return 0 if res["host_crashes"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
