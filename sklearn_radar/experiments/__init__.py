"""The paper's experiments (Scheiner et al. 2019, Tables III and IV) as data, pipelines and search spaces.

:data:`PAPER_EXPERIMENTS` holds experiments #1-#13 (method, coordinate
system, filtering, stage, the paper's V1 score and setting);
:func:`experiment_pipeline` builds the scikit-learn Pipeline of an
experiment and :func:`search_space` its Bayesian-optimisation ranges;
:data:`SKLEARN_BASELINES` and :func:`baseline_pipeline` are the scikit-learn
clusterers the run compares with, on #3's input; :func:`object_pipeline` and
:func:`object_search_space` are the object experiment (the framework's stages
set up for panoptic quality, from the object-level ablation).
"""

from ._baselines import BASELINE_INPUT, SKLEARN_BASELINES, SLIDING_BASELINE, baseline_pipeline
from ._objects import OBJECT_EXPERIMENT, object_pipeline, object_search_space
from ._paper import (
    PAPER_EXPERIMENTS,
    PIPELINE_COLUMNS,
    PaperExperiment,
    derived_params,
    experiment_pipeline,
    get_experiment,
    paper_experiments,
    paper_params,
    search_space,
)

__all__ = [
    "BASELINE_INPUT",
    "OBJECT_EXPERIMENT",
    "PAPER_EXPERIMENTS",
    "PIPELINE_COLUMNS",
    "SKLEARN_BASELINES",
    "SLIDING_BASELINE",
    "PaperExperiment",
    "baseline_pipeline",
    "derived_params",
    "experiment_pipeline",
    "get_experiment",
    "object_pipeline",
    "object_search_space",
    "paper_experiments",
    "paper_params",
    "search_space",
]
