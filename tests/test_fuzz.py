"""Fuzzing the FMU through fmpy's low-level API (tests/fuzz_fmu.py), a few hundred sequences.

Reference: the FMI 2.0 contract as a host sees it -- whatever the call sequence
and values, the host process never dies (exit code 0 of every child process,
including interpreter exit, where pythonfmu 0.7.0's wrapper has a
use-after-free that the runtime works around, docs/fmu.md), and every call
that returns fmi2Discard/fmi2Error/fmi2Fatal while logging is on has logged its
reason.  The long run (``python tests/fuzz_fmu.py --sequences 10000 --json``)
is a script, see docs/robustness.md.
"""
import fuzz_fmu


def test_fuzz_300_sequences_no_host_crash(tmp_path):
    fmu = fuzz_fmu.build_fuzz_fmu(tmp_path)
    res = fuzz_fmu.run_fuzz(fmu, 300, first_seed=20261121, batch=50, jobs=2)
    assert res["sequences"] == 300
    assert res["host_crashes"] == 0, res["crashes"]
    assert res["unlogged_refusals"] == 0, res["unlogged_examples"]
    # the fuzzer really provoked refusals (otherwise it tests nothing)
    assert res["fmi_discards"] > 100
    assert res["logged_errors_on_ok"] > 100
    assert res["calls"] > 300 * 5


def test_fuzzer_counts_a_crash_instead_of_dying(tmp_path):
    """The parent survives a child that dies: a non-FMU file makes every child
    fail, and each batch is counted as a crash, not raised."""
    bad = tmp_path / "not_an_fmu.fmu"
    bad.write_bytes(b"garbage")
    res = fuzz_fmu.run_fuzz(bad, 4, batch=2, jobs=2)
    assert res["host_crashes"] >= 2 and len(res["crashes"]) == res["host_crashes"]
