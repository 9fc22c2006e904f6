"""Documentation, code comments and test comments read as reference text, not as a lab diary.

Reference: the project's rule "no timings, dates, machine loads or issue numbers in code
comments, docstrings or docs; history lives in git".  The check looks for the marks a diary
leaves -- an issue number, an ISO calendar date, the load of the machine, a section of
earlier measurement runs, a timing in seconds of CPU or wall time, a to-do line or heading
(the patterns in ``DIARY``, tried on lines written for them in
``test_the_patterns_find_diary_lines``) -- in README.md, docs/*.md, every source file of the
package (every line) and the tests: the comments and docstrings of tests/**/*.py (a test may hold
such text as data, e.g. the lines this file feeds to the detector) and every line of the C
hosts in tests/.  Measured numbers belong in the generated validation report
(docs/validation.md, written by benchmarks/report.py from benchmark JSON).

``KNOWN_DIARY`` lists the pages that other work in progress still has to clean.  It may only
shrink: a listed file that no longer contains any diary mark fails the test until it is
removed from the list (the final state is an empty list).
"""
import ast
import io
import pathlib
import re
import tokenize

ROOT = pathlib.Path(__file__).resolve().parents[2]

DIARY = [
    (re.compile(r"\bissues? #?\d+", re.IGNORECASE), "issue number"),
    (re.compile(r"\b20\d\d-[01]\d-[0-3]\d\b"), "calendar date"),
    (re.compile(r"load average", re.IGNORECASE), "machine load"),
    (re.compile(r"earlier measurements", re.IGNORECASE), "'Earlier measurements'"),
    (re.compile(r"\b\d+(\.\d+)?\s*(s|ms|min)\s+(of\s+)?(CPU|wall)\b", re.IGNORECASE), "timing"),
    (re.compile(r"\bLeft:"), "'Left:' to-do list"),
    (re.compile(r"^#+\s*(What is left|Left open|Left|To do)\s*$", re.IGNORECASE), "to-do list heading"),
]

# Files still carrying diary marks while their owners rewrite them; must shrink to empty.
KNOWN_DIARY: set = set()


def _checked_files():
    """(path, whole): ``whole`` True scans every line, False the comments and docstrings only."""
    files = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
    files += sorted(p for p in (ROOT / "gearfmu").rglob("*") if p.suffix in {".py", ".c", ".h"})
    files += sorted(p for p in (ROOT / "tests").rglob("*") if p.suffix in {".c", ".h"})
    return [(p, True) for p in files] + [(p, False) for p in sorted((ROOT / "tests").rglob("*.py"))]


def diary_marks(text: str, lines=None):
    """(line number, what, line) of every diary mark in ``text``; with ``lines`` (a list of
    (line number, text)) in those lines only."""
    hits = []
    for n, line in enumerate(text.splitlines(), 1) if lines is None else lines:
        for pattern, what in DIARY:
            if pattern.search(line):
                hits.append((n, what, line.strip()[:100]))
    return hits


def prose_lines(source: str):
    """(line number, text) of the comments and docstrings of Python ``source``: the text of
    every comment token, and every line of a string that stands alone as a statement (module,
    class and function docstrings, attribute docstrings).  Strings used as values are left out."""
    out = [(tok.start[0], tok.string) for tok in tokenize.generate_tokens(io.StringIO(source).readline)
           if tok.type == tokenize.COMMENT]
    lines = source.splitlines()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str):
            out += [(n, lines[n - 1]) for n in range(node.lineno, node.end_lineno + 1)]
    return sorted(out)


#: Text that benchmarks/report.py writes from benchmark JSON: the place where measured times
#: belong, so the "timing" mark does not apply there (every other mark does).
GENERATED_FILES = {"docs/validation.md"}
GENERATED_BLOCK = ("<!-- report:speed:begin -->", "<!-- report:speed:end -->")


def generated_lines(text: str):
    """Line numbers of ``text`` inside the blocks report.py writes (between the speed markers)."""
    inside, out = False, set()
    for n, line in enumerate(text.splitlines(), 1):
        if GENERATED_BLOCK[0] in line:
            inside = True
        if inside:
            out.add(n)
        if GENERATED_BLOCK[1] in line:
            inside = False
    return out


def file_diary_marks(path: pathlib.Path, whole: bool):
    text = path.read_text(errors="replace")
    hits = diary_marks(text) if whole else diary_marks(text, prose_lines(text))
    rel = path.relative_to(ROOT).as_posix()
    generated = (set(range(1, text.count("\n") + 2)) if rel in GENERATED_FILES
                 else generated_lines(text))
    return without_generated_timings(hits, generated)


def without_generated_timings(hits, generated):
    """``hits`` less the "timing" marks on the ``generated`` line numbers."""
    return [h for h in hits if not (h[1] == "timing" and h[0] in generated)]


def test_the_patterns_find_diary_lines():
    # the detector itself, on lines written for it (a detector that finds nothing proves nothing)
    assert [w for _, w, _ in diary_marks("fixed in issue 3")] == ["issue number"]
    assert [w for _, w, _ in diary_marks("measured 2026-11-22 on the CI box")] == ["calendar date"]
    assert [w for _, w, _ in diary_marks("(load average 7.8)")] == ["machine load"]
    assert [w for _, w, _ in diary_marks("## Earlier measurements")] == ["'Earlier measurements'"]
    assert [w for _, w, _ in diary_marks("Left: the stalls at level 4")] == ["'Left:' to-do list"]
    assert [w for _, w, _ in diary_marks("## What is left")] == ["to-do list heading"]
    assert [w for _, w, _ in diary_marks("small grids keep it at ~20 s CPU")] == ["timing"]
    assert [w for _, w, _ in diary_marks("0.8-1.0 s wall for the full tables")] == ["timing"]
    # reference text that must not trigger
    assert diary_marks("M = 2000-5000, ISO 6336-1:2019, Sainsot et al. 2004, the left flank") == []
    assert diary_marks("stop_time_s = 0.05 s; wall_s: wall time of the compiled loop, s") == []


def test_generated_blocks_may_carry_times_but_no_other_mark():
    text = ("intro at ~20 s CPU\n<!-- report:speed:begin -->\n| plan | 1.2 s wall |\n"
            "| machine | load average 3 |\n<!-- report:speed:end -->\nafter: 3 s wall\n")
    marks = [(n, w) for n, w, _ in without_generated_timings(diary_marks(text), generated_lines(text))]
    assert marks == [(1, "timing"), (4, "machine load"), (6, "timing")]


def test_tests_are_read_in_their_comments_and_docstrings_only():
    source = ('''"""Module doc (issue 3)."""\n'''
              "X = '2026-11-22'  # a date as data, then a comment: load average 7.8\n"
              "def f():\n"
              '''    """Doc: Earlier measurements."""\n'''
              "    return diary_marks('fixed in issue 3')\n")
    assert [(n, w) for n, w, _ in diary_marks(source, prose_lines(source))] == [
        (1, "issue number"), (2, "machine load"), (4, "'Earlier measurements'")]


def test_no_diary_marks_in_docs_code_and_tests():
    found = []
    for p, whole in _checked_files():
        rel = p.relative_to(ROOT).as_posix()
        if rel in KNOWN_DIARY:
            continue
        for n, what, line in file_diary_marks(p, whole):
            found.append(f"{rel}:{n}: {what}: {line}")
    assert not found, ("diary marks (history lives in git; measured numbers go to the "
                       "generated docs/validation.md):\n" + "\n".join(found))


def test_known_exceptions_only_shrink():
    whole = {p.relative_to(ROOT).as_posix(): w for p, w in _checked_files()}
    stale = [rel for rel in sorted(KNOWN_DIARY)
             if rel not in whole or not file_diary_marks(ROOT / rel, whole[rel])]
    assert not stale, f"clean now, remove from KNOWN_DIARY in tests/docs/test_docs_hygiene.py: {stale}"
