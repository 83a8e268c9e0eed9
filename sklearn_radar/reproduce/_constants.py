"""The experiment numbers, step keys and paper figures that the run and the report refer to, in one place.

The experiment numbers are read from the paper's metadata
(:data:`sklearn_radar.experiments.PAPER_EXPERIMENTS`) where it says what an
experiment is: the expert setting is the one fixed setting derived from no
other, the best stage-1 method is the one that the control experiments and
stage 2 build on, and so on.
"""

from __future__ import annotations

from ..experiments import OBJECT_EXPERIMENT, PAPER_EXPERIMENTS, get_experiment
from ..experiments._learned import LEARNED_EXPERIMENT

#: Every experiment number (1-13), in run order.
NUMBERS = tuple(e.number for e in PAPER_EXPERIMENTS)

#: The stage-1 (point clustering, Table III) experiments.
STAGE1 = tuple(e.number for e in PAPER_EXPERIMENTS if e.stage == 1)

#: The stage-2 (cluster merging, Table IV) experiments: #12 and #13.
STAGE2 = tuple(e.number for e in PAPER_EXPERIMENTS if e.stage == 2)

#: The expert setting (#1): fixed, derived from no other experiment.
EXPERT = next(e.number for e in PAPER_EXPERIMENTS if not e.tuned and e.derived_from is None)

#: The best stage-1 method (#8), whose setting the controls (#10, #11) and stage 2 (#12, #13) reuse.
BEST_STAGE1 = get_experiment(STAGE2[0]).derived_from

#: The control experiments that take #8's setting instead of a search: #10 and #11.
DERIVED_FROM_BEST = tuple(e.number for e in PAPER_EXPERIMENTS if not e.tuned and e.derived_from == BEST_STAGE1)

#: #8's setting on unfiltered data (#10): the filter-effect comparison runs it beside #8.
BEST_STAGE1_UNFILTERED = next(n for n in DERIVED_FROM_BEST if not get_experiment(n).filtered)

#: The FCS box baseline (#3): the input of the scikit-learn baselines and the "baseline" panel of Fig. 6.
FCS_BASELINE = 3

#: The paper's Bayesian-optimisation budget (30 random points + 70 guided).
PAPER_N_ITER = 100

#: Step keys of ``--experiments`` besides the experiment numbers.
FILTER = "filter"
FILTER_EFFECT = "filter-effect"
BASELINES = "baselines"
#: Beyond the paper: the framework's stages set up for objects (``experiments.object_pipeline``).
OBJECTS = OBJECT_EXPERIMENT
TRACKING = "tracking"
#: Beyond the paper: the paper's next stage, a classifier of the clusters.
CLASSIFICATION = "classification"

#: Beyond the paper: the grouping learned from the training half's instances (``experiments._learned``).
LEARNED = LEARNED_EXPERIMENT

#: Every step key, in the order they run.
ALL_EXPERIMENTS = (
    FILTER,
    *(str(n) for n in NUMBERS),
    OBJECTS,
    FILTER_EFFECT,
    BASELINES,
    LEARNED,
    TRACKING,
    CLASSIFICATION,
)
#: The steps a run without ``--experiments`` runs: all but the learned grouping, whose fit (25-40 s at one thread
#: on the default run's training half) would add a quarter to the default run's time.
DEFAULT_EXPERIMENTS = tuple(key for key in ALL_EXPERIMENTS if key != LEARNED)

#: The settings the tracking step streams online (causal), by step key, in the report's order: the object
#: experiment (when the run has it; the Tracker is tuned on its ids), the learned grouping's causal model (when the
#: run has the learned step), then the paper's: the expert's, the best stage 1 and both stage-2 modes.  Another
#: setting is one more key here (and its branch in ``_tracking.setting_to_track``).
TRACKED = (OBJECTS, LEARNED, *(str(number) for number in (EXPERT, BEST_STAGE1, *STAGE2)))

#: The settings whose clusters the classification step classifies, one per line, in the report's order: the expert's,
#: the FCS box baseline, the best stage 1 (the V1 winner) and stage 2 by predicted continuation (#1, #3, #8, #13;
#: the paper's setting where the run lacks the experiment), and the settings meant for objects where the run has
#: them: the object experiment (PQ-tuned) and the learned grouping.  Beside them the step classifies the strongest
#: offline scikit-learn baseline and the point-wise classifier.
CLASSIFIED = (
    EXPERT,
    FCS_BASELINE,
    BEST_STAGE1,
    STAGE2[-1],
    OBJECTS,
    LEARNED,
)

#: Length of the time windows of the object-level, tracking and semantic scores, s (Scheiner et al. 2021 evaluate
#: 500 ms).
SCORE_WINDOW_S = 0.5

#: The paper's chosen filter setting (eta_1 in m/s, d_xy in m): the defaults of DopplerDensityFilter.
PAPER_FILTER_SETTING = (0.10, 1.4)

#: The coordinate systems of Table I: the ``frame`` argument of the filter evaluation, and their names.
FRAMES = ("frame", "car")
FRAME_NAMES = {"frame": "FCS", "car": "CCS"}

#: ``best_source`` of a search record: the search's own optimum, or the paper's setting scored beside it.
SOURCE_SEARCH = "search"
SOURCE_PAPER = "the paper's setting (scored beside the search)"
