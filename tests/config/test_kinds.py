"""The one shape of every registry of kinds (nnrobust/kinds.py): the paper's kinds, the registered
laws, the criteria, the paths and the disturbances are each a Kinds, filled by their room's
modules when the room is imported."""

from dataclasses import dataclass

import pytest

from nnrobust.kinds import Kinds


@dataclass(frozen=True)
class Kind:
    name: str
    value: int


def test_a_kind_is_declared_once_by_name_in_order():
    kinds = Kinds("widget")
    kinds.declare(Kind("b", 1), Kind("a", 2))
    kinds.declare(Kind("b", 1))  # the same declaration again: a module imported twice
    assert list(kinds) == ["b", "a"] and kinds["a"].value == 2
    with pytest.raises(ValueError, match="a widget named 'b' is already declared"):
        kinds.declare(Kind("b", 3))


def test_every_registry_is_a_kinds_filled_when_its_room_is_imported():
    import nnrobust.controllers  # noqa: F401  (the rooms' package faces discover their kinds)
    import nnrobust.plant  # noqa: F401
    import nnrobust.subtasks  # noqa: F401
    import nnrobust.trajectories  # noqa: F401
    from nnrobust.controllers.registry import LAWS, PAPER_KINDS
    from nnrobust.plant.disturbance import DISTURBANCE_KINDS
    from nnrobust.subtasks.registry import CRITERION_KINDS
    from nnrobust.trajectories.registry import PATH_KINDS

    expected = {
        "controller kind": (PAPER_KINDS, {"nn", "no-u0", "sliding-mode", "computed-torque", "pd"}),
        "control law": (LAWS, {"slotine-li", "rbf-nn", "policy"}),
        "criterion": (CRITERION_KINDS, {"manipulability", "joint_limits", "paper"}),
        "path": (PATH_KINDS, {"ellipse", "point_to_point", "waypoints"}),
        "disturbance": (DISTURBANCE_KINDS, {"paper"}),
    }
    for concept, (kinds, names) in expected.items():
        assert isinstance(kinds, Kinds) and kinds.concept == concept
        assert names <= set(kinds), (concept, sorted(kinds))
