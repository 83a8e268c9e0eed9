"""Stage 0: coordinate frames and the Doppler-density filter (Eq. 1)."""

from ._doppler_density_filter import DopplerDensityFilter, doppler_density_keep, neighbor_counts
from ._frame_transform import FrameTransform

__all__ = ["DopplerDensityFilter", "FrameTransform", "doppler_density_keep", "neighbor_counts"]
