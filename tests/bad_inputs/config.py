"""Bad inputs: experiment files and their keys."""

from __future__ import annotations

from pathlib import Path

from nnrobust.core import exceptions as ex

from .common import (
    Case,
    _build,
    _file,
    _read_config,
    _toml,
)
from .run_folders import (
    _fifo,
)
from .urdf import (
    PAPER,
)

CONFIG_CASES = [
    Case(
        "a point of an identified box without the box",
        lambda d: _toml(d, f"{PAPER}[plant]\nregion_coordinates = [1.0]\n"),
        ex.ConfigError,
        "plant.region_coordinates: are a point of plant.region's box: give plant.region too",
    ),
    Case(
        "plant.region naming a JSON file that is not an identified box's region",
        lambda d: _build(plant={"region": str(_file(d, "region.json", '{"format": "x"}'))}),
        ex.ConfigError,
        "region.json: is not an identified region (its format must be 'nnrobust-identified-region/1'; "
        "nnrobust identify writes one)",
    ),
    Case(
        "a TOML date-time in controller.params",
        lambda d: _toml(
            d,
            'base = "paper-ellipse"\n[controller]\nkind = "custom"\nclass = "laws.py:Eq9"\n'
            "params = {Kp = 10.0, Kv = 4.0, when = 1979-05-27T07:32:00Z}\n",
        ),
        ex.ConfigError,
        "experiment.toml: controller.params.when: is a TOML date-time (1979-05-27T07:32:00+00:00), "
        'which no key takes; to pass text, quote it: "1979-05-27T07:32:00+00:00"',
    ),
    Case(
        "a TOML date for a number",
        lambda d: _toml(d, 'base = "paper-ellipse"\n[simulation]\nduration = 1979-05-27\n'),
        ex.ConfigError,
        "experiment.toml: simulation.duration: is a TOML date (1979-05-27), which no key takes",
    ),
    Case(
        "a point-to-point move of 1e-300 s",
        lambda d: _toml(
            d, f"{PAPER}[trajectory]\nkind = 'point_to_point'\ngoal = [0.3, 0.4]\nmove_time = 1e-300\n"
        ),
        ex.ConfigError,
        "trajectory.move_time: must be in [0.001, 1e+09] s, got 1e-300",
    ),
    Case(
        "a base preset with a typo",
        lambda d: _toml(d, 'base = "paper-elipse"\n'),
        ex.ConfigError,
        "experiment.toml: base: unknown preset 'paper-elipse'; did you mean 'paper-ellipse'? presets: ",
    ),
    Case(
        "an integer of 5000 digits (Python reads at most 4300)",
        lambda d: _toml(d, f"{PAPER}[plant]\npayload = {'9' * 5000}\n"),
        ex.ConfigError,
        "experiment.toml: invalid TOML: an integer of 5000 digits (at most 4300 are read, and no key "
        "takes one of more than 19)",
    ),
    Case(
        "a point-to-point move of 1e300 s (its quintic overflowed)",
        lambda d: _toml(
            d, f"{PAPER}[trajectory]\nkind = 'point_to_point'\ngoal = [0.3, 0.4]\nmove_time = 1e300\n"
        ),
        ex.ConfigError,
        "trajectory.move_time: must be in [0.001, 1e+09] s, got 1e+300",
    ),
    Case(
        "a rotation axis of [1e-320, 0, 0] (no length to normalise)",
        lambda d: _toml(d, 'base = "panda-pose"\n[trajectory]\nrotation_axis = [1e-320, 0.0, 0.0]\n'),
        ex.ConfigError,
        "trajectory.rotation_axis: [9.99989e-321, 0, 0] is too short to give a direction "
        "(length below 1e-09)",
    ),
    Case(
        "waypoint times 1e-300 s apart",
        lambda d: _toml(
            d,
            f"{PAPER}[trajectory]\nkind = 'waypoints'\nwaypoints = [[0.3, 0.4], [0.3, 0.5]]\n"
            "waypoint_times = [0.0, 1e-300]\n",
        ),
        ex.ConfigError,
        "trajectory.waypoint_times: must start at 0 or later and increase by at least 0.001 s",
    ),
    Case(
        "a goal at 1e308 m",
        lambda d: _toml(d, f"{PAPER}[trajectory]\nkind = 'point_to_point'\ngoal = [1e308, 0.4]\n"),
        ex.ConfigError,
        "trajectory.goal: [1e+308, 0.4] has a coordinate beyond 1000 m",
    ),
    Case(
        "an ellipse at omega = 1e300 rad/s",
        lambda d: _toml(d, f"{PAPER}[trajectory]\nomega = 1e300\n"),
        ex.ConfigError,
        "trajectory.omega: 1e+300 rad/s is beyond 10000 rad/s",
    ),
    Case(
        "a rocking amplitude of 1e300 rad",
        lambda d: _toml(d, f"{PAPER}[trajectory]\nrotation_amplitude = 1e300\n"),
        ex.ConfigError,
        "trajectory.rotation_amplitude: 1e+300 rad is more than half a turn",
    ),
    Case(
        "experiment file that does not exist",
        lambda d: _read_config(d / "missing.toml"),
        ex.ConfigError,
        "cannot read the file",
    ),
    Case("invalid TOML", lambda d: _toml(d, "[controller\nKp = 1"), ex.ConfigError, "invalid TOML"),
    Case(
        "unknown key (with a suggestion)",
        lambda d: _toml(d, "[controller]\nKpp = [10.0]\n"),
        ex.ConfigError,
        "controller.Kpp: unknown key; did you mean 'Kp'?",
    ),
    Case(
        "unknown section",
        lambda d: _toml(d, "[controler]\nkind = 'nn'\n"),
        ex.ConfigError,
        "did you mean 'controller'?",
    ),
    Case(
        "wrong type",
        lambda d: _toml(d, "[controller]\nk = 'ten'\n"),
        ex.ConfigError,
        "controller.k: expected a number, got str 'ten'",
    ),
    Case(
        "non-finite number",
        lambda d: _toml(d, "[controller]\nk = inf\n"),
        ex.ConfigError,
        "expected a finite number",
    ),
    Case(
        "negative gain",
        lambda d: _toml(d, "[controller]\nKp = [-10.0, 10.0]\n"),
        ex.ConfigError,
        "controller.Kp: -10 is outside (0, 1e+12] 1/s^2",
    ),
    Case(
        "Kv^2 <= Kp (Q not positive definite)",
        lambda d: _toml(d, "[controller]\nKp = [20.0]\nKv = [4.0]\n"),
        ex.ConfigError,
        "Kv^2 = 16 must exceed Kp = 20",
    ),
    Case(
        "zero control period",
        lambda d: _toml(d, "[simulation]\ncontrol_period = 0.0\n"),
        ex.ConfigError,
        "simulation.control_period: must be positive",
    ),
    Case(
        "no integration step per control period (substeps = 0)",
        lambda d: _toml(d, "[simulation]\nsubsteps = 0\n"),
        ex.ConfigError,
        "simulation.substeps: must be positive",
    ),
    Case(
        "no rotation allowed per plant step (max_step_rotation = 0)",
        lambda d: _toml(d, "[simulation]\nmax_step_rotation = 0.0\n"),
        ex.ConfigError,
        "simulation.max_step_rotation: must be at least 1e-06 rad (or m), got 0; to keep",
    ),
    Case(
        "a plant step allowed to turn 1e-300 rad (every period cut to the most steps)",
        lambda d: _toml(d, "[simulation]\nmax_step_rotation = 1e-300\n"),
        ex.ConfigError,
        "simulation.max_step_rotation: must be at least 1e-06 rad (or m), got 1e-300",
    ),
    Case(
        "a sensing delay as long as the run",
        lambda d: _toml(d, "[simulation]\nduration = 0.1\n[sensing]\ndelay = 100000000\n"),
        ex.ConfigError,
        "sensing.delay: 100000000 control periods is the whole run (0.1 s) or more",
    ),
    Case(
        "an NN basis width of 1e-308 (the loops would disagree)",
        lambda d: _toml(d, "[nn]\nwidth = 1e-308\n"),
        ex.ConfigError,
        "nn.width: 1e-308 is outside [1e-09, 1e+09]",
    ),
    Case(
        "an initial task offset of 1e308 m",
        lambda d: _toml(d, "[simulation]\ninitial_task_offset = [1e308, 0.0]\n"),
        ex.ConfigError,
        "simulation.initial_task_offset: [1e+308, 0.0] has an entry beyond 1000 m",
    ),
    Case(
        "control period shorter than the integration step",
        lambda d: _toml(d, "[simulation]\ncontrol_period = 0.001\nintegration_step = 0.002\n"),
        ex.ConfigError,
        "simulation.integration_step: 0.002 s is longer than the control period",
    ),
    Case(
        "control period not a whole number of integration steps",
        lambda d: _toml(d, "[simulation]\ncontrol_period = 0.001\nintegration_step = 0.0003\n"),
        ex.ConfigError,
        "is not a whole number of steps",
    ),
    Case(
        "duration shorter than one control period",
        lambda d: _toml(d, "[simulation]\nduration = 0.0005\n"),
        ex.ConfigError,
        "shorter than one control period",
    ),
    Case(
        "weights that do not sum to C",
        lambda d: _toml(
            d, "[subtasks]\ncriteria = ['manipulability', 'joint_centering']\nweights = [1.0, 1.0]\nC = 1.0\n"
        ),
        ex.ConfigError,
        "sum to 2 but subtasks.C = 1",
    ),
    Case(
        "unknown choice",
        lambda d: _toml(d, "[nn]\nlaw = 'fast'\n"),
        ex.ConfigError,
        "nn.law: expected one of 'corrected', 'printed', got 'fast'",
    ),
    Case(
        "gain vector of the wrong length",
        lambda d: _toml(d, "[controller]\nKp = [1.0, 2.0, 3.0]\n"),
        ex.ConfigError,
        "controller.Kp: has 3 entries, the task has m = 2",
    ),
    Case(
        "initial joint angle outside the limits",
        lambda d: _build(simulation={"q_seed": [0.2, 4.0, 1.0]}),
        ex.ConfigError,
        "simulation.q_seed: joint 'joint2' = 4 is outside its limits [-2.8, 2.8]",
    ),
    Case(
        "start point out of reach",
        lambda d: _build(trajectory={"center": [1.5, 0.4]}),
        ex.ConfigError,
        "is out of reach from q_seed",
    ),
    Case(
        "trajectory that leaves the workspace later",
        lambda d: _build(trajectory={"axis_b": [0.0, 0.8]}),
        ex.ConfigError,
        "trajectory: leaves the workspace: at t =",
    ),
    Case(
        "criterion for another arm",
        lambda d: _build(
            robot={"source": "planar7"}, plant={"disturbance": "none"}, nominal={"kind": "urdf"}
        ),
        ex.ConfigError,
        "'paper' (eq. 19) is for 3 joints",
    ),
    Case(
        "viscous friction too stiff for the RK4 step (substeps = 1 set)",
        lambda d: _build(
            "planar7-ellipse",
            robot={"source": "planar15"},
            simulation={"q_seed": [0.9] + [-0.1] * 14, "substeps": 1},
        ),
        ex.ConfigError,
        "simulation.substeps: viscous friction makes the dynamics stiff",
    ),
    Case(
        "viscous friction too stiff for the RK4 step (substeps unset: chosen)",
        lambda d: _build(
            "planar7-ellipse", robot={"source": "planar15"}, simulation={"q_seed": [0.9] + [-0.1] * 14}
        ),
        None,
        "simulation.substeps = 2 chosen (plant step 0.0005 s)",
        warns=UserWarning,
    ),
    Case(
        "joint stops too stiff for the RK4 step (substeps = 1 set)",
        lambda d: _build(plant={"joint_stop_stiffness": 1e6}, simulation={"substeps": 1}),
        ex.ConfigError,
        "plant.joint_stop_stiffness: the stop of joint",
    ),
    Case(
        "joint stops too stiff for the RK4 step (substeps unset: the stops are sized)",
        lambda d: _build(plant={"joint_stop_stiffness": 1e6}),
        None,
        "joint stops sized to the plant step: the stops of 'joint1'",
        warns=UserWarning,
    ),
    Case(
        "unknown torque-limit choice",
        lambda d: _toml(d, "[plant]\ntorque_limits = 'max'\n"),
        ex.ConfigError,
        "plant.torque_limits: 'max' is not one of urdf, none",
    ),
    Case(
        "torque limit of the wrong type",
        lambda d: _toml(d, "[plant]\ntorque_limits = 60\n"),
        ex.ConfigError,
        "plant.torque_limits: expected a string or a list, got int 60",
    ),
    Case(
        "torque limits, one per joint, of the wrong length",
        lambda d: _build(plant={"torque_limits": [60.0, 40.0]}),
        ex.ConfigError,
        "plant.torque_limits: has 2 entries, the robot has 3 joints",
    ),
    Case(
        "zero torque limit",
        lambda d: _toml(d, "[plant]\ntorque_limits = [60.0, 0.0, 20.0]\n"),
        ex.ConfigError,
        "plant.torque_limits: must be positive",
    ),
    Case(
        "negative sensor noise",
        lambda d: _toml(d, "[sensing]\nposition_noise = [-1e-3]\n"),
        ex.ConfigError,
        "sensing.position_noise: needs one value for all joints or one per joint",
    ),
    Case(
        "negative delay",
        lambda d: _toml(d, "[sensing]\ndelay = -1\n"),
        ex.ConfigError,
        "sensing.delay: must be >= 0 control periods",
    ),
    Case(
        "negative seed",
        lambda d: _toml(d, "[sensing]\nseed = -3\n"),
        ex.ConfigError,
        "sensing.seed: must be an integer in [0, 2^63)",
    ),
    Case(
        "gravity with two entries",
        lambda d: _toml(d, "[robot]\ngravity = [0.0, -9.81]\n"),
        ex.ConfigError,
        "robot.gravity: needs 3 entries",
    ),
    Case(
        "mesh folder that is the filesystem root",
        lambda d: _toml(d, '[robot]\nmesh_folders = ["meshes", "../../../../../../../../../.."]\n'),
        ex.ConfigError,
        "robot.mesh_folders: '/' is not a folder to read meshes from: name the folders that hold the "
        'URDF\'s meshes (e.g. ["../meshes"]), never the filesystem root',
    ),
    Case(
        "400-digit integer",
        lambda d: _toml(d, "[sensing]\nseed = " + "9" * 400 + "\n"),
        ex.ConfigError,
        "sensing.seed: expected an integer in (-2^63, 2^63), got one of 400 digits",
    ),
    Case(
        "400-digit integer for a number",
        lambda d: _toml(d, "[controller]\nk = " + "9" * 400 + "\n"),
        ex.ConfigError,
        "controller.k: expected a finite number of sensible size",
    ),
    Case(
        "TOML nested 5000 deep",
        lambda d: _toml(d, "x = " + "[" * 5000 + "]" * 5000 + "\n"),
        ex.ConfigError,
        "invalid TOML: nested too deeply",
    ),
    Case(
        "experiment file that is a device (/dev/zero)",
        lambda d: _read_config(Path("/dev/zero")),
        ex.ConfigError,
        "/dev/zero: not a regular file",
    ),
    Case(
        "experiment file that is a FIFO",
        lambda d: _read_config(_fifo(d)),
        ex.ConfigError,
        "not a regular file",
    ),
    Case(
        "experiment file over 1 MB",
        lambda d: _toml(d, "# padding\n" * 200_000),
        ex.ConfigError,
        "larger than 1000 kB, the most read for an experiment file",
    ),
    Case(
        "name with a control character",
        lambda d: _toml(d, 'name = "run\\u001b[2J"\n'),
        ex.ConfigError,
        "name: 'run\\x1b[2J' is not a valid name",
    ),
    Case(
        "name that climbs out of out/",
        lambda d: _toml(d, 'name = "../../escape"\n'),
        ex.ConfigError,
        "name: '../../escape' is not a valid name",
    ),
    Case(
        "closed-form nominal model with a URDF perturbation",
        lambda d: _toml(d, "[nominal]\nkind = 'closed-form'\nmass_scale = 1.1\n"),
        ex.ConfigError,
        "nominal.kind: mass_scale, inertia_scale and com_error perturb the URDF model",
    ),
    Case(
        "negative friction scale",
        lambda d: _toml(d, "[plant]\nfriction_scale = -1.0\n"),
        ex.ConfigError,
        "plant.friction_scale: must be in [0, 100], got -1",
    ),
    Case(
        "a per-joint friction scale below zero",
        lambda d: _toml(d, "[plant]\njoint_friction_scales = [1.0, -0.5]\n"),
        ex.ConfigError,
        "plant.joint_friction_scales: each factor must be in [0, 100]",
    ),
    Case(
        "more per-joint disturbance scales than joints",
        lambda d: _build(plant={"joint_disturbance_scales": [1.0, 1.0, 1.0, 1.0]}),
        ex.ConfigError,
        "plant.joint_disturbance_scales: has 4 entries; the robot has 3 joints",
    ),
    Case(
        "a negative payload",
        lambda d: _toml(d, "[plant]\npayload = -1.0\n"),
        ex.ConfigError,
        "plant.payload: must be in [0, 1000] kg, got -1",
    ),
    Case(
        "a disturbance frequency scale of zero",
        lambda d: _toml(d, "[plant]\ndisturbance_omega_scale = 0.0\n"),
        ex.ConfigError,
        "plant.disturbance_omega_scale: must be in (0, 100]",
    ),
    Case(
        "static friction below the Coulomb level",
        lambda d: _toml(d, "[plant]\nstiction = 0.5\n"),
        ex.ConfigError,
        "plant.stiction: the static / Coulomb friction ratio must be in [1, 1e6)",
    ),
    Case(
        "plant engine that does not exist",
        lambda d: _toml(d, "[plant]\nengine = 'bullet'\n"),
        ex.ConfigError,
        "plant.engine: 'bullet' is not one of pinocchio, mujoco",
    ),
    Case(
        "MuJoCo integrator that does not exist",
        lambda d: _toml(d, "[plant]\nmujoco_integrator = 'verlet'\n"),
        ex.ConfigError,
        "plant.mujoco_integrator: 'verlet' is not one of rk4, implicitfast, euler",
    ),
    Case(
        "static friction on MuJoCo (one friction level)",
        lambda d: _build(plant={"engine": "mujoco", "stiction": 1.5}),
        ex.ConfigError,
        "plant.stiction: MuJoCo's frictionloss has one level",
    ),
    Case(
        "negative armature",
        lambda d: _toml(d, "[plant]\narmature = [-0.1]\n"),
        ex.ConfigError,
        "plant.armature: needs one value for all joints or one per joint, each in [0, 1e6)",
    ),
    Case(
        "substeps beyond any need",
        lambda d: _toml(d, "[simulation]\nsubsteps = 100000\n"),
        ex.ConfigError,
        "simulation.substeps: 100000 integration steps per control period; at most 10000",
    ),
    Case(
        "control rate of a terahertz",
        lambda d: _toml(d, "[simulation]\ncontrol_period = 1e-12\n"),
        ex.ConfigError,
        "simulation.duration: 20 s at a control period of 1e-12 s is 2e+13 steps",
    ),
    Case(
        "basis of a million centres",
        lambda d: _toml(d, "[nn]\ncenters = 1000000\n"),
        ex.ConfigError,
        "nn.centers: 1000000 is outside [1, 1000]",
    ),
    Case(
        "run that needs more memory than simulation.memory_limit",
        lambda d: _build(simulation={"duration": 1e5}),
        ex.ConfigError,
        "simulation.memory_limit: this run needs about 211 GB",
    ),
]
