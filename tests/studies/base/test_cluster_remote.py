"""A cluster of hand-started ``dask scheduler`` / ``dask worker`` processes on 127.0.0.1 whose
working folders cannot see the client's files (issue 37): the files the rows read (a URDF named
by a relative path, a custom law's file, the experiment files) travel with the tasks, checked by
SHA-256 on the worker, and the rows equal a local run's; tune and falsify send them too.

Each worker starts in a mount namespace of its own where a tmpfs covers the client's folder
(``unshare -m``, as root; ``unshare -Urm`` otherwise, where user namespaces are allowed). Where
neither is permitted, the client's folder is moved away from the moment its files are sent until
the tasks have finished, so that the workers run while it does not exist.
"""

import contextlib
import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

pytest.importorskip("distributed")
pandas = pytest.importorskip("pandas")
pytest.importorskip("pyarrow")

from nnrobust.cli import main  # noqa: E402
from nnrobust.core import shipped_files  # noqa: E402
from nnrobust.core.exceptions import NNRobustError  # noqa: E402
from nnrobust.studies.sweep import read_results  # noqa: E402

SCHEDULER = [sys.executable, "-m", "distributed.cli.dask_scheduler"]  # `dask scheduler` of this Python
WORKER = [sys.executable, "-m", "distributed.cli.dask_worker"]
REPO = Path(__file__).resolve().parents[3]
CLOCKS = ("task_seconds", "wall_seconds", "realtime_factor", "max_inference_time", "inference_over_period")
"""The columns that time a row: the only ones that differ from machine to machine."""

EXPERIMENT = """base = "paper-ellipse"
[robot]
source = "arm/three_link_planar.urdf"
[simulation]
duration = {duration}
"""

SWEEP = """name = "{name}"
base = "{base}"
controllers = ["no-u0", {{name = "mine", class = "laws/mine.py:Eq9", params = {{Kp = 10.0, Kv = 4.0}}}}]
samples = {samples}
seed = 2
[vary]
"plant.disturbance_scale" = {{uniform = [0.5, 2.0]}}
"""


@pytest.fixture(scope="module")
def client_folder(tmp_path_factory) -> Path:
    """The client's files: a URDF, a custom law, experiment and sweep files naming them by
    relative paths."""
    folder = tmp_path_factory.mktemp("remote") / "client"
    (folder / "arm").mkdir(parents=True)
    (folder / "laws").mkdir()
    shutil.copy(REPO / "urdf" / "three_link_planar.urdf", folder / "arm")
    shutil.copy(REPO / "tests" / "controllers" / "eq9_again.py", folder / "laws" / "mine.py")
    (folder / "short.toml").write_text(EXPERIMENT.format(duration=0.3))
    (folder / "long.toml").write_text(EXPERIMENT.format(duration=2.1))  # tuning needs runs of > 2 s
    (folder / "sweep.toml").write_text(SWEEP.format(name="remote", base="short.toml", samples=3))
    (folder / "tune.toml").write_text(SWEEP.format(name="tune", base="long.toml", samples=1))
    return folder


def _hiding(folder: Path) -> list[str] | None:
    """The command prefix that runs a program with ``folder`` covered by an empty tmpfs, or None
    where this machine permits no mount namespace."""
    probe = folder / ".probe"
    probe.write_text("")
    try:
        for prefix in (["unshare", "-m"], ["unshare", "-Urm"]):
            script = 'mount -t tmpfs none "$1" && test ! -e "$1/.probe"'
            try:
                done = subprocess.run([*prefix, "sh", "-c", script, "sh", str(folder)], capture_output=True)
            except OSError:
                return None
            if done.returncode == 0:
                return [
                    *prefix,
                    "sh",
                    "-c",
                    'mount -t tmpfs none "$1" && shift && exec "$@"',
                    "sh",
                    str(folder),
                ]
        return None
    finally:
        probe.unlink()


class Cluster:
    """A scheduler and two single-threaded workers, each process in a folder of its own."""

    def __init__(self, root: Path, hidden: Path):
        self.root, self.hidden = root, hidden
        self.hide = _hiding(hidden)
        self.processes: list[subprocess.Popen] = []
        self.file = root / "scheduler" / "scheduler.json"
        self.workers = [root / f"worker{i}" for i in (1, 2)]
        self._address: str | None = None

    def start(self) -> None:
        env = {k: v for k, v in os.environ.items() if not k.startswith(("DASK_", "PYTHONPATH"))}
        self.file.parent.mkdir(parents=True)
        loopback = ["--host", "127.0.0.1", "--dashboard-address", "127.0.0.1:0"]
        # --idle-timeout: a scheduler left behind by a test process killed outright ends by itself
        # (the workers follow it after their --death-timeout)
        scheduler = [*SCHEDULER, *loopback, "--port", "0", "--idle-timeout", "300s"]
        self._spawn([*scheduler, "--scheduler-file", str(self.file)], self.file.parent, env)
        for folder in self.workers:
            folder.mkdir()
            command = [
                *WORKER,
                "--scheduler-file",
                str(self.file),
                "--nthreads",
                "1",
                "--no-nanny",
                *loopback,
            ]
            command += ["--local-directory", str(folder), "--death-timeout", "120"]
            self._spawn([*(self.hide or []), *command], folder, {**env, "TMPDIR": str(folder)})

    def _spawn(self, command: list[str], cwd: Path, env: dict) -> None:
        log = open(cwd / "log.txt", "wb")  # the process keeps its own descriptor
        self.processes.append(
            subprocess.Popen(
                command, cwd=cwd, env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True
            )
        )
        log.close()

    def address(self) -> str:
        """The scheduler's address, once both workers have joined."""
        if self._address is None:
            from distributed import Client

            deadline = time.monotonic() + 60
            while not self.file.is_file() and time.monotonic() < deadline:
                time.sleep(0.1)
            assert self.file.is_file(), self.logs()
            address = json.loads(self.file.read_text())["address"]
            with Client(address, timeout="30s") as client:
                try:
                    client.wait_for_workers(2, timeout=60)
                except TimeoutError:
                    pytest.fail(f"the workers did not join: {self.logs()}")
                self.sees = client.run(os.path.exists, str(self.hidden / "sweep.toml"))
                self.folders = client.run(os.getcwd)
            self._address = address
        return self._address

    def logs(self) -> str:
        return " | ".join(
            (p.parent.name + ": " + p.read_text(errors="replace")[-600:]) for p in self.root.glob("*/log.txt")
        )

    def stop(self) -> None:
        """Every process ended and reaped: the workers, then the scheduler (a worker that loses its
        scheduler while it closes can hang in dask's own shutdown)."""
        for group in (self.processes[1:], self.processes[:1]):
            for process in group:
                with contextlib.suppress(ProcessLookupError):
                    os.killpg(process.pid, signal.SIGTERM)
            for process in group:
                try:
                    process.wait(timeout=5)
                except subprocess.TimeoutExpired:
                    with contextlib.suppress(ProcessLookupError):
                        os.killpg(process.pid, signal.SIGKILL)
                    process.wait()


@pytest.fixture(scope="module")
def cluster(tmp_path_factory, client_folder):
    cluster = Cluster(tmp_path_factory.mktemp("cluster"), client_folder)
    try:
        cluster.start()
        yield cluster
    finally:
        cluster.stop()


@contextlib.contextmanager
def unseen(cluster: Cluster, monkeypatch):
    """The block's tasks run where the workers cannot see the client's folder: hidden by their
    mount namespaces, or else moved away from when its files are sent until the cluster's client
    closes."""
    if cluster.hide is not None:
        yield
        return
    from nnrobust.studies.sweep import engine

    folder, away = cluster.hidden, cluster.hidden.with_name("client-away")
    make, connect = engine.shipped_files, engine.cluster_client

    def shipped_then_hidden(client, inputs, ship):
        files = make(client, inputs, ship)
        folder.rename(away)
        return files

    @contextlib.contextmanager
    def client_then_back(*args):
        try:
            with connect(*args) as client:
                yield client
        finally:
            if away.exists():
                away.rename(folder)

    monkeypatch.setattr(engine, "shipped_files", shipped_then_hidden)
    monkeypatch.setattr(engine, "cluster_client", client_then_back)
    yield


def test_a_sweep_on_workers_that_cannot_see_its_files_equals_a_local_run(
    cluster, client_folder, tmp_path, monkeypatch
):
    """The same sweep, --workers 1 and --scheduler of two workers whose folders cannot see the
    client's: every row the same, bit for bit, but its clocks; the workers kept the copies
    by the client's absolute paths under their temporary folder."""
    sweep = client_folder / "sweep.toml"
    local, remote = tmp_path / "local", tmp_path / "remote"
    monkeypatch.chdir(tmp_path)
    assert main(["sweep", str(sweep), "--out", str(local), "--workers", "1", "--quiet"]) == 0
    address = cluster.address()
    if cluster.hide is not None:
        assert set(cluster.sees.values()) == {False}, cluster.sees
    assert sorted(cluster.folders.values()) == [str(f) for f in cluster.workers]
    with unseen(cluster, monkeypatch):
        assert main(["sweep", str(sweep), "--out", str(remote), "--scheduler", address, "--quiet"]) == 0
    a, b = (
        read_results(out).drop(columns=list(CLOCKS)).sort_values(["sample", "controller"], ignore_index=True)
        for out in (local, remote)
    )
    assert list(b["status"]) == ["completed"] * 6, list(b["message"])
    pandas.testing.assert_frame_equal(a, b, check_exact=True)
    law = (client_folder / "laws" / "mine.py").resolve()
    copies = [p for folder in cluster.workers for p in folder.glob(f"nnrobust-inputs*/*/{str(law)[1:]}")]
    assert copies and all(p.read_bytes() == law.read_bytes() for p in copies)


def test_tune_and_falsify_send_the_files_too(cluster, client_folder, tmp_path, monkeypatch):
    """A short tuning of the custom law and a short falsification, on the same workers: every run
    completes, so each read the URDF and the law's file from the copies sent with its task."""
    from nnrobust.studies.falsify import FalsifySpec, run_falsify
    from nnrobust.studies.tune.engine import TuneSpec, run_tune

    address = cluster.address()
    tune = TuneSpec(str(client_folder / "tune.toml"), ["mine"], 2, train_samples=1, validation=0, seed=1)
    search = FalsifySpec(str(client_folder / "sweep.toml"), ["mine"], ["rms_error<=0.05"], 4, seed=1)
    with unseen(cluster, monkeypatch):
        tuned = run_tune(tune, tmp_path / "tune", scheduler=address)
        falsified = run_falsify(search, tmp_path / "falsify", scheduler=address)
    best = tuned["controllers"]["mine"]["best"]
    assert best is not None and best["train"]["status"] == "completed", tuned["controllers"]["mine"]
    entry = falsified["controllers"]["mine"]
    assert entry["simulations"] == entry["random_baseline"]["simulations"] == 4
    assert entry["worst"]["metrics"]["status"] == "completed", entry["worst"]  # refused runs are the worst


def test_a_file_damaged_on_the_way_stops_the_command_naming_it(
    cluster, client_folder, tmp_path, monkeypatch, capsys
):
    """The law's bytes altered after the client took their digest: the workers refuse the bundle
    before any task runs, and the command stops with one line naming the file."""
    law = str((client_folder / "laws" / "mine.py").resolve())
    make = shipped_files.bundle_of

    def damaged(files):
        bundle = make(files)
        entry = bundle.files[law]
        altered = shipped_files.ShippedFile(entry.mirror, entry.sha256, entry.data + b"# altered\n")
        return shipped_files.Bundle({**bundle.files, law: altered})

    monkeypatch.setattr(shipped_files, "bundle_of", damaged)
    address = cluster.address()
    out = tmp_path / "out"
    with unseen(cluster, monkeypatch):
        code = main(
            ["sweep", str(client_folder / "sweep.toml"), "--out", str(out), "--scheduler", address, "--quiet"]
        )
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and err[-1].startswith(f"nnrobust: error: {law}: its bytes on this worker have SHA-256")
    assert "not the client's" in err[-1] and read_results(out).empty


# ---- the bundle, unit by unit ------------------------------------------------------------------


def _bundle(tmp_path, text=b"print('hi')\n"):
    law = tmp_path / "law.py"
    law.write_bytes(text)
    return law, shipped_files.bundle_of([(str(law), hashlib.sha256(text).hexdigest()), ("panda", "x")])


def test_a_file_whose_bytes_do_not_match_its_digest_is_refused_naming_it(tmp_path):
    """On the worker, a file of the bundle whose bytes are not those of its recorded SHA-256 is
    one error naming it, and nothing is written; on the client, a file changed since its digest
    was recorded is refused as well."""
    law, bundle = _bundle(tmp_path)
    assert list(bundle.files) == [str(law)]  # a robot's name is no file: nothing to send
    entry = bundle.files[str(law)]
    damaged = shipped_files.Bundle({str(law): shipped_files.ShippedFile(entry.mirror, entry.sha256, b"evil")})
    with pytest.raises(NNRobustError, match=rf"^{law}: its bytes on this worker have SHA-256 [0-9a-f]{{12}}"):
        shipped_files.materialise(damaged, tmp_path / "cache")
    assert not (tmp_path / "cache" / damaged.digest).exists()
    with pytest.raises(NNRobustError, match=rf"^{law}: changed while the command ran"):
        shipped_files.bundle_of([(str(law), "0" * 64)])


def test_copies_are_read_within_a_task_only_and_written_once_for_concurrent_tasks(tmp_path):
    """Eight threads materialise one bundle at once: one folder, the client's path mirrored in it;
    ``local`` maps the client's path to the copy inside ``within`` only (a context variable, so
    another thread sees its own); a copy changed on disk is written again."""
    law, bundle = _bundle(tmp_path)
    root = tmp_path / "cache"
    results: list = []
    threads = [
        threading.Thread(target=lambda: results.append(shipped_files.materialise(bundle, root)))
        for _ in range(8)
    ]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len({json.dumps({k: str(v) for k, v in r.items()}) for r in results}) == 1
    assert [p.name for p in root.iterdir()] == [bundle.digest]  # no staging folder left behind
    copy = results[0][str(law)]
    assert copy == root / bundle.digest / str(law.resolve())[1:] and copy.read_bytes() == law.read_bytes()
    assert shipped_files.local(law) == law
    seen = {}
    with shipped_files.within(bundle, root):
        assert shipped_files.local(str(law)) == shipped_files.local(law.parent / "." / "law.py") == copy
        assert shipped_files.local(tmp_path / "other.py") == tmp_path / "other.py"
        other = threading.Thread(target=lambda: seen.update(path=shipped_files.local(law)))
        other.start()
        other.join()
    assert seen["path"] == law and shipped_files.local(law) == law
    copy.write_bytes(b"tampered")
    shipped_files._READY.clear()  # a new worker process
    again = shipped_files.materialise(bundle, root)[str(law)]
    assert again.read_bytes() == law.read_bytes()


def test_a_shipped_class_file_is_imported_from_its_copy_and_named_by_the_clients_path(tmp_path):
    """A task within a bundle imports the class file from its copy while the client's file is
    gone; an import of a module beside it says that only the class file travels."""
    from nnrobust.controllers.base import Controller
    from nnrobust.core.exceptions import ConfigError
    from nnrobust.plugins.user_code import load_class

    text = (REPO / "tests" / "controllers" / "eq9_again.py").read_bytes() + b"\n# remote copy\n"
    law, bundle = _bundle(tmp_path, text)
    (tmp_path / "b").mkdir()
    broken, broken_bundle = _bundle(tmp_path / "b", b"import helper_beside\n")
    with shipped_files.within(shipped_files.Bundle({**bundle.files, **broken_bundle.files}), tmp_path / "c"):
        law.unlink()
        broken.unlink()
        cls = load_class(f"{law}:Eq9", Controller, "controller.class")
        assert cls.__name__ == "Eq9" and cls.__module__.startswith("nnrobust_user_law_")
        with pytest.raises(
            ConfigError, match=f"importing {broken} raised ModuleNotFoundError.*only the class file travels"
        ):
            load_class(f"{broken}:Eq9", Controller, "controller.class")


def test_a_shipped_policy_file_is_read_from_its_copy(tmp_path):
    """A learned policy's ONNX file sent with the task: onnxruntime reads the copy, the policy is
    still named by the client's path."""
    pytest.importorskip("onnx")
    pytest.importorskip("onnxruntime")
    import numpy as np

    from nnrobust.controllers.laws.policy import OnnxPolicy
    from tests.policies import linear_policy

    file = linear_policy(tmp_path / "policy.onnx", 4, 2, b=[0.5, -0.5])
    bundle = shipped_files.bundle_of([(str(file), hashlib.sha256(file.read_bytes()).hexdigest())])
    with shipped_files.within(bundle, tmp_path / "cache"):
        file.unlink()
        policy = OnnxPolicy(file, 4, 2)
        assert policy.path == file
        np.testing.assert_allclose(policy(np.zeros(4), 0.0), np.tanh([0.5, -0.5]), rtol=1e-6)
