"""Test-session order (the tests that fork run first), and the one local cluster that the tests
of what a study command computes share (:func:`scheduler`).

A dask ``Client`` leaves its event-loop thread running for the rest of the process, and a
process with a second thread must not fork (nnrobust.core.forked.can_fork). The sweep, tuning,
certificate and falsification tests use dask, so tests/core/test_forked.py, which checks that work is
forked, runs before any of them, whatever the files' names.
"""

import pytest


def pytest_collection_modifyitems(session, config, items):
    items.sort(key=lambda item: 0 if item.nodeid.startswith("tests/core/test_forked.py") else 1)


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
