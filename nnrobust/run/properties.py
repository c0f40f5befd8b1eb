"""Properties a run must have (``--require EXPR``), their signed margins, and the statistical
statements a sweep makes about them: Clopper–Pearson bounds on the failure probability and
Wilks bounds on quantiles (docs/robustness.md, "Certificates").

A property is ``METRIC OP VALUE`` over a metric of metrics.json: ``rms_error_after_2s<=0.05``,
``max_torque_ratio<=1``, ``runaway==false``. Each run gives it a margin, positive when the
property holds:

- ``m <= v`` (or ``<``): (v - m) / s, ``m >= v`` (or ``>``): (m - v) / s, with the scale
  s = |v|, or 1 where v = 0 (the margin is then in the metric's unit);
- ``m == v`` and ``m != v``: +1 when it holds, -1 when it does not (a flag has no distance);
- a run that did not complete, or a metric that is NaN, fails every property: margin -inf.

A strict inequality that holds with equality has margin 0 and fails (``<`` and ``>`` need a
margin > 0; ``<=`` and ``>=`` hold at 0).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from ..core.exceptions import ConfigError

OPERATORS = ("<=", ">=", "==", "!=", "<", ">")
PATTERN = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*(<=|>=|==|!=|<|>)\s*(\S+)\s*$")


@dataclass(frozen=True)
class Property:
    """``metric op value``: what a run must satisfy."""

    metric: str
    op: str
    value: float | bool

    @property
    def text(self) -> str:
        """The property as written."""
        value = str(self.value).lower() if isinstance(self.value, bool) else f"{self.value:g}"
        return f"{self.metric}{self.op}{value}"

    def margin(self, metrics: dict) -> float:
        """The signed, normalised margin of one run's metrics (positive: the property holds)."""
        if metrics.get("status", "completed") != "completed":
            return -math.inf
        m = metrics.get(self.metric)
        if m is None or (isinstance(m, float) and math.isnan(m)):
            return -math.inf
        if self.op in ("==", "!="):
            equal = (bool(m) == self.value) if isinstance(self.value, bool) else (float(m) == self.value)
            return 1.0 if equal == (self.op == "==") else -1.0
        value = float(self.value)
        scale = abs(value) or 1.0
        return ((value - float(m)) if self.op in ("<=", "<") else (float(m) - value)) / scale

    def holds(self, metrics: dict) -> bool:
        """Whether one run satisfies the property."""
        margin = self.margin(metrics)
        return margin > 0 if self.op in ("<", ">") else margin >= 0


def parse(text: str, metrics: list[str] | tuple[str, ...], flags: tuple[str, ...] = ()) -> Property:
    """``--require EXPR`` as a Property; one-line errors name what is wrong and what is valid."""
    import difflib

    key = f"--require {text!r}"
    match = PATTERN.match(text)
    if not match:
        raise ConfigError(
            key,
            f"is not METRIC OP VALUE with OP one of {' '.join(OPERATORS)}, e.g. "
            "rms_error_after_2s<=0.05 or runaway==false",
        )
    metric, op, raw = match.groups()
    if metric not in metrics and metric not in flags:
        close = difflib.get_close_matches(metric, [*metrics, *flags], n=1)
        hint = f"; did you mean {close[0]!r}?" if close else "."
        raise ConfigError(key, f"no metric {metric!r}{hint} Metrics: {', '.join([*metrics, *flags])}")
    if metric in flags:
        if raw.lower() not in ("true", "false") or op not in ("==", "!="):
            raise ConfigError(key, f"{metric} is true or false: compare it with == or != to true or false")
        return Property(metric, op, raw.lower() == "true")
    try:
        value = float(raw)
    except ValueError as err:
        raise ConfigError(key, f"{raw!r} is not a number") from err
    if not math.isfinite(value):
        raise ConfigError(key, f"the bound must be a finite number, got {raw}")
    return Property(metric, op, value)


MACHINE_METRICS = ("wall_seconds",)
"""Metrics no property may read: they depend on the machine's load, not on the run."""


def run_properties(texts: list[str]) -> list[Property]:
    """The properties of ``--require`` over the metrics a run records (metrics.json)."""
    from .results import METRIC_UNITS
    from .verdicts import FLAGS

    numeric = tuple(m for m in METRIC_UNITS if m != "singular_episodes")
    properties = [parse(t, numeric, FLAGS) for t in texts]
    for p in properties:
        if p.metric in MACHINE_METRICS:
            raise ConfigError(
                f"--require {p.text!r}",
                f"{p.metric} measures the machine and its load, not the controller: the same run passes "
                "or fails with what else the machine runs (benchmarks/ measure speed)",
            )
    if len({p.text for p in properties}) != len(properties):
        raise ConfigError("--require", "names a property twice")
    return properties


# ---- certificates -------------------------------------------------------------------------------


MAX_PLANNED_SAMPLES = 1_000_000
"""The most samples a claim may need: a sweep has at most this many rows
(:data:`nnrobust.studies.base.plan.MAX_ROWS`), so a claim that needs more can never be made."""

MIN_BETA = 1e-9
"""The least ``--beta``: closer to 1, the confidence 1 - beta rounds in double precision and the
bound Beta^-1(1 - beta; ...) with it."""


def samples_needed(epsilon: float, beta: float, failures: int = 0) -> int:
    """The fewest samples N from which ``failures`` failures prove P(fail) <= epsilon with
    confidence 1 - beta: the smallest N whose Clopper-Pearson bound (:func:`clopper_pearson_upper`,
    the one the certificate computes) is at most epsilon, i.e. BinomCDF(failures; N, epsilon)
    <= beta (for no failure, N >= ln(1/beta) / ln(1/(1 - epsilon)): 59 for epsilon = beta = 5 %).
    Found by bisection; a claim that needs more than :data:`MAX_PLANNED_SAMPLES` is refused
    with the least epsilon that many samples could prove.
    """
    check_claim(epsilon, beta, failures)
    high = MAX_PLANNED_SAMPLES
    if clopper_pearson_upper(failures, high, beta) > epsilon:
        least = clopper_pearson_upper(failures, high, beta)
        fewer = f" and up to {failures} failures" if failures else ""
        raise ConfigError(
            "--epsilon",
            f"P(fail) <= {epsilon:g} with confidence {confidence_text(beta)}{fewer} needs more than "
            f"{high:,} samples, more rows than a sweep may have; give --epsilon >= {_up(least)}"
            + (" or fewer --failures" if failures else ""),
        )
    low = failures  # the bound is 1 at N = failures: not enough
    while high - low > 1:  # invariant: low is not enough, high is
        middle = (low + high) // 2
        if clopper_pearson_upper(failures, middle, beta) <= epsilon:
            high = middle
        else:
            low = middle
    return high


def _up(x: float) -> str:
    """``x`` to three significant digits, rounded up (a least value that still holds)."""
    digits = 2 - math.floor(math.log10(x))
    return f"{math.ceil(x * 10**digits) / 10**digits:.3g}"


def confidence_text(beta: float) -> str:
    """1 - beta as text that never rounds to 1: ``0.95``, or ``1 - 1e-08``."""
    text = f"{1 - beta:g}"
    return text if float(text) < 1 else f"1 - {beta:g}"


CLAIM_FLAGS = ("--epsilon", "--beta", "--failures")
"""What the command line calls a claim's epsilon, beta and allowed failures."""


def check_claim(epsilon: float, beta: float, failures: int = 0, names: tuple = CLAIM_FLAGS) -> None:
    """One-line errors for a claim no sample size can make, or one that would say nothing:
    P(fail) <= epsilon above one half, or a confidence 1 - beta below one half or closer to 1
    than 1 - :data:`MIN_BETA`. ``names``: what the errors call epsilon, beta and the failures
    (the command line's flags, or a study file's keys).
    """
    epsilon_key, beta_key, failures_key = names
    for flag, value in ((epsilon_key, epsilon), (beta_key, beta)):
        if not (isinstance(value, (int, float)) and 0 < value < 1):
            raise ConfigError(flag, f"must be a probability in (0, 1), got {value}")
    if epsilon > 0.5:
        raise ConfigError(
            epsilon_key,
            f"P(fail) <= {epsilon!r} says next to nothing (failing more often than not is allowed); "
            "give at most 0.5",
        )
    if beta > 0.5:
        raise ConfigError(
            beta_key,
            f"{beta!r} is a confidence 1 - BETA below one half, which proves nothing; give at most 0.5",
        )
    if beta < MIN_BETA:
        raise ConfigError(
            beta_key,
            f"{beta:g} asks a confidence closer to 1 than double precision can bound (1 - BETA "
            f"rounds); give at least {MIN_BETA:g}",
        )
    if not (isinstance(failures, int) and 0 <= failures <= 10_000):
        raise ConfigError(failures_key, f"must be an integer in [0, 10000], got {failures}")


def clopper_pearson_upper(failures: int, samples: int, beta: float) -> float:
    """One-sided (1 - beta) Clopper–Pearson upper bound on a failure probability from
    ``failures`` in ``samples`` independent samples: Beta^-1(1 - beta; k + 1, N - k) (1 at k = N).
    """
    from scipy.stats import beta as beta_distribution

    if failures >= samples:
        return 1.0
    return float(beta_distribution.ppf(1 - beta, failures + 1, samples - failures))


def certificate(prop: Property, margins: list[float], epsilon: float, beta: float) -> dict:
    """The statement N samples make about a property (their margins, one per sample)."""
    failures = sum(1 for m in margins if not (m > 0 if prop.op in ("<", ">") else m >= 0))
    return _statement(prop.text, len(margins), failures, epsilon, beta, "P(fail)")


def _statement(text: str, n: int, failures: int, epsilon: float, beta: float, bounded: str) -> dict:
    """A certificate: ``failures`` of ``n`` independent draws failed ``text``; the one-sided
    Clopper-Pearson bound on ``bounded`` (the failure probability), and whether it is <= epsilon.
    """
    upper = clopper_pearson_upper(failures, n, beta) if n else 1.0
    return {
        "property": text,
        "N": n,
        "k": failures,
        "epsilon": epsilon,
        "beta": beta,
        "p_upper": upper,
        "holds": bool(n and upper <= epsilon),
        "method": f"one-sided Clopper-Pearson (exact binomial) bound on {bounded} over the sweep's "
        "distribution; the samples are independent draws of it",
    }


ALL_OF = "all of: "
"""How the certificate of several properties together names them (``all of: a, b``)."""


def all_certificate(properties: list[Property], records: list[dict], epsilon: float, beta: float) -> dict:
    """The certificate of the properties together: a run fails when any of them fails (k counts
    such runs), so P(some property fails) <= p_upper, the bound a design's requirement needs
    (each property's own bound is smaller, and their union is not bounded by the largest).
    """
    failures = sum(1 for r in records if not all(p.holds(r) for p in properties))
    text = ALL_OF + ", ".join(p.text for p in properties)
    return _statement(text, len(records), failures, epsilon, beta, "P(some property fails)")


def overall_certificate(certificates: list[dict]) -> dict | None:
    """The certificate of the whole requirement among ``certificates`` (of one controller and
    grid cell): the ``all of`` one where there are several properties, else the only one.
    """
    for c in certificates:
        if c["property"].startswith(ALL_OF):
            return c
    return certificates[0] if len(certificates) == 1 else None


def wilks_upper(values: list[float], quantile: float, beta: float) -> float | None:
    """Wilks' distribution-free bound: the smallest order statistic x_(r) with
    P(x_(r) >= the ``quantile``-quantile) >= 1 - beta, i.e. the least r with
    BinomCDF(r - 1; N, quantile) >= 1 - beta; None when N samples are too few.
    """
    from scipy.stats import binom

    ordered = sorted(v for v in values if not math.isnan(v))
    n = len(ordered)
    for r in range(1, n + 1):
        if binom.cdf(r - 1, n, quantile) >= 1 - beta:
            return ordered[r - 1]
    return None


def certify(
    spec, frame, properties: list[Property], epsilon: float, beta: float, stopped_early: bool = False
) -> dict[str, dict]:
    """Per controller: a certificate per property and grid cell, and Wilks' bound on each
    property's metric at the 1 - epsilon quantile with confidence 1 - beta. A row that did not
    complete (diverged, refused) fails every property. With ``stopped_early`` (sequential
    stopping), a cell that has fewer rows than planned says so: its claim was refuted first.
    """
    import hashlib

    out: dict[str, dict] = {}
    described = repr(sorted((k, repr(v)) for k, v in spec.vary.items())) + repr(sorted(spec.set.items()))
    distribution = hashlib.sha256(described.encode()).hexdigest()
    for controller in spec.controllers:
        rows = frame[frame["controller"] == controller]
        cells = (
            [((), rows)]
            if not spec.grid_keys
            else [(key, group) for key, group in rows.groupby(spec.grid_keys, sort=True, dropna=False)]
        )
        certificates, bounds = [], []
        for cell, group in cells:
            records = group.to_dict("records")
            where = dict(zip(spec.grid_keys, cell if isinstance(cell, tuple) else (cell,)))
            found, quantiles = certify_runs(records, properties, epsilon, beta)
            for entry in found:
                entry.update(distribution=distribution, **({"grid": where} if where else {}))
                if stopped_early and len(records) < spec.samples:
                    entry["planned"] = spec.samples
                    entry["method"] += (
                        f"; sequential stopping: stopped after {len(records)} of {spec.samples} rows, "
                        "once some property's failures refuted the claim at the planned N"
                    )
            certificates += found
            bounds += [{**b, **({"grid": where} if where else {})} for b in quantiles]
        out[controller] = {"certificates": certificates, "quantile_bounds": bounds}
    return out


def certify_runs(
    records: list[dict], properties: list[Property], epsilon: float, beta: float
) -> tuple[list[dict], list[dict]]:
    """What N independent runs (their metrics, with ``status``) prove: a certificate per property,
    and Wilks' bound on each ordered property's metric at the 1 - epsilon quantile with
    confidence 1 - beta. A run that did not complete fails every property.
    """
    certificates, bounds = [], []
    if len(properties) > 1:  # the whole requirement: a run fails it when any property fails
        certificates.append(all_certificate(properties, records, epsilon, beta))
    for prop in properties:
        certificates.append(certificate(prop, [prop.margin(r) for r in records], epsilon, beta))
        if prop.op in ("<=", "<", ">=", ">"):
            values = [float(r[prop.metric]) if r.get("status") == "completed" else math.inf for r in records]
            low = prop.op in (">=", ">")
            bound = wilks_upper([-v for v in values] if low else values, 1 - epsilon, beta)
            bounds.append(
                {
                    "metric": prop.metric,
                    "quantile": 1 - epsilon,
                    "confidence": 1 - beta,
                    "bound": None if bound is None else (-bound if low else bound),
                    "side": "lower" if low else "upper",
                    "N": len(records),
                }
            )
    return certificates, bounds


def refuted_groups(
    spec, records: list[dict], properties: list[Property], epsilon: float, beta: float
) -> set[tuple[str, int]]:
    """The (controller, grid cell) groups whose claim is already refuted (sequential stopping):
    for some property, the k failures among the group's rows so far give p_upper(k, N) > epsilon
    at the group's planned N = ``spec.samples``, so no outcome of its remaining rows can prove it.
    A claim is proved only by all N rows: a group is never stopped for looking good.
    """
    failures: dict[tuple[str, int], dict[str, int]] = {}
    for r in records:
        group = (r["controller"], int(r["sample"]) // spec.samples)
        counts = failures.setdefault(group, {})
        for prop in properties:
            if not prop.holds(r):
                counts[prop.text] = counts.get(prop.text, 0) + 1
    return {
        group
        for group, counts in failures.items()
        if any(clopper_pearson_upper(k, spec.samples, beta) > epsilon for k in counts.values())
    }


def format_certificates(certified: dict[str, dict]) -> list[str]:
    """One line per certificate: the claim, N, k, the bound and whether it holds."""
    lines = []
    for controller, entry in certified.items():
        for c in entry["certificates"]:
            where = "".join(f" {k}={v}" for k, v in c.get("grid", {}).items())
            verdict = "holds" if c["holds"] else "not shown"
            lines.append(
                f"{controller}{where}: P({c['property']} fails) <= {c['p_upper']:.3g} with "
                f"confidence {confidence_text(c['beta'])} (N = {c['N']}, k = {c['k']}); P(fail) <= "
                f"{c['epsilon']:g}: {verdict}"
            )
        for b in entry["quantile_bounds"]:
            if b["bound"] is not None:
                side = "<=" if b["side"] == "upper" else ">="
                lines.append(
                    f"{controller}: with confidence {confidence_text(1 - b['confidence'])}, "
                    f"{100 * b['quantile']:g} % "
                    f"of plants give {b['metric']} {side} {b['bound']:.4g} (Wilks, N = {b['N']})"
                )
    return lines
