"""Data sets: the RadarScenes reader/writer and the scene simulator."""

from ._radarscenes_reader import load_radarscenes
from ._radarscenes_writer import write_radarscenes
from ._simulator import make_scenes
from ._statistics import format_statistics, scene_statistics

__all__ = ["format_statistics", "load_radarscenes", "make_scenes", "scene_statistics", "write_radarscenes"]
