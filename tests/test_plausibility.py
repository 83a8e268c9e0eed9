"""Physical plausibility of the input (issue #26): wrong units and layouts raise, naming column, value and cause.

Each wrong-unit case below takes simulated detections (which pass) and changes one column the way a unit or
convention error would; without the checks every one of them ran through silently.
"""

import importlib.util
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import sklearn_radar
from sklearn_radar import ClusterMerger, DopplerDensityFilter, FrameTransform, RadarDBSCAN, config_context
from sklearn_radar._config import ENVIRONMENT_VARIABLE
from sklearn_radar._schema import PLAUSIBLE_VALUES, RADARSCENES_MOUNTING, RAW_LAYOUT, SCAN_SPACING
from sklearn_radar._validation import check_plausible, median_scan_spacing
from sklearn_radar.cluster import SequenceDBSCAN, WindowedDBSCAN
from sklearn_radar.datasets import load_radarscenes, make_scenes, write_radarscenes


@pytest.fixture(scope="module")
def scenes():
    return make_scenes(n_sequences=2, duration=3.0, random_state=5)


@pytest.fixture(scope="module")
def working(scenes):
    return FrameTransform().fit_transform(scenes.data)


def _with(frame, **changes):
    frame = frame.copy()
    for name, change in changes.items():
        frame[name] = change(frame[name].to_numpy())
    return frame


# --------------------------------------------------------------------------
# Real data paths pass
# --------------------------------------------------------------------------


@pytest.mark.parametrize("difficulty", ["easy", "realistic"])
def test_simulated_data_of_both_presets_passes_the_whole_pipeline(difficulty):
    data = make_scenes(n_sequences=2, duration=4.0, random_state=1, difficulty=difficulty).data
    Xt = DopplerDensityFilter().fit_transform(FrameTransform().fit_transform(data))
    labels = ClusterMerger().fit(Xt).labels_
    assert labels.max() >= 1
    raw = data[list(RAW_LAYOUT.columns)].to_numpy(dtype=np.float64)  # the array path too
    DopplerDensityFilter().fit_transform(FrameTransform(frame="car").fit_transform(raw))


def test_a_written_simulated_folder_loads(tmp_path, scenes):
    write_radarscenes(scenes, tmp_path / "data")
    assert len(load_radarscenes(tmp_path / "data").data) == len(scenes.data)


def test_offline_estimators_accept_rows_in_any_order(working):
    # Rows in = rows out, in any order: the spacing check sorts internally and never rejects shuffled rows.
    order = np.random.default_rng(0).permutation(len(working))
    shuffled = working.iloc[order]
    kept = DopplerDensityFilter().fit_transform(shuffled)["keep"].to_numpy()
    np.testing.assert_array_equal(kept, DopplerDensityFilter().fit_transform(working)["keep"].to_numpy()[order])
    for model in (RadarDBSCAN(), ClusterMerger(), SequenceDBSCAN(), WindowedDBSCAN()):
        assert len(model.fit(shuffled).labels_) == len(working)


# --------------------------------------------------------------------------
# Wrong units: one case per kind, each with the message it gives
# --------------------------------------------------------------------------

RAW_CASES = {
    "timestamp in s": (
        {"timestamp": lambda v: v * 1e-6},
        r"column 'timestamp': distinct scan times are a median 0\.0\d+ µs apart .*below the plausible 100 µs: "
        r"timestamp looks like seconds; RadarScenes uses µs",
    ),
    "timestamp in ms": (
        {"timestamp": lambda v: v // 1000},
        r"column 'timestamp': .* median \d\d µs apart .*timestamp looks like milliseconds; RadarScenes uses µs",
    ),
    "timestamp in ns": (
        {"timestamp": lambda v: v * 1000},
        r"column 'timestamp': .*above the plausible 5e\+06 µs: timestamp looks like nanoseconds",
    ),
    "azimuth in degrees": (
        {"azimuth_sc": np.degrees},
        r"column 'azimuth_sc' holds -?\d+\.?\d* rad \(row \d+\), (below|above) the plausible -?3\.14\d* rad: "
        r"it looks like degrees",
    ),
    "sensor yaw in degrees": ({"sensor_yaw": np.degrees}, r"column 'sensor_yaw' holds -85\.0\d* rad .*degrees"),
    "range in mm": (
        {"range_sc": lambda v: v * 1000},
        r"column 'range_sc' holds \d+\.?\d* m .*above the plausible 1000 m",
    ),
    "negative range": ({"range_sc": lambda v: -v}, r"column 'range_sc' holds -\d+.* below the plausible 0 m: a range"),
    "ego speed in km/h on a motorway": (
        {"ego_vx": lambda v: np.full_like(v, 45.0) * 3.6},
        r"column 'ego_vx' holds 162 m/s .*it looks like km/h; sklearn-radar \(as RadarScenes\) uses m/s",
    ),
    "ego speed in km/h in town": (  # within MAX_EGO_SPEED: caught by the path of the ego positions
        {"ego_vx": lambda v: v * 3.6},
        r"column 'ego_vx' integrates to \d+\.?\d* m over time while the ego positions \('ego_x_seq', 'ego_y_seq'\) "
        r"move \d+\.?\d* m \(sequence \d; ratio 3\.6\d*, plausible 0\.6-1\.7\): ego_vx looks like km/h",
    ),
    "ego speed in mph": ({"ego_vx": lambda v: v * 2.23694}, r"ratio 2\.24, .*ego_vx looks like mph"),
    "car x axis backwards": ({"ego_vx": lambda v: np.full_like(v, -40.0)}, r"'ego_vx' holds -40 m/s .*backwards"),
    "Doppler in km/h": (
        {"vr": lambda v: np.r_[v[:-1], -90.0] * 3.6},
        r"column 'vr' holds -324 m/s .*it looks like km/h",
    ),
    "yaw rate in deg/s in a turn": (
        {"ego_yaw_rate": lambda v: np.degrees(np.full_like(v, 0.2))},
        r"column 'ego_yaw_rate' holds 11\.4\d* rad/s .*above the plausible 3\.14\d* rad/s: it looks like deg/s",
    ),
    "mounting x in cm": ({"sensor_x": lambda v: v * 100}, r"column 'sensor_x' holds 386 m .*outside the car"),
    "mounting y in mm": ({"sensor_y": lambda v: v * 1000}, r"column 'sensor_y' holds -?873 m .*outside the car"),
}


@pytest.mark.parametrize("case", sorted(RAW_CASES))
def test_a_wrong_unit_in_raw_detections_is_named(scenes, case):
    changes, message = RAW_CASES[case]
    bad = _with(scenes.data, **changes)
    with pytest.raises(ValueError, match=message) as error:
        FrameTransform().fit(bad)
    assert "set_config(check_plausibility=False)" in str(error.value)
    with config_context(check_plausibility=False):
        FrameTransform().fit(bad)  # the switch lets it through


WORK_CASES = {
    "t in µs (the raw timestamp)": (
        {"t": lambda v: v * 1e6},
        r"column 't': distinct scan times are a median 6\.\d+e\+04 s apart .*above the plausible 5 s: "
        r"t looks like microseconds; t is in s",
    ),
    "t in ms": ({"t": lambda v: v * 1e3}, r"column 't': .* median 6\d\.?\d* s apart .*t looks like milliseconds"),
    "t in µs interpreted as s twice": (
        {"t": lambda v: v * 1e-6},
        r"column 't': .*below the plausible 0\.0001 s: the timestamps it came from look like seconds",
    ),
    "compensated Doppler in km/h": ({"v_r": lambda v: np.r_[v[:-1], 100.0] * 3.6}, r"column 'v_r' holds 360 m/s"),
    "positions in mm of UTM": (
        {"x": lambda v: v * 1000 + 5e10},
        r"column 'x' holds 5\.\d+e\+10 m .*positions are in m",
    ),
}


@pytest.mark.parametrize("case", sorted(WORK_CASES))
@pytest.mark.parametrize("model", [DopplerDensityFilter(), RadarDBSCAN(), ClusterMerger(), WindowedDBSCAN()], ids=repr)
def test_a_wrong_unit_in_working_detections_is_named_by_every_estimator(working, case, model):
    changes, message = WORK_CASES[case]
    with pytest.raises(ValueError, match=f"{type(model).__name__}: implausible input: {message}"):
        model.fit(_with(working, **changes))


def test_the_issue_case_timestamps_in_seconds_no_longer_pass_silently(scenes):
    # Issue 26: a 10 s sequence in s-as-µs collapsed to 1e-5 s, the filter kept 89.6 % instead of 70.9 %.
    bad = _with(scenes.data, timestamp=lambda v: v * 1e-6)
    with pytest.raises(ValueError, match="timestamp looks like seconds; RadarScenes uses µs"):
        DopplerDensityFilter().fit_transform(FrameTransform().fit_transform(bad))


# --------------------------------------------------------------------------
# Wrong layouts of array input
# --------------------------------------------------------------------------


def test_the_whole_table_as_an_array_is_blamed_on_its_layout(scenes):
    with pytest.raises(ValueError, match=r"non-numeric values \(could not convert string to float.*layout looks wrong"):
        FrameTransform().fit(scenes.data.to_numpy())


@pytest.mark.parametrize("model", [FrameTransform(), DopplerDensityFilter(), RadarDBSCAN()], ids=repr)
def test_the_numeric_table_as_an_array_names_the_expected_layout(scenes, model):
    # Before: "column 'x' holds a coordinate of magnitude 1.57e+11 m ... shift the data nearer the origin".
    X = scenes.data.select_dtypes("number").to_numpy()
    layout = "raw detection array" if isinstance(model, FrameTransform) else "working detection array"
    message = rf"21 column\(s\), so the layout \(column order\) looks wrong: .* the {layout}, columns \[.*\]\. Pass"
    with pytest.raises(ValueError, match=message):
        model.fit(X)


def test_with_the_checks_off_the_neighbour_grid_still_suspects_the_layout(scenes):
    X = scenes.data.select_dtypes("number").to_numpy()  # timestamp (1.6e11 µs) lands in 'x'
    with config_context(check_plausibility=False), pytest.raises(ValueError, match=r"magnitude 1\.\d+e\+11 m.*layout"):
        DopplerDensityFilter().fit_transform(X)


def test_an_array_message_lists_the_layout_columns_in_order(working):
    X = working[["x", "y", "v_r", "t"]].to_numpy()
    X[:, 3] *= 1e6  # t in µs
    with pytest.raises(ValueError) as error:
        RadarDBSCAN().fit(X)
    assert "['x', 'y', 'v_r', 't', 'sequence', 'keep', 'range_sc', 'heading', 'azimuth_sc', 'sensor_yaw']" in str(
        error.value
    )
    assert "check the unit, or the layout" in str(error.value)


# --------------------------------------------------------------------------
# The switch
# --------------------------------------------------------------------------


def test_set_config_turns_the_checks_off_and_on(working):
    bad = _with(working, t=lambda v: v * 1e3)
    assert sklearn_radar.get_config() == {"check_plausibility": True}
    try:
        sklearn_radar.set_config(check_plausibility=False)
        DopplerDensityFilter().fit(bad)
        sklearn_radar.set_config()  # None changes nothing
        assert sklearn_radar.get_config()["check_plausibility"] is False
    finally:
        sklearn_radar.set_config(check_plausibility=True)
    with pytest.raises(ValueError, match="t looks like milliseconds"):
        DopplerDensityFilter().fit(bad)


def test_config_context_restores_the_setting_on_an_exception():
    with pytest.raises(RuntimeError), config_context(check_plausibility=False):
        assert sklearn_radar.get_config()["check_plausibility"] is False
        raise RuntimeError
    assert sklearn_radar.get_config()["check_plausibility"] is True


def test_get_config_returns_a_copy():
    sklearn_radar.get_config()["check_plausibility"] = False
    assert sklearn_radar.get_config()["check_plausibility"] is True


def test_the_switch_does_not_let_nan_through(working):
    bad = _with(working, t=lambda v: np.r_[v[:-1], np.nan])
    with config_context(check_plausibility=False), pytest.raises(ValueError, match="NaN or infinity"):
        DopplerDensityFilter().fit(bad)


@pytest.mark.parametrize("value, expected", [("0", False), ("off", False), ("1", True), ("", True)])
def test_the_environment_variable_sets_the_default_of_new_processes(value, expected):
    # What a joblib (loky) or dask worker process sees when started with the variable set.
    script = "import sklearn_radar; print(sklearn_radar.get_config()['check_plausibility'])"
    env = {**os.environ, ENVIRONMENT_VARIABLE: value}
    result = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True)
    assert result.stdout.strip() == str(expected)


def test_config_functions_validate_their_parameters():
    spec = importlib.util.spec_from_file_location(
        "public_functions", Path(__file__).with_name("test_public_functions.py")
    )
    public_functions = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(public_functions)
    for name in ("sklearn_radar.set_config", "sklearn_radar.get_config", "sklearn_radar.config_context"):
        func, func_name, params, required = public_functions._get_func_info(name)
        check = public_functions._check_function_param_validation
        check(func, func_name, params, required, func._skl_parameter_constraints)


# --------------------------------------------------------------------------
# load_radarscenes
# --------------------------------------------------------------------------


@pytest.fixture
def written(tmp_path, scenes):
    write_radarscenes(scenes, tmp_path / "data")
    return tmp_path / "data"


def _edit_radar_data(folder, field, change):
    h5_file = folder / "sequence_1" / "radar_data.h5"
    with h5py.File(h5_file, "r+") as h5:
        array = h5["radar_data"][()]
        array[field] = change(array[field])
        del h5["radar_data"]
        h5.create_dataset("radar_data", data=array)
    return h5_file


def test_load_radarscenes_names_the_file_and_the_field_in_degrees(written):
    h5_file = _edit_radar_data(written, "azimuth_sc", np.degrees)
    with pytest.raises(ValueError, match=rf"{h5_file} \[radar_data\]: implausible input: column 'azimuth_sc'.*degrees"):
        load_radarscenes(written)
    with config_context(check_plausibility=False):
        assert load_radarscenes(written, sequences=1).data["azimuth_sc"].abs().max() > 10


def test_load_radarscenes_checks_the_odometry(written):
    h5_file = written / "sequence_1" / "radar_data.h5"
    with h5py.File(h5_file, "r+") as h5:
        odometry = h5["odometry"][()]
        odometry["yaw_rate"] = np.degrees(odometry["yaw_rate"]) + 10.0
        del h5["odometry"]
        h5.create_dataset("odometry", data=odometry)
    with pytest.raises(ValueError, match=r"\[odometry\]: implausible input: column 'yaw_rate' holds .* rad/s.*deg/s"):
        load_radarscenes(written)


def test_load_radarscenes_compares_the_odometry_speed_with_its_path(written):
    h5_file = written / "sequence_1" / "radar_data.h5"
    with h5py.File(h5_file, "r+") as h5:
        odometry = h5["odometry"][()]
        odometry["vx"] = odometry["vx"] * 3.6  # km/h, within MAX_EGO_SPEED
        del h5["odometry"]
        h5.create_dataset("odometry", data=odometry)
    with pytest.raises(ValueError, match=r"\[odometry\]: implausible input: column 'vx' integrates .*'x_seq'.*km/h"):
        load_radarscenes(written)


def test_a_car_at_rest_is_not_judged_by_its_path():
    n = 200
    at_rest = {"timestamp": np.arange(n) * 15_000.0, "ego_x_seq": np.full(n, 5.0), "ego_y_seq": np.zeros(n)}
    check_plausible({**at_rest, "ego_vx": np.zeros(n)}, "test")
    with pytest.raises(ValueError, match=r"'ego_vx' integrates to 29\.85 m .* move 0 m"):  # 10 m/s, not moving
        check_plausible({**at_rest, "ego_vx": np.full(n, 10.0)}, "test")


def test_load_radarscenes_checks_the_mounting(written):
    sensors = json.loads((written / "sensors.json").read_text())
    sensors["radar_2"]["x"] *= 1000  # mm
    (written / "sensors.json").write_text(json.dumps(sensors))
    with pytest.raises(
        ValueError, match=r"sensors\.json \(rows are the sensors \[1, 2, 3, 4\]\).*'x' holds 3860 m \(row 1\)"
    ):
        load_radarscenes(written)


def test_load_radarscenes_refuses_time_running_backwards_with_the_values(written):
    # The swap happens within the scans' own rows, so scenes.json still covers the file; the order check fires first.
    h5_file = _edit_radar_data(written, "timestamp", lambda v: np.r_[v[:1], v[1:][::-1]])
    with pytest.raises(
        ValueError,
        match=rf"{h5_file} \[radar_data\]: field 'timestamp' is not sorted ascending: "
        r"time runs backwards at row \d+ \(\d+ µs after \d+ µs\)",
    ):
        load_radarscenes(written)


# --------------------------------------------------------------------------
# The spacing statistic and invariants
# --------------------------------------------------------------------------


def test_median_scan_spacing_per_group_in_any_row_order():
    rng = np.random.default_rng(1)
    times = np.r_[np.repeat(np.arange(20) * 60.0, 3), np.repeat(np.arange(12) * 15.0, 2), [0.0, 1.0]]
    sequence = np.r_[np.full(60, 7), np.full(24, 8), [9, 9]]
    order = rng.permutation(len(times))
    medians, sequences, sensors = median_scan_spacing(times[order], sequence[order])
    np.testing.assert_array_equal(medians, [60.0, 15.0])  # sequence 9 has too few scans to be judged
    np.testing.assert_array_equal(sequences, [7, 8])
    assert sensors is None
    in_scan_order = median_scan_spacing(times, sequence)  # rows scan by scan: the runs shortcut
    np.testing.assert_array_equal(in_scan_order[0], medians)


def test_median_scan_spacing_per_sensor_of_a_simulated_recording(scenes):
    data = scenes.data
    medians, sequences, sensors = median_scan_spacing(
        data["timestamp"].to_numpy(np.float64), data["sequence"].to_numpy(), data["sensor_id"].to_numpy()
    )
    assert len(medians) == 8 and sorted(set(sensors.tolist())) == [1, 2, 3, 4]
    assert sequences.tolist() == [1, 1, 1, 1, 2, 2, 2, 2]
    assert np.all((55_000 < medians) & (medians < 65_000))  # µs: each sensor cycles in about 60 ms
    per_sequence = median_scan_spacing(data["timestamp"].to_numpy(np.float64), data["sequence"].to_numpy())[0]
    assert np.all((10_000 < per_sequence) & (per_sequence < 20_000))  # four unsynchronised sensors: about 15 ms


def test_a_time_per_detection_is_not_judged_as_a_scan_rate():
    # Synthetic tables (uniform random t, one detection per time) are not scan-structured: no spacing.
    times = np.random.default_rng(0).uniform(0, 0.25, 1000)
    assert len(median_scan_spacing(times)[0]) == 0
    check_plausible({"t": times}, "test")


def test_every_bound_has_its_argument_and_a_cause():
    for name, bound in PLAUSIBLE_VALUES.items():
        assert bound.column == name and bound.low < bound.high
        assert bound.argument and bound.too_low and bound.too_high
    for rule in SCAN_SPACING.values():
        assert rule.low < rule.high


_FIELD_OF_VIEW = st.floats(min_value=0.06, max_value=1.5)  # rad; 0.06 rad = 3.4 deg, the least a FOV spans


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 2**31), n=st.integers(1, 400), fov=_FIELD_OF_VIEW, speed=st.floats(-15, 60))
def test_plausible_random_tables_never_raise_and_their_azimuth_in_degrees_always_does(seed, n, fov, speed):
    rng = np.random.default_rng(seed)
    n_scans = max(1, n // 20)
    scan, spacing_us = np.sort(rng.integers(0, n_scans, n)), rng.uniform(1e4, 1e5)
    travelled = speed * scan * spacing_us * 1e-6  # m: the ego drives straight at `speed`, as its odometry says
    heading, origin = rng.uniform(-np.pi, np.pi), rng.uniform(-1e6, 1e6, 2)
    raw = {
        "range_sc": rng.uniform(0.0, 300.0, n),
        "azimuth_sc": np.r_[fov, rng.uniform(-fov, fov, n - 1)][:n],
        "vr": rng.uniform(-120.0, 120.0, n),
        "timestamp": scan * spacing_us + 1.5e11,
        "sensor_x": rng.uniform(-5, 5, n),
        "sensor_y": rng.uniform(-1.3, 1.3, n),
        "sensor_yaw": rng.uniform(-np.pi, 2 * np.pi, n),
        "ego_x_seq": origin[0] + travelled * np.cos(heading),
        "ego_y_seq": origin[1] + travelled * np.sin(heading),
        "ego_yaw_seq": rng.uniform(-100, 100, n),  # unwrapped: any value
        "ego_vx": np.full(n, speed),
        "ego_yaw_rate": rng.uniform(-1.0, 1.0, n),
    }
    X = np.column_stack([raw[name] for name in RAW_LAYOUT.columns[:-1]])
    FrameTransform().fit(X)
    X[:, RAW_LAYOUT.position("azimuth_sc")] = np.degrees(X[:, RAW_LAYOUT.position("azimuth_sc")])
    with pytest.raises(ValueError, match=r"'azimuth_sc' .* it looks like degrees"):
        FrameTransform().fit(X)


# --------------------------------------------------------------------------
# Issue 46: units told by one column against another, exact times, duplicate rows, column order, the switch
# --------------------------------------------------------------------------


@pytest.fixture(scope="module")
def turning():
    # Both sequences turn (0.43 and 0.60 rad in 3 s): the yaw against its rate is judged.
    return make_scenes(n_sequences=2, duration=3.0, random_state=1).data


@pytest.mark.parametrize("difficulty", ["easy", "realistic", "radarscenes"])
def test_simulated_data_of_every_preset_passes_the_checks_of_one_column_against_another(difficulty):
    data = make_scenes(n_sequences=3, duration=10.0, random_state=3, difficulty=difficulty).data
    FrameTransform().fit(data)
    FrameTransform().fit(data.iloc[::7])  # a row subset
    FrameTransform().fit(data[data["label_id"] != 11])  # only the moving road users: not judged as km/h


@pytest.mark.parametrize(
    "unit, factor, message",
    [("km/h", 3.6, r"3\.6 times"), ("mph", 2.23694, r"2\.24 times")],
)
def test_a_doppler_in_another_unit_within_its_limit_is_named(scenes, unit, factor, message):
    bad = _with(scenes.data, vr=lambda v: v * factor)
    assert bad["vr"].abs().max() < PLAUSIBLE_VALUES["vr"].high  # the range check alone let it pass
    with pytest.raises(
        ValueError,
        match=rf"column 'vr': \d+% of \d+ detections seen while the ego moves have {message} the radial velocity a "
        rf"static target has from the ego motion .*vr looks like {unit}; sklearn-radar \(as RadarScenes\) uses m/s",
    ):
        FrameTransform().fit(bad)
    with pytest.raises(ValueError, match=f"vr looks like {unit}"):  # the array path reads it too
        FrameTransform().fit(bad[list(RAW_LAYOUT.columns)].to_numpy(np.float64))
    with config_context(check_plausibility=False):
        FrameTransform().fit(bad)


def test_the_doppler_of_a_car_at_rest_is_not_judged(scenes):
    bad = _with(scenes.data, vr=lambda v: v * 3.6, ego_vx=lambda v: np.zeros_like(v), ego_yaw_rate=np.zeros_like)
    bad = _with(bad, ego_x_seq=lambda v: np.full_like(v, v[0]), ego_y_seq=lambda v: np.full_like(v, v[0]))
    FrameTransform().fit(bad)  # no ego motion: the static world has no Doppler to compare with


def test_an_ego_yaw_in_degrees_is_named(turning):
    bad = _with(turning, ego_yaw_seq=np.degrees)
    with pytest.raises(
        ValueError,
        match=r"column 'ego_yaw_seq' changes 5\d\.?\d* times as much as 'ego_yaw_rate' integrated over time "
        r"\(sequence \d; .*plausible up to 5\): ego_yaw_seq looks like degrees; sklearn-radar \(as RadarScenes\) uses "
        r"rad",
    ):
        FrameTransform().fit(bad)
    wrapped = _with(turning, ego_yaw_seq=lambda v: np.mod(np.degrees(v) + 170.0, 360.0) - 180.0)  # wraps at 180 deg
    with pytest.raises(ValueError, match="ego_yaw_seq looks like degrees"):
        FrameTransform().fit(wrapped)


def test_a_yaw_offset_or_a_yaw_in_zero_to_two_pi_is_plausible(turning):
    FrameTransform().fit(_with(turning, ego_yaw_seq=lambda v: np.mod(v, 2 * np.pi)))
    FrameTransform().fit(_with(turning, ego_yaw_seq=lambda v: v + 20 * np.pi))


def test_load_radarscenes_compares_the_odometry_yaw_with_its_rate(tmp_path):
    write_radarscenes(make_scenes(n_sequences=1, duration=3.0, random_state=1), tmp_path / "data")
    h5_file = tmp_path / "data" / "sequence_1" / "radar_data.h5"
    with h5py.File(h5_file, "r+") as h5:
        odometry = h5["odometry"][()]
        odometry["yaw_seq"] = np.degrees(odometry["yaw_seq"])
        del h5["odometry"]
        h5.create_dataset("odometry", data=odometry)
    with pytest.raises(ValueError, match=r"\[odometry\]: implausible input: column 'yaw_seq' changes .*degrees"):
        load_radarscenes(tmp_path / "data")


def test_load_radarscenes_names_a_doppler_in_km_per_hour(written):
    h5_file = _edit_radar_data(written, "vr", lambda v: v * 3.6)
    with pytest.raises(ValueError, match=rf"{h5_file} \[radar_data\]: implausible input: column 'vr': .*km/h"):
        load_radarscenes(written)


def _motion_table(rng, n_scans, speed, yaw_rate, moving_share):
    """A raw table of static detections (and some moving ones) seen by an ego driving on an arc, as odometry says."""
    spacing = rng.uniform(0.01, 0.08)  # s between scans
    t = np.arange(n_scans) * spacing
    rate = np.full(n_scans, yaw_rate) + rng.normal(0, 0.01, n_scans)
    yaw = rng.uniform(-np.pi, np.pi) + np.r_[0.0, np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(t))]
    x = np.r_[0.0, np.cumsum(speed * np.cos(yaw[1:]) * np.diff(t))]
    y = np.r_[0.0, np.cumsum(speed * np.sin(yaw[1:]) * np.diff(t))]
    scan = np.repeat(np.arange(n_scans), 20)
    n = len(scan)
    mount = rng.integers(1, 5, n)
    sensor = {k: np.array([RADARSCENES_MOUNTING[i][k] for i in mount]) for k in ("x", "y", "yaw")}
    azimuth = rng.uniform(-1.0, 1.0, n)
    angle = azimuth + sensor["yaw"]
    static = -((speed - rate[scan] * sensor["y"]) * np.cos(angle) + rate[scan] * sensor["x"] * np.sin(angle))
    moving = rng.random(n) < moving_share
    vr = np.where(moving, rng.uniform(-30, 30, n), static + rng.normal(0, 0.1, n))
    columns = {
        "range_sc": rng.uniform(1, 100, n),
        "azimuth_sc": azimuth,
        "vr": vr,
        "timestamp": np.round(1.5e11 + t[scan] * 1e6),
        "sensor_x": sensor["x"],
        "sensor_y": sensor["y"],
        "sensor_yaw": sensor["yaw"],
        "ego_x_seq": x[scan],
        "ego_y_seq": y[scan],
        "ego_yaw_seq": np.mod(yaw[scan] + np.pi, 2 * np.pi) - np.pi,
        "ego_vx": np.full(n, speed),
        "ego_yaw_rate": rate[scan],
    }
    return np.column_stack([columns[name] for name in RAW_LAYOUT.columns[:-1]])


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**31),
    speed=st.floats(3.0, 40.0),
    yaw_rate=st.floats(-0.5, 0.5).filter(lambda rate: abs(rate) > 0.1),
    moving_share=st.floats(0.0, 0.4),
)
def test_plausible_moving_egos_never_raise_and_their_doppler_in_km_per_hour_or_yaw_in_degrees_always_does(
    seed, speed, yaw_rate, moving_share
):
    X = _motion_table(np.random.default_rng(seed), 120, speed, yaw_rate, moving_share)
    FrameTransform().fit(X)
    in_km_per_hour = X.copy()
    in_km_per_hour[:, RAW_LAYOUT.position("vr")] *= 3.6
    with pytest.raises(ValueError, match="vr looks like km/h"):
        FrameTransform().fit(in_km_per_hour)
    in_degrees = X.copy()
    in_degrees[:, RAW_LAYOUT.position("ego_yaw_seq")] = np.degrees(X[:, RAW_LAYOUT.position("ego_yaw_seq")])
    with pytest.raises(ValueError, match="ego_yaw_seq looks like degrees"):
        FrameTransform().fit(in_degrees)


@pytest.mark.parametrize("where", ["DataFrame", "array"])
def test_float32_timestamps_are_refused_naming_the_column(scenes, where):
    # µs since an epoch (1.6e11) in float32 are rounded to 16384 µs: scans 15 ms apart merge.
    data = _with(scenes.data, timestamp=lambda v: v.astype(np.float32))
    X = data if where == "DataFrame" else data[list(RAW_LAYOUT.columns)].to_numpy(np.float32)
    message = r"FrameTransform: column 'timestamp' is float32, which holds integers exactly only up to 16777216; .*"
    for switch in (True, False):  # the values are lost, whatever the switch
        with config_context(check_plausibility=switch), pytest.raises(ValueError, match=message + "int64"):
            FrameTransform().fit(X)


def test_float32_timestamps_small_enough_to_be_exact_pass(scenes):
    start = scenes.data.groupby("sequence")["timestamp"].transform("min")
    data = scenes.data.assign(timestamp=(scenes.data["timestamp"] - start).astype(np.float32))  # 3 s < 2**24 µs
    FrameTransform().fit(data)
    FrameTransform().fit(data[list(RAW_LAYOUT.columns)].to_numpy(np.float32))


def test_a_float32_timestamp_field_of_a_radarscenes_file_is_refused(written):
    h5_file = written / "sequence_1" / "radar_data.h5"
    with h5py.File(h5_file, "r+") as h5:
        array = h5["radar_data"][()]
        fields = [(name, "<f4" if name == "timestamp" else array.dtype[name]) for name in array.dtype.names]
        rounded = array.astype(fields)
        del h5["radar_data"]
        h5.create_dataset("radar_data", data=rounded)
    with pytest.raises(ValueError, match=r"\[radar_data\]: column 'timestamp' is float32, which holds integers"):
        load_radarscenes(written)


def test_duplicate_rows_are_refused_naming_the_uuid_and_an_example(scenes, working):
    data = scenes.data
    doubled = pd.concat([data, data], ignore_index=True)
    first = data["uuid"].iloc[0]
    with pytest.raises(
        ValueError,
        match=r"FrameTransform: implausible input: column 'uuid' holds '[0-9a-f]{32}' in rows (\d+) and (\d+) "
        r"\(at least \d+ uuid\(s\) repeat\): the table holds duplicate rows .*drop_duplicates\('uuid'\)",
    ) as error:
        FrameTransform().fit(doubled)
    rows = [int(row) for row in re.search(r"in rows (\d+) and (\d+)", str(error.value)).groups()]
    assert rows[1] == rows[0] + len(data)
    repeated_in_place = data.iloc[np.repeat(np.arange(len(data)), 1 + (np.arange(len(data)) == 1234))]
    with pytest.raises(ValueError, match=rf"column 'uuid' holds '{repeated_in_place['uuid'].iloc[1234]}' in rows"):
        FrameTransform().fit(repeated_in_place)
    for model in (DopplerDensityFilter(), RadarDBSCAN(), ClusterMerger()):  # the working table too
        with pytest.raises(ValueError, match=f"{type(model).__name__}: implausible input: column 'uuid'"):
            model.fit(pd.concat([working, working.iloc[:50]]))
    small = data.iloc[:300]
    with pytest.raises(ValueError, match=rf"'{small['uuid'].iloc[7]}' in rows 7 and 300"):  # a small table: all rows
        FrameTransform().fit(pd.concat([small, small.iloc[[7]]], ignore_index=True))
    with config_context(check_plausibility=False):
        FrameTransform().fit(doubled)
    assert first == data["uuid"].iloc[0]


def test_unique_uuids_pass_in_subsets_splits_and_shuffles(scenes):
    data = scenes.data
    assert data["uuid"].is_unique
    rng = np.random.default_rng(3)
    for subset in (data.iloc[::5], data.iloc[rng.permutation(len(data))], data[data["sequence"] == 2]):
        FrameTransform().fit(subset)
    moved = data.assign(sequence=data["sequence"] + 10, uuid=data["uuid"] + "b")
    FrameTransform().fit(pd.concat([data, moved], ignore_index=True))  # equal measurements, other uuids


def test_an_array_in_the_wrong_column_order_is_said_to_be_out_of_order_first(scenes):
    # Issue 46: the first words were "column 'range_sc' holds 1.58e+11 m ... it looks like mm or cm".
    order = list(RAW_LAYOUT.columns)
    order[0], order[3] = order[3], order[0]  # timestamp and range_sc swapped
    X = scenes.data[order].to_numpy(np.float64)
    with pytest.raises(ValueError) as error:
        FrameTransform().fit(X)
    message = str(error.value)
    assert message.startswith(
        "FrameTransform: implausible input: X is a plain array of 13 column(s), so the layout (column order) "
        "looks wrong: a plain array is read by position as the raw detection array, columns ['range_sc', "
    )
    timestamps = message.index("Column 0, read as 'range_sc', holds values like µs timestamps (up to 1.58")
    assert timestamps < message.index("column 'range_sc' holds 1.58") < message.index("looks like mm or cm")


def test_a_range_in_mm_is_still_blamed_on_the_unit_first(scenes):
    X = scenes.data[list(RAW_LAYOUT.columns)].to_numpy(np.float64)
    X[:, 0] *= 1000.0
    with pytest.raises(ValueError, match=r"^FrameTransform: implausible input: column 'range_sc' holds \d+.* m .*mm"):
        FrameTransform().fit(X)


def test_a_plausibility_error_names_the_environment_variable_too(working):
    with pytest.raises(ValueError) as error:
        DopplerDensityFilter().fit(_with(working, t=lambda v: v * 1e3))
    assert "sklearn_radar.set_config(check_plausibility=False)" in str(error.value)
    assert f"{ENVIRONMENT_VARIABLE}=0" in str(error.value)


def test_the_command_line_names_the_environment_variable_and_obeys_it(written):
    _edit_radar_data(written, "azimuth_sc", np.degrees)
    command = [sys.executable, "-m", "sklearn_radar", "stats", "--data", str(written)]
    result = subprocess.run(command, capture_output=True, text=True, env={**os.environ, ENVIRONMENT_VARIABLE: "1"})
    assert result.returncode == 1 and result.stderr.startswith("sklearn-radar: error:")
    assert f"{ENVIRONMENT_VARIABLE}=0" in result.stderr and len(result.stderr.strip().splitlines()) == 1
    result = subprocess.run(command, capture_output=True, text=True, env={**os.environ, ENVIRONMENT_VARIABLE: "0"})
    assert result.returncode == 0, result.stderr


@pytest.mark.parametrize("value", ["maybe", "2", "of"])
def test_an_invalid_environment_variable_is_a_clear_error(written, value):
    env = {**os.environ, ENVIRONMENT_VARIABLE: value}
    script = "import sklearn_radar; sklearn_radar.get_config()"
    result = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True)
    assert result.returncode == 1
    last = result.stderr.strip().splitlines()[-1]
    assert last.startswith(f"ValueError: the environment variable {ENVIRONMENT_VARIABLE}={value!r}")
    assert "'0', 'false', 'no', 'off'" in last and "'1', 'true', 'yes', 'on' or unset" in last
    command = [sys.executable, "-m", "sklearn_radar", "stats", "--data", str(written)]
    result = subprocess.run(command, env=env, capture_output=True, text=True)
    assert result.returncode == 1 and len(result.stderr.strip().splitlines()) == 1
    assert result.stderr.startswith(f"sklearn-radar: error: the environment variable {ENVIRONMENT_VARIABLE}=")
    script = "import sklearn_radar; sklearn_radar.set_config(check_plausibility=True); sklearn_radar.get_config()"
    assert subprocess.run([sys.executable, "-c", script], env=env).returncode == 0  # set_config settles it


@pytest.mark.parametrize("value, expected", [("yes", True), (" OFF ", False), ("False", False), ("on", True)])
def test_the_environment_variable_accepts_its_words_in_any_case(value, expected):
    script = "import sklearn_radar; print(sklearn_radar.get_config()['check_plausibility'])"
    env = {**os.environ, ENVIRONMENT_VARIABLE: value}
    result = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True)
    assert result.stdout.strip() == str(expected)
