"""The output folder of :func:`write_radarscenes`: refusing what the writer did not write, replacing atomically.

Read more in the :ref:`User Guide <user-guide-data>`.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import uuid as uuid_module
from pathlib import Path

from .._files import TEMPORARY_PREFIX, blocking_file, process_alive, remove_entry

#: The file by which ``write_radarscenes(..., overwrite=True)`` knows a folder it wrote: the files it wrote.
MANIFEST = "sklearn_radar_manifest.json"
_MANIFEST_TOOL = "sklearn_radar.datasets.write_radarscenes"


def check_output_folder(path, overwrite, flag="overwrite=True"):
    """Refuse ``path`` as the output of :func:`write_radarscenes` unless writing there deletes nothing of others.

    ``path`` may be absent or an empty folder; with ``overwrite`` it may
    also be a data folder that :func:`write_radarscenes` wrote (see
    :func:`_foreign_entry`).

    Parameters
    ----------
    path : str or path-like
        The data folder to write.
    overwrite : bool
        Whether a folder written before may be replaced.
    flag : str, default="overwrite=True"
        How the error names the overwrite option (the command line's is ``--overwrite``).

    Raises
    ------
    FileExistsError
        In one line, naming ``path`` and why it is not replaced.
    """
    path = Path(path)
    blocking = blocking_file(path)
    if blocking is not None and blocking != path:
        raise FileExistsError(f"cannot create {path}: {blocking} is a file, not a folder")
    if not _is_occupied(path):
        return
    foreign = _foreign_entry(path)
    if foreign is not None:
        raise FileExistsError(f"{path} {foreign}; it is not replaced, even with {flag}: choose another folder")
    if not overwrite:
        raise FileExistsError(f"{path} exists and is not empty (data written before); pass {flag} to replace it")


def _is_occupied(path: Path) -> bool:
    """Whether anything is at ``path`` but an empty folder (a symbolic link counts, whatever it points to)."""
    if path.is_symlink():
        return True
    return path.exists() and (not path.is_dir() or any(path.iterdir()))


def _foreign_entry(path: Path):
    """Why ``path`` is not a data folder that the writer wrote (a phrase), or None if it is one.

    It is one if its manifest names the writer and lists every file below
    it; it may lack listed files (deleted since), but holds nothing else
    and no symbolic link (the writer makes none).
    """
    if path.is_symlink():
        return "is a symbolic link"
    if not path.is_dir():
        return "is a file, not a data folder"
    try:
        manifest = json.loads((path / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        manifest = None
    listed = manifest.get("files") if isinstance(manifest, dict) and manifest.get("tool") == _MANIFEST_TOOL else None
    if not isinstance(listed, list):
        return f"exists and was not written by sklearn-radar (it has no {MANIFEST})"
    listed = {*(name for name in listed if isinstance(name, str)), MANIFEST}
    folders = {folder.as_posix() for name in listed for folder in Path(name).parents}
    for entry in sorted(path.rglob("*")):
        name = entry.relative_to(path).as_posix()
        ours = name in folders if entry.is_dir() and not entry.is_symlink() else name in listed and entry.is_file()
        if not ours or entry.is_symlink():
            return f"holds {name}, which sklearn-radar did not write"
    return None


def _remove_stale_temporaries(path: Path) -> None:
    """Delete what a killed writer of ``path`` left beside it.

    Its staging folders (``.sklearn-radar-tmp-<pid>-<name>.*.tmp``, and
    ``.<name>.*.tmp`` of older versions) go when process ``<pid>`` no longer
    runs; a set-aside old copy (``*.old``) only when ``path`` exists, as it
    may otherwise be the only copy of the data.
    """
    name = re.escape(path.name)
    pattern = re.compile(rf"(?:{re.escape(TEMPORARY_PREFIX)}(?P<pid>\d+)-{name}|\.{name})\.[^/]+\.(?P<kind>tmp|old)")
    try:
        entries = list(path.parent.iterdir())
    except OSError:
        return
    for entry in entries:
        match = pattern.fullmatch(entry.name)
        if match is None or (match["kind"] == "old" and not path.exists()):
            continue
        if match["pid"] is not None and process_alive(int(match["pid"])):
            continue
        remove_entry(entry)  # one removed meanwhile, or not ours to remove: the write goes on


def _move_into_place(staging: Path, path: Path, overwrite: bool) -> None:
    """Rename ``staging`` to ``path``; an existing ``path`` is swapped out, then deleted."""
    check_output_folder(path, overwrite)  # again: the folder may have changed while the data were written
    if not _is_occupied(path):
        if path.exists():
            path.rmdir()
        os.rename(staging, path)
        return
    aside = path.with_name(f"{TEMPORARY_PREFIX}{os.getpid()}-{path.name}.{uuid_module.uuid4().hex}.old")
    os.rename(path, aside)
    try:
        os.rename(staging, path)
    except BaseException:
        os.rename(aside, path)
        raise
    if aside.is_dir() and not aside.is_symlink():
        shutil.rmtree(aside)
    else:
        aside.unlink()
