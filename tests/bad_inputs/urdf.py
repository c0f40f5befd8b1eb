"""Bad inputs: URDF files: malformed, unphysical, hostile."""

from __future__ import annotations

from nnrobust.core import exceptions as ex
from nnrobust.model.urdf_check import (
    InertiaAssumptionWarning,
    MeshOutsideFoldersWarning,
    MissingMeshWarning,
    UndeclaredPrefixWarning,
)

from .common import (
    BILLION_LAUGHS,
    CAD_PRODUCTS,
    FLANGE,
    PREFIXED,
    Case,
    _file,
    _first_axis_then,
    _huge,
    _l2_inertia,
    _load,
    _non_utf8,
    _visual,
    _working_in,
    arm,
)

CYCLE = arm(
    extra='<joint name="j3" type="revolute"><parent link="l2"/><child link="base"/>'
    '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
)

URDF_CASES = [
    Case(
        "URDF file that does not exist",
        lambda d: _load("no/such/robot.urdf"),
        ex.RobotLoadError,
        "no such file",
    ),
    Case("URDF file that is not UTF-8", lambda d: _load(_non_utf8(d)), ex.UrdfSyntaxError, "not UTF-8"),
    Case(
        "malformed XML (unclosed tag)",
        lambda d: _load(arm().replace("</robot>", "")),
        ex.UrdfSyntaxError,
        "malformed XML at line",
    ),
    Case(
        "root element is not <robot>",
        lambda d: _load("<html><body/></html>"),
        ex.UrdfStructureError,
        "needs <robot>",
    ),
    Case(
        "joint whose child link is not defined",
        lambda d: _load(
            arm(extra='<joint name="j9" type="fixed"><parent link="l2"/><child link="ghost"/></joint>')
        ),
        ex.UrdfStructureError,
        "child link 'ghost' is not defined",
    ),
    Case(
        "link that no joint attaches (two roots)",
        lambda d: _load(arm(extra='<link name="floating"/>')),
        ex.UrdfStructureError,
        "have no parent joint",
    ),
    Case(
        "two links with the same name",
        lambda d: _load(arm(extra='<link name="l1"/>')),
        ex.UrdfStructureError,
        "two links are named 'l1'",
    ),
    Case(
        "kinematic cycle (Pinocchio alone returns an empty model)",
        lambda d: _load(CYCLE),
        ex.KinematicCycle,
        "form a closed loop",
    ),
    Case(
        "no movable joint",
        lambda d: _load(
            '<robot name="r"><link name="a"/><joint name="f" type="fixed">'
            '<parent link="a"/><child link="b"/></joint><link name="b"/></robot>'
        ),
        ex.ModelMismatch,
        "no movable joint",
    ),
    Case(
        "planar joint (no single angle or length)",
        lambda d: _load(arm().replace('name="j1" type="revolute"', 'name="j1" type="planar"')),
        ex.ModelMismatch,
        "joints 'j1' (Planar) have no single angle or length",
    ),
    Case(
        "the last link massless (its inertia is dropped: then nothing moves)",
        lambda d: _load(arm(mass="0")),
        ex.InvalidInertia,
        "joint 'j2' moves no mass",
    ),
    Case(
        "a massless frame link with an inertia (an exporter's convention)",
        lambda d: _load(arm(extra=FLANGE)),
        None,
        "massless link flange read with no inertia (a rotational inertia without mass is no body",
        warns=InertiaAssumptionWarning,
    ),
    Case(
        "products of inertia in the CAD sign convention",
        lambda d: _load(_l2_inertia(CAD_PRODUCTS)),
        None,
        "products of inertia read with the opposite sign (+integral of x y dm, the CAD convention; "
        "URDF's ixy is -integral of x y dm): as written, link l2 break",
        warns=InertiaAssumptionWarning,
    ),
    Case(
        "a triangle inequality broken by rounding (0.5 %)",
        lambda d: _load(arm(ixx="0.0201")),
        None,
        "link l2 break the triangle inequality by at most 1 % (rounding), taken as given",
        warns=InertiaAssumptionWarning,
    ),
    Case("negative mass", lambda d: _load(arm(mass="-2")), ex.InvalidInertia, "must not be negative"),
    Case(
        "inertia not positive definite",
        lambda d: _load(arm(ixx="-0.001")),
        ex.InvalidInertia,
        "not positive semi-definite",
    ),
    Case(
        "inertia that breaks the triangle inequality",
        lambda d: _load(arm(ixx="0.05")),
        ex.InvalidInertia,
        "1 link with impossible inertial data: 'l2': principal moments "
        "[0.01, 0.01, 0.05] break the triangle inequality I1 + I2 >= I3 by 60 % of I3",
    ),
    Case(
        "two impossible links, named at once",
        lambda d: _load(
            arm(ixx="0.05").replace(
                'ixx="0.001" ixy="0" ixz="0" iyy="0.01"', 'ixx="-0.001" ixy="0" ixz="0" iyy="0.01"'
            )
        ),
        ex.InvalidInertia,
        "2 links with impossible inertial data: 'l1': the inertia is not positive semi-definite",
    ),
    Case(
        "NaN in an inertial origin",
        lambda d: _load(arm().replace('<origin xyz="0.15 0 0"/>', '<origin xyz="nan 0 0"/>')),
        ex.UrdfStructureError,
        "link 'l2' <origin> xyz: 'nan 0 0' is not 3 finite numbers",
    ),
    Case(
        "inertia with only ixx, iyy, izz (the parser would zero it)",
        lambda d: _load(_l2_inertia('ixx="0.001" iyy="0.01" izz="0.01"')),
        ex.InvalidInertia,
        "link 'l2': <inertia> needs all six of ixx, ixy, ixz, iyy, iyz, izz (missing ixy, ixz, iyz",
    ),
    Case(
        "mass of 1e308 kg",
        lambda d: _load(arm(mass="1e308")),
        ex.InvalidInertia,
        "mass 1e+308 kg is beyond any robot link",
    ),
    Case(
        "inertia of 1e300 kg m^2",
        lambda d: _load(_l2_inertia('ixx="0.001" ixy="0" ixz="0" iyy="1e300" iyz="0" izz="1e300"')),
        ex.InvalidInertia,
        "beyond any robot link (at most 100000 kg m^2)",
    ),
    Case(
        "zero joint axis",
        lambda d: _load(arm().replace('<axis xyz="0 0 1"/>', '<axis xyz="0 0 0"/>', 1)),
        ex.UrdfStructureError,
        "joint 'j1' <axis>: xyz = '0 0 0' is zero",
    ),
    Case(
        "reversed joint limits",
        lambda d: _load(arm().replace('<limit lower="-3" upper="3"', '<limit lower="2" upper="-2"', 1)),
        ex.UrdfStructureError,
        "joint 'j1' <limit>: lower = 2 is above upper = -2",
    ),
    Case(
        "NaN joint limit",
        lambda d: _load(arm().replace('<limit lower="-3"', '<limit lower="nan"', 1)),
        ex.UrdfStructureError,
        "joint 'j1' <limit> lower: 'nan' is not a finite number",
    ),
    Case(
        "revolute joint without <limit>",
        lambda d: _load(arm().replace('<limit lower="-3" upper="3" effort="10" velocity="3"/>', "", 1)),
        ex.UrdfStructureError,
        "joint 'j1': a revolute joint needs <limit",
    ),
    Case(
        "negative joint damping",
        lambda d: _load(_first_axis_then('<dynamics damping="-1"/>')),
        ex.UrdfStructureError,
        "joint 'j1' <dynamics> damping: -1 is outside [0, 1e+07]",
    ),
    Case(
        "unknown joint type",
        lambda d: _load(arm().replace('type="revolute"', 'type="hinge"', 1)),
        ex.UrdfStructureError,
        "joint 'j1': type 'hinge' is not one of revolute",
    ),
    Case(
        "mimic joint left out of the locked joints",
        lambda d: _load(
            arm()
            .replace('<axis xyz="0 0 1"/>', '<axis xyz="0 0 1"/><mimic joint="j1"/>', 2)
            .replace('<mimic joint="j1"/>', "", 1),
            locked_joints=[],
        ),
        ex.UrdfStructureError,
        "joint 'j2' mimics joint 'j1': nnrobust does not model mimic joints",
    ),
    Case(
        "moving link with no mass after it",
        lambda d: _load(_l2_inertia(None)),
        ex.InvalidInertia,
        "joint 'j2' moves no mass",
    ),
    Case(
        "value the C++ parser refuses (its message made one line)",
        lambda d: _load(_first_axis_then('<calibration rising="x"/>')),
        ex.RobotLoadError,
        "the parser says: Error: rising value (x) is not a valid float",
    ),
    Case(
        "mass that is not a number",
        lambda d: _load(arm(mass="heavy")),
        ex.UrdfStructureError,
        "'heavy' is not a finite number",
    ),
    Case(
        "entity expansion ('billion laughs')",
        lambda d: _load(BILLION_LAUGHS),
        ex.UrdfRefused,
        "DTD or entity declarations",
    ),
    Case("file larger than 20 MB", lambda d: _load(_huge(d)), ex.UrdfRefused, "larger than the 20 MB"),
    Case(
        "package:// mesh that escapes the allowed folders (simulates; the viewer leaves it out)",
        lambda d: _visual(
            _file(
                d,
                "escape.urdf",
                arm(
                    visual='<visual><geometry><mesh filename="package://../../../../etc/passwd"/></geometry></visual>'
                ),
            )
        ),
        None,
        "1 visual mesh lies outside the folders meshes are read from (first: "
        "'package://../../../../etc/passwd'); the run's dynamics do not need it",
        warns=MeshOutsideFoldersWarning,
    ),
    Case(
        "URDF text with a mesh outside the working folder (read and embedded before)",
        lambda d: _working_in(
            d, _visual(arm(visual='<visual><geometry><mesh filename="/etc/passwd"/></geometry></visual>'))
        ),
        None,
        "1 visual mesh lies outside the folders meshes are read from (first: '/etc/passwd')",
        warns=MeshOutsideFoldersWarning,
    ),
    Case(
        "URDF text with a file:// mesh outside the working folder",
        lambda d: _working_in(
            d,
            _visual(
                arm(visual='<visual><geometry><mesh filename="file:///etc/hostname"/></geometry></visual>')
            ),
        ),
        None,
        "the viewer draws it only from folders listed in robot.mesh_folders",
        warns=MeshOutsideFoldersWarning,
    ),
    Case(
        "mesh fetched over the network",
        lambda d: _visual(
            _file(
                d,
                "http.urdf",
                arm(
                    visual='<visual><geometry><mesh filename="http://example.com/l1.stl"/></geometry></visual>'
                ),
            )
        ),
        None,
        "a URL: only package:// and file paths are read",
        warns=MeshOutsideFoldersWarning,
    ),
    Case(
        "visual mesh file missing (simulates; the viewer leaves it out)",
        lambda d: _visual(
            _file(
                d,
                "nomesh.urdf",
                arm(visual='<visual><geometry><mesh filename="meshes/l1.stl"/></geometry></visual>'),
            )
        ),
        None,
        "not found",
        warns=MissingMeshWarning,
    ),
    Case(
        "undeclared XML namespace prefixes (drake:, gazebo:, as projects publish them)",
        lambda d: _load(_file(d, "prefixed.urdf", PREFIXED)),
        None,
        "prefixed.urdf: undeclared XML namespace prefixes drake, gazebo: their elements and attributes "
        "are ignored",
        warns=UndeclaredPrefixWarning,
    ),
    Case(
        "undeclared prefix, and a mismatched tag further on",
        lambda d: _load(_file(d, "prefixed.urdf", PREFIXED.replace("</gazebo:plugin>", "</plugin>"))),
        ex.UrdfSyntaxError,
        "prefixed.urdf: malformed XML at line 12, column 71: mismatched tag",
    ),
    Case(
        "task frame that does not exist",
        lambda d: _load("three_link_planar", task_frame="gripper"),
        ex.FrameNotFound,
        "task frame 'gripper' not found; frames in the model: universe",
    ),
    Case(
        "robot name that example-robot-data does not ship",
        lambda d: _load("no_such_robot"),
        ex.RobotLoadError,
        "not a URDF file, not planar<N>, and not a robot example-robot-data ships",
    ),
]

PAPER = 'base = "paper-ellipse"\n'
"""An experiment file's first line: start from the paper's case (b)."""
