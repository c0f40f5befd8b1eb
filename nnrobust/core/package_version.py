"""The package's one version string (a leaf module: the package face and a cluster's version
check both read it here).
"""

from __future__ import annotations

from functools import cache


@cache
def package_version() -> str:
    """pyproject.toml's version as installed (read on first use: it costs 30 ms)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("nnrobust")
    except PackageNotFoundError:  # a source tree that was never installed
        return "0+unknown"
