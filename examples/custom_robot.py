"""Your own arm from a URDF: a four-link planar arm written here, checked, loaded by Pinocchio and
driven along an ellipse by the paper's controller.

The URDF could come from any exporter; nnrobust reads its inertias, limits, efforts, damping and
friction, refuses physically impossible data with a message that names the link, and picks the
task frame at the end of the longest chain.

    python examples/custom_robot.py [--duration S] [--out DIR]
"""

import argparse
from pathlib import Path

import numpy as np

import nnrobust

LINKS = [  # length [m], mass [kg], effort limit [N m]
    (0.35, 3.0, 60.0),
    (0.30, 2.2, 40.0),
    (0.25, 1.5, 25.0),
    (0.20, 1.0, 15.0),
]


def planar_arm_urdf() -> str:
    """Four revolute joints about z; each link a slender rod along x with a tip frame."""
    parts = ['<?xml version="1.0"?>', '<robot name="four_link_planar">', '  <link name="base"/>']
    parent, offset = "base", 0.0
    for i, (length, mass, effort) in enumerate(LINKS, start=1):
        izz = mass * length**2 / 12
        parts += [
            f'  <joint name="joint{i}" type="revolute"><parent link="{parent}"/><child link="link{i}"/>',
            f'    <origin xyz="{offset} 0 0"/><axis xyz="0 0 1"/>',
            f'    <limit lower="-2.8" upper="2.8" effort="{effort}" velocity="3.0"/>',
            '    <dynamics damping="0.5" friction="0.2"/></joint>',
            f'  <link name="link{i}"><inertial><origin xyz="{length / 2} 0 0"/><mass value="{mass}"/>',
            f'    <inertia ixx="1e-4" ixy="0" ixz="0" iyy="{izz}" iyz="0" izz="{izz}"/></inertial></link>',
        ]
        parent, offset = f"link{i}", length
    parts += [
        '  <joint name="tool_joint" type="fixed"><parent link="link4"/><child link="tool"/>',
        f'    <origin xyz="{offset} 0 0"/></joint>',
        '  <link name="tool"/>',
        "</robot>",
    ]
    return "\n".join(parts) + "\n"


def main() -> None:
    """Parse the arguments and run the example."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=10.0, help="simulated time [s]")
    parser.add_argument("--out", default="out/examples", help="folder of the URDF and the run folder")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    urdf = out / "four_link_planar.urdf"
    urdf.write_text(planar_arm_urdf())

    robot = nnrobust.load_robot(str(urdf), task="planar")
    q = np.array([0.6, -0.5, -0.5, -0.4])
    print(f"{robot.name}: n = {robot.nq}, task frame {robot.task_frame!r}, x(q) = {robot.task_position(q)}")
    print("M(q) diagonal [kg m^2]:", np.round(np.diag(robot.mass(q)), 4))

    config = nnrobust.ExperimentConfig().replace(
        name="four-link",
        robot={"source": str(urdf), "task": "planar"},
        nominal={"kind": "urdf", "relative_error": 0.2, "seed": 3},  # the controller's model is 20 % off
        trajectory={"center": [0.55, 0.35], "axis_a": [0.2, 0.0], "axis_b": [0.0, 0.1]},
        controller={"kind": "nn", "Kp": [25.0], "Kv": [10.0]},
        nn={"basis_input": "error", "sigma": 0.05, "eps_min": 0.2},
        subtasks={"criteria": ["manipulability", "joint_limits"], "C": 1.0},
        simulation={"duration": args.duration, "q_seed": q.tolist()},
    )
    result = nnrobust.run_experiment(config)
    metrics = result.metrics()
    print(
        f"status {metrics['status']}, RMS error {1e3 * metrics['rms_error']:.2f} mm, "
        f"RMS torque {metrics['rms_torque']:.2f} N m, backend {result.backend}"
    )
    for warning in metrics["warnings"]:
        print("warning:", warning)
    nnrobust.write_run(out / "four-link-nn", result, overwrite=True, animation=False)


if __name__ == "__main__":
    main()
