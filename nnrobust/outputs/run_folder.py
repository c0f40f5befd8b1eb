"""Run folders: claimed before a run, written so that a good result is never lost, read back
defensively (docs/bad-inputs.md, "Run folders").

The rules:

- A run folder holds a marker file, ``.nnrobust-run``; ``--overwrite`` replaces only folders
  that have it (or that hold nothing but the files a run writes), never a folder of the user's.
- The output folder is checked before the simulation starts (not a file, not a symbolic link,
  not the working folder or one of its ancestors, a parent we can write) and locked for the
  whole run, so two runs into the same folder cannot both write it.
- The arrays, the metrics and the configuration are written first, to a hidden sibling folder
  that is renamed into place; plots and the animation come after, each renamed into place when
  complete. An interrupted or failed plot leaves a complete run whose marker says so.
- A run that did not complete never replaces a completed one: it goes to ``<folder>.<status>``
  instead, and the message says so.
"""

from __future__ import annotations

import contextlib
import functools
import json
import os
import shutil
import tempfile
import warnings
import zipfile
from pathlib import Path

from ..core.exceptions import ExtrasInterrupted, NNRobustError, RunFolderError, RunFolderExists
from ..core.folders import locked, write_new
from ..core.forked import ForkedJobs
from ..core.signals import signals_deferred

MARKER = ".nnrobust-run"
"""The file that makes a folder a run folder (JSON: format, status, extras)."""

RUN_FILES = frozenset(
    {MARKER, "config.toml", "result.npz", "metrics.json", "plots", "animation.html", "timing.json"}
)
"""Everything a run writes: a folder holding only these is a run folder even without the marker
(run folders written before the marker existed)."""


def is_run_folder(folder: Path) -> bool:
    """Whether ``folder`` is a run folder nnrobust wrote (marker, or only a run's files)."""
    if not folder.is_dir() or folder.is_symlink():
        return False
    if (folder / MARKER).is_file():
        return True
    names = {p.name for p in folder.iterdir()}
    return "result.npz" in names and names <= RUN_FILES


def _status_of(folder: Path) -> str:
    """The status recorded in a run folder ("" when unreadable)."""
    for name, key in ((MARKER, "status"), ("metrics.json", "status")):
        try:
            return str(json.loads((folder / name).read_text())[key])
        except (OSError, ValueError, KeyError, TypeError):
            continue
    return ""


def folder_path(folder: object) -> Path:
    """``folder`` as a Path, if it is a str or a path-like of text with no NUL character."""
    if not isinstance(folder, (str, os.PathLike)) or isinstance(os.fspath(folder), bytes):
        raise RunFolderError(
            f"the run folder needs a str or pathlib.Path, got {type(folder).__name__} {repr(folder)[:80]}"
        )
    if "\0" in os.fspath(folder):
        raise RunFolderError(f"the run folder {os.fspath(folder)[:80]!r} has a NUL character; no folder can")
    return Path(folder)


def check_out_folder(folder: str | Path, overwrite: bool) -> Path:
    """Check, before anything is simulated, that ``folder`` can take a run; returns it.

    Raises RunFolderExists (exists, no ``overwrite``) or RunFolderError (a file, a symbolic
    link, the working folder or an ancestor of it, a non-empty folder that is not a run folder,
    a parent that cannot be created or written).
    """
    folder = folder_path(folder)
    if folder.name in ("", ".", ".."):
        raise RunFolderError(f"{folder}: name the run folder itself (e.g. out/my-run), not '.' or '..'")
    if folder.is_symlink():
        raise RunFolderError(f"{folder} is a symbolic link; give the folder it points to, or another --out")
    resolved = folder.resolve()
    cwd = Path.cwd().resolve()
    if resolved == cwd or resolved in cwd.parents or resolved == Path(resolved.anchor):
        raise RunFolderError(
            f"{folder} is the working folder or one of its ancestors; choose a folder "
            "below it, e.g. out/my-run"
        )
    if folder.exists() and not folder.is_dir():
        raise RunFolderError(f"{folder} exists and is not a folder; choose another --out")
    if folder.is_dir() and any(folder.iterdir()):
        if not overwrite:
            raise RunFolderExists(f"{folder} exists; pass --overwrite (overwrite=True) to replace it")
        if not is_run_folder(folder):
            raise RunFolderError(
                f"{folder} is not a run folder (no {MARKER}); --overwrite replaces only "
                "run folders nnrobust wrote. Choose another --out"
            )
    check_parent(folder)
    return folder


def check_parent(folder: Path) -> None:
    """Make ``folder``'s parent, or refuse at once: a file on its path, no permission to write."""
    parent = folder.parent
    existing = next((p for p in (parent, *parent.parents) if p.exists()), None)
    if existing is not None and not existing.is_dir():
        raise RunFolderError(f"cannot create {folder}: {existing} is a file, not a folder")
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise RunFolderError(f"cannot create {parent}: {err.strerror or err}") from err
    if not parent.is_dir() or not os.access(parent, os.W_OK | os.X_OK):
        raise RunFolderError(f"cannot write in {parent} (permission denied); choose another --out")


def _write_marker(folder: Path, status: str, extras: str) -> None:
    from ..core.package_version import package_version

    tmp = folder / f"{MARKER}.partial"
    record = {"format": 1, "nnrobust": package_version(), "status": status, "extras": extras}
    write_new(tmp, json.dumps(record) + "\n")  # never through a link planted at that name
    os.replace(tmp, folder / MARKER)


def _write_core(tmp: Path, result, metrics: dict) -> None:
    from ..run.results import json_default

    tmp.mkdir()
    (tmp / "config.toml").write_text(result.config, encoding="utf-8")
    result.save_npz(tmp / "result.npz")
    (tmp / "metrics.json").write_text(json.dumps(metrics, indent=2, default=json_default) + "\n")
    _write_marker(tmp, result.status, "pending")


def _rescue_arrays(result, folder: Path) -> str:
    """After a failed write: the arrays in the temporary folder, if they fit anywhere."""
    try:
        fd, path = tempfile.mkstemp(prefix=f"nnrobust-{folder.name[:40]}-", suffix=".npz")
        os.close(fd)
    except OSError:
        return "the new arrays could not be saved anywhere"
    try:
        result.save_npz(path)
        return f"the new arrays are in {path}"
    except OSError:
        with contextlib.suppress(OSError):
            os.unlink(path)  # no empty file left behind
        return "the new arrays could not be saved anywhere"


def _place(tmp: Path, folder: Path) -> None:
    """Move the written folder into place; an existing run folder is swapped out and deleted only
    once the new one is there (the caller holds signals back, so never between the two renames).
    """
    if folder.is_dir() and any(folder.iterdir()):
        old = folder.parent / f".{folder.name}.old-{os.getpid()}"
        os.replace(folder, old)
        try:
            os.replace(tmp, folder)
        except OSError:
            os.replace(old, folder)
            raise
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(tmp, folder)  # onto nothing, or an empty folder


FIGURE_NAMES = ("path", "errors", "joints", "torques", "subtask", "snapshots", "nn", "signals")
"""The figures of a run (nnrobust.outputs.plots.FIGURES, named here so that matplotlib is not imported)."""

FIGURE_WEIGHTS = {
    "path": 2.0,
    "errors": 1.1,
    "joints": 1.1,
    "torques": 0.8,
    "subtask": 0.9,
    "snapshots": 1.0,
    "nn": 1.2,
    "signals": 1.0,
}
"""Relative cost of drawing each figure (measured on the Panda's run: the 3-D path costs most)."""

PLOTS_PARTIAL, ANIMATION_PARTIAL = ".plots.partial", ".animation.html.partial"


def _import_plots() -> None:
    from . import plots  # noqa: F401 - matplotlib, imported ahead of the figures


def _figure_input(folder: str) -> tuple:
    """What a figure is drawn from: the run as written in ``folder``, and where figures go."""
    return load_run(folder), Path(folder) / PLOTS_PARTIAL


def _draw_figure(data: tuple, name: str) -> None:
    from . import plots

    result, plots_tmp = data
    plots.plot_run(result, plots_tmp, [name])


class Drawing:
    """The figures and the animation of a run folder.

    The figures are drawn by forked processes (:class:`nnrobust.core.forked.ForkedJobs`) from the
    run as written in the folder (so ``nnrobust plot`` draws the same from the folder later); the
    first of those processes is forked when the Drawing is made, so that, made before the
    simulation as the command line does, it imports matplotlib while the simulation runs. This
    process writes the animation meanwhile. A context manager: leaving it stops the drawing
    processes if :meth:`write` did not run.
    """

    def __init__(self, plots: bool = True, animation: bool = True):
        self.plots, self.animation = plots, animation
        self._figures = (
            ForkedJobs(
                [functools.partial(_draw_figure, name=name) for name in FIGURE_NAMES],
                [FIGURE_WEIGHTS[name] for name in FIGURE_NAMES],
                prepare=_import_plots,
                load=_figure_input,
            )
            if plots
            else None
        )

    def close(self) -> None:
        """Stop the drawing processes (if :meth:`write` did not run)."""
        if self._figures is not None:
            self._figures.close()

    def __enter__(self) -> Drawing:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def write(self, folder: Path, result) -> str:
        """Plots and animation of ``result`` into ``folder`` (its arrays and metrics written), each
        written beside its final name and renamed into place; returns what the marker is to
        record, complete or failed (on Ctrl-C it records interrupted itself).
        """
        plots = self.plots and result.t.size > 1
        drawable = result.info is not None and result.chain is not None
        animation = self.animation and drawable and result.t.size > 1
        if not plots:
            self.close()
        plots_tmp, html_tmp = folder / PLOTS_PARTIAL, folder / ANIMATION_PARTIAL

        def write_animation():
            html = _animation_html(result)
            if html is not None:
                write_new(html_tmp, html)

        try:
            if plots and self._figures is not None:
                _clean_partials(folder)
                plots_tmp.mkdir()
                self._figures.run(str(folder), meanwhile=write_animation if animation else None)
                shutil.rmtree(folder / "plots", ignore_errors=True)
                os.replace(plots_tmp, folder / "plots")
            elif animation:
                write_animation()
            if html_tmp.exists():
                os.replace(html_tmp, folder / "animation.html")
        except KeyboardInterrupt:
            _clean_partials(folder)
            _write_marker(folder, result.status, "interrupted")
            raise
        except OSError as err:
            _clean_partials(folder)
            warnings.warn(
                f"{folder}: plots or animation not written ({err.strerror or err}); the arrays "
                "and metrics are saved",
                stacklevel=3,
            )
            return "failed"
        return "complete"


def _clean_partials(folder: Path) -> None:
    for name in (PLOTS_PARTIAL, ANIMATION_PARTIAL):
        path = folder / name
        if path.is_symlink() or (path.exists() and not path.is_dir()):
            path.unlink()  # a link is removed, never followed
        elif path.is_dir():
            shutil.rmtree(path, ignore_errors=True)


def _animation_html(result) -> str | None:
    """animation.html's text, or a warning when the robot's visuals cannot be drawn."""
    from .viewer.scene import animation_html

    try:
        return animation_html(result)
    except NNRobustError as err:
        warnings.warn(f"no animation.html: {err}", stacklevel=4)
        return None


def write_run(
    folder: str | Path,
    result,
    overwrite: bool = False,
    plots: bool = True,
    animation: bool = True,
    drawing: Drawing | None = None,
) -> Path:
    """Write a run folder: config.toml, result.npz, metrics.json and the marker first (atomically),
    then plots/ and animation.html (by ``drawing``, made before the simulation, whose own plots
    and animation settings then apply; else by a :class:`Drawing` made now). Returns the folder
    written.

    An existing run folder is replaced only when ``overwrite`` is true, only once the new arrays
    and metrics are complete, and never by a run that did not complete when the old one did: that
    run goes to ``<folder>.<status>`` (returned) instead. Ctrl-C during the plots raises
    :class:`ExtrasInterrupted` after the folder is in place.
    """
    from ..run.results import Result

    folder_path(folder)
    if not isinstance(result, Result):
        raise RunFolderError(
            f"write_run needs a Result (what run_experiment returns), got {type(result).__name__}"
        )
    try:
        metrics = result.metrics()
    except (KeyError, ValueError, IndexError, TypeError, AttributeError) as err:
        raise RunFolderError(
            f"write_run: this Result cannot be summarised ({type(err).__name__}: {str(err)[:200]}); "
            "give it the Result run_experiment returns (one made by hand lacks what a run records, "
            "such as its h and manipulability signals)"
        ) from err
    folder = check_out_folder(folder, overwrite)
    if result.status != "completed" and is_run_folder(folder) and _status_of(folder) == "completed":
        kept = folder
        folder = check_out_folder(folder.with_name(f"{folder.name}.{result.status}"), True)
        warnings.warn(
            f"{kept} holds a completed run and is kept; this {result.status} run is written to {folder}",
            stacklevel=2,
        )
    tmp = folder.parent / f".{folder.name}.partial-{os.getpid()}"
    shutil.rmtree(tmp, ignore_errors=True)
    placed = False
    try:
        with signals_deferred():  # a finished simulation is saved whole, then Ctrl-C is honoured
            _write_core(tmp, result, metrics)
            _place(tmp, folder)
            placed = True
    except KeyboardInterrupt:  # delivered as the save ended: the folder is whole, its extras pending
        shutil.rmtree(tmp, ignore_errors=True)
        if placed:
            raise ExtrasInterrupted(folder, "as the run was saved, before its plots") from None
        raise
    except OSError as err:
        shutil.rmtree(tmp, ignore_errors=True)
        where = "the previous run there is unchanged" if folder.exists() else "nothing was written there"
        raise RunFolderError(
            f"could not write {folder} ({err.strerror or err}); {where}; {_rescue_arrays(result, folder)}"
        ) from err
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    try:
        with drawing or Drawing(plots, animation) as draw:
            extras = draw.write(folder, result)
    except KeyboardInterrupt:
        raise ExtrasInterrupted(folder) from None
    _write_marker(folder, result.status, extras)
    return folder


def redraw_run(folder: str | Path, plots: bool = True, animation: bool = True) -> str:
    """Draw the figures and the animation of a run folder again from its result.npz, as
    :func:`write_run` drew them (after a drawing that was interrupted, failed or skipped); the
    arrays and metrics are not touched. Returns what the marker now records, complete or failed;
    Ctrl-C raises :class:`ExtrasInterrupted` with the folder marked as after any interrupted
    drawing.
    """
    folder = Path(folder)
    result = load_run(folder)
    if not is_run_folder(folder):
        raise RunFolderError(
            f"{folder} is not a run folder (no {MARKER}); only folders nnrobust wrote are drawn into"
        )
    with locked(folder):
        try:
            with Drawing(plots, animation) as draw:
                extras = draw.write(folder, result)
        except KeyboardInterrupt:
            raise ExtrasInterrupted(folder) from None
        _write_marker(folder, result.status, extras)
    return extras


MAX_RESULT_BYTES = 4e9
"""Most a received result.npz may expand to (a 4 MB zip bomb would otherwise ask for gigabytes)."""

MAX_SMALL_FILE = 10_000_000
"""Most bytes of a run folder's metrics.json or config.toml (a few kB when nnrobust writes them)."""


def _regular(path: Path, folder: Path) -> None:
    """A run folder's file must be a regular file (a FIFO would hang the reader, /dev/zero never end)."""
    if path.is_symlink() or not path.is_file():
        kind = "a symbolic link" if path.is_symlink() else "not a regular file"
        raise RunFolderError(f"{folder}: {path.name} is {kind}; a run folder holds regular files")


def _check_member(archive: zipfile.ZipFile, info: zipfile.ZipInfo, folder: Path) -> None:
    """An array of result.npz holds the bytes its header claims, of a dtype without Python
    objects: a crafted header claiming 80 TB would otherwise be allocated before it is read.
    """
    import numpy as np

    if not info.filename.endswith(".npy"):
        return
    damaged = f"{folder}: a damaged run folder (result.npz: {info.filename}"
    with archive.open(info) as fh:
        try:
            version = np.lib.format.read_magic(fh)
            if version == (1, 0):
                shape, _, dtype = np.lib.format.read_array_header_1_0(fh)
            elif version == (2, 0):
                shape, _, dtype = np.lib.format.read_array_header_2_0(fh)
            else:
                raise ValueError(f"format version {version[0]}.{version[1]}; a run's arrays are 1.0 or 2.0")
        except Exception as err:  # numpy parses the header with Python's tokenizer: any of its errors
            raise RunFolderError(
                f"{damaged} has no readable array header: {type(err).__name__}: {str(err)[:200]})"
            ) from err
        header = fh.tell()
    if dtype.hasobject:
        raise RunFolderError(f"{damaged} holds Python objects, which are never unpickled)")
    shown = str(tuple(shape))
    shown = shown if len(shown) <= 60 else shown[:57] + "..."
    if any(int(size) < 0 for size in shape):
        raise RunFolderError(f"{damaged}'s header claims shape {shown}, with a negative size)")
    claimed = dtype.itemsize
    for size in shape:
        claimed *= int(size)
    held = info.file_size - header
    if claimed > held:
        raise RunFolderError(
            f"{damaged}'s header claims shape {shown} of {dtype}, {claimed / 1e9:.3g} GB, "
            f"but holds {held} bytes)"
        )


def check_run_folder(folder: Path) -> None:
    """Validate a run folder received from anywhere, before anything reads it: regular files of
    bounded size, a result.npz that expands to at most :data:`MAX_RESULT_BYTES`, metrics.json a
    table whose numbers are numbers.
    """
    if not folder.is_dir():
        raise RunFolderError(f"{folder}: not a run folder (no such folder)")
    for name in ("result.npz", "metrics.json"):
        if not (folder / name).exists() and not (folder / name).is_symlink():
            raise RunFolderError(f"{folder}: not a run folder ({name} is missing)")
        _regular(folder / name, folder)
    if (folder / "config.toml").exists() or (folder / "config.toml").is_symlink():
        _regular(folder / "config.toml", folder)
    for name in ("metrics.json", "config.toml"):
        path = folder / name
        if path.exists() and path.stat().st_size > MAX_SMALL_FILE:
            raise RunFolderError(
                f"{folder}: {name} has {path.stat().st_size / 1e6:.0f} MB; a run's has a few kB"
            )
    try:
        with zipfile.ZipFile(folder / "result.npz") as archive:
            expanded = sum(info.file_size for info in archive.infolist())
            if expanded <= MAX_RESULT_BYTES:
                for info in archive.infolist():
                    _check_member(archive, info, folder)
    except (zipfile.BadZipFile, OSError) as err:
        raise RunFolderError(
            f"{folder}: a damaged run folder (result.npz is not an .npz archive: {err})"
        ) from err
    if expanded > MAX_RESULT_BYTES:
        raise RunFolderError(
            f"{folder}: result.npz would expand to {expanded / 1e9:.3g} GB; at most "
            f"{MAX_RESULT_BYTES / 1e9:g} GB is read"
        )
    try:
        metrics = json.loads((folder / "metrics.json").read_text())
    except RecursionError as err:
        raise RunFolderError(f"{folder}: a damaged run folder (metrics.json is nested too deeply)") from err
    except (ValueError, OSError) as err:
        raise RunFolderError(f"{folder}: a damaged run folder (metrics.json cannot be read: {err})") from err
    if not isinstance(metrics, dict):
        raise RunFolderError(f"{folder}: a damaged run folder (metrics.json is not a table)")
    from ..run.results import METRIC_UNITS

    for key in METRIC_UNITS:
        value = metrics.get(key)
        if (
            value is not None
            and key != "singular_episodes"
            and (isinstance(value, bool) or not isinstance(value, (int, float)))
        ):
            raise RunFolderError(
                f"{folder}: a damaged run folder (metrics.json: {key} is "
                f"{type(value).__name__} {str(value)[:40]!r}, not a number)"
            )
    from ..plant.mujoco_engine import ENGINES

    engine, audit = metrics.get("plant_engine", "pinocchio"), metrics.get("engine_audit")
    if engine not in ENGINES or not (audit is None or isinstance(audit, dict)):
        raise RunFolderError(
            f"{folder}: a damaged run folder (metrics.json: plant_engine "
            f"{str(engine)[:40]!r} is not one of {', '.join(ENGINES)}, or engine_audit "
            "is not a table)"
        )


def _check_shapes(result, folder: Path) -> None:
    """The arrays of a loaded run agree: t is 1-D with N samples, q, dq, tau N x n, x, x_d, e N x m,
    the chain N x (n + 1) x 3, every signal N long, all of them real numbers.
    """
    n_t = result.t.shape[0] if result.t.ndim == 1 else -1
    if n_t < 1:
        raise RunFolderError(
            f"{folder}: a damaged run folder (result.npz: t has shape {result.t.shape}, not N samples)"
        )
    joints = result.q.shape[1] if result.q.ndim == 2 else -1
    expected: dict[str, tuple[int, ...]] = {"q": (n_t, joints), "dq": (n_t, joints), "tau": (n_t, joints)}
    m = result.e.shape[1] if result.e.ndim == 2 else -1
    width = result.x.shape[-1] if result.x.ndim == 2 else -1
    expected.update({"x": (n_t, width), "x_d": (n_t, m), "e": (n_t, m)})
    if result.chain is not None:
        expected["chain"] = (n_t, joints + 1, 3)
    for name, shape in expected.items():
        array = getattr(result, name)
        if joints < 1 or m < 1 or array.shape != shape:
            raise RunFolderError(
                f"{folder}: a damaged run folder (result.npz: {name} has shape "
                f"{array.shape}, expected {shape} for {n_t} samples)"
            )
    for name in ("t", *expected):
        array = getattr(result, name)
        if array.dtype.kind not in "fiu":
            raise RunFolderError(
                f"{folder}: a damaged run folder (result.npz: {name} holds {array.dtype} values, "
                "not real numbers)"
            )
    for name, values in result.signals.items():
        if values.dtype.kind not in "fiub":
            raise RunFolderError(
                f"{folder}: a damaged run folder (result.npz: signal {name!r} holds {values.dtype} "
                "values, not real numbers)"
            )
        if values.shape != (n_t,):
            raise RunFolderError(
                f"{folder}: a damaged run folder (result.npz: signal {name!r} has shape "
                f"{values.shape}, expected ({n_t},))"
            )


def load_run(folder: str | Path):
    """Read a run folder received from anywhere; a missing, hostile, truncated or garbled one is
    one clear error naming the file (:func:`check_run_folder` first; never unpickled:
    ``allow_pickle`` stays off).
    """
    from ..run.results import Result

    folder = Path(folder)
    check_run_folder(folder)
    try:
        result = Result.load(folder)
    except (
        OSError,
        ValueError,
        KeyError,
        EOFError,
        TypeError,
        AttributeError,
        IndexError,
        zipfile.BadZipFile,
    ) as err:
        what = "metrics.json" if isinstance(err, json.JSONDecodeError) else "result.npz or metrics.json"
        raise RunFolderError(
            f"{folder}: a damaged run folder ({what} cannot be read: {type(err).__name__}: {err})"
        ) from err
    _check_shapes(result, folder)
    return result
