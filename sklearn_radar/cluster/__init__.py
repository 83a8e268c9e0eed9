"""Stage 1: RadarDBSCAN (Eqs. 2-5)."""

from ._radar_dbscan import RadarDBSCAN, ScanStream, min_points_at_range

__all__ = ["RadarDBSCAN", "ScanStream", "min_points_at_range"]
