"""Does the test suite catch broken physics? Each mutation breaks one key line of the plant, the
sensors, the limits or a controller in a copy of the source tree; the tests that guard it must
then fail, on the Python loop alone (the copy has no compiled extension).

    python benchmarks/mutations.py [--json out/bench/mutations.json] [--only NAME]

A mutation that the suite does not catch ("SURVIVED") is a hole in the tests. Each mutation runs
the test files listed beside it (pytest -x), in a fresh copy of the tracked files.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

MUTATIONS = [
    # name, file, original text, mutated text, test files that must catch it
    (
        "coulomb friction deleted from the plant",
        "nnrobust/plant/plant.py",
        "fr.viscous * v + fr.coulomb * mode, fr.torque(v)",
        "fr.viscous * v, fr.viscous * v",
        ["tests/plant/test_stick_slip.py", "tests/plant/test_plant.py"],
    ),
    (
        "coulomb friction deleted from the friction law",
        "nnrobust/plant/friction.py",
        "return self.viscous * v + self.coulomb * sign",
        "return self.viscous * v + 0 * sign",
        ["tests/plant/test_stick_slip.py", "tests/plant/test_plant.py"],
    ),
    (
        "stiction ignored (held only up to F_c)",
        "nnrobust/plant/stick_slip.py",
        "static, coulomb = plant.friction.static[rest], plant.friction.coulomb[rest]",
        "static, coulomb = plant.friction.coulomb[rest], plant.friction.coulomb[rest]",
        ["tests/plant/test_stick_slip.py"],
    ),
    (
        "sigma-modification removed",
        "nnrobust/controllers/nn_compensator.py",
        "if self.sigma > 0.0:\n            decay",
        "if False:\n            decay",
        ["tests/controllers/test_controllers.py", "tests/test_long_runs.py"],
    ),
    (
        "noise added after the encoder's rounding",
        "nnrobust/plant/sensing.py",
        "q_m = q + self.position_noise * self._rng.standard_normal(q.size)",
        "q_m = q",
        ["tests/plant/test_limits.py"],
    ),
    (
        "torque saturation removed",
        "nnrobust/plant/limits.py",
        "return tau if limit is None else np.clip(tau, -limit, limit)",
        "return tau",
        ["tests/plant/test_limits.py"],
    ),
    (
        "joint stops removed",
        "nnrobust/plant/limits.py",
        "        if not d.any():\n            return np.zeros_like(q)",
        "        if True:\n            return np.zeros_like(q)",
        ["tests/plant/test_limits.py"],
    ),
    (
        "disturbance sign flipped",
        "nnrobust/plant/plant.py",
        "net = tau - friction - self.disturbance(t)",
        "net = tau - friction + self.disturbance(t)",
        ["tests/plant/test_plant.py", "tests/plant/test_stick_slip.py"],
    ),
    (
        "Slotine-Li's Coriolis part taken at q'_r instead of the Christoffel C(q, q')",
        "nnrobust/controllers/laws/slotine_li.py",
        "return Y(self._zero, a_r) + 0.25 * (Y(v + v_r, self._zero) - Y(v - v_r, self._zero))",
        "return Y(v_r, a_r)",
        ["tests/controllers/test_slotine_li.py"],
    ),
    (
        "the RBF network's learning sign flipped",
        "nnrobust/controllers/laws/rbf_nn.py",
        "drive, rate = np.outer(phi, w), ",
        "drive, rate = -np.outer(phi, w), ",
        ["tests/controllers/test_rbf_nn.py"],
    ),
    (
        "the RBF network's e-modification dropped",
        "nnrobust/controllers/laws/rbf_nn.py",
        "rate = np.outer(phi, w), self.F * self.kappa * np.linalg.norm(w)",
        "rate = np.outer(phi, w), 0.0 * self.kappa * np.linalg.norm(w)",
        ["tests/controllers/test_rbf_nn.py"],
    ),
    (
        "NN compensator weakened to a third",
        "nnrobust/controllers/task_space.py",
        "MUTATE-U0",
        "MUTATE-U0",
        ["tests/run/test_experiment.py"],
    ),
]


def _u0_mutation(text: str) -> str:
    """The task-space law uses a third of the robust term (an NN 'a few times worse')."""
    marker = "u0, z_next, signals = self.compensator.output("
    if marker not in text:
        raise SystemExit(f"mutations.py: {marker!r} not found in task_space.py (update the mutation)")
    i = text.index(marker)
    end = text.index("\n", i)
    return text[:end] + "\n            u0 = u0 / 3.0" + text[end:]


def _copy_tree(dest: Path) -> None:
    files = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout
    for name in files.splitlines():
        src, dst = ROOT / name, dest / name
        if src.is_file():
            dst.parent.mkdir(parents=True, exist_ok=True)
            dst.write_bytes(src.read_bytes())


RUNNER = (
    "import sys; sys.meta_path[:] = [f for f in sys.meta_path if 'editable' not in type(f).__module__]; "
    "sys.path.insert(0, '.'); import nnrobust; assert nnrobust.__file__.startswith(sys.argv[1]), "
    "nnrobust.__file__; import pytest; sys.exit(pytest.main(['-x', '-q', '-p', 'no:cacheprovider', "
    "*sys.argv[2:]]))"
)
"""Runs pytest on the copy: the installed (editable) nnrobust is hidden, so the copy's is used."""


def run(name: str, path: str, original: str, mutated: str, tests: list[str]) -> dict:
    """Apply one mutation to a fresh copy and run its tests; caught = the tests failed."""
    with tempfile.TemporaryDirectory() as tmp:
        dest = Path(tmp)
        _copy_tree(dest)
        target = dest / path
        text = target.read_text()
        if original == "MUTATE-U0":
            text = _u0_mutation(text)
        else:
            if original not in text:
                raise SystemExit(f"mutations.py: {name}: the line to mutate is not in {path} (update it)")
            text = text.replace(original, mutated, 1)
        target.write_text(text)
        env = {**os.environ, "NNROBUST_REQUIRE_COMPILED": "0"}
        start = time.perf_counter()
        proc = subprocess.run(
            [sys.executable, "-c", RUNNER, str(dest), *tests],
            cwd=dest,
            env=env,
            capture_output=True,
            text=True,
        )
        lines = [line for line in proc.stdout.splitlines() if line.strip()]
        return {
            "mutation": name,
            "file": path,
            "tests": tests,
            "caught": proc.returncode == 1,
            "exit_code": proc.returncode,
            "seconds": time.perf_counter() - start,
            "summary": lines[-1] if lines else proc.stderr.strip()[-300:],
        }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the results as JSON to this file")
    parser.add_argument("--only", help="run only the mutation whose name contains this text")
    args = parser.parse_args()
    rows = []
    for mutation in MUTATIONS:
        if args.only and args.only not in mutation[0]:
            continue
        row = run(*mutation)
        rows.append(row)
        print(
            f"{'caught  ' if row['caught'] else 'SURVIVED'} {row['mutation']:45s} {row['seconds']:6.1f} s  "
            f"{row['summary']}",
            flush=True,
        )
    survived = [r["mutation"] for r in rows if not r["caught"]]
    print(
        f"{len(rows) - len(survived)} of {len(rows)} mutations caught"
        + (f"; survived: {', '.join(survived)}" if survived else "")
    )
    if args.json:
        from nnrobust.run.results import write_json_atomic

        write_json_atomic(args.json, {"rows": rows})
    sys.exit(1 if survived else 0)


if __name__ == "__main__":
    main()
