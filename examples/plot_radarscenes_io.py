"""
Loading and writing RadarScenes data
====================================

:func:`~sklearn_radar.datasets.load_radarscenes` reads the folder layout of
the public RadarScenes data set into the data :class:`~sklearn.utils.Bunch`
that every example uses, and :func:`~sklearn_radar.datasets.write_radarscenes`
writes such a Bunch back, so that simulated data opens in the RadarScenes
devkit and real data runs through the same pipelines.  This example writes a
short simulated recording, looks at the files, and reads it back.
"""

# %%
# Write
# -----
# One simulated recording of 5 s, written to a temporary folder.  The folder
# holds ``sensors.json`` (mounting), ``sequences.json`` (the list of
# recordings and their train/validation category) and one ``sequence_N/``
# folder per recording with ``radar_data.h5`` and ``scenes.json``.
import json
import tempfile
from pathlib import Path

import h5py
import matplotlib.pyplot as plt
import numpy as np

from sklearn_radar import LABELS, describe_columns
from sklearn_radar.datasets import load_radarscenes, make_scenes, write_radarscenes

scenes = make_scenes(n_sequences=1, duration=5.0, random_state=0)
workdir = tempfile.TemporaryDirectory()
folder = write_radarscenes(scenes, Path(workdir.name) / "data")
for path in sorted(folder.rglob("*")):
    size = f"{path.stat().st_size / 1024:8.1f} KiB" if path.is_file() else ""
    print(f"{path.relative_to(folder)!s:<32}{size}")

# %%
# The files
# ---------
# ``radar_data.h5`` holds two compound datasets: ``radar_data`` (one row per
# detection, the 14 RadarScenes fields) and ``odometry`` (ego pose and
# motion, about 50 Hz).
with h5py.File(folder / "sequence_1" / "radar_data.h5") as h5:
    for name in ("radar_data", "odometry"):
        print(f"{name}: {h5[name].shape[0]} rows")
        print(
            "   "
            + ", ".join(
                f"{field} {h5[name].dtype[field]}" for field in h5[name].dtype.names
            )
        )

# %%
# ``scenes.json`` has one entry per scan ("scene") of one sensor, keyed by its
# timestamp in µs, with the range of its rows in ``radar_data`` and its
# odometry row:
catalogue = json.loads((folder / "sequence_1" / "scenes.json").read_text())
first_key = next(iter(catalogue["scenes"]))
print(f"{len(catalogue['scenes'])} scenes; the first, {first_key}:")
print(json.dumps(catalogue["scenes"][first_key], indent=1))
print("sensors.json:", json.dumps(json.loads((folder / "sensors.json").read_text())))

# %%
# Read back
# ---------
# The loaded Bunch has the same table: the 14 fields plus ``sequence`` and the
# context columns (each scan's odometry and each sensor's mounting, copied
# onto every row).  The file stores 32-bit floats, as the simulator's table
# does, so this round trip is exact.
loaded = load_radarscenes(folder)
print(loaded.DESCR)
print("same columns:", list(loaded.data.columns) == list(scenes.data.columns))
print("same targets:", np.array_equal(loaded.target, scenes.target))
largest = max(
    np.abs(
        loaded.data[c].to_numpy(np.float64) - scenes.data[c].to_numpy(np.float64)
    ).max()
    for c in ("range_sc", "azimuth_sc", "vr", "x_seq", "y_seq", "ego_x_seq")
)
print(f"largest difference in range, angle, Doppler or position: {largest:.2g}")
print(describe_columns())
print(
    "road-user classes:",
    sorted({LABELS[k] for k in loaded.data["label_id"][loaded.target >= 0]}),
)

# %%
# One scan of each sensor
# -----------------------
# The four sensors are not synchronised: each scan is one sensor's cycle with
# its own timestamp.  Here the first scan of each sensor after 2 s, in the car
# frame, coloured by sensor; crosses are moving road users.
data = loaded.data
t = (data["timestamp"] - data["timestamp"].min()) * 1e-6
fig, ax = plt.subplots(figsize=(7, 6))
for sensor in (1, 2, 3, 4):
    scan = data["timestamp"][(data["sensor_id"] == sensor) & (t >= 2.0)].min()
    rows = (data["timestamp"] == scan).to_numpy()
    moving = rows & (loaded.target >= 0)
    ax.scatter(
        data["y_cc"][rows & ~moving],
        data["x_cc"][rows & ~moving],
        s=8,
        c=f"C{sensor}",
        label=f"sensor {sensor} ({rows.sum()} detections)",
    )
    ax.scatter(
        data["y_cc"][moving], data["x_cc"][moving], s=40, marker="x", c=f"C{sensor}"
    )
ax.set(
    xlim=(60, -60),
    ylim=(-10, 100),
    aspect="equal",
    xlabel="y_cc (m, left)",
    ylabel="x_cc (m, forward)",
    title="One scan per sensor (crosses: moving road users)",
)
ax.legend(loc="lower left")
fig.tight_layout()
plt.show()

workdir.cleanup()
