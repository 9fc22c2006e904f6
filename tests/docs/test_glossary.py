"""The glossary says which paper each seed label is, and the code cites the papers by author and year.

Reference: docs/references.md, the table of the four papers (label, authors, title); the glossary
(docs/glossary.md) must name the same paper for every label, and the comments and docstrings of
gearfmu/ may carry a label only beside its paper's author-year citation.
"""
import ast
import io
import pathlib
import re
import tokenize

ROOT = pathlib.Path(__file__).resolve().parents[2]
LABEL = re.compile(r"\b[Ss]eed (00\d)\b")
#: files whose comments may still use the bare labels (none)
PENDING = ()


def _rows(text: str):
    """{label: cells} of the markdown table rows that start with a seed label."""
    return {m.group(1): [c.strip() for c in line.strip().strip("|").split("|")]
            for line in text.splitlines() if (m := re.match(r"\| seed (00\d) \|", line))}


def _title(cell: str) -> str:
    return re.search(r"\*([^*]+)\*", cell).group(1)


def citations():
    """{label: author-year citation} from the glossary's table."""
    return {k: v[1] for k, v in _rows((ROOT / "docs" / "glossary.md").read_text(encoding="utf-8")).items()}


def test_glossary_names_the_paper_of_every_label():
    refs = _rows((ROOT / "docs" / "references.md").read_text(encoding="utf-8"))
    gloss = _rows((ROOT / "docs" / "glossary.md").read_text(encoding="utf-8"))
    assert set(refs) == set(gloss) == {"000", "001", "003", "004"}
    for label, cells in refs.items():
        assert _title(cells[1]) == _title(gloss[label][2]), label
        # the author-year citation names the paper's first author and its year
        cited = gloss[label][1]
        first_author = re.search(r"[A-Z]\. (?:[A-Z]\. )*([A-Z][a-z]+)", cells[1]).group(1)
        assert cited.startswith(first_author) and re.search(r"\b20\d\d$", cited), (label, cited)


def _prose(path: pathlib.Path):
    """(line number, text) of the comments and docstrings of a Python or C file."""
    src = path.read_text(encoding="utf-8")
    if path.suffix in (".c", ".h"):
        return [(src.count("\n", 0, m.start()) + 1 + i, line)
                for m in re.finditer(r"/\*.*?\*/|//[^\n]*", src, re.S) for i, line in enumerate(m.group(0).split("\n"))]
    out = [(t.start[0], t.string) for t in tokenize.generate_tokens(io.StringIO(src).readline)
           if t.type == tokenize.COMMENT]
    lines = src.splitlines()
    for node in ast.walk(ast.parse(src)):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr) \
                and isinstance(body[0].value, ast.Constant) and isinstance(body[0].value.value, str):
            d = body[0].value
            out += [(n, lines[n - 1]) for n in range(d.lineno, d.end_lineno + 1)]
    return out


def bare_labels(path: pathlib.Path, cite=None):
    """(line, text) of the comment and docstring lines of ``path`` with a seed label not beside its
    paper's citation."""
    cite = cite or citations()
    return [(n, line.strip()) for n, line in _prose(path)
            for m in LABEL.finditer(line) if cite.get(m.group(1), "\0") not in line]


def test_the_check_finds_a_bare_label(tmp_path):
    p = tmp_path / "m.py"
    p.write_text('"""Film stiffness (seed 000 eq 8)."""\nX = "seed 000"  # a value\n# He & Yang 2023 (seed 004)\n')
    assert [n for n, _ in bare_labels(p)] == [1]


def test_code_cites_the_papers_by_author_and_year():
    cite = citations()
    found = []
    for p in sorted((ROOT / "gearfmu").rglob("*")):
        rel = p.relative_to(ROOT).as_posix()
        if p.suffix in (".py", ".c", ".h") and not rel.startswith(PENDING):
            found += [f"{rel}:{n}: {line[:90]}" for n, line in bare_labels(p, cite)]
    assert not found, "cite the paper by author and year (docs/glossary.md):\n" + "\n".join(found)
