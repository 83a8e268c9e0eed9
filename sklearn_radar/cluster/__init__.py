"""Stage 1 (RadarDBSCAN, Eqs. 2-5), stage 2 (ClusterMerger, Eq. 6 and continuation) and the learned grouping."""

from ._cluster_merger import ClusterMerger
from ._link_clustering import LinkClustering
from ._radar_dbscan import RadarDBSCAN, min_points_at_range
from ._radar_dbscan_stream import ScanStream
from ._velocity import estimate_velocities, estimate_velocity
from ._windowed import SequenceDBSCAN, SequenceHDBSCAN, SlidingDBSCAN, WindowedDBSCAN, WindowedHDBSCAN

__all__ = [
    "ClusterMerger",
    "LinkClustering",
    "RadarDBSCAN",
    "ScanStream",
    "SequenceDBSCAN",
    "SequenceHDBSCAN",
    "SlidingDBSCAN",
    "WindowedDBSCAN",
    "WindowedHDBSCAN",
    "estimate_velocities",
    "estimate_velocity",
    "min_points_at_range",
]
