"""The whole framework on a live stream: each radar scan labelled when it arrives, with persistent object ids.

:class:`OnlinePipeline` labels one scan at a time; :func:`iter_scans` gives the scans of a detection table in
arrival order, as ``sklearn-radar stream`` replays them.
"""

from ._objects import ObjectList
from ._pipeline import OnlinePipeline, ScanResult
from ._scans import iter_scans

__all__ = ["ObjectList", "OnlinePipeline", "ScanResult", "iter_scans"]
