"""The documentation cites only what a reader of the repository can open.

Reference: the repository's own file tree (git's list of tracked files is not needed: the
working tree of a checkout is what a reader has).  Every relative Markdown link and every
back-quoted repository path in README.md and docs/ must name a file or folder that exists, and
no file may point at material outside the repository (the design notes the project was started
from are not shipped: what a reader needs from them is in docs/, with the original sources in
docs/references.md).
"""
import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
SOURCES = [p for d in ("gearfmu", "tests", "examples", "benchmarks", "docs", "modeldescription")
           for p in (ROOT / d).rglob("*") if p.suffix in {".py", ".md", ".c", ".h", ".toml"}]
SOURCES += [ROOT / "README.md", ROOT / "build_fmu.py"]

# files the project was started from, which are not part of the repository
OUTSIDE = re.compile(r"REFERENCES\.md|DESIGN\.md|/work/shared|\.\./shared/|shared/seeds")
LINK = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")
PATH = re.compile(r"`((?:gearfmu|docs|tests|examples|benchmarks|modeldescription)/[A-Za-z0-9_./-]+)`")


def test_no_file_points_outside_the_repository():
    hits = []
    for p in SOURCES:
        if p.name == "test_docs_links.py":
            continue
        for n, line in enumerate(p.read_text(errors="replace").splitlines(), 1):
            if OUTSIDE.search(line):
                hits.append(f"{p.relative_to(ROOT)}:{n}: {line.strip()[:90]}")
    assert not hits, "files outside the repository are cited:\n" + "\n".join(hits)


@pytest.mark.parametrize("doc", DOCS, ids=lambda p: p.name)
def test_links_and_paths_exist(doc):
    text = doc.read_text()
    missing = []
    for target in LINK.findall(text):
        if "://" in target or target.startswith("mailto:"):
            continue
        if not (doc.parent / target).exists():
            missing.append(f"link {target}")
    for target in PATH.findall(text):
        path = target.rstrip(".")
        if any(ch in path for ch in "*<>{}") or path.endswith("/output") or "/output/" in path:
            continue  # patterns and generated output folders, not files
        if not (ROOT / path).exists():
            missing.append(f"path {target}")
    assert not missing, f"{doc.relative_to(ROOT)} names what does not exist: {missing}"
