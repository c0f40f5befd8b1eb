"""Every bad input nnrobust is tested with, and the error it must give: one module per section
(urdf, config, run_folders, tune, custom, parts, scheduler, api, properties, falsify, study,
native_law, identify; common.py: what they share).

Shared by tests/test_hostile_input.py and by ``python -m tests.bad_inputs`` (run from the
repository root), which writes docs/bad-inputs.md from the messages actually raised.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

from nnrobust.core import exceptions as ex

from .api import (
    API_CASES,
)
from .common import (
    Case,
)
from .config import (
    CONFIG_CASES,
)
from .custom import (
    CUSTOM_CASES,
)
from .falsify import (
    FALSIFY_CASES,
)
from .identify import (
    IDENTIFY_CASES,
)
from .native_law import (
    NATIVE_LAW_CASES,
)
from .parts import (
    PART_CASES,
)
from .properties import (
    PROPERTY_CASES,
)
from .run_folders import (
    RUN_FOLDER_CASES,
    VIEWER_CASES,
)
from .scheduler import (
    SCHEDULER_CASES,
)
from .study import (
    STUDY_CASES,
)
from .tune import (
    TUNE_CASES,
)
from .urdf import (
    URDF_CASES,
)

REPO = Path(__file__).resolve().parents[2]

CASES = (
    URDF_CASES
    + CONFIG_CASES
    + RUN_FOLDER_CASES
    + VIEWER_CASES
    + TUNE_CASES
    + CUSTOM_CASES
    + PART_CASES
    + PROPERTY_CASES
    + FALSIFY_CASES
    + STUDY_CASES
    + API_CASES
    + SCHEDULER_CASES
    + NATIVE_LAW_CASES
    + IDENTIFY_CASES
)


def message_of(case: Case, folder: Path) -> str:
    """Run the case and return the message it gives (error or warning)."""
    action = case.make(folder)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            action()
        except ex.NNRobustError as err:
            return str(err)
    return "; ".join(str(w.message) for w in caught if case.warns and issubclass(w.category, case.warns))


def render_table(folder: Path) -> str:
    """docs/bad-inputs.md, from the messages actually raised."""
    lines = [
        "# Bad inputs and the messages they get",
        "",
        "Every row is a test case in a section of `tests/bad_inputs/`; `tests/test_hostile_input.py` checks",
        "the exception class and message, and that the command line answers each with exit code 2",
        "and one line. Regenerate this page with `python -m tests.bad_inputs` (repository root).",
        "Paths of the scratch folder the cases run in are shown as `<dir>` (its parent `<dir>/..`),",
        "and the checkout's own folder as `<repo>`.",
        "",
        "Rules that hold for every input:",
        "",
        "- **Messages** are one line of at most 1,000 characters: control characters are escaped and",
        "  the middle of a longer message is elided.",
        "- **Files are read bounded**: an experiment or sweep file must be a regular file of at most",
        "  1 MB (a device or a FIFO is refused, never read), a URDF at most 20 MB.",
        "- **Size**: before a run starts, the memory it needs is estimated (its recorded arrays, and",
        "  the Pinocchio models, which grow as n^3 with n joints), and a run above",
        "  `simulation.memory_limit` (2 GB by default) or above the memory the machine has available",
        "  is refused; `simulation.substeps` is at most 10,000, `nn.centers` at most 1,000, a run at",
        "  most 10^9 control steps.",
        "- **Run folders** (`nnrobust/outputs/run_folder.py`) carry a marker file, `.nnrobust-run`, with the",
        "  run's status. `--overwrite` replaces only folders that have it (or that hold nothing but a",
        "  run's files). The output folder is checked before the simulation and locked for the whole",
        "  run, so a second run into it is refused at once. The arrays and metrics are saved first and",
        "  renamed into place whole; plots and the animation follow, and Ctrl-C while they are written",
        "  leaves the saved run with `extras = interrupted` in its marker; `nnrobust plot FOLDER` draws",
        "  them later. A run that did not complete never replaces a completed one: it is written",
        "  beside it, to `<folder>.<status>`. If a write fails (a full disk), the previous run is",
        "  untouched and the new arrays are saved to the temporary folder if they fit there; the",
        "  message says where.",
        "- **Study folders** of `sweep`, `tune` and `falsify` (`nnrobust/studies/base/folder.py`) carry a",
        "  hidden marker, `.nnrobust-sweep` (`-tune`, `-falsify`), with what their rows are computed",
        "  from, by content: the options that change results, nnrobust's version and the SHA-256 of",
        "  every file",
        "  read (the base experiment and the files it starts from, the URDF, user classes); a user's own",
        "  `sweep.toml` never makes a folder one. A resume on anything else is refused, naming what",
        "  changed; the same content resumes wherever it has moved. Each Parquet part records that",
        "  digest and is named by the SHA-256 of its bytes, so a part copied from another run, a row",
        "  twice, or a part changed after it was written is refused by name, never counted. They are",
        "  locked while a command writes them (two sweeps into one folder: the second is refused at",
        "  once, never a row twice). `--overwrite`",
        "  removes only what the command wrote (results/, plots/, worst/, summary.json, ...), never",
        "  the folder or a file of the user's, and the working folder or its ancestors are refused as",
        "  `--out`. A sample that raises inside a sweep is a row with status `error`; the sweep goes on.",
        "- **Signals**: SIGTERM and SIGHUP stop a run as Ctrl-C does; the partial run is written,",
        "  marked `interrupted`, and no hidden folder, lock file or viewer process is left behind.",
        "  The worker processes of a local cluster (sweep, tune, falsify, study) never receive a",
        "  Ctrl-C or a hang-up sent to the terminal's process group: the command stops them itself,",
        "  with one line and no worker traceback.",
        "",
        "| input | exception | message |",
        "|---|---|---|",
    ]
    for case in CASES:
        message = message_of(case, folder)
        for path, name in (
            (folder.resolve(), "<dir>"),
            (folder, "<dir>"),
            (folder.resolve().parent, "<dir>/.."),
            (REPO, "<repo>"),
        ):
            message = message.replace(str(path), name)
        message = re.sub(r"pid \d+", "pid <pid>", message).replace("|", "\\|").replace("\n", " ")
        name = case.error.__name__ if case.error else "warning, loads"
        lines.append(f"| {case.what} | `{name}` | {message} |")
    return "\n".join(lines) + "\n"
