"""The whole framework on a live stream: each radar scan labelled when it arrives, with persistent object ids."""

from ._objects import ObjectList
from ._pipeline import OnlinePipeline, ScanResult

__all__ = ["ObjectList", "OnlinePipeline", "ScanResult"]
