"""The learned grouping with ids given late (issue #44): what a stream that answers a fixed time after a scan gains.

The causal model sees each detection's past only; the offline model sees 0.15 s on both sides of it
(``_link_features.LOCAL_WINDOW``), so its links between detections up to a time ``now`` are known at ``now + 0.15``
s.  Per preset and seed, on the data and split of ``experiment_tracking_errors.py``, an offline model with the causal
model's capacity and Doppler-density filter (``experiment_sliding_grouping.OFFLINE``: 40 boosting iterations, trees
6 levels deep, the filter causal; every candidate pair, where the causal model keeps 16 per detection) is fitted on
the training half and its links taken on both halves; forms of ids, each
given the choice of ``experiment_sliding_grouping.py`` (fit's link threshold and ``min_cluster_size`` or one of
``--thresholds`` x ``--sizes``, by training MOTA of the Tracker at its defaults, then the Tracker tuned on the
training half and scored on the test half):

* ``lag L``: the sliding re-clustering of ``experiment_sliding_grouping.py`` on the offline links (every scan, the
  last ``--length`` s), a detection's id the one its cluster has ``L`` s after its scan (``--lags``), confirmed when
  that id has ``min_cluster_size`` detections by then: ids of a scan known ``0.15 + L`` s after it;
* ``offline``: the offline model's own labels (every link of the sequence, past and future: the limit of a long
  lag), fed to the Tracker as they are (no threshold or size chosen).

``--links causal`` takes instead the main job's causal model and its causal links (each detection's past only, as
``experiment_sliding_grouping.py`` does): ids of a scan known ``L`` s after it, and no ``offline`` form.  With it,
``lag 0`` is that benchmark's ``sliding`` form, so the two can be told apart: what the look-ahead of the links gives,
and what the delay of the ids gives.

The summary compares each form, paired by seed, with the causal and sliding forms of the same data in
``--against`` (``experiment_sliding_grouping.py``'s records, the main job's causal model).

Run (3-5 minutes per preset and seed on one core; records ``benchmarks/results/lagged_grouping/``)::

    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/experiment_lagged_grouping.py --data realistic radarscenes easy \\
        --seeds 0 1 2 3 4 --save benchmarks/results/lagged_grouping
    python benchmarks/experiment_lagged_grouping.py --summary --save benchmarks/results/lagged_grouping
    OMP_NUM_THREADS=1 nice -n 19 python benchmarks/experiment_lagged_grouping.py --links causal --lags 0 0.25 0.4 \\
        --data realistic radarscenes easy --seeds 0 1 2 3 4 --save benchmarks/results/lagged_grouping/causal
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

from experiment_sliding_grouping import _record_path as sliding_record
from experiment_sliding_grouping import (
    choice_arguments,
    chosen_and_scored,
    confirmed_of,
    fitted,
    pair_grid,
    sliding_ids,
)
from experiment_tracking import _mean_se
from experiment_tracking_errors import data_arguments, parsed, records, saved_records


def measure(preset, seed, options):
    """Each form's chosen thresholds, tracked test scores and reported miss kinds, for one data set."""
    start = time.perf_counter()
    causal = options.links == "causal"
    halves, model = fitted(preset, seed, options, causal=causal)
    record = {"model": model}
    train, test = halves["train"], halves["test"]
    for lag in options.lags:

        def labelled(part, value, size, lag=lag):
            part["ids"], _ = sliding_ids(part["links"], len(part["t"]), value, options.length, lag)
            part["confirmed"] = confirmed_of(part["ids"], part["t"], size, lag)

        record[f"lag {lag:g}"] = chosen_and_scored(train, test, pair_grid(model, options), labelled, options, seed)

    def offline(part, *_):  # the offline labels as they are: no threshold or size to choose
        part["ids"] = part["confirmed"] = part["offline"]

    if not causal:
        record["offline"] = chosen_and_scored(train, test, [(None, None)], offline, options, seed)
    record["seconds"] = time.perf_counter() - start
    shown = ", ".join(f"{form} {record[form]['scores']['mota']:.3f}" for form in forms(record))
    print(f"{preset} seed {seed}: MOTA {shown} ({record['seconds']:.0f} s)", flush=True)
    return record


def forms(record):
    """The forms of ids in a record, lags first."""
    return [key for key in record if key.startswith("lag ")] + (["offline"] if "offline" in record else [])


def table(preset, runs, against):
    """Per form: test MOTA, IDF1, HOTA, mean ± SE over seeds; paired differences (± 2 SE) to ``against``'s forms."""
    seeds = sorted(runs)
    lines = [f"\n{preset}: {len(seeds)} seed(s), test half; mean ± standard error; paired differences ± 2 SE"]
    keys = ("mota", "idf1", "hota")
    lines.append(f"{'':<22} " + " ".join(f"{k.upper():>16}" for k in keys))
    named = forms(runs[seeds[0]])
    rows = {form: {k: np.array([runs[s][form]["scores"][k] for s in seeds]) for k in keys} for form in named}
    base = [s for s in seeds if s in against]
    for name in ("causal", "sliding"):
        if base:
            rows[f"{name} (--against)"] = {k: np.array([against[s][name]["scores"][k] for s in base]) for k in keys}
    for form, values in rows.items():
        lines.append(f"{form:<22} " + " ".join(f"{_cell(values[k]):>16}" for k in keys))
    for form in named:
        for name in ("causal", "sliding"):
            if len(base) == len(seeds):
                diffs = [rows[form][k] - rows[f"{name} (--against)"][k] for k in keys]
                cells = " ".join(f"{_cell(d, paired=True):>16}" for d in diffs)
                lines.append(f"{form + ' - ' + name:<22} " + cells)
    for form in named:
        if form == "offline":  # nothing chosen
            continue
        chosen = ", ".join(f"{runs[s][form]['threshold']}/{runs[s][form]['min_cluster_size']}" for s in seeds)
        lines.append(f"{form}: link threshold / min_cluster_size chosen per seed: {chosen}")
    return "\n".join(lines)


def _cell(values, paired=False):
    """Mean ± SE; ``paired``: a paired difference, signed, ± 2 SE."""
    mean, se = _mean_se(values)
    return f"{mean:+.3f} ± {2 * se:.3f}" if paired else f"{mean:.3f} ± {se:.3f}"


def _record_path(folder, preset, seed):
    return Path(folder) / f"lagged_{preset}_{seed}.json"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    data_arguments(parser)
    choice_arguments(parser)
    parser.add_argument("--lags", type=float, nargs="+", default=[0.0, 0.1, 0.25], help="s after the links are known")
    parser.add_argument(
        "--links",
        choices=("offline", "causal"),
        default="offline",
        help="the links' model: seeing 0.15 s on both sides of a detection, or its past only (the main job's)",
    )
    parser.add_argument(
        "--against",
        default=str(Path(__file__).parent / "results" / "sliding_grouping"),
        help="experiment_sliding_grouping.py's records of the same data (its causal and sliding forms)",
    )
    options = parsed(parser, argv)
    for preset in options.presets:
        runs = records(options, preset, measure, _record_path)
        if runs:
            against = saved_records(options.against, preset, runs, sliding_record)
            print(table(preset, runs, against), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
