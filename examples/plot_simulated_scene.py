"""
Simulated radar scene
=====================

:func:`~sklearn_radar.datasets.make_scenes` simulates an ego car with the four
RadarScenes radars in urban traffic.  This example shows one recording in the
sequence (world) frame, with every moving road user in its own colour and the
static background in grey, and prints the statistics that tell whether the
simulation is realistic.
"""

# %%
# Simulate one recording of 20 s.
import matplotlib.pyplot as plt
import numpy as np

from sklearn_radar.datasets import format_statistics, make_scenes, scene_statistics

scenes = make_scenes(n_sequences=1, duration=20.0, random_state=3)
print(format_statistics(*scene_statistics(scenes)))

# %%
# Left: all detections of the recording in the sequence frame, with the ego
# path.  Right: a 0.25 s window in the car frame (x forward, y left), the
# time window the clustering stages work on.
data, target = scenes.data, scenes.target
background = target == -1
fig, (world, window) = plt.subplots(1, 2, figsize=(12, 5.5))
world.scatter(
    data.x_seq[background], data.y_seq[background], s=0.2, c="0.75", label="background"
)
world.scatter(
    data.x_seq[~background],
    data.y_seq[~background],
    s=1.0,
    c=target[~background] % 10,
    cmap="tab10",
)
world.plot(scenes.odometry.x_seq, scenes.odometry.y_seq, "k-", lw=0.8, label="ego path")
world.set(
    xlabel="x_seq (m)",
    ylabel="y_seq (m)",
    title="20 s in the sequence frame",
    aspect="equal",
)
world.legend(loc="lower left", markerscale=10)

t = data.timestamp.to_numpy()
now = (t >= t.min() + 8_000_000) & (t < t.min() + 8_250_000)
colour = np.where(target[now] >= 0, target[now] % 10, np.nan)
window.scatter(
    data.y_cc[now][background[now]], data.x_cc[now][background[now]], s=6, c="0.6"
)
window.scatter(
    data.y_cc[now][~background[now]],
    data.x_cc[now][~background[now]],
    s=12,
    c=colour[~background[now]],
    cmap="tab10",
    vmin=0,
    vmax=9,
)
window.set(
    xlim=(50, -50),
    ylim=(-30, 100),
    xlabel="y_cc (m, left)",
    ylabel="x_cc (m, forward)",
    title="0.25 s in the car frame",
    aspect="equal",
)
fig.tight_layout()
plt.show()
