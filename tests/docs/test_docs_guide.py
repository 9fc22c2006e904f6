"""The README's quick reference and the user guide say the same thing.

Reference: the user guide pages themselves.  README.md repeats two blocks of the guide so that a
reader of the repository's front page has them at hand: the command synopsis (docs/cli.md) and
the FMU's variables table (docs/fmu_import.md).  Both copies must stay identical, and every page
of docs/ must be reachable from the map docs/index.md.
"""
import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parents[2]


def _first_code_block(text: str) -> str:
    return re.search(r"```\n(.*?)```", text, re.S).group(1)


def _variables_table(text: str) -> str:
    start = text.index("| name | causality | unit | meaning |")
    rows = []
    for line in text[start:].splitlines():
        if not line.startswith("|"):
            break
        rows.append(re.sub(r"\]\((docs/)?", "](", line))  # links are relative to each file
    return "\n".join(rows)


def test_readme_command_block_is_the_cli_page_block():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    section = readme.split("## Command line", 1)[1]
    assert _first_code_block(section) == _first_code_block((ROOT / "docs" / "cli.md").read_text(encoding="utf-8"))


def test_readme_variables_table_is_the_guide_table():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    guide = (ROOT / "docs" / "fmu_import.md").read_text(encoding="utf-8")
    assert _variables_table(readme) == _variables_table(guide)


def test_every_docs_page_is_on_the_map():
    index = (ROOT / "docs" / "index.md").read_text(encoding="utf-8")
    linked = set(re.findall(r"\]\(([A-Za-z0-9_]+\.md)", index))
    pages = {p.name for p in (ROOT / "docs").glob("*.md")} - {"index.md"}
    assert not pages - linked, f"pages missing from docs/index.md: {sorted(pages - linked)}"
