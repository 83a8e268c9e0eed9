"""The main job: re-run the paper's experiments (``sklearn-radar reproduce``) and apply a tuned pipeline."""

from ._run import ALL_EXPERIMENTS, parse_experiments, reproduce

#: Applying a tuned pipeline (``sklearn-radar cluster``) lives in :mod:`sklearn_radar._cluster_command`, which
#: writes with this package's helpers: its names are read from there when first asked for.
_CLUSTER_COMMAND = ("cluster_radarscenes", "load_params", "write_predictions")


def __getattr__(name):
    if name in _CLUSTER_COMMAND:
        from .. import _cluster_command

        return getattr(_cluster_command, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "ALL_EXPERIMENTS",
    "cluster_radarscenes",
    "load_params",
    "parse_experiments",
    "reproduce",
    "write_predictions",
]
