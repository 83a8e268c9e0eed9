"""Files and folders the package writes: atomically, with permission bits as the umask allows, never replacing
what the package did not write, and removing the temporaries of killed writers."""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import tempfile
from pathlib import Path

#: Every temporary file or folder written beside an output starts with this, then the writer's process id and "-".
TEMPORARY_PREFIX = ".sklearn-radar-tmp-"
_TEMPORARY = re.compile(re.escape(TEMPORARY_PREFIX) + r"(\d+)-")


def shown_path(path) -> str:
    """A path as text that can be printed and written as UTF-8: undecodable bytes appear as ``\\xff``."""
    return os.fsencode(path).decode("utf-8", "backslashreplace")


def current_umask() -> int:
    """The process's umask, read without changing it where Linux's /proc tells it (``os.umask`` is process-wide)."""
    try:
        with open("/proc/self/status", encoding="ascii", errors="replace") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    old = os.umask(0o022)
    os.umask(old)
    return old


def file_mode() -> int:
    """Permission bits of a new file as ordinary tools create it: ``0o666`` less the umask."""
    return 0o666 & ~current_umask()


def folder_mode() -> int:
    """Permission bits of a new folder as ordinary tools create it: ``0o777`` less the umask."""
    return 0o777 & ~current_umask()


def process_alive(pid: int) -> bool:
    """Whether process ``pid`` may still be writing: True unless it is known to have ended.

    The own process, another user's process and every process on Windows
    (where ``os.kill`` would end it) count as alive, so that their
    temporaries are never taken for stale.
    """
    if pid == os.getpid() or os.name == "nt":
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # e.g. another user's process
        return True
    return True


def remove_entry(entry: Path) -> bool:
    """Delete a file or a folder tree (a symlink itself, never its target); False if it could not be."""
    try:
        if entry.is_dir() and not entry.is_symlink():
            shutil.rmtree(entry)
        else:
            entry.unlink()
    except OSError:  # removed meanwhile by another process, or not ours to remove
        return False
    return True


def blocking_file(folder):
    """``folder`` or its first ancestor that exists and is not a folder (so ``folder`` cannot be made); else None."""
    for candidate in (Path(folder), *Path(folder).parents):
        if candidate.exists() or candidate.is_symlink():
            return None if candidate.is_dir() else candidate
    return None


def check_ours_to_replace(path, heads, what, choose="file"):
    """Refuse to replace ``path`` unless it is absent, empty, or starts with one of ``heads`` (we wrote it).

    Parameters
    ----------
    path : str or path-like
        The file about to be written.
    heads : tuple of bytes
        The first bytes of the files this package writes there.
    what : str
        What they are, for the message: ``"a predictions file"``.
    choose : str, default="file"
        What to choose instead, for the message: ``"output file"``.

    Raises
    ------
    FileExistsError
        Naming ``path``, when it is a symbolic link or another's file (which is kept).
    OSError
        Naming ``path``, when it cannot be read.
    """
    path = Path(path)
    if path.is_symlink():
        problem = "is a symbolic link"
    elif not path.is_file() or path.stat().st_size == 0:
        return  # absent, or a folder (atomic_write says so), or empty: nothing is lost
    else:
        try:
            with open(path, "rb") as stream:
                start = stream.read(max(len(head) for head in heads))
        except OSError as error:
            raise OSError(f"cannot read {path}: {error.strerror or error}") from None
        if any(start.startswith(head) for head in heads):
            return
        problem = f"exists and is not {what} written by sklearn-radar"
    raise FileExistsError(f"{path} {problem}; it is not replaced: choose another {choose}")


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
