"""Test-session order: the tests that fork run first.

A dask ``Client`` leaves its event-loop thread running for the rest of the process, and a
process with a second thread must not fork (nnrobust.core.forked.can_fork). The sweep, tuning,
certificate and falsification tests use dask, so tests/core/test_forked.py, which checks that work is
forked, runs before any of them, whatever the files' names.
"""


def pytest_collection_modifyitems(session, config, items):
    items.sort(key=lambda item: 0 if item.nodeid.startswith("tests/core/test_forked.py") else 1)
