"""What a tuning is (:class:`TuneSpec`), its constants, and its uncertainty set as a sweep."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from ...core.exceptions import ConfigError
from ..base.tuned import tunable, with_controllers

OBJECTIVES = ("rms_error_after_2s", "rms_torque", "torque_chatter")
"""What every setting is recorded with (the Pareto front's axes, all minimised): [m], [N m], [N m].
The search minimises the first under the constraints."""

CONSTRAINTS = (
    "rms_torque_over_limit",
    "saturated_over_limit",
    "runaway",
    "joint_limit_violation",
    "completed",
)
"""Each setting's constraints, met when <= 0 (the order of :func:`judge`'s list)."""

FAILED = (1.0, 1e4, 1e4)
"""Objective values of a setting whose run failed (diverged, refused): worse than any real one."""

MARKER = "tune.toml"

TRIALS = "trials"

WIDEN_FROM = 0.5
"""Fraction of a controller's settings after which a best setting on a bound widens its space."""

MAX_WIDENINGS = 4
"""Decades a bound may move out; past them it is reported in ``at_bound`` as searched to its end."""

GAIN_SHARE = 0.3
"""Share of a robust law's budget spent on its gains with u_0 = 0 (see :class:`~.search.ControllerSearch`)."""


@dataclass
class TuneSpec:
    """What a tuning is: target, controllers, budget, samples, constraints, seed.

    Attributes:
        target: a preset, an experiment file or a sweep file (its [vary] is the uncertainty set).
        controllers: controller kinds to tune.
        budget: simulations per controller (the training runs; validation is extra).
        train_samples: samples each setting is simulated on (common random numbers).
        validation: held-out samples the best setting is checked on.
        max_rms_torque: [N m] constraint (inf: none).
        max_saturated: constraint on the fraction of saturated steps (1: none).
        seed: seed of the optimiser and of the samples.
        set: fixed overrides of the target's experiment (``--set KEY=VALUE``, as a sweep file's
            [set]: every run takes them; a key the target's [vary] draws is refused).

    """

    target: str
    controllers: list[str]
    budget: int
    train_samples: int = 1
    validation: int = 4
    max_rms_torque: float = math.inf
    max_saturated: float = 1.0
    seed: int = 0
    set: dict = field(default_factory=dict)

    def __post_init__(self):
        checks = [
            ("--budget", self.budget >= 2 and self.budget <= 100_000, "an integer in [2, 100000]"),
            ("--train-samples", 1 <= self.train_samples <= 1000, "an integer in [1, 1000]"),
            ("--validation", 0 <= self.validation <= 1000, "an integer in [0, 1000]"),
            ("--max-rms-torque", self.max_rms_torque > 0, "> 0 [N m]"),
            ("--max-saturated", 0 <= self.max_saturated <= 1, "in [0, 1]"),
            ("--seed", 0 <= self.seed < 2**31, "an integer in [0, 2^31)"),
        ]
        for flag, ok, valid in checks:
            if not ok:
                raise ConfigError(flag, f"must be {valid}")
        if self.budget < self.train_samples:
            raise ConfigError(
                "--budget",
                f"{self.budget} simulations cannot run one setting on {self.train_samples} training samples",
            )
        if not self.controllers or len(set(self.controllers)) != len(self.controllers):
            raise ConfigError(
                "--controllers",
                f"needs distinct names among {', '.join(tunable())}, custom "
                "classes as file.py:Class, or the custom entries of a sweep file; got "
                f"{', '.join(self.controllers) or 'none'}",
            )

    @property
    def trials(self) -> int:
        """Settings per controller: the budget over the training samples."""
        return self.budget // self.train_samples

    def to_toml(self) -> str:
        """The resolved tuning (DIR/tune.toml)."""
        from ...config import dump_toml

        return dump_toml(
            {
                "target": self.target,
                "controllers": self.controllers,
                "budget": self.budget,
                "train_samples": self.train_samples,
                "validation": self.validation,
                "max_rms_torque": self.max_rms_torque if math.isfinite(self.max_rms_torque) else "inf",
                "max_saturated": self.max_saturated,
                "seed": self.seed,
                **({"set": dict(self.set)} if self.set else {}),
            }
        )


def sweep_of(spec: TuneSpec):
    """The uncertainty set as a sweep: the target's [vary] draws (or only seeds), no grid."""
    from ..base.plan import SweepSpec, load_sweep

    path = Path(spec.target)
    is_sweep = False
    if path.suffix == ".toml" and path.is_file():
        from ...config import parse_toml, read_text_file

        data = parse_toml(read_text_file(path, what="tuning target"), str(path))
        is_sweep = "base" in data and "controllers" in data
    else:
        from ..base.plan import shipped_sweeps

        is_sweep = spec.target in shipped_sweeps()
    size = spec.train_samples + spec.validation
    if is_sweep:
        sweep = load_sweep(spec.target)
        if sweep.grid_keys:
            raise ConfigError(
                "vary",
                f"tuning draws its samples from [vary] distributions; the grid keys "
                f"{', '.join(sweep.grid_keys)} are lists (make them a distribution or "
                "set them in [set])",
            )
        sweep.samples, sweep.seed = size, spec.seed
        varied = sorted(set(spec.set) & set(sweep.vary))
        if varied:
            raise ConfigError(
                f"--set {varied[0]}", "is drawn by the sweep file's [vary]: it cannot also be fixed"
            )
        sweep.set = {**sweep.set, **spec.set}
    else:
        base = str(path.resolve()) if path.suffix == ".toml" else spec.target
        sweep = SweepSpec(
            name=path.stem if path.suffix == ".toml" else spec.target,
            base=base,
            controllers=[],
            samples=size,
            seed=spec.seed,
            set=dict(spec.set),
        )
    return with_controllers(sweep, spec.controllers)


ROUND_SIMULATIONS = 2
"""Simulations per controller per round of the optimiser (a batch of settings, each on every
training sample): fixed, so that the settings asked, and the results, are the same on any number
of workers (they were sized to the cluster, so one worker and two tuned differently). Every
controller's batch runs in the same round: 6 controllers on 2 samples are 12 tasks a round."""
