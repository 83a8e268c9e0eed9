"""The main job: re-run the paper's experiments (``sklearn-radar reproduce``) and apply a tuned pipeline."""

from ..cli._cluster import cluster_radarscenes, write_predictions
from ..experiments._saved import load_params
from ._run import ALL_EXPERIMENTS, parse_experiments, reproduce

__all__ = [
    "ALL_EXPERIMENTS",
    "cluster_radarscenes",
    "load_params",
    "parse_experiments",
    "reproduce",
    "write_predictions",
]
