"""Test-session configuration shared by every test file.

The suite runs in parallel (pytest-xdist, ``-n auto`` in pyproject's [tool.pytest.ini_options]) with
``--dist loadgroup``.  Many files build something expensive once per module (an FMU, tables, a
compiled host, a pool of film runs) in a module-scoped fixture.  A test that uses such a fixture is
put in its module's group, so the module's tests that share it run on one worker and the fixture is
built once; every other test is scheduled on its own and fills the gaps.  The groups are handed
out first (largest pieces of work first, small independent tests last), which shortens the tail
of the run.  With ``-n 0`` the same order is used in one process.
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
    shared = {}
    for item in items:
        if _shares_a_fixture(item):
            group = item.nodeid.split("::", 1)[0]
            item.add_marker(pytest.mark.xdist_group(group))
            shared[item.nodeid] = True
    # stable: each module's grouped tests stay together and in their written order
    items.sort(key=lambda it: 0 if it.nodeid in shared else 1)
