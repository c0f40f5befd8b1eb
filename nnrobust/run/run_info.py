"""What the analysis of a run needs to know of its experiment, typed: the figures' criterion label
and unit, the viewer's robot, what makes two runs comparable. A :class:`~nnrobust.run.results.Result`
carries it and its run folder stores it (result.npz), so that nothing parses config.toml again.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field


@dataclass(frozen=True)
class RunInfo:
    """A run's experiment as its analysis reads it.

    Attributes:
        name: the experiment's name.
        controller: the controller's label (its kind, or a custom class's name).
        robot_source, locked_joints, chain, mesh_folders: the robot as configured
            (``robot.source``, ``robot.locked_joints``, ``robot.chain``, ``robot.mesh_folders``),
            from which the viewer loads its visuals.
        task_frame: the frame whose position (or pose) is the task, as configured (None: the
            default rule).
        task: ``planar``, ``position`` or ``pose``.
        trajectory: the desired trajectory's settings (``[trajectory]`` as a table).
        criteria: the self-motion criteria h_i of eq. (4) the run weighted (empty: none).
        criterion_weights: their weights.
        criterion_units: the unit of each (matplotlib text).

    """

    name: str = ""
    controller: str = ""
    robot_source: str = ""
    locked_joints: tuple[str, ...] | None = None
    chain: tuple[str, ...] | None = None
    mesh_folders: tuple[str, ...] | None = None
    task_frame: str | None = None
    task: str = "planar"
    trajectory: dict = field(default_factory=dict)
    criteria: tuple[str, ...] = ()
    criterion_weights: tuple[float, ...] = ()
    criterion_units: tuple[str, ...] = ()

    @classmethod
    def from_config(cls, config, n: int | None = None) -> RunInfo:
        """The analysis view of an :class:`~nnrobust.config.ExperimentConfig`; ``n`` (the arm's
        joints) picks the default criteria when ``subtasks.criteria`` is unset.
        """
        from ..config import controller_label
        from ..model.tasks import TASK_KINDS
        from ..subtasks import criterion_unit, default_criteria

        rc, sub = config.robot, config.subtasks
        m = TASK_KINDS[rc.task]
        if sub.criteria is not None:
            names = list(sub.criteria)
        elif n is not None:
            names = default_criteria(n, rc.task)
        else:
            names = []
        weights = list(sub.weights) if sub.weights else [sub.C / len(names)] * len(names)
        return cls(
            name=config.name,
            controller=controller_label(config),
            robot_source=str(rc.source),
            locked_joints=None if rc.locked_joints is None else tuple(rc.locked_joints),
            chain=None if rc.chain is None else tuple(rc.chain),
            mesh_folders=None if rc.mesh_folders is None else tuple(rc.mesh_folders),
            task_frame=rc.task_frame,
            task=rc.task,
            trajectory=json.loads(json.dumps(_table(config.trajectory))),
            criteria=tuple(names),
            criterion_weights=tuple(float(w) for w in weights),
            criterion_units=tuple(criterion_unit(c, m) for c in names),
        )

    def to_json(self) -> str:
        """One line of JSON (result.npz's ``info``)."""
        return json.dumps(asdict(self), sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> RunInfo:
        """Read :meth:`to_json`'s text (from a run folder received from anywhere): a key or a
        value of the wrong kind is a ValueError naming it.
        """
        data = json.loads(text)
        if not isinstance(data, dict) or set(data) - set(TYPES):
            raise ValueError(f"run info is not a table of {sorted(TYPES)}")
        for key, value in data.items():
            kind = TYPES[key]
            ok = (
                (value is None and kind.endswith("?"))
                or (kind.rstrip("?") == "str" and isinstance(value, str))
                or (kind == "dict" and isinstance(value, dict))
                or (
                    kind.startswith("strs")
                    and isinstance(value, list)
                    and all(isinstance(v, str) for v in value)
                )
                or (
                    kind == "floats"
                    and isinstance(value, list)
                    and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
                )
            )
            if not ok:
                raise ValueError(f"run info {key!r} is not {kind.rstrip('?')}: {value!r:.80}")
            if isinstance(value, list):
                data[key] = tuple(value)
        return cls(**data)

    @property
    def criterion_label(self) -> tuple[str, str]:
        """(h(q) as the run weighted it, e.g. ``h(q) = 0.5 joint_limits + ...``; its unit)."""
        if not self.criteria:
            return "no subtask criterion", "-"
        unit = " + ".join(dict.fromkeys(self.criterion_units))  # a sum of terms of different units
        terms = [
            (c if w == 1 else f"{w:g} {c}")
            if c != "paper"
            else (_criterion_formula(c) if w == 1 else f"{w:g} [{_criterion_formula(c)}]")
            for w, c in zip(self.criterion_weights, self.criteria)
        ]
        return "h(q) = " + " + ".join(terms), unit

    @property
    def robot(self) -> tuple:
        """What identifies the arm: (source, chain, task frame)."""
        return (self.robot_source, self.chain, self.task_frame)


TYPES = {
    "name": "str",
    "controller": "str",
    "robot_source": "str",
    "locked_joints": "strs?",
    "chain": "strs?",
    "mesh_folders": "strs?",
    "task_frame": "str?",
    "task": "str",
    "trajectory": "dict",
    "criteria": "strs",
    "criterion_weights": "floats",
    "criterion_units": "strs",
}
"""The kind of each field in result.npz's JSON (``?``: may be null)."""


def _criterion_formula(name: str) -> str:
    """A criterion as a formula for a title: its description in :data:`~nnrobust.subtasks.CRITERIA`."""
    from ..subtasks import CRITERIA

    text = CRITERIA.get(name, name)
    if text.startswith("eq. ("):  # "eq. (19): formula (three joints)" -> "formula, eq. (19)"
        label, _, text = text.partition(": ")
        text = text.removesuffix(" (three joints)") + ", " + label
    return text


def _table(section) -> dict:
    """A section as a table: its fields (None included), then the keys its kinds declare beyond
    them, flat, as the experiment file has them.
    """
    table = {k: v for k, v in asdict(section).items() if k != "extra"}
    return {**table, **getattr(section, "extra", {})}
