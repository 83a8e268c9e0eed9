"""The whole framework on a live stream: each radar scan labelled when it arrives, with persistent object ids.

:class:`OnlinePipeline` labels one scan at a time; :func:`iter_scans` gives the scans of a detection table in
arrival order, as ``sklearn-radar stream`` replays them; :class:`Tracker` follows the objects from scan to scan
with lasting track ids.
"""

from ._objects import ObjectList
from ._pipeline import OnlinePipeline, ScanResult
from ._scans import iter_scans
from ._tracker import Tracker

__all__ = ["ObjectList", "OnlinePipeline", "ScanResult", "Tracker", "iter_scans"]
