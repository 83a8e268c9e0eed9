"""Filter evaluation (Tables I and II of Scheiner et al. 2019): hand-made cases and
agreement with DopplerDensityFilter run directly."""

import re
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from sklearn_radar import DopplerDensityFilter, FrameTransform
from sklearn_radar.datasets import make_scenes
from sklearn_radar.evaluation import (
    PAPER_TABLE_II,
    FilterEvaluationOptions,
    filter_error_windows,
    filter_errors,
    filter_grid,
    filter_removal_rates,
    filter_settings_table,
    plot_filter_errors,
)

VR_SUBSET = (0.05, 0.10, 0.35)
D_SUBSET = (0.8, 1.4, 2.0)


def _options(vr_thresholds=VR_SUBSET, d_xys=D_SUBSET, **options):
    return FilterEvaluationOptions(vr_thresholds=vr_thresholds, d_xys=d_xys, **options)


# ----------------------------------------------------------------------------
# Removal rates
# ----------------------------------------------------------------------------
def test_removal_rates_hand_made():
    keep = np.array([False, True, True, False, False, True, True, True])
    target = np.array([-1, -1, -1, -1, 0, 0, 5, 5])
    rates = filter_removal_rates(keep, target)
    # background: rows 0..3, removed rows 0 and 3 -> 2/4; objects: rows 4..7, removed row 4 -> 1/4
    assert rates["background_removed"] == pytest.approx(2 / 4)
    assert rates["objects_removed"] == pytest.approx(1 / 4)
    assert rates["n_background"] == 4
    assert rates["n_objects"] == 4


def test_removal_rates_empty_groups_are_zero_not_nan():
    only_background = filter_removal_rates([False, True, False], [-1, -1, -1])
    assert only_background["objects_removed"] == 0.0 and only_background["n_objects"] == 0
    assert only_background["background_removed"] == pytest.approx(2 / 3)
    only_objects = filter_removal_rates(np.array([1, 1, 0]), [2, 2, 4])  # 0/1 accepted as keep
    assert only_objects["background_removed"] == 0.0 and only_objects["n_background"] == 0
    assert only_objects["objects_removed"] == pytest.approx(1 / 3)


def test_removal_rates_reject_bad_input():
    with pytest.raises(ValueError, match="lengths"):
        filter_removal_rates([True, False], [-1])
    with pytest.raises(ValueError, match="boolean"):
        filter_removal_rates([0.5, 1.0], [-1, 0])


# ----------------------------------------------------------------------------
# Errors on hand-made times (window 0.15 s, min_kept 0.75)
# ----------------------------------------------------------------------------
def _hand_made():
    """Rows of (target, t, keep); expected windows are counted in the comments."""
    rows = []
    # Object 0, t0 = 0.00, t1 = 0.50 -> complete windows k = 0, 1, 2 (0.45 <= 0.50; 0.60 > 0.50).
    #   k=0 [0.00, 0.15): 4 detections, 3 kept -> 75 % exactly -> not an error
    rows += [(0, t, kept) for t, kept in zip((0.00, 0.03, 0.06, 0.09), (True, True, False, True), strict=True)]
    #   k=1 [0.15, 0.30): 50 detections, 37 kept -> 74 % -> error
    times = np.linspace(0.16, 0.28, 50)
    rows += [(0, t, i < 37) for i, t in enumerate(times)]
    #   k=2 [0.30, 0.45): 2 detections, none kept -> error
    rows += [(0, 0.31, False), (0, 0.40, False)]
    #   incomplete [0.45, 0.60): 0/2 kept, ignored
    rows += [(0, 0.46, False), (0, 0.50, False)]
    # Object 7: present 0.14 s < 0.15 s -> no window although nothing is kept.
    rows += [(7, t, False) for t in (2.00, 2.05, 2.10, 2.14)]
    # Object 3, t0 = 1.00, t1 = 1.15: exactly one complete window [1.00, 1.15) holding
    #   1.00 (removed) and 1.10 (kept) -> 1/2 -> error; 1.15 starts the next (incomplete) window.
    rows += [(3, 1.00, False), (3, 1.10, True), (3, 1.15, False)]
    # Background, all removed and interleaved: never counted.
    rows += [(-1, t, False) for t in (0.0, 0.2, 1.05, 2.02)]
    target, t, keep = (np.array(column) for column in zip(*rows, strict=True))
    order = np.random.default_rng(0).permutation(len(target))  # order must not matter
    return keep.astype(bool)[order], target.astype(int)[order], t.astype(float)[order]


def test_filter_errors_hand_made():
    keep, target, t = _hand_made()
    # object 0: windows 1 and 2; object 3: its one window; object 7: none
    assert filter_errors(keep, target, t) == 2 + 1


def test_filter_error_windows_hand_made():
    keep, target, t = _hand_made()
    windows = filter_error_windows(keep, target, t)
    assert list(windows.columns) == ["instance", "start_s", "n", "kept", "kept_share", "error"]
    assert windows["instance"].tolist() == [0, 0, 0, 3]
    np.testing.assert_allclose(windows["start_s"], [0.00, 0.15, 0.30, 1.00], atol=1e-12)
    assert windows["n"].tolist() == [4, 50, 2, 2]
    assert windows["kept"].tolist() == [3, 37, 0, 1]
    np.testing.assert_allclose(windows["kept_share"], [0.75, 0.74, 0.0, 0.5])
    assert windows["error"].tolist() == [False, True, True, True]


def test_filter_errors_edges_and_parameters():
    # Duration exactly one window: counted (complete); just under: not counted.
    t_exact = np.array([10.00, 10.05, 10.15])
    assert filter_errors([False, False, False], [1, 1, 1], t_exact) == 1
    assert filter_errors([False, False, False], [1, 1, 1], t_exact - [0, 0, 0.001]) == 0
    # A stricter share turns the 75 % window into an error, a looser one clears the 74 % one.
    keep, target, t = _hand_made()
    assert filter_errors(keep, target, t, min_kept=0.76) == 4
    assert filter_errors(keep, target, t, min_kept=0.5) == 1 + 0  # only the 0/2 window (1/2 is not < 0.5)
    # A longer window: object 0 (0.50 s) gets 1 complete 0.3 s window [0, 0.3): 40/54 kept = 74 % -> error.
    assert filter_errors(keep, target, t, window=0.3) == 1
    assert filter_errors([], np.zeros(0, int), []) == 0
    assert len(filter_error_windows([True], [-1], [0.0])) == 0
    with pytest.raises(ValueError, match="window"):
        filter_errors(keep, target, t, window=0.0)
    with pytest.raises(ValueError, match="min_kept"):
        filter_errors(keep, target, t, min_kept=1.5)


def _reference_errors(keep, target, t, window=0.15, min_kept=0.75):
    """Loop-by-loop transcription of the rule, for cross-checks on random data."""
    errors = 0
    for instance in np.unique(target[target >= 0]):
        mine = target == instance
        t0, t1 = t[mine].min(), t[mine].max()
        k = 0
        while t0 + (k + 1) * window <= t1:
            inside = mine & (t >= t0 + k * window) & (t < t0 + (k + 1) * window)
            n = inside.sum()
            if n > 0 and keep[inside].sum() / n < min_kept:
                errors += 1
            k += 1
    return errors


def test_filter_errors_match_reference_on_random_data():
    rng = np.random.default_rng(1)
    n = 4000
    target = rng.integers(-1, 40, n)
    t = rng.uniform(0.0, 3.0, n)
    keep = rng.random(n) < 0.8
    expected = _reference_errors(keep, target, t)
    assert expected > 0
    assert filter_errors(keep, target, t) == expected


# ----------------------------------------------------------------------------
# Grid against DopplerDensityFilter run directly
# ----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def scenes():
    return make_scenes(n_sequences=2, duration=8.0, random_state=0)


@pytest.fixture(scope="module")
def grids(scenes):
    return {
        frame: filter_grid(scenes.data, scenes.target, _options(frame=frame, n_jobs=1)) for frame in ("frame", "car")
    }


def _direct(scenes, frame, vr_threshold, d_xy):
    Xt = FrameTransform(frame=frame).fit_transform(scenes.data)
    keep = DopplerDensityFilter(vr_threshold=vr_threshold, d_xy=d_xy).fit_transform(Xt)["keep"].to_numpy()
    return keep, Xt["t"].to_numpy()


@pytest.mark.parametrize("frame", ["frame", "car"])
@pytest.mark.parametrize("vr_threshold, d_xy", [(0.10, 1.4), (0.35, 0.8), (0.05, 2.0)])
def test_grid_equals_direct_filter(scenes, grids, frame, vr_threshold, d_xy):
    grid = grids[frame]
    keep, t = _direct(scenes, frame, vr_threshold, d_xy)
    target = scenes.target
    background = target == -1
    assert grid.errors.loc[vr_threshold, d_xy] == _reference_errors(keep, target, t)
    assert grid.background_removed.loc[vr_threshold, d_xy] == pytest.approx(np.mean(~keep[background]))
    assert grid.objects_removed.loc[vr_threshold, d_xy] == pytest.approx(np.mean(~keep[~background]))


def test_grid_layout(grids, scenes):
    grid = grids["frame"]
    assert grid.frame == "frame"
    for name in ("errors", "background_removed", "objects_removed"):
        table = grid[name]
        assert table.index.name == "vr_threshold" and table.columns.name == "d_xy"
        np.testing.assert_allclose(table.index, VR_SUBSET)
        np.testing.assert_allclose(table.columns, D_SUBSET)
    assert grid.errors.dtypes.map(lambda d: d.kind == "i").all()
    assert grid.n_background == int(np.sum(scenes.target == -1))
    assert grid.n_objects == int(np.sum(scenes.target >= 0))


@pytest.mark.parametrize("frame", ["frame", "car"])
def test_errors_monotone_in_vr_threshold(scenes, grids, frame):
    # By Eq. 1 a larger eta_1 removes a superset (the neighbour counts do not change) ...
    loose, _ = _direct(scenes, frame, 0.05, 1.4)
    strict, _ = _direct(scenes, frame, 0.35, 1.4)
    assert not np.any(strict & ~loose)  # removed at 0.05 m/s -> removed at 0.35 m/s
    assert np.sum(~strict) > np.sum(~loose)
    # ... so error counts and removal shares never fall as vr_threshold grows.
    grid = grids[frame]
    assert np.all(np.diff(grid.errors.to_numpy(), axis=0) >= 0)
    assert np.all(np.diff(grid.background_removed.to_numpy(), axis=0) >= 0)
    assert np.all(np.diff(grid.objects_removed.to_numpy(), axis=0) >= 0)


def test_grid_parallel_equals_serial(scenes, grids):
    parallel = filter_grid(scenes.data, scenes.target, _options(frame="car", n_jobs=2))
    for name in ("errors", "background_removed", "objects_removed"):
        pd.testing.assert_frame_equal(parallel[name], grids["car"][name])


def test_grid_verbose_prints_progress(scenes, capsys):
    filter_grid(scenes.data, scenes.target, _options((0.1,), (0.8, 1.4), frame="car", verbose=1))
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 2
    assert all(line.startswith("filter grid [car] d_xy=") for line in lines)
    assert any("d_xy=1.40 m" in line for line in lines)
    assert lines[-1].endswith("2/2 done")
    filter_grid(scenes.data, scenes.target, _options((0.1,), (0.8,), frame="car", verbose=0))
    assert capsys.readouterr().out == ""


def test_grid_rejects_bad_input(scenes):
    with pytest.raises(ValueError, match="DataFrame"):
        filter_grid(scenes.data.to_numpy(), scenes.target)
    with pytest.raises(ValueError, match="lengths"):
        filter_grid(scenes.data, scenes.target[:-1])
    with pytest.raises(ValueError, match="options"):
        filter_grid(scenes.data, scenes.target, {"frame": "car"})


@pytest.mark.parametrize(
    "options, message",
    [
        ({"d_xys": (0.0, 1.0)}, r"d_xys must be finite and > 0"),
        ({"vr_thresholds": (0.1, 0.1)}, "vr_thresholds must not repeat"),
        ({"vr_thresholds": ()}, "vr_thresholds must not be empty"),
        ({"min_neighbors": (2, 3)}, "equal length"),
        ({"min_neighbors": (2.5, 3, 4, 10)}, "min_neighbors must be integers"),
        ({"threshold_ratios": (1, 0, 10, 50)}, "threshold_ratios must be positive"),
        ({"frame": "world"}, "'frame' parameter of FilterEvaluationOptions"),
        ({"dt": -0.1}, "'dt' parameter"),
        ({"window": 0.0}, "'window' parameter"),
        ({"min_kept": 1.5}, "'min_kept' parameter"),
        ({"n_jobs": 1.5}, "'n_jobs' parameter"),
    ],
)
def test_options_are_checked_when_made(options, message):
    with pytest.raises(ValueError, match=message):
        FilterEvaluationOptions(**options)


def test_options_are_frozen_and_compare_by_what_changes_the_results():
    options = FilterEvaluationOptions(vr_thresholds=[0.1, 0.2], d_xys=np.array([1, 2]), threshold_ratios=(1, 5, 10, 50))
    assert options.vr_thresholds == (0.1, 0.2) and options.d_xys == (1.0, 2.0)
    assert options.threshold_ratios == (1.0, 5.0, 10.0, 50.0) and options.min_neighbors == (2, 3, 4, 10)
    same = FilterEvaluationOptions(vr_thresholds=(0.1, 0.2), d_xys=(1.0, 2.0), n_jobs=2, verbose=1)
    assert options == same and hash(options) == hash(same)
    assert options != FilterEvaluationOptions(vr_thresholds=(0.1, 0.2), d_xys=(1.0, 2.0), causal=True)
    with pytest.raises(AttributeError):
        options.frame = "car"


# ----------------------------------------------------------------------------
# Table II
# ----------------------------------------------------------------------------
#: Folder of the rows of Tables II-IV exactly as they stand in the paper's LaTeX source (copied, not retyped).
PAPER_TABLES = Path(__file__).resolve().parents[1] / "data"


def _latex_rows(table):
    """The rows of Table ``table`` ("II", "III" or "IV"): the lines of its verbatim copy that are not comments."""
    text = (PAPER_TABLES / f"scheiner2019_table_{table.lower()}.tex").read_text(encoding="utf-8")
    return [line for line in text.splitlines() if line.strip() and not line.startswith("%")]


def _number(cell):
    return re.search(r"\d+(\.\d+)?", cell).group()


def _parse_table_ii(lines):
    """(frame, vr_threshold m/s, d_xy m, removal rate %, errors) per row: the numbers of each cell, in order."""
    rows = []
    for line in lines:
        cs, vr, d, rate, errors = (cell.strip() for cell in line.strip().removesuffix("\\\\").split("&"))
        frame = "car" if "CCS" in cs else "frame"
        rows.append((frame, float(_number(vr)), float(_number(d)), float(_number(rate)), int(_number(errors))))
    return rows


def test_paper_table_ii():
    paper = _parse_table_ii(_latex_rows("II"))
    assert paper[1] == ("frame", 0.10, 1.4, 29.10, 0)  # the parser, on the bold (chosen) row, by hand
    assert list(PAPER_TABLE_II.columns) == ["frame", "vr_threshold", "d_xy", "paper_removal_rate", "paper_errors"]
    assert list(PAPER_TABLE_II.itertuples(index=False, name=None)) == paper
    assert PAPER_TABLE_II["paper_errors"].dtype.kind == "i"
    assert (DopplerDensityFilter().vr_threshold, DopplerDensityFilter().d_xy) == paper[1][1:3]  # the chosen setting


def test_settings_table(scenes):
    table = filter_settings_table(scenes.data, scenes.target)
    paper_columns = ["frame", "vr_threshold", "d_xy", "paper_removal_rate", "paper_errors"]
    assert list(table.columns) == [*paper_columns, "removal_rate", "object_removal_rate", "errors"]
    pd.testing.assert_frame_equal(table[paper_columns], PAPER_TABLE_II)
    assert table["removal_rate"].between(0, 100).all() and table["removal_rate"].gt(0).all()
    assert table["object_removal_rate"].between(0, 100).all()
    assert (table["errors"] >= 0).all() and table["errors"].dtype.kind == "i"
    # The CCS row against the filter run directly (percent).
    keep, t = _direct(scenes, "car", 0.10, 1.4)
    background = scenes.target == -1
    assert table.loc[0, "removal_rate"] == pytest.approx(100 * np.mean(~keep[background]))
    assert table.loc[0, "errors"] == _reference_errors(keep, scenes.target, t)


def test_settings_table_custom_settings(scenes):
    settings = pd.DataFrame({"vr_threshold": [0.05, 0.35], "d_xy": [2.0, 2.0], "note": ["a", "b"]})
    table = filter_settings_table(scenes.data, scenes.target, settings, _options(frame="car"))
    assert table["frame"].tolist() == ["car", "car"]
    assert table["note"].tolist() == ["a", "b"]
    assert table.loc[1, "removal_rate"] >= table.loc[0, "removal_rate"]  # larger eta_1 removes more
    with pytest.raises(ValueError, match="missing"):
        filter_settings_table(scenes.data, scenes.target, pd.DataFrame({"d_xy": [1.0]}))


# ----------------------------------------------------------------------------
# Plot
# ----------------------------------------------------------------------------
def test_plot_filter_errors():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    vr = pd.Index([0.05, 0.10, 0.15], name="vr_threshold")
    d = pd.Index([0.8, 1.0, 1.2, 1.4], name="d_xy")
    errors = pd.DataFrame(np.arange(12).reshape(3, 4), index=vr, columns=d)
    ax = plot_filter_errors(errors)
    texts = [text.get_text() for text in ax.texts]
    assert len(texts) == 12 + 1
    assert texts.count("*") == 1
    cells = {
        (text.get_position()[1], text.get_position()[0]): text.get_text() for text in ax.texts if text.get_text() != "*"
    }
    assert cells[(1, 3)] == "7"  # vr_threshold 0.10 (row 1), d_xy 1.4 (column 3)
    star = next(text for text in ax.texts if text.get_text() == "*")
    assert round(star.get_position()[0]) == 3 and round(star.get_position()[1]) == 1
    assert "m" in ax.get_xlabel() and "m/s" in ax.get_ylabel()
    assert len(ax.figure.axes) == 2  # the heatmap and its colour bar
    assert len(plot_filter_errors(errors, ax=plt.subplots()[1], chosen=None).texts) == 12
    assert ax.get_ylim()[0] > ax.get_ylim()[1]  # the first row (0.05) on top, as in a table
    assert ax.images[0].get_clim() == (0, 11)  # from 0 to the largest count
    shared = plot_filter_errors(errors, ax=plt.subplots()[1], vmax=50, colorbar=False)
    assert shared.images[0].get_clim() == (0, 50) and len(shared.figure.axes) == 1
    with pytest.raises(ValueError, match="chosen"):
        plot_filter_errors(errors, chosen=(0.3, 1.4))
    plt.close("all")


def test_plot_filter_errors_without_matplotlib(monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    monkeypatch.setitem(sys.modules, "matplotlib.pyplot", None)
    with pytest.raises(ImportError, match="pip install matplotlib"):
        plot_filter_errors(pd.DataFrame([[0]]))
