"""The largest (or smallest) values a configuration may give where both loops must compute the
same thing: beyond them a sampled loop is numerically meaningless, or one loop's rounding tells
a different story from the other's. The configuration checks and the components' declarations
(nnrobust/controllers/registry.py) read them from here.
"""

MAX_GAIN = 1e12
"""Largest gain or adaptation rate accepted: beyond it a 1 ms sampled loop is numerically
meaningless, and the two loops' rounding would tell different stories."""

RANGE_LIMITS = (1e-9, 1e9)
"""Accepted span of the NN basis ranges (velocity_range, error_range) and width: a Gaussian of
width 1e-300 underflows to 0/0 in one loop and not the other."""

MAX_PINV = 1e3
"""Largest ``controller.pinv_threshold`` and ``pinv_max_damping`` [m/rad]: a task Jacobian's
singular values are metres per radian."""

MAX_CENTERS = 1000
"""Most Gaussian centres per input coordinate of the NN basis (``nn.centers``)."""


def finite_number(value: object) -> bool:
    """Whether ``value`` is a real number that is finite as a float: not a bool, not NaN or
    infinite, not an integer too large for a float (10**400 raises OverflowError in
    ``math.isfinite`` and TypeError in ``np.isfinite``).
    """
    import math
    import numbers

    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


MAX_PAYLOAD = 1000.0
"""Largest ``plant.payload`` and payload load [kg]."""

MAX_FACTOR = 100.0
"""Largest factor on a nominal inertial parameter (``nominal.factors``) or on the plant's friction
or disturbance (``plant.friction_scale``, ...)."""
MAX_PHYSICAL = 1e6
"""Largest friction coefficient, stop damping or closed-form parameter accepted: beyond it the
plant is so stiff that no plant step resolves it (a 1e10 friction scale asked for 1.7e8 RK4 steps
per period)."""
MAX_STOP_STIFFNESS = 1e6
"""Largest ``plant.joint_stop_stiffness`` [1/rad] (the default is 100)."""


MAX_STEP_ROTATION = 0.02
"""Default simulation.max_step_rotation [rad or m]: the most the fastest joint may turn in one plant
step at the start of a control period before that period's step is cut
(:func:`nnrobust.run.simulation.period_substeps`)."""
