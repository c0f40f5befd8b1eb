"""The stage table's rows: what each stage of a study's case is, without what runs it (that is
:mod:`.stages`, which binds each row to its functions). A leaf module, so that the command line's
help reads the table without importing the engines.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class StageRow:
    """One stage of a case."""

    name: str
    """Its key in the report's ``stages`` (how it ended) and in the CLI's replay commands."""
    budgets: tuple[str, ...]
    """The study's ``[budgets]`` keys it reads."""
    folders: tuple[str, ...]
    """Its folders under ``cases/C/`` (besides ``tune-seedS``, one per optimiser seed)."""
    does: str
    """What it does, for ``nnrobust study --help`` ("" for a stage the help does not name)."""
    side_by_side: bool = False
    """Runs on the cluster beside the other side-by-side stages (they need none of each other's
    results); otherwise alone, in the table's order."""
    reported: bool = True
    """Whether the report's ``stages`` names it."""


TUNE_BUDGETS = ("tune", "seeds", "train_samples", "max_rms_torque", "max_saturated")

STAGE_ROWS: tuple[StageRow, ...] = (
    StageRow("tune", TUNE_BUDGETS, (), "tune (each optimiser seed)"),
    StageRow(
        "validate",
        ("validation", "tolerance"),
        ("validate",),
        "validate every seed's setting on fresh draws and keep the best",
    ),
    StageRow(
        "train",
        (),
        ("train", "validate-train"),
        "train each learned policy an entry's train table names (PPO or SAC, each seed, on the "
        "kept setting of its base law) and keep its best seed on the same fresh draws",
    ),
    StageRow(
        "certify",
        ("certify", "epsilon", "beta"),
        ("certify",),
        "certify the kept settings on draws the selection never saw (with paired comparisons)",
        side_by_side=True,
    ),
    StageRow("falsify", ("falsify", "margin"), ("falsify",), "falsify them", side_by_side=True),
    StageRow(
        "realtime",
        ("realtime",),
        ("realtime",),
        "where the study asks, export and time them out of Python (realtime)",
    ),
    StageRow(
        "engine",
        ("second_engine",),
        ("certify-mujoco",),
        "where the study asks, run the certification draws on MuJoCo (second_engine)",
        side_by_side=True,
    ),
    StageRow("responses", (), ("responses",), "", reported=False),
)
"""The stages of a case, in the report's order (docs/study.md)."""


def study_description() -> str:
    """``nnrobust study --help``'s description, from the table."""
    said = [row.does for row in STAGE_ROWS if row.does]
    together = ", ".join(row.name for row in STAGE_ROWS if row.side_by_side)
    return (
        "Run a study file's cases and controllers through every stage, in this order: "
        + "; ".join(said)
        + ". Each stage is the sweep, tune, falsify or export command's own engine and folder; the "
        f"seeds' tunings run side by side, and so do the stages that need none of each other's results "
        f"({together}). Writes DIR/report.html, report.json, tables/ and figures/. Re-running the same "
        "command resumes (docs/study.md)."
    )
