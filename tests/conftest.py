"""Test-session configuration shared by every test file.

The suite runs in parallel: pytest-xdist with ``-n auto --dist loadfile`` (pyproject's
[tool.pytest.ini_options]).  Many files build something expensive once per module (an FMU,
tables, a compiled host, a pool of film runs) in a module-scoped fixture; ``loadfile`` keeps each
file on one worker, so such a fixture is built once.  The files whose tests share a module, class
or package fixture are handed out first (the large pieces of work first, the files of small
independent tests last), which shortens the tail of the run.  ``-n 0`` runs the same order in
one process.
"""
import pytest

_SHARED_SCOPES = ("module", "class", "package")


def _shares_a_fixture(item) -> bool:
    """True when the test uses a fixture built once for its module, class or package."""
    info = getattr(item, "_fixtureinfo", None)
    if info is None:
        return False
    for name in item.fixturenames:
        defs = info.name2fixturedefs.get(name)
        if defs and defs[-1].scope in _SHARED_SCOPES:
            return True
    return False


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    heavy = {it.nodeid.split("::", 1)[0] for it in items if _shares_a_fixture(it)}
    # stable: every file keeps its tests together and in their written order
    items.sort(key=lambda it: 0 if it.nodeid.split("::", 1)[0] in heavy else 1)
