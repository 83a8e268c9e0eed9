"""The main job on a busy machine: ``sklearn-radar reproduce`` at load 0 and beside busy loops, wall and CPU time.

Run: ``python benchmarks/bench_load.py`` (the default run, ``reproduce`` with its default settings on simulated
data, twice: many minutes) or ``python benchmarks/bench_load.py --classification`` (only
``--experiments 1,classification``, the step of issue 46: a minute or two).  ``--experiments`` and ``--n-iter``
reduce the run further (passed to ``reproduce``); ``--load`` sets the busy loops (default 4), ``--n-jobs`` is
passed on; ``--warmup`` runs the command once untimed first (numba's cache, the disk cache).

Each condition runs the same command in a fresh process: once with nothing else started by this script ("load 0":
other users of the machine still count, so the load average before and after each run is printed), once while
``--load`` processes each spin a core in a pure-Python busy loop (load about 4 with the default; ``--nice``
sets their niceness, 0 as the run's by default, 19 for background jobs).  The busy loops
start before the run, stop when it ends, also when this script is interrupted or killed (each checks a few times a
second that this script is still its parent).  OMP_NUM_THREADS, OPENBLAS_NUM_THREADS, MKL_NUM_THREADS and the like
are removed from the run's environment (``--keep-env`` keeps them), so that the run's own bound on its threads is
what is measured.

Printed per condition: wall time, the run's CPU time (user + system of the command and the processes it waited for,
from ``wait4``), CPU/wall, and each step's time from the run's progress lines; then the ratios loaded / load 0.  With
``--load 4`` at niceness 0 on an otherwise idle 2-core machine, a run on one thread is one of 5 runnable processes
on 2 cores: it gets about 0.4 core, so its wall time stretches up to about 2.5x without any oversubscription.  CPU
time is what oversubscription (threads waiting on each other for cores they do not get) inflates.
"""

from __future__ import annotations

import argparse
import atexit
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

#: Environment variables that bound the libraries' threads from outside: removed so that the run's own bound counts.
THREAD_VARIABLES = (
    "OMP_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "MKL_NUM_THREADS",
    "BLIS_NUM_THREADS",
    "VECLIB_MAXIMUM_THREADS",
    "NUMEXPR_NUM_THREADS",
    "NUMBA_NUM_THREADS",
)

#: One busy loop: spins until its parent (this script) is gone, checking a few times a second.
BUSY_LOOP = """
import os
parent = os.getppid()
os.nice(NICE)
while os.getppid() == parent:
    for _ in range(200_000):
        pass
"""

_busy = []


def start_load(n, nice=0):
    """Start ``n`` busy-loop processes at niceness ``nice`` (stopped by :func:`stop_load`, at exit, or when this
    process dies)."""
    code = BUSY_LOOP.replace("NICE", str(int(nice)))
    for _ in range(n):
        _busy.append(subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.DEVNULL))


def stop_load():
    """Stop the busy loops started by :func:`start_load` (each by its own process id)."""
    while _busy:
        process = _busy.pop()
        if process.poll() is None:
            process.kill()
        process.wait()


def _stop_on_signal(signum, frame):
    stop_load()
    raise SystemExit(128 + signum)


def run_once(command, env, log):
    """Run ``command``: (wall s, CPU s of it and the processes it waited for, exit code); its output to ``log``."""
    with open(log, "w") as out:
        started = time.perf_counter()
        process = subprocess.Popen(command, stdout=out, stderr=subprocess.STDOUT, env=env, cwd=ROOT)
        _, status, usage = os.wait4(process.pid, 0)
        wall = time.perf_counter() - started
    process.returncode = os.waitstatus_to_exitcode(status)
    return wall, usage.ru_utime + usage.ru_stime, process.returncode


def step_times(log):
    """``{step title: seconds}`` from the run's ``[k/n] ... done in X s`` progress lines."""
    found = {}
    for line in Path(log).read_text(errors="replace").splitlines():
        match = re.match(r"\s*\[(\d+)/(\d+)\] (.*?) done in ([\d.]+) s", line)
        if match:
            found[f"[{match[1]}/{match[2]}] {match[3][:60]}"] = float(match[4])
    return found


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--classification", action="store_true", help="only --experiments 1,classification")
    parser.add_argument("--experiments", default=None, help="passed to reproduce (default: its default, all)")
    parser.add_argument("--n-iter", type=int, default=None, help="passed to reproduce (default: its default)")
    parser.add_argument("--n-jobs", type=int, default=None, help="passed to reproduce (default: not given)")
    parser.add_argument("--load", type=int, default=4, help="busy-loop processes of the loaded run (default 4)")
    parser.add_argument("--nice", type=int, default=0, help="niceness of the busy loops (default 0, as the run)")
    parser.add_argument("--warmup", action="store_true", help="run the command once untimed first")
    parser.add_argument("--keep-env", action="store_true", help="keep OMP_NUM_THREADS and the like")
    parser.add_argument("--keep", default=None, help="folder to keep the runs' outputs and logs in")
    args = parser.parse_args(argv)
    if args.classification and args.experiments:
        parser.error("give --classification or --experiments, not both")
    experiments = "1,classification" if args.classification else args.experiments

    atexit.register(stop_load)
    signal.signal(signal.SIGTERM, _stop_on_signal)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    if not args.keep_env:
        for name in THREAD_VARIABLES:
            env.pop(name, None)
    folder = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="bench-load-"))
    folder.mkdir(parents=True, exist_ok=True)

    def command(name):
        line = [sys.executable, "-m", "sklearn_radar", "reproduce", "--out", str(folder / name)]
        if experiments:
            line += ["--experiments", experiments]
        if args.n_iter is not None:
            line += ["--n-iter", str(args.n_iter)]
        if args.n_jobs is not None:
            line += ["--n-jobs", str(args.n_jobs)]
        return line

    print(f"command: {' '.join(command('<out>')[1:])}; busy loops: {args.load} at niceness {args.nice}")
    outside = ", ".join(f"{n}={os.environ[n]}" for n in THREAD_VARIABLES if n in os.environ) or "none set"
    print(
        f"cores: {os.cpu_count()}; thread variables of this shell ({'kept' if args.keep_env else 'removed'}): {outside}"
    )
    try:
        if args.warmup:
            wall, cpu, code = run_once(command("warmup"), env, folder / "warmup.log")
            print(f"warm-up: {wall:.1f} s wall, {cpu:.1f} s CPU (exit {code})")
        found = {}
        for name, load in (("load 0", 0), (f"load {args.load}", args.load)):
            before = os.getloadavg()[0]
            start_load(load, args.nice)
            try:
                if load:
                    time.sleep(2.0)  # the busy loops running before the clock starts
                wall, cpu, code = run_once(command(name.replace(" ", "")), env, folder / f"{name.replace(' ', '')}.log")
            finally:
                stop_load()
            after = os.getloadavg()[0]
            if code != 0:
                print(f"{name}: the run failed (exit {code}); its output: {folder / (name.replace(' ', '') + '.log')}")
                return 1
            found[name] = (wall, cpu, step_times(folder / f"{name.replace(' ', '')}.log"))
            print(
                f"{name}: wall {wall:.1f} s, CPU {cpu:.1f} s (CPU/wall {cpu / wall:.2f}); "
                f"load average {before:.2f} before, {after:.2f} after"
            )
        (wall0, cpu0, steps0), (wall1, cpu1, steps1) = found.values()
        print(f"\nratio load {args.load} / load 0: wall {wall1 / wall0:.2f}x, CPU {cpu1 / cpu0:.2f}x")
        print(f"\n{'step':66s} {'load 0 (s)':>10s} {f'load {args.load} (s)':>10s} {'ratio':>6s}")
        for step, seconds in steps0.items():
            loaded = steps1.get(step)
            ratio = f"{loaded / seconds:6.2f}" if loaded is not None and seconds > 0 else "     -"
            print(f"{step:66s} {seconds:10.1f} {loaded if loaded is not None else float('nan'):10.1f} {ratio}")
    finally:
        stop_load()
        if not args.keep:
            shutil.rmtree(folder, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
