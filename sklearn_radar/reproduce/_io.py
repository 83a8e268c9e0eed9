"""Atomic output: a file appears whole or not at all."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


def check_writable(folder):
    """Create ``folder`` if needed and prove that a file can be written there (OSError names it)."""
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".write-test-"):
            pass
    except OSError as error:
        raise OSError(f"cannot write to the output folder {folder}: {error.strerror or error}") from None


def current_umask():
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


def file_mode():
    """Permission bits of a new file as ordinary tools create it: ``0o666`` less the umask."""
    return 0o666 & ~current_umask()


def atomic_write_text(path, text):
    """Write ``text`` to ``path`` through a temporary sibling and a rename."""
    atomic_write(path, lambda stream: stream.write(text.encode("utf-8")))


def atomic_write(path, write):
    """Call ``write(binary stream)`` on a temporary sibling of ``path``, then rename it into place."""
    path = Path(path)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        os.chmod(temporary, file_mode())  # mkstemp creates 0600 whatever the umask
        with os.fdopen(handle, "wb") as stream:
            write(stream)
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise
