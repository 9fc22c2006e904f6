"""Helpers that several test files share (tests/README.md "Layout"): hosts, cases and references
written once, imported as ``from support.<module> import ...``.  No test file imports another test
file (tests/project/test_layout.py)."""
