"""Bad inputs: study files, their folders and what they write; the environments and the served robot."""

from __future__ import annotations

from pathlib import Path

from nnrobust.core import exceptions as ex

from .common import (
    Case,
    _file,
)
from .falsify import (
    SMALL_STUDY,
)


def _small_study(folder: Path, cases='"paper-ellipse"', controllers='{name = "pd", tune = false}', top="",
                 budgets="epsilon = 0.5\nbeta = 0.5\n", files=()) -> Path:  # fmt: skip
    for name in files:  # case files beside the study
        (folder / "cases-in").mkdir(exist_ok=True)
        (folder / "cases-in" / name).write_text('base = "paper-ellipse"\n')
    text = SMALL_STUDY.format(cases=cases, controllers=controllers, top=top, budgets=budgets)
    return _file(folder, "study.toml", text)


def _load_small_study(folder: Path, **kwargs):
    from nnrobust.studies.study import load_study

    path = _small_study(folder, **kwargs)
    return lambda: load_study(path)


def _study_through_a_link(folder: Path, link: str = "cases", out: str = "o"):
    """S with a link planted in its out folder (``link``, e.g. its cases/) to someone else's folder."""

    def check():
        from nnrobust.studies.study import load_study
        from nnrobust.studies.study.engine import prepare

        victim = folder / "victim"
        victim.mkdir(exist_ok=True)
        (folder / out / link).parent.mkdir(parents=True, exist_ok=True)
        if not (folder / out / link).is_symlink():
            (folder / out / link).symlink_to(victim)
        return prepare(load_study(_small_study(folder)), folder / out, False)

    return check


def _deep_report(folder: Path):
    """A received study folder whose report.json nests 100 000 arrays deep."""

    def check():
        import nnrobust

        (folder / "received").mkdir(exist_ok=True)
        (folder / "received" / "study.toml").write_text('name = "x"\n')
        (folder / "received" / "report.json").write_text("[" * 100_000 + "]" * 100_000)
        return nnrobust.load_summary(folder / "received")

    return check


def _env_step(action):
    def check():
        from nnrobust.studies.learning.env import ArmEnv

        env = ArmEnv("paper-ellipse", duration=0.05)
        env.reset(seed=0)
        return env.step(action)

    return check


def _vector_env(**kwargs):
    def check():
        from nnrobust.studies.learning.vector import ArmVectorEnv

        return ArmVectorEnv("paper-ellipse", num_envs=2, duration=0.05, **kwargs)

    return check


def _serve(wait: float):
    def check():
        from nnrobust.config.presets import load_preset
        from nnrobust.outputs.serve import serve

        return serve(load_preset("paper-ellipse"), "never-written", wait_seconds=wait)

    return check


TRAINED = '{{name = "ppo", kind = "{kind}", train = {train}, params = {params}}}'


def _trained(
    train='{algorithm = "ppo", budget = 1.0}', params='{action = "residual", base = "pd"}', kind="policy"
):
    return TRAINED.format(kind=kind, train=train, params=params)


STUDY_CASES = [
    Case(
        "a study whose box file does not exist",
        lambda d: _load_small_study(d, top='box = "identified/box.toml"\n'),
        ex.ConfigError,
        "box.toml is not a file (nnrobust identify writes DIR/box.toml)",
    ),
    Case(
        "study: a trained policy's train table with an algorithm it does not know",
        lambda d: _load_small_study(d, controllers=_trained(train='{algorithm = "dqn", budget = 1.0}')),
        ex.ConfigError,
        "study.toml: controllers[0].train.algorithm: expected one of ppo, sac, got 'dqn'",
    ),
    Case(
        "study: a trained policy's budget of 0 simulated seconds",
        lambda d: _load_small_study(d, controllers=_trained(train='{algorithm = "sac", budget = 0}')),
        ex.ConfigError,
        "study.toml: controllers[0].train.budget: expected simulated seconds of training > 0, got 0",
    ),
    Case(
        "study: a train table on a law that is not a policy",
        lambda d: _load_small_study(d, controllers=_trained(kind="pd", params="{}")),
        ex.ConfigError,
        "study.toml: controllers[0].train: only a policy entry (kind = \"policy\") is trained, not 'ppo'",
    ),
    Case(
        "study: a trained policy that also names its file",
        lambda d: _load_small_study(d, controllers=_trained(params='{file = "p.onnx", action = "torque"}')),
        ex.ConfigError,
        "study.toml: controllers[0].params.file: the train stage writes a trained policy's file",
    ),
    Case(
        "study: a trained policy's train table with a misspelt key",
        lambda d: _load_small_study(
            d, controllers=_trained(train='{algorithm = "ppo", budget = 1.0, sedes = 3}')
        ),
        ex.ConfigError,
        "study.toml: controllers[0].train.sedes: unknown key; did you mean 'seeds'?",
    ),
    Case(
        "study: a trained residual on a law with no compiled twin",
        lambda d: _load_small_study(d, controllers=_trained(params='{action = "residual", base = "my-law"}')),
        ex.ConfigError,
        "study.toml: controllers[0].params.base: 'my-law': a trained policy's base law runs on the "
        "compiled loop",
    ),
    Case(
        "study: a case file named as a spreadsheet formula (its name would start a CSV row)",
        lambda d: _load_small_study(
            d, cases="\"cases-in/=cmd|' -C calc'!A0.toml\"", files=["=cmd|' -C calc'!A0.toml"]
        ),
        ex.ConfigError,
        "study.toml: cases[0]: the case file \"=cmd|' -C calc'!A0.toml\" gives the case the name "
        "\"=cmd|' -C calc'!A0\", which must be 1-40 letters, digits, '_' or '-'",
    ),
    Case(
        "study: a case file named ..toml (its folder would be cases/ itself)",
        lambda d: _load_small_study(d, cases='"cases-in/..toml"', files=["..toml"]),
        ex.ConfigError,
        "study.toml: cases[0]: the case file '..toml' gives the case the name '.', which must be",
    ),
    Case(
        "study: controllers X and X-tuned (X's kept setting is certified as X-tuned)",
        lambda d: _load_small_study(d, controllers='"pd", {name = "pd-tuned", kind = "pd"}'),
        ex.ConfigError,
        "study.toml: controllers: 'pd-tuned' is the name the study gives the kept setting of 'pd', which "
        "is tuned here: rename one of them",
    ),
    Case(
        "study: seed 2^63 - 1 (the stages' seeds are offsets from it)",
        lambda d: _load_small_study(d, top="seed = 9223372036854775807\n"),
        ex.ConfigError,
        "study.toml: seed: expected an integer in [0, 2^62) (the stages' seeds derive from it), got "
        "9223372036854775807",
    ),
    Case(
        "study: a claim that says nothing (budgets.epsilon = 0.7)",
        lambda d: _load_small_study(d, budgets="epsilon = 0.7\nbeta = 0.5\n"),
        ex.ConfigError,
        "study.toml: budgets.epsilon: P(fail) <= 0.7 says next to nothing",
    ),
    Case(
        "study: 101 cases",
        lambda d: _load_small_study(
            d, cases=", ".join(f'{{name = "c{i}", base = "paper-ellipse"}}' for i in range(101))
        ),
        ex.ConfigError,
        "study.toml: cases: 101 cases: a study has at most 100",
    ),
    Case(
        "study: a link planted as the out folder's cases/",
        _study_through_a_link,
        ex.NNRobustError,
        "o/cases is a symbolic link: a study writes only into folders of its own; move it away, or "
        "choose another --out",
    ),
    Case(
        "study: a link planted as a stage's folder (cases/C/certify)",
        lambda d: _study_through_a_link(d, "cases/paper-ellipse/certify", "o2"),
        ex.NNRobustError,
        "o2/cases/paper-ellipse/certify is a symbolic link: a study writes only into folders of its own",
    ),
    Case(
        "read_results of a folder that does not exist (a typo)",
        lambda d: lambda: __import__("nnrobust").read_results(d / "swep"),
        ex.NNRobustError,
        "swep does not exist: read_results reads the folder a sweep wrote (its --out)",
    ),
    Case(
        "read_results of a folder that is not a sweep's",
        lambda d: lambda: __import__("nnrobust").read_results(d),
        ex.NNRobustError,
        "is not a sweep's folder (no .nnrobust-sweep, no results/)",
    ),
    Case(
        "a received study report nested 100 000 deep",
        _deep_report,
        ex.NNRobustError,
        "received/report.json: not a summary: its JSON nests too deeply",
    ),
    Case(
        "serve --wait nan (it would wait forever)",
        lambda d: _serve(float("nan")),
        ex.NNRobustError,
        "serve: --wait nan: the seconds to wait for the controller are a number in (0, 86400]",
    ),
    Case(
        "serve --wait -1",
        lambda d: _serve(-1.0),
        ex.NNRobustError,
        "serve: --wait -1.0: the seconds to wait for the controller are a number in (0, 86400]",
    ),
    Case(
        "Gymnasium: a NaN action (its reward would be NaN)",
        lambda d: _env_step([float("nan")] * 3),
        ex.ConfigError,
        "ArmEnv.step: action: entry (0,) is nan: actions are finite",
    ),
    Case(
        "Gymnasium: the action None",
        lambda d: _env_step(None),
        ex.ConfigError,
        "ArmEnv.step: action: expected shape (3,), got () (None)",
    ),
    Case(
        "Gymnasium: one number for a 3-joint arm (it was broadcast to every joint)",
        lambda d: _env_step(0.7),
        ex.ConfigError,
        "ArmEnv.step: action: expected shape (3,), got () (0.7)",
    ),
    Case(
        "Gymnasium: a vector environment on 0 threads",
        lambda d: _vector_env(threads=0),
        ex.ConfigError,
        "threads: expected an integer in [1, 256], got 0",
    ),
]

BROKEN_LAWS = Path(__file__).parents[1] / "plugins" / "broken_laws.cpp"
"""Laws in C++ that do what a law must not, one class each (one compile for every case)."""
