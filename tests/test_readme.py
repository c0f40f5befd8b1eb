"""The README's walkthrough works as written: its TOML experiment runs, and its run folder's
config.toml repeats the run exactly."""

import re
from pathlib import Path

import numpy as np

from nnrobust.cli import main
from nnrobust.run.results import Result

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_panda_experiment_runs_and_repeats(tmp_path, capsys):
    blocks = re.findall(r"```toml\n(.*?)```", README.read_text(), flags=re.S)
    assert len(blocks) == 2
    experiment = tmp_path / "my-panda.toml"
    experiment.write_text(blocks[0])
    out, again = tmp_path / "out" / "my-panda", tmp_path / "out" / "my-panda-again"
    assert main(["run", str(experiment), "--out", str(out), "--duration", "1.0", "--no-plots"]) == 0
    assert "completed" in capsys.readouterr().out
    assert (out / "animation.html").stat().st_size > 1_000_000
    assert (
        main(
            ["run", str(out / "config.toml"), "--out", str(again), "--quiet", "--no-plots", "--no-animation"]
        )
        == 0
    )
    np.testing.assert_array_equal(Result.load(out).tau, Result.load(again).tau)
    assert main(["compare", str(out), str(again)]) == 0


def test_readme_tiago_experiment_tracks_its_waypoints(tmp_path, capsys):
    import json

    block = re.findall(r"```toml\n(.*?)```", README.read_text(), flags=re.S)[1]
    experiment = tmp_path / "my-tiago.toml"
    experiment.write_text(block)
    out = tmp_path / "out" / "my-tiago"
    assert main(["run", str(experiment), "--out", str(out), "--quiet", "--no-plots", "--no-animation"]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["status"] == "completed" and metrics["rms_error_after_2s"] < 1e-3  # "about 0.5 mm"


def test_readme_python_blocks_run_as_written(tmp_path, monkeypatch):
    """Every fenced Python block of the README runs as written (in a scratch folder)."""
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    assert blocks
    monkeypatch.chdir(tmp_path)
    for block in blocks:
        exec(compile(block, "README.md", "exec"), {"__name__": "readme"})
    assert (tmp_path / "out" / "from-python" / "result.npz").is_file()
    assert (tmp_path / "out" / "from-python-plots" / "path.png").is_file()
