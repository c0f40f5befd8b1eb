"""``nnrobust learn`` (docs/learning.md#ppo-and-sac): one policy per seed with its curve, a rerun
keeps what was trained, and another training in the same folder is refused in one line."""

import csv
import json

import pytest

from nnrobust.cli import main
from nnrobust.run import compiled

pytest.importorskip("stable_baselines3")
pytestmark = pytest.mark.skipif(not compiled.available(), reason="the compiled loop is not built")

ARGS = ["paper-ellipse", "--budget", "0.2", "--duration", "0.1", "--num-envs", "2", "--hyper", "n_steps=32",
        "--hyper", "batch_size=64", "--validation-episodes", "2", "--eval-every", "0.1", "--controller",
        "no-u0", "--seeds", "2", "--quiet"]  # fmt: skip


def test_learn_trains_each_seed_and_a_rerun_keeps_them(tmp_path, capsys):
    out = tmp_path / "learned"
    assert main(["learn", *ARGS, "--out", str(out)]) == 0
    rows = list(csv.DictReader((out / "curves.csv").open()))
    assert {r["seed"] for r in rows} == {"0", "1"} and (out / "curves.png").is_file()
    records = [json.loads((out / f"seed-{k}" / "policy.onnx.json").read_text()) for k in (0, 1)]
    assert [r["seed"] for r in records] == [0, 1] and all(r["algorithm"] == "ppo" for r in records)
    assert records[0]["curve"] != records[1]["curve"]  # two seeds, two trainings
    mtime = (out / "seed-0" / "policy.onnx").stat().st_mtime_ns
    assert main(["learn", *ARGS, "--out", str(out)]) == 0  # kept, not trained again
    assert (out / "seed-0" / "policy.onnx").stat().st_mtime_ns == mtime
    capsys.readouterr()
    changed = [a if a != "0.2" else "0.3" for a in ARGS]
    assert main(["learn", *changed, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--out" in err and "budget_seconds" in err and len(err.strip().splitlines()) == 1


def test_learn_refuses_a_ppo_budget_below_one_rollout(tmp_path, capsys):
    """PPO trains on whole rollouts (n_steps x environments): a smaller budget would be rounded up
    to one, silently; it is refused, naming the rollout."""
    short = [a for a in ARGS if a not in ("n_steps=32", "batch_size=64") and a != "--hyper"]
    assert main(["learn", *short, "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert "less than one PPO rollout (256 steps x 2 environments" in err and "0.512 s" in err


def test_learn_on_a_tuned_law_records_its_setting(tmp_path):
    tuning = tmp_path / "tuning"
    tuning.mkdir()
    best = {"controller.Kp": [400.0, 400.0], "controller.Kv": [40.0, 40.0]}
    (tuning / "summary.json").write_text(json.dumps({"controllers": {"no-u0": {"best": {"params": best}}}}))
    one = [a if a != "2" or i != ARGS.index("--seeds") + 1 else "1" for i, a in enumerate(ARGS)]
    out = tmp_path / "learned"
    assert main(["learn", *one, "--tuned", str(tuning), "--out", str(out)]) == 0
    record = json.loads((out / "seed-0" / "policy.onnx.json").read_text())
    assert record["tuned"] == {"file": str(tuning), "settings": best} and record["controller"] == "no-u0"
    assert main(["learn", *one, "--out", str(out)]) == 2  # the same folder, the untuned law: refused
