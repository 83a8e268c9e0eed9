"""sklearn-radar: multi-stage clustering of automotive radar detections.

An implementation of Scheiner, Appenrodt, Dickmann and Sick, "A Multi-Stage
Clustering Framework for Automotive Radar Data" (ITSC 2019) as scikit-learn
estimators, with a RadarScenes reader/writer and a scene simulator.
The detection table is described in :mod:`sklearn_radar._schema`.

The names below and the subpackages are imported on first use (as in
scikit-learn and SciPy), so that ``import sklearn_radar`` and the command
line start quickly; ``from sklearn_radar import RadarDBSCAN`` works as usual.
"""

import importlib

__version__ = "0.1.0.dev0"

__all__ = [
    "LABELS",
    "RADARSCENES_MOUNTING",
    "ClusterMerger",
    "DopplerDensityFilter",
    "FrameTransform",
    "RadarDBSCAN",
    "__version__",
    "config_context",
    "describe_columns",
    "get_config",
    "instance_target",
    "set_config",
]

# Public name -> the module that defines it.
_LAZY = {
    "LABELS": "._schema",
    "RADARSCENES_MOUNTING": "._schema",
    "describe_columns": "._schema",
    "instance_target": "._schema",
    "config_context": "._config",
    "get_config": "._config",
    "set_config": "._config",
    "ClusterMerger": ".cluster",
    "RadarDBSCAN": ".cluster",
    "DopplerDensityFilter": ".preprocessing",
    "FrameTransform": ".preprocessing",
}
_SUBPACKAGES = {
    "classification",
    "cluster",
    "datasets",
    "evaluation",
    "experiments",
    "metrics",
    "model_selection",
    "online",
    "preprocessing",
    "reproduce",
}


def __getattr__(name):
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name], __name__), name)
    elif name in _SUBPACKAGES:
        value = importlib.import_module(f".{name}", __name__)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__) | _SUBPACKAGES)
