"""Atomic output: a file appears whole or not at all; what a killed process leaves is removed next time."""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path

from .._files import TEMPORARY_PREFIX, file_mode, process_alive, remove_entry

_TEMPORARY = re.compile(re.escape(TEMPORARY_PREFIX) + r"(\d+)-")


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


def blocking_file(folder):
    """``folder`` or its first ancestor that exists and is not a folder (so ``folder`` cannot be made); else None."""
    for candidate in (Path(folder), *Path(folder).parents):
        if candidate.exists() or candidate.is_symlink():
            return None if candidate.is_dir() else candidate
    return None


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


def atomic_write(path, write):
    """Call ``write(binary stream)`` on a temporary sibling of ``path``, then rename it into place."""
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
        os.replace(temporary, path)
    except BaseException as error:
        Path(temporary).unlink(missing_ok=True)
        if isinstance(error, OSError):
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
