"""Stage 1: RadarDBSCAN (Eqs. 2-5)."""

from ._radar_dbscan import RadarDBSCAN, min_points_at_range

__all__ = ["RadarDBSCAN", "min_points_at_range"]
