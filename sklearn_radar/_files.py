"""Files and folders the package writes: permission bits as the umask allows, and the temporaries of killed writers."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

#: Every temporary file or folder written beside an output starts with this, then the writer's process id and "-".
TEMPORARY_PREFIX = ".sklearn-radar-tmp-"


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
