"""What the stages of a study's case share (:mod:`.stages` binds them into the stage table): the
seeds of the draws each stage runs on, the sweep of a list of entries on the case's box, the
stages run side by side, one progress display for them, and :class:`CaseRun`, what every stage
reads and what the earlier ones found.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .spec import StudyCase, StudySpec
from .stage_table import StageRow

# ---- what the stages share ----------------------------------------------------------------------
VALIDATION_SEED = 1_000_003
"""Added to the study's seed for the validation draws (the tunings draw from seed + s, s < 20)."""

CERTIFY_SEED = 2_000_003
"""Added to the study's seed for the certification draws: independent of training and validation."""

TRAIN_SEED = 3_000_003
"""Added to the study's seed for a trained policy's seeds: its training episodes are the case's
draws with seed + s, its learning curve's validation episodes those with seed + s + 1 000 003;
neither are the tunings', the validation's or the certification's draws."""


def seed_name(controller: str, seed: int) -> str:
    """The validation entry of one (controller, optimiser seed) setting."""
    return f"{controller}-seed{seed}"


def sweep_of(spec: StudySpec, case: StudyCase, names: list[str], entries: dict, samples: int, seed: int):
    """A sweep of ``names`` (with their ``entries``) on ``samples`` draws of the case's box."""
    from ..base.plan import SweepSpec

    return SweepSpec(
        name=f"{spec.name}-{spec.case_name(case)}",
        base=case.base,
        controllers=list(names),
        samples=samples,
        seed=seed,
        set=spec.case_set(case),
        vary=dict(spec.vary),
        entries={k: v for k, v in entries.items() if k in names},
    )


def draws_differ(sweep) -> bool:
    """Whether a case's draws are different plants before any runs: a ``[vary]`` box, sensor
    noise, or a nominal model whose error is drawn from each draw's seed. Where none is, every
    draw is the same plant and a tuning setting needs one run (the budget buys settings).
    """
    from ...config import nominal_kind
    from ..base.plan import base_config

    config = base_config(sweep)
    sensing, nominal = config.sensing, config.nominal
    noisy = any(sensing.position_noise) or any(sensing.velocity_noise)
    return bool(sweep.vary or noisy or (nominal_kind(config) in ("urdf", "identified") and nominal.perturbed))


def varies(frame) -> bool:
    """Whether the rows of a sweep differ from draw to draw: a case with no randomness (no box,
    no noise) gives every draw the same plant, so "held-out" draws are the training plant.
    """
    import numpy as np

    for _, rows in frame.groupby("controller"):
        values = rows["rms_error_after_2s"].to_numpy(dtype=float)
        values = values[np.isfinite(values)]
        if values.size > 1 and np.ptp(values) > 0:
            return True
    return False


def has_mujoco() -> bool:
    """Whether MuJoCo, the second engine, is installed."""
    try:
        import mujoco  # noqa: F401
    except ImportError:
        return False
    return True


STOP_SECONDS = 30.0
"""How long stages asked to stop are waited for (each notices within a second,
:data:`nnrobust.studies.base.cluster.POLL_SECONDS`) before the cluster is closed under them."""


def side_by_side(stages: list) -> list:
    """Each stage's result (callables, each a stage engine run with its own client of the study's
    cluster), the stages run on threads side by side: one's last tasks and the next one's first
    share the workers. The first error (or interrupt) asks the others to stop at their next check
    (:func:`nnrobust.core.signals.stop_stages`); once every stage has ended, each keeping what it
    computed, it is raised.
    """
    if len(stages) == 1:
        return [stages[0]()]
    from concurrent.futures import FIRST_EXCEPTION, ThreadPoolExecutor, wait

    from ...core.signals import signals_held, stop_stages

    pool = ThreadPoolExecutor(len(stages), thread_name_prefix="nnrobust-stage")
    futures = [pool.submit(stage) for stage in stages]
    try:
        finished, _ = wait(futures, return_when=FIRST_EXCEPTION)
        first = next((f.exception() for f in futures if f in finished and f.exception()), None)
        if first is not None:
            raise first
    except BaseException:
        stop_stages()
        try:
            with signals_held():  # a second Ctrl-C would close the cluster under the stages
                wait(futures, timeout=STOP_SECONDS)
        finally:
            stop_stages(False)
            pool.shutdown(wait=False)
        raise
    pool.shutdown()
    return [f.result() for f in futures]


class Together:
    """One progress display for the stages running side by side: the sum of their done and total
    runs, told to ``progress(done, total)``.
    """

    def __init__(self, progress):
        self.progress, self.counts, self.lock = progress, {}, threading.Lock()

    def stage(self):
        """The ``progress`` callback of one more stage."""
        if self.progress is None:
            return None
        key = len(self.counts)
        self.counts[key] = (0, 0)

        def told(done: int, total: int) -> None:
            with self.lock:
                self.counts[key] = (done, total)
                counts = self.counts.values()
                self.progress(sum(d for d, _ in counts), sum(t for _, t in counts))

        return told


def certified(
    spec: StudySpec, sweep, folder: Path, address: str, overwrite: bool, progress, ship: bool = False
):
    """(summary, rows) of a certification sweep run into ``folder``: its statistics, paired
    comparisons and a certificate per property (the study's epsilon and beta), summary.json written.
    """
    from ...run.properties import certify, run_properties
    from ..sweep.engine import read_results, run_sweep
    from ..sweep.summary import summarize, write_summary

    run_sweep(sweep, folder, scheduler=address, overwrite=overwrite, progress=progress, ship_files=ship)
    rows = read_results(folder)
    summary = summarize(sweep, rows)
    b = spec.budgets
    properties = run_properties(spec.certified_properties())
    for label, entry in certify(sweep, rows, properties, b["epsilon"], b["beta"]).items():
        summary["controllers"][label].update(entry)
    write_summary(folder, summary)
    return summary, rows


@dataclass
class CaseRun:
    """One case of a study as its stages run: what they all read, what the earlier stages found
    (``tunings``, ``validation``, ``certification``), and ``out``, the case's report entry.
    """

    spec: StudySpec
    """The study as this case runs it (:meth:`StudySpec.for_case`: its controllers and entries)."""
    case: StudyCase
    sweep: Any
    """The case's sweep (:meth:`StudySpec.case_sweep`): its experiment, [set] and box."""
    here: Path
    address: str
    overwrite: bool
    say: Callable[[str], None]
    progress: Any
    ship: bool
    stage_file: Callable[[Path, str], None]
    """Writes a stage's input file, keeping what it held first (the engine puts it back when a
    stage refuses its folder)."""
    out: dict = field(default_factory=dict)
    tunings: dict = field(default_factory=dict)
    validation: dict = field(default_factory=dict)
    certification: dict = field(default_factory=dict)
    together: Any = None
    """The one progress display of the stages run side by side (:class:`Together`)."""

    @property
    def name(self) -> str:
        """The case's name (its folder under ``cases/``)."""
        return self.spec.case_name(self.case)

    @property
    def case_file(self) -> Path:
        """The case's sweep as a file (the tunings' and the falsification's target)."""
        return self.here / "case.toml"

    @property
    def tuned(self) -> list[str]:
        """The controllers the study tunes (neither fixed nor trained)."""
        return self.spec.searched


@dataclass(frozen=True)
class Stage:
    """One entry of the stage table: its row (:class:`.stage_table.StageRow`) and what runs it."""

    row: StageRow
    run: Callable[[CaseRun], Callable[[], Any] | str]
    finish: Callable[[CaseRun, Any], None] = lambda case, result: None

    @property
    def name(self) -> str:
        """The row's name."""
        return self.row.name

    @property
    def budgets(self) -> tuple[str, ...]:
        """The row's [budgets] keys."""
        return self.row.budgets

    @property
    def folders(self) -> tuple[str, ...]:
        """The row's folders."""
        return self.row.folders

    @property
    def side_by_side(self) -> bool:
        """Whether it runs beside the other side-by-side stages."""
        return self.row.side_by_side

    @property
    def reported(self) -> bool:
        """Whether the report names it."""
        return self.row.reported
