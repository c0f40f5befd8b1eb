"""The any-arm presets: each runs with every controller, and the NN controller beats no-u0 >= 3x.

Shortened to 4 s (the metric is the RMS task error over t >= 2 s); docs/robots.md has the 10 s
numbers.
"""

import pytest

from nnrobust.experiment import run_experiment
from nnrobust.presets import load_preset

PRESETS = ["panda-ellipse", "panda-pose", "ur5-ellipse", "planar7-ellipse"]


def _run(preset, kind, duration):
    config = load_preset(preset).replace(controller={"kind": kind},
                                         simulation={"duration": duration})
    result = run_experiment(config)
    assert result.status == "completed", result.message
    return result.metrics()


@pytest.mark.parametrize("preset", PRESETS)
def test_nn_beats_no_u0_threefold(preset):
    nn, baseline = _run(preset, "nn", 4.0), _run(preset, "no-u0", 4.0)
    assert nn["rms_error_after_2s"] * 3 < baseline["rms_error_after_2s"]
    if preset == "panda-pose":
        assert nn["rms_orientation_error_after_2s"] * 3 < baseline["rms_orientation_error_after_2s"]


@pytest.mark.parametrize("preset", PRESETS)
def test_pd_baseline_runs(preset):
    metrics = _run(preset, "pd", 1.0)
    assert metrics["max_error"] < 0.1  # it tracks, roughly
