"""``--scheduler`` / ``--workers``: the run and ``cluster`` on a local dask cluster that the tests start themselves.

The references are single-process runs of the same code path without dask
(and, for ``cluster``, one pipeline fitted on the whole table): a cluster
run must give the same figures and the same bytes.
"""

import json
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from sklearn_radar._executor import connect_executor
from sklearn_radar.cli import main
from sklearn_radar.datasets import load_radarscenes
from sklearn_radar.experiments import experiment_pipeline
from sklearn_radar.reproduce import cluster_radarscenes, load_params, reproduce, write_predictions

distributed = pytest.importorskip("dask.distributed")

#: The tiny run every comparison makes: one tuned stage-1 experiment, two candidates per step.
RUN = {"n_iter": 4, "experiments": "3", "seed": 0, "n_points": 2}
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _env():
    """Subprocess environment that imports this checkout's package."""
    return {**os.environ, "PYTHONPATH": os.pathsep.join([ROOT, os.environ.get("PYTHONPATH", "")])}


@pytest.fixture(scope="module")
def local_cluster():
    """Two worker processes (one thread each), as ``--workers 2`` starts them."""
    import logging

    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=logging.ERROR
    ) as cluster:
        yield cluster


@pytest.fixture(scope="module")
def single_process_run(tiny_folder, tmp_path_factory):
    out = tmp_path_factory.mktemp("single") / "out"
    reproduce(tiny_folder, out, stream=open(os.devnull, "w"), **RUN)
    return out


def _figures(out):
    """results.json without what may differ between equal runs (wall times, the run's own settings)."""

    def strip(value):
        if isinstance(value, dict):
            return {k: strip(v) for k, v in value.items() if "time" not in k}
        if isinstance(value, list):
            return [strip(v) for v in value]
        return value

    return strip(json.loads((out / "results.json").read_text()))


def _free_port():
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


# ----------------------------------------------------------------------------- without the flags


def test_without_the_flags_dask_is_not_imported(tiny_folder, tmp_path):
    out = tmp_path / "out"
    code = f"""
import sys
from sklearn_radar.cli import main
assert main(["reproduce", "--data", {str(tiny_folder)!r}, "--out", {str(out)!r}, "--n-iter", "1",
             "--experiments", "1"]) == 0
assert main(["cluster", "--data", {str(tiny_folder)!r}, "--params", {str(out / "params.json")!r},
             "--out", {str(tmp_path / "p.json")!r}]) == 0
print(sorted(m for m in sys.modules if m.split(".")[0] in ("dask", "distributed")))
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=_env(), timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().splitlines()[-1] == "[]"
    assert (tmp_path / "p.json").is_file()


# ----------------------------------------------------------------------------- bad input: one line, quickly


def test_unreachable_scheduler_is_a_one_line_error_naming_the_address(tiny_folder, tmp_path, capsys):
    address = f"tcp://127.0.0.1:{_free_port()}"  # nothing listens there
    code = main(["reproduce", "--data", str(tiny_folder), "--out", str(tmp_path / "o"), "--scheduler", address])
    err = capsys.readouterr().err
    assert code == 1
    assert err.count("\n") == 1 and err.startswith("sklearn-radar: error:")
    assert address in err
    assert not (tmp_path / "o").exists()  # nothing started


def test_malformed_scheduler_address_is_a_one_line_error(tiny_folder, tmp_path, capsys):
    params = tmp_path / "params.json"
    reproduce(tiny_folder, tmp_path / "r", n_iter=1, experiments="1", stream=open(os.devnull, "w"))
    params.write_text((tmp_path / "r" / "params.json").read_text())
    code = main(
        [
            *("cluster", "--data", str(tiny_folder), "--params", str(params), "--out", str(tmp_path / "p.json")),
            *("--scheduler", "not an address::"),
        ]
    )
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1
    assert "not an address::" in err
    assert not (tmp_path / "p.json").exists()


@pytest.mark.parametrize("value", ["0", "-2", "two", "1.5"])
@pytest.mark.parametrize("command", ["reproduce", "cluster"])
def test_bad_workers_value_is_a_one_line_error_naming_the_flag(command, value, tmp_path, capsys):
    args = ["--data", str(tmp_path), "--out", str(tmp_path / "o"), "--workers", value]
    if command == "cluster":
        args += ["--params", str(tmp_path / "params.json")]
    code = main([command, *args])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert "--workers" in err and repr(value) in err


def test_missing_dask_is_a_one_line_error_naming_the_extra(tiny_folder, tmp_path):
    # A fresh interpreter in which importing dask fails, as on a machine without the extra.
    code = f"""
import sys
sys.modules["dask"] = None
from sklearn_radar.cli import main
sys.exit(main(["reproduce", "--data", {str(tiny_folder)!r}, "--out", {str(tmp_path / "o")!r}, "--workers", "2"]))
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=_env(), timeout=120)
    assert done.returncode == 1
    assert done.stderr.count("\n") == 1, done.stderr
    assert "pip install 'sklearn-radar[distributed]'" in done.stderr


def test_both_scheduler_and_workers_is_an_error(tmp_path):
    with pytest.raises(ValueError, match="not both"):
        reproduce(tmp_path / "data", tmp_path / "o", scheduler="tcp://127.0.0.1:1", workers=2)


# ----------------------------------------------------------------------------- the search on the cluster


def test_search_on_the_cluster_equals_the_single_process_run(local_cluster, tiny_folder, single_process_run, tmp_path):
    import io

    progress = io.StringIO()
    out = tmp_path / "out"
    reproduce(tiny_folder, out, stream=progress, scheduler=local_cluster.scheduler_address, **RUN)
    assert "dask cluster at" in progress.getvalue()
    cluster_figures, single_figures = _figures(out), _figures(single_process_run)
    assert cluster_figures == single_figures
    assert len(single_figures["experiments"]["3"]["convergence"]) == RUN["n_iter"]
    assert (out / "params.json").read_text() == (single_process_run / "params.json").read_text()


#: Every step that reads the data: statistics (always), filter evaluation, an untuned, a tuned, a derived and a
#: stage-2 experiment, the filter effect, the baselines and the classifier.
EVERY_STEP = {"n_iter": 2, "experiments": "filter,1,8,10,13,filter-effect,baselines,classification", "seed": 0}


def _without_clock(figures):
    """:func:`_figures` without the filter effect's measured clustering times (all else must be equal)."""
    effect = figures.get("filter_effect")
    if effect:
        for side in ("filtered", "unfiltered"):
            effect[side].pop("clustering_s")
    return figures


def test_a_cluster_run_never_loads_a_sequence_here_and_equals_one_process(
    local_cluster, tiny_folder, tmp_path, monkeypatch
):
    from sklearn_radar.reproduce import _sequences

    alone = tmp_path / "alone"
    reproduce(tiny_folder, alone, stream=open(os.devnull, "w"), **EVERY_STEP)

    def no_loading_here(*args, **kwargs):
        raise AssertionError("a sequence was loaded in the command's process")

    # The workers are other processes: they load the sequences with the real function.
    monkeypatch.setattr(_sequences, "load_radarscenes", no_loading_here)
    on_cluster = tmp_path / "cluster"
    reproduce(
        tiny_folder, on_cluster, stream=open(os.devnull, "w"), scheduler=local_cluster.scheduler_address, **EVERY_STEP
    )
    assert _without_clock(_figures(on_cluster)) == _without_clock(_figures(alone))
    assert (on_cluster / "report.md").is_file()
    assert sorted(p.name for p in on_cluster.glob("*.png")) == sorted(p.name for p in alone.glob("*.png"))
    with pytest.raises(AssertionError, match="command's process"):
        reproduce(tiny_folder, tmp_path / "here", stream=open(os.devnull, "w"), **{**EVERY_STEP, "experiments": "1"})


def test_simulated_data_is_simulated_on_the_workers_and_equals_one_process(local_cluster, tmp_path, monkeypatch):
    from sklearn_radar.reproduce import _sequences

    run = {"n_iter": 2, "experiments": "filter,3", "seed": 1}
    alone = tmp_path / "alone"
    reproduce(None, alone, stream=open(os.devnull, "w"), **run)

    def no_simulation_here(*args, **kwargs):
        raise AssertionError("a sequence was simulated in the command's process")

    monkeypatch.setattr(_sequences, "simulate_sequences", no_simulation_here)
    on_cluster = tmp_path / "cluster"
    reproduce(None, on_cluster, stream=open(os.devnull, "w"), scheduler=local_cluster.scheduler_address, **run)
    assert _figures(on_cluster) == _figures(alone)
    assert _figures(alone)["meta"]["data"]["n_sequences"] > 1


def test_independent_searches_run_concurrently_and_equal_one_after_the_other(local_cluster, tiny_folder, tmp_path):
    # #3 and #5 (stage 1) need nothing from each other: on a cluster they start at once, each in a thread of
    # this process.  The progress goes to an open file, which must never have to travel to a worker.
    run = {**RUN, "experiments": "3,5", "n_points": 1}
    alone = tmp_path / "alone"
    reproduce(tiny_folder, alone, stream=open(os.devnull, "w"), **run)
    together, log = tmp_path / "together", tmp_path / "progress.log"
    with open(log, "w") as progress:
        reproduce(tiny_folder, together, stream=progress, scheduler=local_cluster.scheduler_address, **run)
    text = log.read_text()
    assert "2 independent searches run on the cluster" in text
    assert "search #3 ended (" in text and "search #5 ended (" in text and "(2/2 of the concurrent searches)" in text
    figures = _figures(together)
    assert figures == _figures(alone)
    assert figures["experiments"]["3"]["params"] != figures["experiments"]["5"]["params"]


def test_local_workers_keep_glibc_default_memory_trimming(local_cluster, monkeypatch):
    # dask's MALLOC_TRIM_THRESHOLD_ made the clustering kernels 2.1x slower per detection in its workers.  dask
    # also writes it into the spawning process's environment (the module's default local_cluster did).
    from sklearn_radar._executor import MALLOC_TRIM

    monkeypatch.setenv(MALLOC_TRIM, "65536")
    with connect_executor(workers=1) as cluster:
        environment = cluster.client.run(lambda: dict(os.environ))
        assert "MALLOC_TRIM" not in cluster.describe()
    (worker,) = environment.values()
    assert MALLOC_TRIM not in worker
    assert worker.get("OMP_NUM_THREADS") == "1"  # dask's other settings stay
    assert os.environ[MALLOC_TRIM] == "65536"  # this process's environment is given back


def test_workers_started_as_documented_run_without_malloc_trim_and_others_are_named(local_cluster, tmp_path):
    # The docs' way for workers on other machines: dask worker with DASK_CONFIG holding WORKER_CONFIG.
    from sklearn_radar._executor import MALLOC_TRIM, WORKER_CONFIG, malloc_trim_setting

    (tmp_path / "dask.yaml").write_text(WORKER_CONFIG)
    env = {**_env(), "DASK_CONFIG": str(tmp_path)}
    env.pop(MALLOC_TRIM, None)
    worker = subprocess.Popen(
        [sys.executable, "-m", "distributed.cli.dask_worker", local_cluster.scheduler_address, "--nthreads", "1"],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        with connect_executor(scheduler=local_cluster.scheduler_address) as cluster:
            cluster.client.wait_for_workers(3, timeout=60)
            values = cluster.client.run(malloc_trim_setting)
        assert sorted(v is None for v in values.values()) == [False, False, True]  # the fixture's two have it
        with connect_executor(scheduler=local_cluster.scheduler_address) as cluster:
            assert cluster.n_malloc_trim == 2
            assert f"2 worker(s) run with dask's {MALLOC_TRIM}" in cluster.describe()
            assert f"pre-spawn-environ.{MALLOC_TRIM}: null" in cluster.describe()
    finally:
        worker.terminate()
        worker.wait(timeout=30)


# ----------------------------------------------------------------------------- cluster: per sequence, a stream


@pytest.fixture(scope="module")
def saved_params(single_process_run):
    return single_process_run / "params.json"


def _whole_table_predictions(tiny_folder, saved_params, path):
    """The reference: the saved pipeline fitted once on every detection, written in one piece."""
    setting = load_params(saved_params)
    scenes = load_radarscenes(tiny_folder)
    pipeline = experiment_pipeline(setting["experiment"], params=setting["params"])
    write_predictions(scenes.data["uuid"].to_numpy(), pipeline.fit_predict(scenes.data), path)
    return path.read_bytes()


def test_cluster_streams_per_sequence_and_equals_the_whole_table_fit(tiny_folder, saved_params, tmp_path, monkeypatch):
    from sklearn_radar.cli import _cluster as _cluster_command

    loaded = []

    def load_one(path, sequences=None):
        bunch = load_radarscenes(path, sequences=sequences)
        loaded.append(np.unique(bunch.groups).tolist())
        return bunch

    monkeypatch.setattr(_cluster_command, "load_radarscenes", load_one)
    summary = cluster_radarscenes(tiny_folder, saved_params, tmp_path / "p.json")
    assert loaded == [[1], [2], [3], [4]]  # one sequence at a time, never the whole table
    reference = _whole_table_predictions(tiny_folder, saved_params, tmp_path / "ref.json")
    assert (tmp_path / "p.json").read_bytes() == reference
    document = json.loads(reference)
    assert summary["n_detections"] == len(document["predictions"])
    assert summary["n_clusters"] == len({v[1] for v in document["predictions"].values()} - {-1})


def test_cluster_on_the_workers_writes_the_same_bytes(local_cluster, tiny_folder, saved_params, tmp_path):
    cluster_radarscenes(tiny_folder, saved_params, tmp_path / "p.json", scheduler=local_cluster.scheduler_address)
    reference = _whole_table_predictions(tiny_folder, saved_params, tmp_path / "ref.json")
    assert (tmp_path / "p.json").read_bytes() == reference


def test_cluster_command_with_local_workers(tiny_folder, saved_params, tmp_path):
    out = tmp_path / "p.json"
    args = ["cluster", "--data", str(tiny_folder), "--params", str(saved_params), "--out", str(out), "--workers", "2"]
    done = subprocess.run(
        [sys.executable, "-m", "sklearn_radar", *args], capture_output=True, text=True, env=_env(), timeout=300
    )
    assert done.returncode == 0, done.stderr
    assert out.read_bytes() == _whole_table_predictions(tiny_folder, saved_params, tmp_path / "ref.json")


def test_a_sequence_that_cannot_be_read_fails_the_stream_without_output(local_cluster, tiny_folder, tmp_path):
    import shutil

    broken = tmp_path / "broken"
    shutil.copytree(tiny_folder, broken)
    (broken / "sequence_3" / "radar_data.h5").unlink()
    params = tmp_path / "params.json"
    reproduce(tiny_folder, tmp_path / "r", n_iter=1, experiments="1", stream=open(os.devnull, "w"))
    params.write_text((tmp_path / "r" / "params.json").read_text())
    with pytest.raises(FileNotFoundError, match="sequence_3"):
        cluster_radarscenes(broken, params, tmp_path / "p.json", scheduler=local_cluster.scheduler_address)
    assert not (tmp_path / "p.json").exists()
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]


# ----------------------------------------------------------------------------- fault tolerance


#: Kills one worker process while it computes, after the search's first tasks finished (a later step's run).
KILLER = """
import json, logging, os, signal, sys, threading, time
import dask.distributed as distributed
from sklearn_radar.reproduce import reproduce

data, out, run, delay = sys.argv[1], sys.argv[2], json.loads(sys.argv[3]), float(sys.argv[4])
killed = []


def kill_one_worker(address, stop):
    # Without a delay: once the cluster was busy, then idle (between search steps), the next busy worker.
    # With one (searches at once keep the cluster busy): a busy worker, delay seconds after the first task.
    client = distributed.Client(address, set_as_default=False)
    pids = client.run(os.getpid)
    seen_busy = seen_idle = False
    first_busy = None
    while not stop.is_set():
        busy = [w for w, keys in client.processing().items() if keys]
        if busy and first_busy is None:
            first_busy = time.monotonic()
        ready = seen_idle if delay == 0 else first_busy is not None and time.monotonic() - first_busy >= delay
        if busy and ready:
            os.kill(pids[busy[0]], signal.SIGKILL)
            killed.append(busy[0])
            break
        seen_busy |= bool(busy)
        seen_idle |= seen_busy and not busy
        time.sleep(0.005)
    client.close()


if __name__ == "__main__":
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=logging.CRITICAL
    ) as cluster:
        stop = threading.Event()
        killer = threading.Thread(target=kill_one_worker, args=(cluster.scheduler_address, stop))
        killer.start()
        try:
            reproduce(data, out, stream=open(os.devnull, "w"), scheduler=cluster.scheduler_address, **run)
        finally:
            stop.set()
            killer.join()
    print(json.dumps(killed))
"""


@pytest.mark.parametrize("concurrent", [False, True], ids=["one search", "searches at once"])
def test_a_worker_killed_mid_search_loses_nothing(tiny_folder, single_process_run, tmp_path, concurrent):
    """SIGKILL the worker process computing a task mid-search; the run ends with the same figures."""
    # In a subprocess: a worker restarted by its nanny under pytest's output capture hung the test process.
    script = tmp_path / "kill_a_worker.py"
    script.write_text(KILLER)
    out = tmp_path / "out"
    run, reference = RUN, single_process_run
    if concurrent:  # the search loops are tasks on the workers too: one of them dies with its worker
        run = {**RUN, "experiments": "3,5", "n_iter": 8, "n_points": 1}
        reference = tmp_path / "reference"
        reproduce(tiny_folder, reference, stream=open(os.devnull, "w"), **run)
    done = subprocess.run(
        [sys.executable, str(script), str(tiny_folder), str(out), json.dumps(run), "1.0" if concurrent else "0"],
        capture_output=True,
        text=True,
        env=_env(),
        timeout=600,
    )
    assert done.returncode == 0, done.stderr
    assert len(json.loads(done.stdout.strip().splitlines()[-1])) == 1, "no worker was killed during the search"
    assert _figures(out) == _figures(reference)
    assert json.loads((out / "run.json").read_text())["complete"] is True


def _nap(seconds, folder, k, *data):
    time.sleep(seconds)
    (Path(folder) / f"nap-{k}").touch()  # the naps done so far, for the test to count


def _block(k):
    return k


def _search_like(n_tasks, seconds, folder):
    """Queue ``n_tasks`` naps from a worker, as a search's loop queues its candidates, and wait for them.

    Like the candidates, the naps work on data placed on the workers, more
    than 5 pieces (dask would otherwise hold them back as root tasks).
    """
    from distributed import worker_client

    with worker_client() as client:
        blocks = [client.submit(_block, k, pure=False) for k in range(6)]
        naps = [client.submit(_nap, seconds, folder, k, *blocks, pure=False) for k in range(n_tasks)]
        (Path(folder) / "queued").touch()
        client.gather(naps)
    return n_tasks


def _sequence_length(sequence):
    return len(sequence)


def test_a_steps_tasks_go_ahead_of_queued_search_tasks(local_cluster, tmp_path):
    # The run's steps wait for their per-sequence tasks one after the other, while the concurrent searches keep
    # the workers' queue full: a step's tasks must not wait for that whole queue.
    from sklearn_radar.reproduce._sequences import RunSequences

    with connect_executor(scheduler=local_cluster.scheduler_address) as cluster:
        sequences = RunSequences.simulated(2, 1.0, 0, executor=cluster)
        sequences.map(_sequence_length)  # placed before the queue fills
        # Queued from a task, as the concurrent searches queue their candidates: dask ranks such sub-tasks ahead of
        # anything the command submits later, unless the command's tasks have a higher priority.
        search = cluster.client.submit(_search_like, 30, 0.2, str(tmp_path), pure=False)
        while not (tmp_path / "queued").exists():
            time.sleep(0.05)
        lengths = sequences.map(_sequence_length)
        waiting = 30 - len(list(tmp_path.glob("nap-*")))
        assert search.result() == 30
    assert lengths == sequences.sizes
    assert waiting > 10  # most of the queue (3 s of naps on 2 workers) was still ahead when the step finished


def test_local_workers_that_would_slow_a_small_run_down_are_not_started(tmp_path):
    # One search at a time on the default run's data: a local cluster was 2x slower than one process, so the run
    # stays here and its first line says so; with searches at once, a folder or --scheduler, the cluster is used.
    from sklearn_radar._executor import LocalExecutor
    from sklearn_radar.reproduce._budget import Budget
    from sklearn_radar.reproduce._run import _in_process_reason, parse_experiments

    small = _in_process_reason(None, Budget.default(), parse_experiments("3"), 1)
    assert "one search at a time" in small
    assert _in_process_reason(None, Budget.default(), parse_experiments("8,12"), 1)  # #12 waits for #8: one at a time
    assert _in_process_reason(None, Budget.default(), parse_experiments("3"), 2) is None  # 2 repeats at once
    assert _in_process_reason(None, Budget.default(), parse_experiments(None), 1) is None  # 12 searches at once
    assert _in_process_reason(None, Budget.full(), parse_experiments("3"), 1) is None  # larger data
    assert _in_process_reason(tmp_path, Budget.default(), parse_experiments("3"), 1) is None  # a folder
    with connect_executor(workers=2, in_process_reason=small) as executor:
        assert isinstance(executor, LocalExecutor)
        assert executor.describe() == f"--workers 2: {small}; running in this process"
    code = (
        "import sys\n"
        "from sklearn_radar._executor import connect_executor\n"
        "with connect_executor(workers=2, in_process_reason='small') as executor:\n"
        "    pass\n"
        "assert 'distributed' not in sys.modules, 'dask was imported'\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, env=_env(), cwd=ROOT)
