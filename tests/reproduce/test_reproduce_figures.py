"""The report's figures show what their captions say: the filter's removals on top and zoomed, values on the bars,
one colour per road user across the scene's panels, readable convergence curves."""

from pathlib import Path
from types import SimpleNamespace

import matplotlib.pyplot as plt
import numpy as np
import pytest

from sklearn_radar.reproduce._context import RunContext
from sklearn_radar.reproduce._results import RunResults
from sklearn_radar.reproduce._sequences import RunSequences

DEFAULT_RUN = Path(__file__).parents[1] / "data" / "results_default_run.json"


@pytest.fixture(scope="module")
def sequences(tiny_folder):
    return RunSequences.from_folder(tiny_folder)


def _removed_objects(sequence):
    """Which detections of moving road users the filter at the paper's setting removes (the filter run here)."""
    from sklearn_radar.preprocessing import DopplerDensityFilter, FrameTransform
    from sklearn_radar.reproduce._sections._filter import CHOSEN

    prepared = FrameTransform(frame="frame").fit_transform(sequence.scenes.data)
    keep = DopplerDensityFilter(vr_threshold=CHOSEN[0], d_xy=CHOSEN[1]).fit_transform(prepared)["keep"].to_numpy()
    return prepared, ~keep.astype(bool) & (np.asarray(sequence.scenes.target) >= 0)


def test_the_removed_road_user_detections_are_on_top_large_in_their_own_colour_and_zoomed(sequences):
    from sklearn_radar.reproduce._sections._filter import filter_scene_figure

    number = max(sequences.ids, key=lambda n: _removed_objects(sequences.fetch(n))[1].sum())
    prepared, removed = _removed_objects(sequences.fetch(number))
    assert removed.sum() > 0
    fig = filter_scene_figure(RunContext(sequences=sequences, drawn_sequence=number))
    overview, zoom = fig.axes
    for ax in (overview, zoom):
        (mine,) = [c for c in ax.collections if c.get_label() == "removed, moving road users"]
        others = [c for c in ax.collections if c is not mine]
        assert len(others) == 3 and mine.get_zorder() > max(c.get_zorder() for c in others)
        assert len(mine.get_offsets()) == removed.sum()
        assert min(mine.get_sizes()) >= 40 > max(max(c.get_sizes()) for c in others)
        colour = tuple(mine.get_facecolor()[0])
        assert all(colour not in {tuple(f) for f in c.get_facecolor()} for c in others)
    (x0, x1), (y0, y1) = zoom.get_xlim(), zoom.get_ylim()
    x, y = prepared["x"].to_numpy()[removed], prepared["y"].to_numpy()[removed]
    assert x0 < x.min() and x.max() < x1 and y0 < y.min() and y.max() < y1  # the zoom holds every removed one
    assert (x1 - x0) < 0.8 * np.ptp(overview.get_xlim()) or (y1 - y0) < 0.8 * np.ptp(overview.get_ylim())
    assert [p.get_linestyle() for p in overview.patches] == ["--"]  # the zoom's area marked on the overview
    plt.close(fig)


def _bars_results(repeats):
    """Results of three experiments as the V1 bars read them: test V1 per repeat and the paper's V1 (%)."""
    scores = {3: [0.50, 0.54, 0.52], 8: [0.61, 0.60, 0.62], 13: [0.70, 0.70, 0.70]}
    paper = {3: 69.2, 8: 71.55, 13: 71.8}
    experiments = {
        number: SimpleNamespace(
            number=number,
            paper_v1_percent=paper[number],
            v1_test=values[0],
            repeats=[SimpleNamespace(v1_test=v) for v in values[:repeats]] if repeats > 1 else None,
            search=None,
            derived_from_8=None,
        )
        for number, values in scores.items()
    }
    return SimpleNamespace(meta=SimpleNamespace(repeats=repeats), experiments=experiments), scores, paper


@pytest.mark.parametrize("repeats", [1, 3])
def test_every_v1_bar_has_its_value_written_and_repeats_have_error_bars(repeats):
    from sklearn_radar.reproduce._sections._figures import v1_bars_figure

    results, scores, paper = _bars_results(repeats)
    fig = v1_bars_figure(results)
    (ax,) = fig.axes
    written = sorted(text.get_text() for text in ax.texts)
    if repeats == 1:
        ours = [f"{100 * values[0]:.2f}" for values in scores.values()]
    else:
        ours = [f"{100 * np.mean(v):.2f} \u00b1 {100 * np.std(v, ddof=1):.2f}" for v in scores.values()]
    assert written == sorted(ours + [f"{value:.2f}" for value in paper.values()])  # as the tables print them
    error_bars = [c for c in ax.containers if type(c).__name__ == "ErrorbarContainer"]
    assert len(error_bars) == (repeats > 1)
    plt.close(fig)


def test_a_road_user_has_one_colour_in_every_panel_of_the_scene_and_no_two_share_one(sequences):
    """Clusters drawn in the colour of their majority road user, whatever their labels; the palette never repeats."""
    from sklearn_radar.reproduce._sections._figures import scene_figure

    number = sequences.ids[0]
    sequence = sequences.fetch(number)
    objects = np.asarray(sequence.scenes.target)
    target = np.asarray(sequence.target)
    times = sequence.scenes.data["timestamp"].to_numpy()
    late = times > np.median(times)
    # #3: one cluster per road user, numbered otherwise than the target; #8: each road user split in two by time.
    first = np.where(target >= 0, 1000 + objects, -1)
    second = np.where(target >= 0, 2 * objects + late, -1)
    results = SimpleNamespace(
        meta=SimpleNamespace(objective="v1"),
        experiments={3: SimpleNamespace(v1_test=0.5), 8: SimpleNamespace(v1_test=0.6)},
    )
    context = RunContext(sequences=sequences, drawn_sequence=number, labels={3: first, 8: second})
    fig = scene_figure(results, context)
    shown = np.unique(objects[target >= 0])
    assert len(shown) > 1
    rows = target >= 0
    for ax in fig.axes[1:]:  # the target and the two clusterings
        (coloured,) = [c for c in ax.collections if c.get_zorder() == 3]
        colours = [tuple(np.round(c[:3], 6)) for c in coloured.get_facecolor()]
        assert len(colours) == rows.sum()  # drawn in row order
        by_object = {k: {c for c, o in zip(colours, objects[rows], strict=True) if o == k} for k in shown}
        assert all(len(found) == 1 for found in by_object.values())
        if ax is fig.axes[1]:
            expected = by_object
        assert by_object == expected  # the same colour per road user in every panel
    assert len({next(iter(c)) for c in expected.values()}) == len(shown)  # no two road users alike
    plt.close(fig)
    from sklearn_radar.reproduce._sections._figures import distinct_colours

    for n in (5, 20, 54, 80):
        palette = distinct_colours(n)
        assert len(set(palette)) == n and all(max(c) - min(c) > 0.05 for c in palette)  # distinct, none grey


def test_a_cluster_takes_the_colour_of_the_road_user_most_of_its_detections_belong_to():
    from sklearn_radar.reproduce._sections._figures import majority_object

    labels = np.array([0, 0, 0, 0, 1, 1, 2, -1, 3])
    objects = np.array([7, 7, 9, -1, 9, 9, -1, 7, 4])
    target = np.array([0, 0, 1, -1, 1, 1, -1, 0, -1])  # object 4's detection left out by the pre-clustering
    # cluster 0: two of 7, one of 9 -> 7; cluster 1 -> 9; cluster 2 and 3: no road-user detection of the target
    np.testing.assert_array_equal(majority_object(labels, objects, target), [7, 7, 7, 7, 9, 9, -1, -1, -1])


def test_the_convergence_plot_keeps_the_width_and_names_the_curves_that_end_together():
    from sklearn_radar.reproduce._sections._figures import convergence_curves, convergence_figure

    results = RunResults.read(DEFAULT_RUN)
    curves = convergence_curves(results)
    together = {"#8": [[0.5, 0.79, 0.79]], "#12": [[0.6, 0.6, 0.79]], "#13": [[0.79, 0.79, 0.79]]}
    curves.update(together)
    fig = convergence_figure(curves, results)
    fig.canvas.draw()
    for ax in fig.axes:
        assert ax.get_position().width > 0.7  # the legend below, not beside, the plot
    experiments = fig.axes[0]
    ends = [t.get_text() for t in experiments.texts]
    assert "#8, #12, #13: 79.00 %" in ends  # the three that end together, named together
    styles = {line.get_label().split()[0]: line.get_linestyle() for line in experiments.get_lines()}
    assert len({styles[name] for name in ("#12", "#13")}) == 2  # one on top of the other, told apart
    kept = [
        f"#{n}" for n, e in results.experiments.items() if e.search is not None and e.search.best_source != "search"
    ]
    assert kept == ["#12"]  # the paper's setting kept: the curve ends below the table's CV score
    labels = [line.get_label() for line in experiments.get_lines()]
    assert "#12 \u2020" in labels and "#13" in labels
    plt.close(fig)
