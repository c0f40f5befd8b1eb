"""``nnrobust identify``: a robot's identified model from its log (docs/identification.md)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..core.exceptions import ConfigError
from .common import Command, say_unless_quiet


def identify_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``nnrobust identify``."""
    parser.add_argument(
        "logs",
        nargs="+",
        metavar="LOG",
        help="the log: one CSV or Parquet file, one run folder, one ROS 2 bag or MCAP file, or text "
        "files (one per signal, or their folder)",
    )
    parser.add_argument(
        "--robot", required=True, help="the robot: a URDF file or a robot's name (nnrobust robots)"
    )
    parser.add_argument(
        "--out",
        required=True,
        help="folder to write (nominal.json, box.toml, region.json, identification.json, parameters.csv, "
        "report.html)",
    )
    parser.add_argument(
        "--locked-joints",
        metavar="A,B",
        help="joints held fixed, as robot.locked_joints (default: the robot's rule)",
    )
    parser.add_argument(
        "--friction",
        default="viscous,coulomb",
        metavar="TERMS",
        help="each joint's friction terms, comma-separated, of viscous, coulomb, offset "
        "(default: viscous,coulomb)",
    )
    parser.add_argument(
        "--topic",
        help="a ROS 2 bag's or MCAP file's sensor_msgs/msg/JointState topic (default: its only one)",
    )
    parser.add_argument("--armature", action="store_true", help="identify each joint's rotor inertia too")
    parser.add_argument(
        "--cutoff",
        type=float,
        default=10.0,
        metavar="HZ",
        help="the low-pass filter's cut-off [Hz] (default 10)",
    )
    parser.add_argument("--order", type=int, default=4, help="the Butterworth filter's order (default 4)")
    parser.add_argument(
        "--filter-torque",
        action="store_true",
        help="pass the torque through the same filter (default: as logged, its noise white)",
    )
    parser.add_argument(
        "--delay", type=float, default=0.0, metavar="S", help="the torque's measurement delay [s] (default 0)"
    )
    parser.add_argument(
        "--reversal-guard",
        type=float,
        default=1.5,
        metavar="PERIODS",
        help="cut-off periods on either side of a joint's velocity reversal whose samples leave the "
        "fit (the filter smears the acceleration's jump there; default 1.5, 0: none)",
    )
    parser.add_argument(
        "--stick-band",
        type=float,
        default=0.01,
        metavar="RAD_S",
        help="|q'| below which a joint sticks; its samples leave the fit (default 0.01 rad/s)",
    )
    parser.add_argument(
        "--fit-share",
        type=float,
        default=0.7,
        metavar="F",
        help="the share of the log, from its start, that fits; the rest is held out (default 0.7)",
    )
    parser.add_argument(
        "--confidence",
        type=float,
        default=0.95,
        metavar="LEVEL",
        help="the level 1 - alpha of the parameters' confidence region and intervals (default 0.95)",
    )
    parser.add_argument(
        "--allow-unexcited",
        action="store_true",
        help="fit although the log leaves base parameters unexcited (the URDF's values stand for them)",
    )
    parser.add_argument("--overwrite", action="store_true", help="replace an earlier identification in --out")
    parser.add_argument("--quiet", action="store_true", help="print nothing but errors")


def _locked_joints(text: str | None) -> list[str] | None:
    """``--locked-joints A,B``'s names (None: the robot's rule)."""
    return None if text is None else [j for j in text.split(",") if j]


def _friction_terms(text: str) -> tuple[str, ...]:
    """``--friction``'s terms (a ConfigError names what is valid)."""
    from ..model.regressor import FRICTION_TERMS

    terms = tuple(t.strip() for t in text.split(",") if t.strip())
    unknown = [t for t in terms if t not in FRICTION_TERMS]
    if unknown or len(set(terms)) != len(terms):
        raise ConfigError("--friction", f"{text!r}: name each of {', '.join(FRICTION_TERMS)} at most once")
    return terms


def cmd_identify(args) -> int:
    """Identify a robot from its log."""
    from ..studies.identify.engine import IdentifyOptions, identify
    from ..studies.identify.signals import FilterChoice

    terms = _friction_terms(args.friction)
    for option, value, low in (("--cutoff", args.cutoff, 0.0), ("--stick-band", args.stick_band, 0.0)):
        if not value > low or value != value or value == float("inf"):
            raise ConfigError(option, f"must be a positive number, got {value}")
    if not 1 <= args.order <= 8:
        raise ConfigError("--order", f"must be 1 to 8, got {args.order}")
    if not 0 <= args.reversal_guard <= 10:
        raise ConfigError("--reversal-guard", f"must be 0 to 10 cut-off periods, got {args.reversal_guard}")
    if not abs(args.delay) < 1.0:
        raise ConfigError("--delay", f"must be under 1 s in size, got {args.delay}")
    options = IdentifyOptions(
        friction=terms,
        armature=args.armature,
        filter=FilterChoice(
            args.cutoff, args.order, args.delay, torque=args.filter_torque, reversal_guard=args.reversal_guard
        ),
        stick_band=args.stick_band,
        fit_share=args.fit_share,
        allow_unexcited=args.allow_unexcited,
        confidence=args.confidence,
        topic=args.topic,
    )
    locked = _locked_joints(args.locked_joints)
    say = say_unless_quiet(args.quiet)
    summary = identify(
        args.logs, args.robot, args.out, options, locked_joints=locked, overwrite=args.overwrite, say=say
    )
    if not args.quiet:
        shares = summary["residuals"]
        print(
            f"{'joint':<16} {'torque rms':>11} {'URDF':>8} {'least sq.':>10} {'physical':>9}"
            "   (held-out residual / torque RMS; URDF: its bodies and <dynamics> friction)"
        )
        for j, name in enumerate(summary["joints"]):
            print(
                f"{name:<16} {summary['torque_rms']['held_out'][j]:>9.3f} Nm"
                + "".join(
                    f"{100 * shares[k]['held_out_share'][j]:>9.1f}%"
                    for k in ("urdf", "least_squares", "physical")
                )
            )
        region = summary["confidence"]
        print(f"parameters' {100 * region['level']:g} % confidence region: {region['method']}")
        checks = summary["checks"]
        model = (Path(args.out) / "nominal.json").absolute()
        print(
            f"physical: yes (least M(q) eigenvalue {checks['mass_matrix_least_eigenvalue']:.3g}); wrote "
            f'{model}: use it as [nominal] kind = "identified", file = "{model}"'
        )
        box = model.parent / "box.toml"
        print(
            f"wrote {box}: the plants of the {100 * region['level']:g} % box ({len(summary['parameters'])} "
            f"coordinates, each within +-{region['box_half_width']:.4g} standard deviations): use it as "
            f'box = "{box}" in a sweep, falsify or study file'
        )
    return 0


IDENTIFY = Command(
    "identify",
    help="identify a robot's model from its log (nominal.json for [nominal] kind = 'identified')",
    description="Fit a robot's base inertial parameters and joint friction to a log of its joint "
    "positions, velocities and torques (CSV, Parquet, text files or a run folder): weighted least "
    "squares on Pinocchio's torque regressor, then the physically consistent model (every body's "
    "pseudo-inertia positive semi-definite), with the held-out residual per joint "
    "(docs/identification.md). The motion to log: nnrobust identify design.",
    arguments=identify_arguments,
    run=cmd_identify,
)


def design_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``nnrobust identify design``."""
    from ..studies.identify.design import DesignOptions

    d = DesignOptions()
    parser.add_argument(
        "--robot", required=True, help="the robot: a URDF file or a robot's name (nnrobust robots)"
    )
    parser.add_argument(
        "--out",
        required=True,
        metavar="TRAJ.toml",
        help="the experiment file to write (the task frame's path; the joint trajectory and the "
        "search's record go to TRAJ.json beside it)",
    )
    parser.add_argument("--locked-joints", metavar="A,B", help="joints held fixed, as robot.locked_joints")
    parser.add_argument(
        "--task",
        choices=("planar", "position"),
        help="the experiment's task (default: planar for an arm whose task frame moves in a plane)",
    )
    parser.add_argument(
        "--harmonics", type=int, default=d.harmonics, help=f"L, harmonics (default {d.harmonics})"
    )
    parser.add_argument(
        "--frequency",
        type=float,
        default=d.frequency,
        metavar="HZ",
        help=f"the base frequency (default {d.frequency:g} Hz)",
    )
    parser.add_argument("--periods", type=int, default=2, help="periods the experiment runs (default 2)")
    parser.add_argument(
        "--position-margin",
        type=float,
        default=d.position_margin,
        metavar="F",
        help=f"share of each joint's range kept free at either end (default {d.position_margin:g})",
    )
    parser.add_argument(
        "--velocity-share",
        type=float,
        default=d.velocity_share,
        metavar="F",
        help=f"share of each velocity limit the trajectory may use (default {d.velocity_share:g})",
    )
    parser.add_argument(
        "--torque-share",
        type=float,
        default=d.torque_share,
        metavar="F",
        help=f"share of each effort limit the URDF model's torque may use (default {d.torque_share:g})",
    )
    parser.add_argument(
        "--max-velocity", type=float, metavar="RAD_S", help="velocity limit of joints whose URDF gives none"
    )
    parser.add_argument(
        "--friction",
        default="viscous,coulomb",
        metavar="TERMS",
        help="the friction terms of the fit whose condition number is minimised (default: viscous,coulomb)",
    )
    parser.add_argument(
        "--evaluations",
        type=int,
        default=d.evaluations,
        help=f"the CMA-ES search's budget of evaluations (default {d.evaluations})",
    )
    parser.add_argument(
        "--criterion",
        default=d.criterion,
        choices=("condition", "d-optimal"),
        help="what the search minimises: condition (identify's condition number; the default) or "
        "d-optimal (the confidence region's volume)",
    )
    parser.add_argument("--seed", type=int, default=0, help="the search's seed (default 0)")
    parser.add_argument("--overwrite", action="store_true", help="replace TRAJ.toml and TRAJ.json")
    parser.add_argument("--quiet", action="store_true", help="print nothing but errors")


def cmd_identify_design(args) -> int:
    """Design an exciting trajectory for a robot's identification."""
    from ..studies.identify.design import DesignOptions, write_design

    if not 1 <= args.periods <= 100:
        raise ConfigError("--periods", f"must be 1 to 100, got {args.periods}")
    options = DesignOptions(
        harmonics=args.harmonics,
        frequency=args.frequency,
        position_margin=args.position_margin,
        velocity_share=args.velocity_share,
        torque_share=args.torque_share,
        max_velocity=args.max_velocity,
        friction=_friction_terms(args.friction),
        evaluations=args.evaluations,
        seed=args.seed,
        criterion=args.criterion,
    )
    locked = _locked_joints(args.locked_joints)
    say = say_unless_quiet(args.quiet)
    design, toml_path, json_path = write_design(
        args.robot, args.out, options, args.periods, args.task, locked, args.overwrite, say
    )
    if not args.quiet:
        print(
            f"condition number {design.condition:.4g} (the search's start {design.start_condition:.4g}) "
            f"after {design.evaluations} evaluations ({design.stop}), {design.seconds:.1f} s"
        )
        width = max(len(j) for j in design.joints)
        print(
            f"{'joint':<{width}}  {'range':>6} {'velocity':>9} {'torque':>7}   "
            "(peak share of each limit's room)"
        )
        for j, name in enumerate(design.joints):
            cells = [design.peaks[k][j] for k in ("position", "velocity", "torque")]
            print(
                f"{name:<{width}}  "
                + " ".join(f"{'-' if c != c else f'{100 * c:.0f}%':>{w}}" for c, w in zip(cells, (6, 9, 7)))
            )
        print(f"wrote {toml_path} (the experiment) and {json_path} (the joint trajectory and the search)")
    return 0


IDENTIFY_DESIGN = Command(
    "identify-design",
    help="design an exciting trajectory for identify (also: nnrobust identify design)",
    description="Design the finite-Fourier joint trajectory that minimises the condition number "
    "of the base regressor identify checks (or, with --criterion d-optimal, the confidence region's "
    "volume), within the joints' ranges, velocity and effort limits, at rest at its start and every "
    "period's end (CMA-ES); write it as an experiment file that runs it joint by joint "
    "(controller.kind = 'joint-fourier') and its joint coefficients as JSON (docs/identification.md, "
    "'Designing the excitation').",
    arguments=design_arguments,
    run=cmd_identify_design,
)
