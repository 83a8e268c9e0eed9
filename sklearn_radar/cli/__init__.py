"""The command line, ``sklearn-radar`` (also ``python -m sklearn_radar``): one module per command.

``simulate``, ``stats`` and ``reproduce`` are thin and live in the parser's
module; ``cluster`` and ``stream`` apply a saved setting to a RadarScenes
folder (:ref:`user-guide-command-line`).
"""

from ._main import main

__all__ = ["main"]
