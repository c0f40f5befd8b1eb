"""The files that travel with a cluster's tasks (nnrobust/shipped_files.py), unit by unit: a
bundle checked by SHA-256 where it arrives, written once per machine, read within a task only.
"""

import hashlib
import json
import threading
from pathlib import Path

import pytest

from nnrobust import shipped_files
from nnrobust.exceptions import NNRobustError

REPO = Path(__file__).resolve().parents[1]


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
    from nnrobust.exceptions import ConfigError
    from nnrobust.user_code import load_class

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

    from .policies import linear_policy

    file = linear_policy(tmp_path / "policy.onnx", 4, 2, b=[0.5, -0.5])
    bundle = shipped_files.bundle_of([(str(file), hashlib.sha256(file.read_bytes()).hexdigest())])
    with shipped_files.within(bundle, tmp_path / "cache"):
        file.unlink()
        policy = OnnxPolicy(file, 4, 2)
        assert policy.path == file
        np.testing.assert_allclose(policy(np.zeros(4), 0.0), np.tanh([0.5, -0.5]), rtol=1e-6)
