"""The paper's experiments as data: Tables III/IV, pipelines and search spaces."""

import math
import re
from numbers import Integral
from pathlib import Path

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.pipeline import Pipeline

from sklearn_radar import ClusterMerger, DopplerDensityFilter, FrameTransform, RadarDBSCAN
from sklearn_radar._skopt import Integer
from sklearn_radar.datasets import make_scenes
from sklearn_radar.experiments import (
    PAPER_EXPERIMENTS,
    derived_params,
    experiment_pipeline,
    get_experiment,
    paper_experiments,
    paper_params,
    search_space,
)

TUNED = [2, 3, 4, 5, 6, 7, 8, 9, 12, 13]
FIXED = [1, 10, 11]

#: The "Optimized Parameter Sets" columns printed in Tables III and IV, per experiment.
OPTIMISED = {
    **{n: ("eps_xy", "eps_vr", "min_samples", "vr_min") for n in (2, 3, 4, 5)},
    6: ("eps_xyv", "vr_scale", "min_samples", "vr_min"),
    7: ("eps_xy", "eps_vr", "min_samples", "vr_min", "alpha_r"),
    8: ("eps_xyv", "vr_scale", "min_samples", "vr_min", "alpha_r"),
    9: ("eps_xyv", "vr_scale", "min_samples", "vr_min", "alpha_r"),
    12: ("eps_d", "eps_phi", "eps_v", "min_samples", "eps_t2"),
    13: ("eps_d", "eps_v", "min_samples", "eps_t2"),
}


#: Folder of the rows of Tables II-IV exactly as they stand in the paper's LaTeX source (copied, not retyped).  The
#: tests parse them, so every cell of sklearn_radar.experiments is checked against the paper itself.
PAPER_TABLES = Path(__file__).resolve().parents[1] / "data"


def _latex_rows(table):
    """The rows of Table ``table`` ("II", "III" or "IV"): the lines of its verbatim copy that are not comments."""
    text = (PAPER_TABLES / f"scheiner2019_table_{table.lower()}.tex").read_text(encoding="utf-8")
    return [line for line in text.splitlines() if line.strip() and not line.startswith("%")]


#: The paper's symbols as parameter names of RadarDBSCAN (Table III) and ClusterMerger (Table IV).
SYMBOLS = {
    r"\epsilon_{xy}": "eps_xy",
    r"\epsilon_{v_r}": "eps_vr",
    r"N_{\text{min}}": "min_samples",
    r"v_{r,\text{min}}": "vr_min",
    r"\epsilon_{xyv_r}": "eps_xyv",
    r"\epsilon^{'}_{v_r}": "vr_scale",
    r"N_\text{min,50}": "min_samples",
    r"\alpha_r": "alpha_r",
    r"\epsilon_{d}": "eps_d",
    r"\epsilon_{\phi}": "eps_phi",
    r"\epsilon_{v}": "eps_v",
    r"\epsilon_{t2}": "eps_t2",
    r"\epsilon_{\text{pred,min}}": "eps_d",
}
#: Equation labels of the paper's source and their numbers; the criterion equations name the metric.
EQUATIONS = {"filter_metric": 1, "min_pts": 2, "step1_1": 3, "step1_2": 4, "step1_3": 5}
METRICS = {3: "box", 4: "xy", 5: "xyv"}
#: The paper, on Table II: "The chosen setting of 0.1 m/s and 1.4 m velocity and distance thresholds".
CHOSEN_FILTER = {"vr_threshold": 0.10, "d_xy": 1.4}


def _value(text):
    number = re.search(r"\d+(\.\d+)?", text).group()
    return int(number) if "." not in number else float(number)


def _parse(lines, stage):
    """{number: {"frame", "equations", "v1", "params"}} from table rows of the paper's LaTeX source."""
    rows = {}
    for line in lines:
        cells = [cell.strip() for cell in re.split(r"(?<!\\)&", line.strip().removesuffix("\\\\"))]
        if stage == 1:
            _, number, _, cs, equations, v1, params = cells
        else:
            (_, number, method, v1, params), cs, equations = cells, "FCS", ""
        pairs = re.findall(r"\$(.+?)=(.+?)\$", params)
        setting = {SYMBOLS[symbol]: _value(value) for symbol, value in pairs}
        numbers = sorted(EQUATIONS[label] for label in re.findall(r"eq:(\w+)", equations))
        if stage == 1:  # the criterion's equation names the metric; no Eq. 2 means a fixed N_min
            setting = {"metric": METRICS[max(numbers)], **setting, "eps_t": 0.25}  # caption: eps_t = 0.25
            setting.setdefault("alpha_r", 0.0)
        elif int(number) >= 12:
            setting = {"mode": "velocity" if "velocity" in method else "continuation", **setting}
        rows[int(number)] = {
            "frame": "car" if "CCS" in cs else "frame",
            "equations": tuple(numbers),
            "v1": _value(v1),
            "params": setting,
        }
    return rows


PAPER = _parse(_latex_rows("III"), 1)
PAPER_STAGE2 = _parse(_latex_rows("IV"), 2)


def _in_package_units(number):
    """The paper's setting in the package's units: eps_phi in radians (the paper prints degrees)."""
    params = dict(PAPER[number]["params"] if number < 12 else PAPER_STAGE2[number]["params"])
    if "eps_phi" in params:
        params["eps_phi"] = math.radians(params["eps_phi"])
    return params


def _hand_built(number):
    """Experiment ``number`` assembled by hand from the parsed tables: frame, filter flag, estimator."""
    base = PAPER[number if number < 12 else 8]  # Table IV: stage 2 starts from "Step 1 -- best setting", #8
    stage1 = RadarDBSCAN(**base["params"])
    last = ("cluster", stage1) if number < 12 else ("merge", ClusterMerger(**_in_package_units(number), stage1=stage1))
    filtered = 1 in base["equations"]
    return Pipeline(
        [
            ("frame", FrameTransform(frame=base["frame"])),
            ("filter", DopplerDensityFilter(**CHOSEN_FILTER) if filtered else "passthrough"),
            last,
        ]
    )


@pytest.fixture(scope="module")
def tiny():
    return make_scenes(n_sequences=1, duration=3.0, random_state=1).data


def test_the_latex_excerpt_parses_into_every_experiment():
    assert sorted(PAPER) == list(range(1, 12)) and sorted(PAPER_STAGE2) == [3, 8, 12, 13]
    assert list(paper_experiments().index) == [e.number for e in PAPER_EXPERIMENTS] == list(range(1, 14))
    assert PAPER[8]["params"] == {
        "metric": "xyv",
        "eps_xyv": 1.04,
        "vr_scale": 1.03,
        "min_samples": 3.87,
        "vr_min": 1.00,
        "alpha_r": 0.99,
        "eps_t": 0.25,
    }  # the parser itself, one row by hand
    # Table IV repeats the two stage-1 bases of Table III.
    for number in (3, 8):
        assert PAPER_STAGE2[number]["params"].items() <= PAPER[number]["params"].items()
        assert PAPER_STAGE2[number]["v1"] == PAPER[number]["v1"]


@pytest.mark.parametrize("number", range(1, 14))
def test_tables_are_the_papers(number):
    experiment, row = get_experiment(number), PAPER[number] if number < 12 else PAPER_STAGE2[number]
    assert experiment.number == number
    assert experiment.v1_percent == row["v1"]
    assert experiment.frame == row["frame"]
    assert experiment.params == _in_package_units(number)  # eps_phi: degrees -> radians
    step = "cluster" if number < 12 else "merge"
    assert paper_params(number) == {f"{step}__{key}": value for key, value in experiment.params.items()}
    table = paper_experiments()
    assert table.loc[number, "v1_percent"] == row["v1"] and table.loc[number, "frame"] == row["frame"]
    if number < 12:
        assert experiment.stage == 1
        assert experiment.equations == row["equations"]
        assert experiment.filtered == (1 in row["equations"])
    else:
        assert experiment.stage == 2 and experiment.derived_from == 8
        assert experiment.filtered == (1 in PAPER[8]["equations"])  # stage 2 runs on #8's filtered data
    if number == 12:
        assert experiment.eps_phi_deg == PAPER_STAGE2[12]["params"]["eps_phi"] == 23.11


def test_only_the_expert_setting_and_the_transfers_of_8_are_untuned():
    # Table III: #1 is the expert setting; #10 and #11 reuse #8's optimum (identical numbers in Table III for
    # #10; #11 its eps values on the box criterion).  Everything else was optimised.
    assert PAPER[10]["params"] == PAPER[8]["params"]
    assert (PAPER[11]["params"]["eps_xy"], PAPER[11]["params"]["eps_vr"]) == (
        PAPER[8]["params"]["eps_xyv"],
        PAPER[8]["params"]["vr_scale"],
    )
    assert [e.number for e in PAPER_EXPERIMENTS if not e.tuned] == FIXED == [1, 10, 11]
    assert list(paper_experiments().index[~paper_experiments()["tuned"]]) == FIXED


def test_expert_setting_is_radar_dbscans_default():
    expert = PAPER[1]["params"]  # Table III, #1
    assert {key: RadarDBSCAN().get_params()[key] for key in expert} == expert
    assert experiment_pipeline(1).named_steps["cluster"].get_params() == RadarDBSCAN().get_params()


def test_fixed_experiments_derive_from_8():
    assert search_space(1) == search_space(10) == search_space(11) == {}
    assert derived_params(10) == paper_params(10) == paper_params(8)
    assert derived_params(11) == paper_params(11)
    tuned = {"cluster__eps_xyv": 1.3, "cluster__vr_scale": 2.5, "cluster__min_samples": 3.4, "cluster__vr_min": 0.7}
    transferred = derived_params(11, tuned)
    assert (transferred["cluster__eps_xy"], transferred["cluster__eps_vr"], transferred["cluster__min_samples"]) == (
        1.3,
        2.5,
        3,
    )
    assert transferred["cluster__metric"] == "box" and transferred["cluster__alpha_r"] == 0.0
    experiment_pipeline(11, params=transferred)  # valid pipeline parameters
    with pytest.raises(ValueError, match="10 and 11"):
        derived_params(8)


@pytest.mark.parametrize("number", TUNED)
def test_search_space_contains_the_papers_optimum(number):
    space = search_space(number)
    step = "cluster" if number < 12 else "merge"
    assert set(space) == {f"{step}__{name}" for name in OPTIMISED[number]}
    optimum = paper_params(number)
    for key, dimension in space.items():
        low, high = dimension.bounds
        value = optimum[key]
        assert low <= value <= high, (key, value, dimension)
        assert value in dimension
        if isinstance(dimension, Integer):
            assert isinstance(value, Integral)
        assert dimension.name == key


def test_min_samples_is_integer_for_fixed_and_real_for_range_adaptive_n_min():
    for number in (2, 3, 4, 5, 6):
        assert isinstance(search_space(number)["cluster__min_samples"], Integer)
    for number in (7, 8, 9):
        assert search_space(number)["cluster__min_samples"].bounds == (1.5, 8.0)
        assert not isinstance(search_space(number)["cluster__min_samples"], Integer)


@pytest.mark.parametrize("number", TUNED)
def test_sampled_points_are_valid_pipeline_parameters(number, tiny):
    # A sampled point changes exactly the searched parameters: the result is that of the hand-built
    # pipeline (paper setting from the LaTeX tables) with the same point set.
    space = search_space(number)
    rng = np.random.RandomState(number)
    for _ in range(2):
        point = {key: dimension.rvs(random_state=rng)[0] for key, dimension in space.items()}
        pipeline = experiment_pipeline(number).set_params(**point)
        labels = clone(pipeline).fit_predict(tiny)
        np.testing.assert_array_equal(labels, _hand_built(number).set_params(**point).fit_predict(tiny))


@pytest.mark.parametrize("number", range(1, 14))
def test_pipeline_steps(number, tiny):
    experiment = get_experiment(number)
    pipeline = experiment_pipeline(number, n_jobs=2)
    assert [name for name, _ in pipeline.steps] == ["frame", "filter", "cluster" if number < 12 else "merge"]
    assert isinstance(pipeline.named_steps["frame"], FrameTransform)
    assert pipeline.named_steps["frame"].frame == experiment.frame
    filter_step = pipeline.named_steps["filter"]
    if experiment.filtered:
        assert isinstance(filter_step, DopplerDensityFilter) and filter_step.n_jobs == 2
        assert (filter_step.vr_threshold, filter_step.d_xy) == (0.10, 1.4)
    else:
        assert filter_step == "passthrough"
    last = pipeline.steps[-1][1]
    setting = _in_package_units(number)
    if number < 12:
        assert isinstance(last, RadarDBSCAN) and last.n_jobs == 2
        assert {k: last.get_params()[k] for k in setting} == setting
    else:
        assert isinstance(last, ClusterMerger) and isinstance(last.stage1, RadarDBSCAN)
        assert {k: last.get_params()[k] for k in setting} == setting
        assert {k: last.stage1.get_params()[k] for k in PAPER[8]["params"]} == PAPER[8]["params"]
    # The same labels as the experiment assembled by hand from the paper's tables.
    labels = pipeline.fit_predict(tiny)
    np.testing.assert_array_equal(labels, _hand_built(number).fit_predict(tiny))
    assert labels.max() >= 5  # a case with clusters to tell apart


def test_memory_reaches_pipeline_and_cluster_merger(tmp_path):
    assert experiment_pipeline(3, memory=str(tmp_path)).memory == str(tmp_path)
    stage2 = experiment_pipeline(13, memory=str(tmp_path))
    assert stage2.memory == stage2.named_steps["merge"].memory == str(tmp_path)


def test_params_and_stage1_params():
    pipeline = experiment_pipeline(5, params={"cluster__eps_xy": 0.9, "filter__d_xy": 1.2})
    assert pipeline.named_steps["cluster"].eps_xy == 0.9 and pipeline.named_steps["filter"].d_xy == 1.2
    stage1 = {"cluster__metric": "box", "cluster__eps_xy": 0.6, "cluster__eps_vr": 12.3, "vr_min": 0.25}
    merger = experiment_pipeline(13, stage1_params=stage1).named_steps["merge"]
    assert merger.stage1.get_params() == RadarDBSCAN(metric="box", eps_xy=0.6, eps_vr=12.3, vr_min=0.25).get_params()
    with pytest.raises(ValueError, match="stage1_params"):
        experiment_pipeline(8, stage1_params=stage1)


@pytest.mark.parametrize("number", [0, 14, "8"])
def test_unknown_experiment_raises(number):
    with pytest.raises(ValueError, match="number"):
        experiment_pipeline(number)
    with pytest.raises(ValueError, match="number"):
        search_space(number)
