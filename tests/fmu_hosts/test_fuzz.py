"""Fuzzing both FMU runtimes with random FMI call sequences, with the same expectations.

Reference: the FMI 2.0 contract as a host sees it -- whatever the call sequence
and values, the host process never dies (exit code 0 of every child process,
including interpreter exit, where pythonfmu 0.7.0's wrapper has a
use-after-free that the runtime works around, docs/fmu.md), every call
that returns fmi2Discard/fmi2Error/fmi2Fatal while logging is on has logged its
reason, and a call that logs an error does not return fmi2OK (FMI 2.0 section 2.1.3: the
status is the call's verdict).  Both runtimes run the same FMI layer (docs/fmu.md "The
binary"), so the same sequences give the same statuses, messages and values call for call
(FMU-state calls aside: the two runtimes' state layouts differ).  Hosts: fmpy's low-level API
(tests/fmu_hosts/fuzz_fmu.py) and a C host (tests/fmu_hosts/fmi_fuzz.c).  The long runs are scripts, see
docs/robustness.md.
"""
import pytest

import fuzz_fmu

# the whole file is out of the quick subset (tests/README.md "Quick subset")
pytestmark = pytest.mark.slow

RUNTIMES = ("pythonfmu", "standalone")


@pytest.fixture(scope="module")
def fuzz_fmus(tmp_path_factory):
    d = tmp_path_factory.mktemp("fuzz")
    return {rt: fuzz_fmu.build_fuzz_fmu(d / rt, rt) for rt in RUNTIMES}


@pytest.mark.parametrize("runtime", RUNTIMES)
def test_fuzz_300_sequences_no_host_crash(fuzz_fmus, runtime):
    res = fuzz_fmu.run_fuzz(fuzz_fmus[runtime], 300, first_seed=20261121, batch=50, jobs=2)
    assert res["sequences"] == 300
    assert res["host_crashes"] == 0, res["crashes"]
    assert res["unlogged_refusals"] == 0, res["unlogged_examples"]
    assert res["logged_errors_on_ok"] == 0 and res["fmi_fatal"] == 0
    # the fuzzer really provoked refusals (otherwise it tests nothing)
    assert res["fmi_discards"] > 50 and res["fmi_errors"] > 1000
    assert res["calls"] > 300 * 5


def test_fuzz_both_runtimes_answer_every_call_alike(fuzz_fmus, tmp_path):
    """200 sequences without FMU-state calls, through fmpy: per sequence, the digest of every
    call's status, messages (other than fmi2OK ones) and values read is the same for both.  The
    standalone FMU here offers Co-Simulation only, as the pythonfmu one does (Model Exchange adds
    variables, so the drawn value references would differ)."""
    fmus = {"pythonfmu": fuzz_fmus["pythonfmu"],
            "standalone": fuzz_fmu.build_fuzz_fmu(tmp_path / "standalone_cs", "standalone", interface="cs")}
    traces = {rt: fuzz_fmu.run_fuzz(fmus[rt], 200, first_seed=4242, batch=100, jobs=2, trace=True)["traces"]
              for rt in RUNTIMES}
    assert len(traces["pythonfmu"]) == 200
    differ = sorted(k for k, v in traces["pythonfmu"].items() if traces["standalone"].get(k) != v)
    assert differ == [], f"seeds to replay with GEARFMU_FUZZ_TRACE=1: {differ[:5]}"


def test_fuzzer_counts_a_crash_instead_of_dying(tmp_path):
    """The parent survives a child that dies: a non-FMU file makes every child
    fail, and each batch is counted as a crash, not raised."""
    bad = tmp_path / "not_an_fmu.fmu"
    bad.write_bytes(b"garbage")
    res = fuzz_fmu.run_fuzz(bad, 4, batch=2, jobs=2)
    assert res["host_crashes"] >= 2 and len(res["crashes"]) == res["host_crashes"]


# ------------------------------------------------------------------- the C host
@pytest.mark.parametrize("runtime", RUNTIMES)
def test_c_fuzz_no_crash_every_refusal_logged(fuzz_fmus, runtime):
    """tests/fmu_hosts/fmi_fuzz.c drives the FMU with 2000 random call sequences (every one starts with a
    call the instantiated state forbids), in child processes: no host crash, every status other
    than fmi2OK/fmi2Warning logged a message, every status a valid fmi2Status, and the state
    table refused out-of-order calls as such (logged "illegal call sequence").  The long run is
    ``python tests/fmu_hosts/fuzz_fmu.py --runtime standalone --sequences 10600 --json`` (docs/robustness.md)."""
    res = fuzz_fmu.run_c_fuzz(fuzz_fmus[runtime], 2000, first_seed=20261125, batch=1000, jobs=2)
    assert res["sequences"] == 2000
    assert res["host_crashes"] == 0, res["crashes"]
    assert res["unlogged_refusals"] == 0, res["unlogged_examples"]
    assert res["bad_status"] == 0 and res["fatals"] == 0
    # every sequence that got an instance broke the order, and was told so
    assert res["sequences_breaking_order"] == res["sequences"] - res["instantiate_refused"]
    assert res["illegal_sequence_refusals"] > 2000 and res["discards"] > 500
    assert res["calls"] > 2000 * 20


def test_c_fuzzer_counts_a_crash_instead_of_dying(tmp_path):
    """A binary whose every fmi2 function aborts: each child dies, and each is counted as a
    host crash (with its seed) while the fuzzer goes on."""
    import re
    import shutil
    import subprocess
    import zipfile

    fmu = fuzz_fmu.build_fuzz_fmu(tmp_path, "standalone")
    with zipfile.ZipFile(fmu) as z:
        names = z.namelist()
        so = next(n for n in names if n.startswith("binaries/linux64/") and n.endswith(".so"))
        files = {n: z.read(n) for n in names if n != so}
    src = tmp_path / "abort.c"
    funcs = set(re.findall(r"LOAD\((\w+)\)", fuzz_fmu.C_FUZZER.read_text())) - {"name"}
    src.write_text("#include <stdlib.h>\n" + "".join(f"void *fmi2{f}(void) {{ abort(); }}\n" for f in funcs))
    lib = tmp_path / "abort.so"
    subprocess.run([shutil.which("gcc") or "cc", "-shared", "-fPIC", "-o", str(lib), str(src)], check=True)
    bad = tmp_path / "aborting.fmu"
    with zipfile.ZipFile(bad, "w") as z:
        for n, data in files.items():
            z.writestr(n, data)
        z.write(lib, so)
    res = fuzz_fmu.run_c_fuzz(bad, 3, batch=10, jobs=1)
    assert res["host_crashes"] == 3 and [c["seed"] for c in res["crashes"]] == [0, 1, 2]
