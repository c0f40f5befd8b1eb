"""Test-session order (the tests that fork run first), how pytest-xdist shares the tests among
its processes (a module with a module-scoped fixture on one process), and the one local cluster
that the tests of what a study command computes share (:func:`scheduler`).

A dask ``Client`` leaves its event-loop thread running for the rest of the process, and a
process with a second thread must not fork (nnrobust.core.forked.can_fork). The sweep, tuning,
certificate and falsification tests use dask, so tests/core/test_forked.py, which checks that work is
forked, runs before any of them, whatever the files' names.
"""

import functools
from pathlib import Path

import pytest

FORKED = "tests/core/test_forked.py"


@functools.cache
def _has_module_fixture(path: str) -> bool:
    """Whether the test module at ``path`` (relative to the project) defines a module-scoped
    fixture: a study, a tuning or a compiled law built once for the module's tests."""
    file = Path(__file__).parent.parent / path
    return file.suffix == ".py" and file.is_file() and 'scope="module"' in file.read_text()


def pytest_collection_modifyitems(session, config, items):
    """The tests that fork first, then the modules whose tests share a module-scoped fixture
    (the longest units of work: started first, they do not end the run on one process), then the
    rest, each group in collection order."""

    def rank(item):
        path = item.nodeid.split("::", 1)[0]
        return 0 if path == FORKED else 1 if _has_module_fixture(path) else 2

    items.sort(key=rank)


def pytest_xdist_make_scheduler(config, log):
    """``-n``'s default distribution (``--dist load``), but the tests of a module with a
    module-scoped fixture go to one process, so that the fixture is built once, not once per
    process (the study fixture alone takes about a minute). xdist's own ``--dist loadgroup`` does
    not group with pytest 9 (it renames ``item._nodeid``, which pytest 9 no longer reads).
    Another ``--dist`` is left to xdist."""
    if config.getvalue("dist") != "load":
        return None
    from xdist.scheduler import LoadScopeScheduling  # here: only a run with -n imports xdist

    class ModuleFixturesTogether(LoadScopeScheduling):
        def __init__(self, config, log=None):
            super().__init__(config, log)
            self.config.option.loadscopereorder = False  # pytest_collection_modifyitems's order

        def _split_scope(self, nodeid: str) -> str:
            path = nodeid.split("::", 1)[0]
            return path if path != FORKED and _has_module_fixture(path) else nodeid

    return ModuleFixturesTogether(config, log)


@pytest.fixture(scope="session")
def scheduler():
    """The address of one local cluster of 2 workers (nnrobust.studies.base.cluster.local_cluster)
    per test process, started when a test first asks for it and closed at the session's end.

    For the tests that check what a sweep, tuning, falsification or study computes: each passes
    it as ``scheduler`` (``--scheduler``) instead of starting a cluster of its own, which took a
    few seconds a test (the processes, then each worker importing nnrobust). A scheduler of the
    user's also sends the files the rows read with the tasks, so these tests run that path too
    (a row is the same either way: tests/studies/base/test_cluster_remote.py). Tests of how a
    command's own cluster starts, is interrupted or loses a worker, and tests whose laws end or
    hang their worker, keep a cluster of their own.
    """
    pytest.importorskip("distributed")
    import logging

    from nnrobust.studies.base.cluster import local_cluster

    cluster = local_cluster(2, silence_logs=logging.CRITICAL)
    try:
        yield cluster.scheduler_address
    finally:
        cluster.close()
