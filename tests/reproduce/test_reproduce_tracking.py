"""The reproduce run's tracking step: the settings streamed online with a tuned Tracker, a baseline tracker."""

import contextlib
import io
import json

import numpy as np
import pytest

import sklearn_radar.reproduce._learned as learned_step
from sklearn_radar.cli import main
from sklearn_radar.datasets import load_radarscenes
from sklearn_radar.experiments import experiment_pipeline, object_pipeline
from sklearn_radar.experiments._learned import load_learned
from sklearn_radar.metrics import hota_scores, tracking_scores
from sklearn_radar.online import OnlinePipeline, Tracker
from sklearn_radar.online._replay import replay
from sklearn_radar.reproduce._baseline_tracker import NearestCentroidTracker
from sklearn_radar.reproduce._results import RunResults
from sklearn_radar.reproduce._tracking import TRACKER_GRID, candidates, fixed_frame, run_tracker


@pytest.fixture(scope="module")
def tracked(tiny_folder, tmp_path_factory):
    """A run of objects, #1, #13 and the tracking step: #1 and #13 stream the run's settings, #8 and #12 the paper's."""
    out = tmp_path_factory.mktemp("tracking") / "out"
    with contextlib.redirect_stdout(io.StringIO()):
        code = main(
            [
                "reproduce",
                "--data",
                str(tiny_folder),
                "--out",
                str(out),
                "--n-iter",
                "2",
                "--experiments",
                "objects,1,13,tracking",
            ]
        )
    assert code == 0
    return out


@pytest.fixture(scope="module")
def tracked_learned(tiny_folder, tmp_path_factory):
    """A run of objects, the learned grouping (few boosting iterations: the plumbing, not the model) and tracking."""
    out = tmp_path_factory.mktemp("tracking_learned") / "out"
    patch = pytest.MonkeyPatch()
    patch.setattr(learned_step, "LEARNED_PARAMS", {"link__max_iter": 10})
    args = ["reproduce", "--data", str(tiny_folder), "--out", str(out), "--n-iter", "2"]
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            assert main([*args, "--experiments", "objects,learned,tracking"]) == 0
    finally:
        patch.undo()
    return out


def _replayed(scenes, sequences, pipeline, tracker=None):
    """The final object ids (and track ids with a tracker) of ``sequences`` streamed one at a time, and their rows."""
    ids, tracks, rows = [], [], []
    for number in sequences:
        part = np.flatnonzero(scenes.data["sequence"].to_numpy() == number)
        replayed = replay(OnlinePipeline(pipeline, tracker=tracker), scenes.data.iloc[part])
        ids.append(replayed["object_ids"])
        tracks.append(replayed["track_id"])
        rows.append(part)
    return np.concatenate(ids), None if tracker is None else np.concatenate(tracks), np.concatenate(rows)


def _scores(scenes, rows, ids):
    inputs = {
        "times": scenes.data["timestamp"].to_numpy()[rows] * 1e-6,
        "groups": scenes.data["sequence"].to_numpy()[rows],
        "window": 0.5,
    }
    truth = np.asarray(scenes.target)[rows]
    return tracking_scores(truth, ids, **inputs) | hota_scores(truth, ids, **inputs)


def test_the_step_streams_the_object_setting_first_then_the_papers(tracked):
    results = json.loads((tracked / "results.json").read_text())
    assert results["meta"]["completed"] == ["1", "13", "objects", "tracking"]
    settings = results["tracking"]["settings"]
    assert list(settings) == ["objects", "1", "8", "12", "13"]
    sources = {key: entry["setting_source"] for key, entry in settings.items()}
    assert sources == {
        "objects": "tuned for PQ",
        "1": "fixed #1",
        "8": "paper's #8",
        "12": "paper's #12",
        "13": "tuned #13",
    }
    for entry in settings.values():
        for scores in (entry["reported"], entry["final"], entry["tracked"]):
            assert 0.0 <= scores["idf1"] <= 1.0 and scores["mota"] <= 1.0
            assert scores["n_matches"] + scores["misses"] == scores["n_objects"] > 0
        for scores in (entry["reported"], entry["tracked"]):
            assert 0.0 <= scores["assa"] <= 1.0 and 0.0 <= scores["deta"] <= 1.0
    assert settings["13"]["params"] == {
        **results["experiments"]["13"]["stage1_params"],
        **results["experiments"]["13"]["params"],
    }
    assert settings["objects"]["params"] == {**results["objects"]["stage1_params"], **results["objects"]["params"]}


def test_the_scores_are_those_of_the_whole_test_half(tracked, tiny_folder):
    """Summed per sequence = tracking_scores and hota_scores over all test sequences at once, with the Tracker."""
    results = RunResults.read(tracked / "results.json")
    test = results.meta.data.test_sequences
    scenes = load_radarscenes(tiny_folder)
    entry = results.tracking.settings["1"]
    tracker = Tracker(**results.tracking.tracker.params)
    final, tracks, rows = _replayed(scenes, test, experiment_pipeline(1, params=entry.params), tracker)
    for ids, found in ((final, entry.final), (tracks, entry.tracked)):
        expected = _scores(scenes, rows, ids)
        assert (found.idf1, found.mota, found.id_switches, found.n_objects) == pytest.approx(
            (expected["idf1"], expected["mota"], expected["id_switches"], expected["n_objects"]), abs=1e-12
        )
    expected = _scores(scenes, rows, tracks)
    assert (entry.tracked.hota, entry.tracked.deta, entry.tracked.assa) == pytest.approx(
        (expected["hota"], expected["deta"], expected["assa"]), abs=1e-12
    )


def test_the_tracker_is_the_best_of_its_grid_on_the_training_half(tracked, tiny_folder):
    """Each candidate streamed through OnlinePipeline(tracker=...) on the training half: the chosen one has the best
    training MOTA, the one recorded; the test half plays no part."""
    results = RunResults.read(tracked / "results.json")
    scenes = load_radarscenes(tiny_folder)
    chosen = results.tracking.tracker
    assert chosen.tuned_on == "objects" and chosen.criterion == "MOTA"
    objects = results.objects.kept
    pipeline = object_pipeline(2, stage1_params=objects.stage1_params, params=objects.params)
    train = results.meta.data.train_sequences
    found = []
    for candidate in candidates(TRACKER_GRID):
        _, tracks, rows = _replayed(scenes, train, pipeline, Tracker(**candidate))
        found.append(_scores(scenes, rows, tracks)["mota"])
    assert chosen.n_candidates == len(found)
    assert chosen.train_score == pytest.approx(max(found), abs=1e-12)
    assert chosen.params == candidates(TRACKER_GRID)[int(np.argmax(found))]


def test_params_json_saves_the_tuned_tracker(tracked):
    saved = json.loads((tracked / "params.json").read_text())
    results = json.loads((tracked / "results.json").read_text())
    assert saved["tracker"] == results["tracking"]["tracker"]
    Tracker(**saved["tracker"]["params"])  # valid parameters


def test_the_report_leads_with_the_object_setting_and_the_baseline(tracked):
    report = (tracked / "report.md").read_text()
    assert "## Beyond the paper: object tracking online" in report
    section = report.split("## Beyond the paper: object tracking online")[1].split("\n## ")[0]
    rows = [line for line in section.splitlines() if line.startswith("| ") and not line.startswith("| setting")]
    names = [row.split("|")[1].strip() for row in rows]
    assert names[0].startswith("objects (tuned for PQ)")
    baseline = next(i for i, name in enumerate(names) if name.startswith("baseline: SlidingDBSCAN"))
    first_paper = next(i for i, name in enumerate(names) if name.startswith("#"))
    assert baseline < first_paper
    assert "(tuned #13)" in section and "(paper's #8)" in section
    assert "most of their clusters are static background" in section
    assert "on the objects setting's ids" in section and "The run has no object experiment" not in section
    assert "![tracks](tracks.png)" in section and (tracked / "tracks.png").is_file()
    glance = report.split("## At a glance")[1].split("\n## ")[0]
    assert "tracking online, test half:" in glance and "the baseline tracker (SlidingDBSCAN" in glance


def test_the_learned_grouping_streams_its_saved_causal_model_with_its_tuned_tracker(tracked_learned, tiny_folder):
    """The causal model the learned step saved, replayed here on the test half with the Tracker tuned on its own
    training ids: the recorded scores are its ids'; it comes second, after the object setting."""
    results = RunResults.read(tracked_learned / "results.json")
    settings = results.tracking.settings
    assert list(settings) == ["objects", "learned", "1", "8", "12", "13"]
    entry = settings["learned"]
    assert entry.number is None and entry.method == "learned"
    assert entry.setting_source == "causal, fitted on the training half"
    assert entry.params["link__causal"] is True and entry.params["filter__causal"] is True
    assert entry.params["link__max_iter"] == 10
    assert results.tracking.tracker.tuned_on == "objects"
    assert results.tracking.learned_tracker.tuned_on == "learned"
    model = load_learned(tracked_learned / results.learned.causal.model_file)
    scenes = load_radarscenes(tiny_folder)
    tracker = Tracker(**results.tracking.learned_tracker.params)
    final, tracks, rows = _replayed(scenes, results.meta.data.test_sequences, model, tracker)
    for ids, found in ((final, entry.final), (tracks, entry.tracked)):
        expected = _scores(scenes, rows, ids)
        assert (found.idf1, found.mota, found.id_switches, found.n_objects) == pytest.approx(
            (expected["idf1"], expected["mota"], expected["id_switches"], expected["n_objects"]), abs=1e-12
        )
    assert entry.tracked.hota == pytest.approx(_scores(scenes, rows, tracks)["hota"], abs=1e-12)


def test_the_learned_tracker_is_the_best_of_its_grid_on_the_learned_stream_of_the_training_half(
    tracked_learned, tiny_folder
):
    results = RunResults.read(tracked_learned / "results.json")
    chosen = results.tracking.learned_tracker
    model = load_learned(tracked_learned / results.learned.causal.model_file)
    scenes = load_radarscenes(tiny_folder)
    found = []
    for candidate in candidates(TRACKER_GRID):
        _, tracks, rows = _replayed(scenes, results.meta.data.train_sequences, model, Tracker(**candidate))
        found.append(_scores(scenes, rows, tracks)["mota"])
    assert chosen.criterion == "MOTA" and chosen.n_candidates == len(found)
    assert chosen.train_score == pytest.approx(max(found), abs=1e-12)
    assert chosen.params == candidates(TRACKER_GRID)[int(np.argmax(found))]


def test_the_report_names_the_tracked_learned_grouping(tracked_learned):
    report = (tracked_learned / "report.md").read_text()
    section = report.split("## Beyond the paper: object tracking online")[1].split("\n## ")[0]
    rows = [row for row in section.splitlines() if row.startswith("| ") and not row.startswith("| setting")]
    names = [row.split("|")[1].strip() for row in rows]
    ours = names[: next(i for i, name in enumerate(names) if name.startswith("baseline: SlidingDBSCAN"))]
    assert ours[0].startswith("objects (tuned for PQ)")
    assert "learned (causal, fitted on the training half)" in ours
    assert "with a Tracker chosen the same way on that stream's training-half ids" in section
    assert "the Tracker follows its confirmed clusters only" in section
    glance = report.split("## At a glance")[1].split("\n## ")[0]
    line = next(line for line in glance.splitlines() if "tracking online, test half:" in line)
    assert "learned" in line


def test_the_tracking_table_names_what_its_count_of_objects_counts(tracked):
    """The MOTA denominator, objects summed over frames: not the data section's object instances, and said so."""
    results = RunResults.read(tracked / "results.json")
    report = (tracked / "report.md").read_text()
    section = report.split("## Beyond the paper: object tracking online")[1].split("\n## ")[0]
    header = next(line for line in section.splitlines() if line.startswith("| setting |"))
    columns = [cell.strip() for cell in header.strip("|").split("|")]
    assert "objects" not in columns and "object-windows" in columns
    assert "*object-windows* counts each annotated moving road user once in every 0.5 s window it is seen in" in section
    for number, result in results.tracking.settings.items():
        if not number.isdigit():
            continue
        row = next(line for line in section.splitlines() if line.startswith(f"| #{number} ") and "| final |" in line)
        cells = [cell.strip() for cell in row.strip("|").split("|")]
        assert cells[columns.index("object-windows")] == str(result.final.n_objects)


def test_the_offline_tracker_feed_is_the_online_pipelines(tiny_folder):
    """The tuning feeds the Tracker the fixed-frame columns itself: the same ids as OnlinePipeline(tracker=...)."""
    scenes = load_radarscenes(tiny_folder)
    rows = np.flatnonzero(scenes.data["sequence"].to_numpy() == scenes.data["sequence"].iloc[0])
    data = scenes.data.iloc[rows].reset_index(drop=True)
    pipeline = experiment_pipeline(1)
    params = {"min_hits": 2, "max_age": 1.0, "gate": 5.0}
    online = replay(OnlinePipeline(pipeline, tracker=Tracker(**params)), data)
    offline = run_tracker(Tracker(**params), fixed_frame(data), online["reported"])
    assert (online["track_id"] >= 0).any()
    np.testing.assert_array_equal(offline, online["track_id"])


def test_the_offline_tracker_feed_of_the_learned_grouping_is_the_online_pipelines(tracked_learned, tiny_folder):
    """With the learned grouping the Tracker follows the confirmed clusters only; the tuning feeds it the same."""
    results = RunResults.read(tracked_learned / "results.json")
    model = load_learned(tracked_learned / results.learned.causal.model_file)
    scenes = load_radarscenes(tiny_folder)
    rows = np.flatnonzero(scenes.data["sequence"].to_numpy() == scenes.data["sequence"].iloc[0])
    data = scenes.data.iloc[rows].reset_index(drop=True)
    params = {"min_hits": 2, "max_age": 1.0, "gate": 5.0}
    online = replay(OnlinePipeline(model, tracker=Tracker(**params)), data)
    assert np.any((online["reported"] >= 0) & ~online["confirmed"])  # some clusters are not followed
    np.testing.assert_array_equal(online["followed"], np.where(online["confirmed"], online["reported"], -1))
    offline = run_tracker(Tracker(**params), fixed_frame(data), online["followed"])
    assert (online["track_id"] >= 0).any()
    np.testing.assert_array_equal(offline, online["track_id"])


def test_the_baseline_tracker_follows_two_objects_and_confirms_after_min_hits():
    tracker = NearestCentroidTracker(gate=1.0, min_hits=2, max_age=0.5)
    x0 = np.array([0.0, 0.2, 10.0, 10.2])
    ids = []
    for k in range(4):  # two objects 10 m apart, moving 0.3 m per scan (inside the gate), new cluster ids each scan
        ids.append(tracker.update(x0 + 0.3 * k, np.zeros(4), 0.1 * k, np.array([0, 0, 1, 1]) + 2 * k))
    assert (ids[0] == -1).all()  # not confirmed after one scan
    assert ids[1][0] == ids[1][1] != ids[1][2] == ids[1][3] >= 0
    for later in ids[2:]:
        np.testing.assert_array_equal(later, ids[1])
    far = tracker.update(np.array([30.0]), np.zeros(1), 0.4, np.array([0]))  # outside every gate: a new track
    assert far[0] == -1
    gone = tracker.update(x0 + 0.3 * 3, np.zeros(4), 1.5, np.array([0, 0, 1, 1]))  # after max_age: new tracks
    assert (gone == -1).all()


def test_results_without_tracking_still_load():
    """Older results files have no 'tracking' key: it reads as None and the section is left out."""
    from pathlib import Path

    from sklearn_radar.reproduce._sections import _tracking

    for path in sorted((Path(__file__).parents[1] / "data").glob("results_*.json")):
        results = RunResults.read(path)
        assert results.tracking is None
        assert _tracking.markdown(results) == []


def test_the_tuning_sentence_says_defaults_only_when_no_tracker_was_tuned():
    from types import SimpleNamespace

    from sklearn_radar.reproduce._sections._tracking import _tuned_lines

    tuned = SimpleNamespace(
        tuned_on="objects", criterion="MOTA", n_candidates=12, params={"min_hits": 8}, train_score=0.1
    )
    learned = SimpleNamespace(criterion="MOTA", params={"min_hits": 3}, train_score=0.2)
    untuned = _tuned_lines(SimpleNamespace(tracker=None, learned_tracker=learned, baseline=None))[0]
    assert "The run has no object experiment" in untuned and "min_hits=3" in untuned
    both = _tuned_lines(SimpleNamespace(tracker=tuned, learned_tracker=None, baseline=None))[0]
    assert "on the objects setting's ids" in both and "The run has no object experiment" not in both
