"""Documentation and code comments read as reference text, not as a lab diary.

Reference: the project's rule "no timings, dates, machine loads or issue numbers in code
comments, docstrings or docs; history lives in git".  The check looks for the marks a diary
leaves -- "issue 3", a calendar date such as 2026-11-22, "load average", "Earlier measurements",
a "Left:" to-do line or heading -- in README.md, docs/*.md and every source file of the package (comments
and docstrings included).  Measured numbers belong in the generated validation report
(docs/validation.md, written by benchmarks/report.py from benchmark JSON).

``KNOWN_DIARY`` lists the pages that other work in progress still has to clean.  It may only
shrink: a listed file that no longer contains any diary mark fails the test until it is
removed from the list (the final state is an empty list).
"""
import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parents[1]

DIARY = [
    (re.compile(r"\bissues? #?\d+", re.IGNORECASE), "issue number"),
    (re.compile(r"\b20\d\d-[01]\d-[0-3]\d\b"), "calendar date"),
    (re.compile(r"load average", re.IGNORECASE), "machine load"),
    (re.compile(r"earlier measurements", re.IGNORECASE), "'Earlier measurements'"),
    (re.compile(r"\bLeft:"), "'Left:' to-do list"),
    (re.compile(r"^#+\s*(What is left|Left open|Left|To do)\s*$", re.IGNORECASE), "to-do list heading"),
]

# Files still carrying diary marks while their owners rewrite them; must shrink to empty.
KNOWN_DIARY = {
}


def _checked_files():
    files = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
    files += sorted(p for p in (ROOT / "gearfmu").rglob("*") if p.suffix in {".py", ".c", ".h"})
    return files


def diary_marks(text: str):
    """(line number, what, line) of every diary mark in ``text``."""
    hits = []
    for n, line in enumerate(text.splitlines(), 1):
        for pattern, what in DIARY:
            if pattern.search(line):
                hits.append((n, what, line.strip()[:100]))
    return hits


def test_the_patterns_find_diary_lines():
    # the detector itself, on lines written for it (a detector that finds nothing proves nothing)
    assert [w for _, w, _ in diary_marks("fixed in issue 3")] == ["issue number"]
    assert [w for _, w, _ in diary_marks("measured 2026-11-22 on the CI box")] == ["calendar date"]
    assert [w for _, w, _ in diary_marks("(load average 7.8)")] == ["machine load"]
    assert [w for _, w, _ in diary_marks("## Earlier measurements")] == ["'Earlier measurements'"]
    assert [w for _, w, _ in diary_marks("Left: the stalls at level 4")] == ["'Left:' to-do list"]
    assert [w for _, w, _ in diary_marks("## What is left")] == ["to-do list heading"]
    # reference text that must not trigger
    assert diary_marks("M = 2000-5000, ISO 6336-1:2019, Sainsot et al. 2004, the left flank") == []


def test_no_diary_marks_in_docs_and_code():
    found = []
    for p in _checked_files():
        rel = p.relative_to(ROOT).as_posix()
        if rel in KNOWN_DIARY:
            continue
        for n, what, line in diary_marks(p.read_text(errors="replace")):
            found.append(f"{rel}:{n}: {what}: {line}")
    assert not found, ("diary marks (history lives in git; measured numbers go to the "
                       "generated docs/validation.md):\n" + "\n".join(found))


def test_known_exceptions_only_shrink():
    stale = [rel for rel in sorted(KNOWN_DIARY)
             if not (ROOT / rel).exists() or not diary_marks((ROOT / rel).read_text(errors="replace"))]
    assert not stale, f"clean now, remove from KNOWN_DIARY in tests/test_docs_hygiene.py: {stale}"
