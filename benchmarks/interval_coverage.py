"""How often does a paired comparison's 95 % interval of the median difference cover the true
median? The percentile bootstrap (what the reports printed before) against the distribution-free
order-statistic interval (what they print now), at the N the studies use.

    python benchmarks/interval_coverage.py --json docs/data/interval_coverage.json \
        [--figure docs/img/interval_coverage.png] [--trials 4000]

For each N and each distribution of the paired differences d (normal; lognormal minus its median,
skewed; Student t with 3 degrees of freedom, heavy-tailed; a two-component mixture, bimodal: each
centred so that its median is 0), ``--trials`` samples of N are drawn with a fixed seed; each gets
both intervals (nnrobust.studies.base.paired's, the bootstrap with 2000 resamples), and the share
that contains 0 is its coverage. The order-statistic interval's exact coverage 1 - 2 P(Binomial(N, 1/2) < l)
(nnrobust.studies.base.paired.order_coverage) holds for any continuous distribution: the measured shares must
sit on it within sampling error.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from nnrobust.run.results import write_json_atomic
from nnrobust.studies.base.paired import bootstrap_interval, order_coverage, order_interval

SIZES = (5, 8, 11, 20, 29, 59)
"""The certification draws of the shipped studies (11: the tuned studies, 29: the example) and the
validation draws (4 to 20), and 59 (the fewest that prove a 5 %/5 % claim)."""

RESAMPLES = 2000


def _normal(rng, n):
    return rng.normal(0.0, 1.0, n)


def _skewed(rng, n):
    return rng.lognormal(0.0, 1.0, n) - 1.0  # the lognormal's median is 1


def _heavy(rng, n):
    return rng.standard_t(3, n)


def _bimodal(rng, n):
    side = rng.random(n) < 0.5
    return np.where(side, rng.normal(-2.0, 0.5, n), rng.normal(2.0, 0.5, n))  # median 0 by symmetry


DISTRIBUTIONS = {"normal": _normal, "skewed": _skewed, "heavy-tailed": _heavy, "bimodal": _bimodal}


def coverage(n: int, draw, trials: int, seed: int) -> dict:
    """The share of ``trials`` samples of ``n`` differences whose intervals contain the median 0."""
    rng = np.random.default_rng(seed)
    order = boot = 0
    for i in range(trials):
        d = draw(rng, n)
        low, high = order_interval(d, 0.05)
        order += low <= 0.0 <= high
        low, high = bootstrap_interval(d, 0.05, RESAMPLES, seed + i)
        boot += low <= 0.0 <= high
    return {"order": order / trials, "bootstrap": boot / trials}


def main() -> None:
    """Measure every (N, distribution) and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the rows here")
    parser.add_argument("--figure", help="draw the coverage against N here (PNG)")
    parser.add_argument("--trials", type=int, default=4000)
    args = parser.parse_args()
    start = time.perf_counter()
    rows = []
    print(f"{'N':>4s} {'distribution':>13s} {'order stat.':>11s} {'exact':>7s} {'bootstrap':>9s}")
    for n in SIZES:
        for k, (name, draw) in enumerate(DISTRIBUTIONS.items()):
            found = coverage(n, draw, args.trials, seed=1000 * n + k)
            row = {"n": n, "distribution": name, "exact": order_coverage(n, 0.05), **found}
            rows.append(row)
            print(f"{n:4d} {name:>13s} {row['order']:11.3f} {row['exact']:7.3f} {row['bootstrap']:9.3f}")
    result = {
        "trials": args.trials,
        "resamples": RESAMPLES,
        "sizes": list(SIZES),
        "rows": rows,
        "seconds": time.perf_counter() - start,
    }
    if args.json:
        write_json_atomic(args.json, result)
    if args.figure:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6.4, 3.6))
        for name in DISTRIBUTIONS:
            mine = [r for r in rows if r["distribution"] == name]
            ax.plot([r["n"] for r in mine], [100 * r["bootstrap"] for r in mine], "o--", ms=4,
                    label=f"bootstrap, {name}")  # fmt: skip
        exact = [r for r in rows if r["distribution"] == "normal"]
        ax.plot([r["n"] for r in exact], [100 * r["exact"] for r in exact], "k-", lw=2,
                label="order statistics, exact (any distribution)")  # fmt: skip
        ax.axhline(95, color="0.5", ls=":", label="nominal 95 %")
        ax.set_xlabel("paired draws N")
        ax.set_ylabel("coverage of the true median [%]")
        ax.set_title(f"95 % intervals of a median difference ({args.trials} samples per point)")
        ax.legend(fontsize=7)
        ax.grid(True, alpha=0.3)
        fig.tight_layout()
        fig.savefig(args.figure, dpi=120)


if __name__ == "__main__":
    main()
