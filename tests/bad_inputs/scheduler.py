"""Bad inputs: claims, properties and clusters of the sweep command."""

from __future__ import annotations

from nnrobust.core import exceptions as ex

from .common import (
    Case,
)


def _require(*texts: str):
    def check():
        from nnrobust.run.properties import run_properties

        return run_properties(list(texts))

    return check


def _claim(epsilon, beta, failures=0):
    def check():
        from nnrobust.run.properties import samples_needed

        return samples_needed(epsilon, beta, failures)

    return check


def _mutated(change):
    def run():
        from nnrobust.config.presets import load_preset
        from nnrobust.run.experiment import build

        config = load_preset("paper-ellipse")
        change(config)
        return build(config)

    return run


def _scheduler(address: str):
    def check():
        from nnrobust.studies.base.cluster import check_scheduler

        return check_scheduler(address)

    return check


def _workers(count: int):
    def check():
        from nnrobust.studies.base.cluster import cluster_client as _client

        with _client(count, None):
            pass

    return check


SCHEDULER_CASES = [
    Case(
        "--scheduler 'not a url'",
        lambda d: _scheduler("not a url"),
        ex.NNRobustError,
        "--scheduler 'not a url': not a dask scheduler's address; give tcp://HOST:PORT",
    ),
    Case(
        "--scheduler with TLS",
        lambda d: _scheduler("tls://127.0.0.1:8786"),
        ex.NNRobustError,
        "tls:// is not supported (a TLS cluster needs dask's security settings",
    ),
    Case(
        "--scheduler at a refused port",
        lambda d: _scheduler("tcp://127.0.0.1:1"),
        ex.NNRobustError,
        "--scheduler tcp://127.0.0.1:1: cannot connect (Connection refused)",
    ),
    Case(
        "--workers -1", lambda d: _workers(-1), ex.NNRobustError, "--workers -1: give at least 1 local worker"
    ),
]
