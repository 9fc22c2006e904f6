"""The benchmarks share code through one module, benchmarks/harness.py, never through each other.

A benchmark (benchmarks/bench_*.py) is a script that prints its JSON; what several need (timing, JSON
output, the fmpy loops, the C host, the C kernel through ctypes, the per-step cost split) lives in
the harness, so that changing one benchmark never changes another's numbers.
"""
import ast
import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[2]
BENCH = ROOT / "benchmarks"


def imported_modules(path: pathlib.Path):
    """Top-level names of every module ``path`` imports (import statements anywhere in the file,
    and importlib.import_module / __import__ with a constant name)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names.update(a.name.split(".")[0] for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            names.add(node.module.split(".")[0])
        elif isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant) \
                and isinstance(node.args[0].value, str) \
                and (getattr(node.func, "attr", None) == "import_module" or getattr(node.func, "id", None) == "__import__"):
            names.add(node.args[0].value.split(".")[0])
    return names


def cross_imports(folder: pathlib.Path):
    """(importer, imported benchmark) pairs: a file of ``folder`` importing one of its bench_*.py modules."""
    benches = {p.stem for p in folder.glob("bench_*.py")}
    return sorted((p.name, m) for p in folder.glob("*.py") for m in imported_modules(p) & benches)


def test_the_check_finds_a_cross_import(tmp_path):
    (tmp_path / "bench_a.py").write_text("import json\nfrom harness import emit\n")
    (tmp_path / "bench_b.py").write_text("def f():\n    from bench_a import x\n")
    (tmp_path / "harness.py").write_text("import importlib\nm = importlib.import_module('bench_b')\n")
    assert cross_imports(tmp_path) == [("bench_b.py", "bench_a"), ("harness.py", "bench_b")]


def test_no_benchmark_imports_another():
    assert cross_imports(BENCH) == []


def test_the_benchmarks_that_share_code_use_the_harness():
    users = {p.name for p in BENCH.glob("bench_*.py") if "harness" in imported_modules(p)}
    assert {"bench_fmu.py", "bench_fmu_rtf.py", "bench_integrators.py", "bench_gearbox_fmu.py"} <= users
    assert not imported_modules(BENCH / "harness.py") & {p.stem for p in BENCH.glob("*.py")}
