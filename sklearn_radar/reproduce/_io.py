"""A run's output folder: nothing is deleted or replaced that this package did not write.

A run's output folder is recognised by the marker a run writes first
(:func:`run_marker`), and a folder that holds a file of a run's name
without such a marker is refused (:func:`check_run_folder`).  Writing
files atomically is :mod:`sklearn_radar._files`' work.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from .._files import sha256, shown_path

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
    """Refuse (ValueError naming both) an ``out`` that is, lies inside or holds the folder ``data`` (paths resolved)."""
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
        f"{out_name} {shown_path(out)} {where} the {data_name} folder {shown_path(data)}: the report would mix with "
        f"the data; choose an {out_name} apart from {data_name}"
    )


def check_run_folder(folder, marker_name, run_files):
    """Refuse (FileExistsError) a ``folder`` where a run would replace a file no run wrote (it has no run marker)."""
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
