"""Permission bits of the files and folders the package writes: what the umask allows, as ordinary tools do."""

from __future__ import annotations

import os


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
