"""Atomic output: a file appears whole or not at all; what a killed process leaves is removed next time.

Nothing is deleted or replaced that this package did not write: a run's
output folder is recognised by the marker a run writes first
(:func:`run_marker`), and a folder that holds a file of a run's name
without such a marker is refused (:func:`check_run_folder`).
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import tempfile
from pathlib import Path

from .._files import TEMPORARY_PREFIX, blocking_file, file_mode, process_alive, remove_entry

_TEMPORARY = re.compile(re.escape(TEMPORARY_PREFIX) + r"(\d+)-")
#: The ``tool`` of a run marker: the marker of a folder that a reproduce run wrote.
RUN_TOOL = "sklearn-radar reproduce"


def run_marker(file):
    """The run marker at ``file`` as a dict if a reproduce run wrote it (its ``tool`` and ``run_id``); else None."""
    try:
        marker = json.loads(Path(file).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(marker, dict) or marker.get("tool") != RUN_TOOL or not isinstance(marker.get("run_id"), str):
        return None
    return marker


def check_apart(data, out, data_name="data", out_name="out"):
    """Refuse an output folder that is the data folder, lies inside it or holds it.

    A report written into the data would mix a run's files with the
    recordings (and a later ``simulate --overwrite`` would refuse the folder).
    Both paths are compared resolved (symbolic links followed, ``..``
    removed), whether they exist or not.

    Parameters
    ----------
    data, out : str or path-like
        The data folder (or its parent) and the output folder.
    data_name, out_name : str, default="data", "out"
        How the error names them (the command line's options).

    Raises
    ------
    ValueError
        Naming both.
    """
    data_path, out_path = Path(data).resolve(), Path(out).resolve()
    if out_path == data_path:
        where = "is"
    elif data_path in out_path.parents:
        where = "is inside"
    elif out_path in data_path.parents:
        where = "holds"
    else:
        return
    raise ValueError(
        f"{out_name} {_shown(out)} {where} the {data_name} folder {_shown(data)}: the report would mix with the "
        f"data; choose an {out_name} apart from {data_name}"
    )


def _shown(path):
    """A path as printable text (undecodable bytes as ``\\xff``)."""
    return os.fsencode(path).decode("utf-8", "backslashreplace")


def check_run_folder(folder, marker_name, run_files):
    """Refuse an output folder where a run would replace a file that no run wrote.

    A run may write into any folder; it replaces the files named
    ``marker_name`` and ``run_files`` there, so they must be absent or the
    folder must be a run's (its marker written by a run).  Other files
    stay either way.

    Raises
    ------
    FileExistsError
        Naming the folder and the first such file.
    """
    folder = Path(folder)
    if not folder.is_dir() or run_marker(folder / marker_name) is not None:
        return  # absent (created later), a file (check_writable says so), or a run's folder
    clashes = [name for name in (marker_name, *run_files) if os.path.lexists(folder / name)]
    if clashes:
        raise FileExistsError(
            f"{folder} holds {clashes[0]}, which no sklearn-radar run wrote (the folder has no {marker_name} of a "
            f"run), so a run there would replace it; choose another output folder or move the file"
        )


def previous_run_files(folder, marker):
    """The names a previous run's marker lists whose files are unchanged (same SHA-256): safe to remove."""
    files = marker.get("files") if isinstance(marker, dict) else None
    if not isinstance(files, dict):
        return []
    folder = Path(folder)
    return [
        name
        for name, digest in files.items()
        if isinstance(name, str)
        and Path(name).name == name
        and (folder / name).is_file()
        and sha256(folder / name) == digest
    ]


def sha256(path):
    """The SHA-256 of a file, hex."""
    digest = hashlib.sha256()
    with open(path, "rb") as stream:
        for block in iter(lambda: stream.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def temporary_prefix(name=""):
    """``.sklearn-radar-tmp-<pid>-<name>``: the prefix of this process's temporary files and folders."""
    return f"{TEMPORARY_PREFIX}{os.getpid()}-{name}"


def check_writable(folder):
    """Create ``folder`` if needed and prove that a file can be written there (OSError names it).

    Returns
    -------
    created : list of Path
        The folders created, deepest first (:func:`remove_empty_folders` undoes it).
    """
    folder = Path(folder)
    created = []
    try:
        parent = folder
        while not parent.exists() and parent != parent.parent:
            created.append(parent)
            parent = parent.parent
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder, prefix=temporary_prefix("write-test-")):
            pass
    except OSError as error:
        remove_empty_folders(created)
        blocking = blocking_file(folder)
        if blocking is not None:
            reason = "it is a file" if blocking == folder else f"{blocking} is a file, not a folder"
        else:
            reason = error.strerror or str(error)
        raise OSError(f"cannot write to the output folder {folder}: {reason}") from None
    return created


def remove_empty_folders(folders):
    """Remove each of ``folders`` (deepest first) that exists and is empty."""
    for folder in folders:
        try:
            folder.rmdir()
        except OSError:
            return


def remove_stale_temporaries(folder, legacy=()):
    """Delete the temporary files and folders that killed processes left in ``folder``.

    A stale entry is named ``.sklearn-radar-tmp-<pid>-...`` with no process
    ``<pid>`` running, or ``.<name>.<random>.tmp`` for a ``name`` in
    ``legacy`` (the temporary files of older versions).  A running
    process's entries are kept.

    Returns
    -------
    removed : list of str
        The names removed.
    """
    folder = Path(folder)
    legacy = tuple(f".{name}." for name in legacy)
    removed = []
    try:
        entries = list(folder.iterdir())
    except OSError:
        return removed
    for entry in entries:
        match = _TEMPORARY.match(entry.name)
        stale = (match is not None and not process_alive(int(match.group(1)))) or (
            entry.name.startswith(legacy) and entry.name.endswith(".tmp")
        )
        if stale and remove_entry(entry):  # one that cannot be removed is not worth failing the run for
            removed.append(entry.name)
    return removed


def atomic_write_text(path, text):
    """Write ``text`` to ``path`` through a temporary sibling and a rename."""
    atomic_write(path, lambda stream: stream.write(text.encode("utf-8")))


def atomic_write(path, write, replaceable=None):
    """Call ``write(binary stream)`` on a temporary sibling of ``path``, then rename it into place.

    ``replaceable(path)``, if given, is called just before the rename and
    raises to keep what is at ``path`` (the temporary file is removed).
    """
    path = Path(path)
    if path.is_dir():
        raise IsADirectoryError(f"cannot write {path}: it is a folder; give a file name")
    try:
        handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=temporary_prefix(f"{path.name}."), suffix=".tmp")
    except OSError as error:
        raise _write_error(error, path) from None
    try:
        os.chmod(temporary, file_mode())  # mkstemp creates 0600 whatever the umask
        with os.fdopen(handle, "wb") as stream:
            write(stream)
        if replaceable is not None:
            replaceable(path)
        os.replace(temporary, path)
    except BaseException as error:
        Path(temporary).unlink(missing_ok=True)
        if isinstance(error, OSError) and error.errno is not None:  # not a refusal of ``replaceable``
            raise _write_error(error, path) from None
        raise


def _write_error(error, path):
    """The OSError of a failed write, naming ``path`` (not the temporary file) and without the errno."""
    if isinstance(error, FileNotFoundError):
        reason = f"the folder {path.parent} does not exist"
    elif isinstance(error, NotADirectoryError):
        reason = f"{path.parent} is not a folder"
    else:
        reason = error.strerror or str(error)
    return type(error)(f"cannot write {path}: {reason}")
