"""Mutation check: do the tests catch small, deliberate bugs in the core formulas and kernels?

Run on demand (not in CI)::

    python scripts/mutation_check.py                  # every mutant, the repository's package and tests
    python scripts/mutation_check.py --list           # the mutants, and whether each snippet still matches
    python scripts/mutation_check.py -k M7 -k FT1     # a few mutants
    python scripts/mutation_check.py --tests-root /tmp/wt-before   # the package here, older tests

Each mutant is (file, exact source snippet, replacement, test modules).
The package and the tests are copied to a temporary folder; one mutant at
a time is written into the copy and its test modules are run there with
``python -m pytest -x`` (working directory = the copy, ``PYTHONPATH`` =
the copy, ``--import-mode=importlib``), so the mutated copy is what gets
imported -- checked once before the run.  ``NUMBA_CACHE_DIR`` points into
the temporary folder: the numba cache of the real package is never reused,
and the cache entries of the mutated module (and of the numba modules that
import it, whose cached machine code inlines it) are dropped before each
run and restored after it.

A mutant is *caught* when its tests fail (or time out), *survived* when
they pass.  Mutants are matched by their snippet, never by line number: a
snippet that no longer occurs in the file is reported as *stale* (it needs
updating, the run goes on); one that occurs more than once as *ambiguous*,
unless the mutant says ``every=True`` (the same slip made at every
occurrence, e.g. in the offline and the causal kernel).
Before the mutants, the unmutated copy must pass every selected module.

Exit status: 0 when every (non-stale) mutant is caught, 1 otherwise, 2 when
the unmutated copy fails its tests.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

# Test modules per area (paths relative to the tests root's parent).
DBSCAN = (
    "tests/cluster/test_radar_dbscan.py",
    "tests/cluster/test_radar_dbscan_kernels.py",
    "tests/cluster/test_radar_dbscan_streaming.py",
)
FILTER = ("tests/preprocessing/test_doppler_density_filter.py",)
VELOCITY = ("tests/cluster/test_velocity.py",)
MERGER = ("tests/cluster/test_cluster_merger.py",)
V_MEASURE = ("tests/metrics/test_v_measure.py",)
FRAME = ("tests/preprocessing/test_frame_transform.py",)

FILTER_PY = "sklearn_radar/preprocessing/_doppler_density_filter.py"
NEIGHBORS_PY = "sklearn_radar/_neighbors.py"
DBSCAN_PY = "sklearn_radar/cluster/_radar_dbscan.py"
KERNELS_PY = "sklearn_radar/cluster/_radar_dbscan_kernels.py"
VELOCITY_PY = "sklearn_radar/cluster/_velocity.py"
MERGER_PY = "sklearn_radar/cluster/_cluster_merger.py"
MERGE_KERNELS_PY = "sklearn_radar/cluster/_merge_kernels.py"
V_MEASURE_PY = "sklearn_radar/metrics/_v_measure.py"
FRAME_PY = "sklearn_radar/preprocessing/_frame_transform.py"


@dataclass(frozen=True)
class Mutant:
    id: str
    file: str  # relative to the package root's parent
    snippet: str  # exact source text, must occur exactly once
    replacement: str
    tests: tuple
    description: str
    original: bool = False  # one of the twelve kinds of issue 19's first experiment
    every: bool = False  # replace every occurrence of the snippet (else it must occur exactly once)


MUTANTS = (
    # --- Eq. 1, the Doppler-density filter rule -------------------------------------------------------------
    Mutant("F1", FILTER_PY, "remove = n < 1", "remove = n < 0", FILTER, "Eq. 1: the rule N < 1 (no neighbour) dropped"),
    Mutant(
        "F2",
        FILTER_PY,
        "(speed < vr_threshold / ratio)",
        "(speed <= vr_threshold / ratio)",
        FILTER,
        "Eq. 1: |v_r| < eta_i made inclusive",
        original=True,
    ),
    Mutant("F3", FILTER_PY, "& (n < n_min)", "& (n <= n_min)", FILTER, "Eq. 1: N < N_i made inclusive"),
    Mutant(
        "F4",
        FILTER_PY,
        "(speed < vr_threshold / ratio)",
        "(speed < vr_threshold * ratio)",
        FILTER,
        "Eq. 1: eta_i = eta_1 * ratio instead of eta_1 / ratio",
    ),
    Mutant(
        "F5",
        FILTER_PY,
        "speed = np.abs(np.asarray(v_r, dtype=np.float64))",
        "speed = np.asarray(v_r, dtype=np.float64)",
        FILTER,
        "Eq. 1: signed v_r compared instead of |v_r|",
    ),
    # --- neighbour search shared by the filter and RadarDBSCAN ----------------------------------------------
    Mutant(
        "N1",
        NEIGHBORS_PY,
        "if ddx * ddx + ddy * ddy <= radius2:",
        "if ddx * ddx + ddy * ddy < radius2:",
        FILTER,
        "filter neighbours: distance <= d_xy made strict",
    ),
    Mutant(
        "N2",
        NEIGHBORS_PY,
        "while hi < end and times[hi] <= t_high:",
        "while hi < end and times[hi] < t_high:",
        FILTER + DBSCAN,
        "time window: the upper edge t + eps_t made exclusive",
        original=True,
    ),
    # --- Eq. 2, range-adaptive N_min(r) ----------------------------------------------------------------------
    Mutant(
        "M2a",
        DBSCAN_PY,
        "np.clip(np.asarray(range_m, dtype=np.float64), 25.0, 125.0)",
        "np.clip(np.asarray(range_m, dtype=np.float64), 25.0, 100.0)",
        DBSCAN,
        "Eq. 2: range clipped to [25, 100] m instead of [25, 125] m",
        original=True,
    ),
    Mutant(
        "M2b",
        DBSCAN_PY,
        "min_samples * (1.0 + alpha_r * relative)",
        "min_samples * (1.0 + alpha_r**2 * relative)",
        DBSCAN,
        "Eq. 2: slope alpha_r squared",
        original=True,
    ),
    Mutant(
        "M2c",
        DBSCAN_PY,
        "min_samples * (1.0 + alpha_r * relative)",
        "min_samples * (1.0 + relative)",
        DBSCAN,
        "Eq. 2: slope alpha_r dropped",
        original=True,
    ),
    Mutant(
        "M2d",
        DBSCAN_PY,
        'relative = r / 50.0 - 1.0 if range_scaling == "linear" else 50.0 / r - 1.0',
        'relative = 50.0 / r - 1.0 if range_scaling == "linear" else r / 50.0 - 1.0',
        DBSCAN,
        "Eq. 2: linear and reciprocal forms swapped",
    ),
    # --- point rules of RadarDBSCAN ------------------------------------------------------------------------
    Mutant(
        "G1",
        DBSCAN_PY,
        'active & (np.abs(c["v_r"]) > self.vr_min)',
        'active & (np.abs(c["v_r"]) >= self.vr_min)',
        DBSCAN,
        "vr_min gate: |v_r| > vr_min made inclusive",
        original=True,
    ),
    Mutant(
        "G2",
        DBSCAN_PY,
        'active = np.ones(n, dtype=bool) if c["keep"] is None else c["keep"] != 0',
        "active = np.ones(n, dtype=bool)",
        DBSCAN,
        "rows removed by the filter (keep = False) take part",
    ),
    # --- Eqs. 3-5, the neighbourhood criteria --------------------------------------------------------------
    Mutant(
        "M7",
        KERNELS_PY,
        "along = points.cos_h[k] * dx + points.sin_h[k] * dy\n"
        "        across = points.cos_h[k] * dy - points.sin_h[k] * dx\n",
        "along = points.cos_h[k] * dx - points.sin_h[k] * dy\n"
        "        across = points.cos_h[k] * dy + points.sin_h[k] * dx\n",
        DBSCAN,
        "Eq. 3: box rotated by -heading instead of +heading",
        original=True,
    ),
    Mutant(
        "B1",
        KERNELS_PY,
        "abs(along) < eps_xy and abs(across) < eps_xy and abs(dv) < eps_vr",
        "abs(along) <= eps_xy and abs(across) <= eps_xy and abs(dv) < eps_vr",
        DBSCAN,
        "Eq. 3 (rotated box): |along|, |across| < eps_xy made inclusive",
    ),
    Mutant(
        "B2",
        KERNELS_PY,
        "return abs(dx) < eps_xy and abs(dy) < eps_xy and abs(dv) < eps_vr",
        "return abs(dx) <= eps_xy and abs(dy) <= eps_xy and abs(dv) < eps_vr",
        DBSCAN,
        "Eq. 3 (unrotated box): |dx|, |dy| < eps_xy made inclusive",
        original=True,
    ),
    Mutant(
        "B3",
        KERNELS_PY,
        "along = points.cos_h[k] * dx + points.sin_h[k] * dy\n"
        "        across = points.cos_h[k] * dy - points.sin_h[k] * dx\n",
        "along = points.sin_h[k] * dx + points.cos_h[k] * dy\n"
        "        across = points.sin_h[k] * dy - points.cos_h[k] * dx\n",
        DBSCAN,
        "Eq. 3: sin and cos swapped in the box rotation",
    ),
    Mutant(
        "B4",
        KERNELS_PY,
        "if points.t[i] >= points.t[j] else",
        "if points.t[i] <= points.t[j] else",
        DBSCAN,
        "Eq. 3: box axes of the earlier detection of the pair (criterion and border ranking)",
        every=True,
    ),
    Mutant(
        "E4",
        KERNELS_PY,
        "return dx * dx + dy * dy < eps_xy * eps_xy and abs(dv) < eps_vr",
        "return dx * dx + dy * dy <= eps_xy * eps_xy and abs(dv) < eps_vr",
        DBSCAN,
        "Eq. 4: distance < eps_xy made inclusive",
    ),
    Mutant(
        "E4b",
        KERNELS_PY,
        "return dx * dx + dy * dy < eps_xy * eps_xy and abs(dv) < eps_vr",
        "return dx * dx + dy * dy < eps_xy * eps_xy",
        DBSCAN,
        "Eq. 4: the Doppler condition |dv_r| < eps_vr dropped",
    ),
    Mutant(
        "E5",
        KERNELS_PY,
        "dv * dv / (crit.vr_scale * crit.vr_scale) < crit.eps_xyv * crit.eps_xyv",
        "dv * dv / (crit.vr_scale * crit.vr_scale) < crit.eps_xyv",
        DBSCAN,
        "Eq. 5: threshold eps_xyv not squared",
    ),
    # --- core points, borders and the causal neighbourhood ------------------------------------------------
    Mutant(
        "C1",
        KERNELS_PY,
        "core[i] = count >= need",
        "core[i] = count > need",
        DBSCAN,
        "core point: the point no longer counts itself toward N_min (offline and causal)",
        original=True,
        every=True,
    ),
    Mutant(
        "C2",
        KERNELS_PY,
        "need = max(math.ceil(min_points[i]) - 1, 0)",
        "need = max(int(min_points[i]) - 1, 0)",
        DBSCAN,
        "core point: real-valued N_min rounded down instead of up (offline and causal)",
        every=True,
    ),
    Mutant(
        "P1",
        KERNELS_PY,
        "if d < closest_distance:",
        "if closest < 0:",
        DBSCAN,
        "border point: joins the first core neighbour found instead of the closest (offline and causal)",
        every=True,
    ),
    Mutant(
        "T1",
        KERNELS_PY,
        "if lag < 0.0 or lag > crit.eps_t:",
        "if lag < 0.0 or lag >= crit.eps_t:",
        DBSCAN,
        "causal neighbourhood: lag = eps_t excluded",
    ),
    # --- full velocity (Kellner et al.), used by Eq. 6 ------------------------------------------------------
    Mutant(
        "V1",
        VELOCITY_PY,
        "hx = (ri * sj - rj * si) / det",
        "hx = (ri * sj + rj * si) / det",
        VELOCITY,
        "velocity: sign error in the 2x2 pair solution",
    ),
    Mutant(
        "V2",
        VELOCITY_PY,
        "return 0.5 * (high - low)",
        "return high - low",
        VELOCITY,
        "velocity: angular spread of the doubled angles not halved",
    ),
    Mutant(
        "V3",
        VELOCITY_PY,
        "(n_inliers >= min_detections)",
        "(n_inliers > min_detections)",
        VELOCITY,
        "velocity: min_detections inliers are not enough",
    ),
    Mutant(
        "V4",
        VELOCITY_PY,
        "inlier = np.abs(residual) < threshold",
        "inlier = residual < threshold",
        VELOCITY,
        "velocity: inlier test without the absolute value",
    ),
    # --- stage 2: Eq. 6 and continuation ----------------------------------------------------------------------
    Mutant(
        "R1",
        MERGER_PY,
        "(np.abs(np.hypot(*va.T) - np.hypot(*vb.T)) < self.eps_v)",
        "(np.hypot(*(va - vb).T) < self.eps_v)",
        MERGER,
        "Eq. 6: dv as the norm of the velocity difference instead of the difference of speeds",
    ),
    Mutant(
        "R2",
        MERGER_PY,
        "(np.arctan2(va[:, 1], va[:, 0]) - np.arctan2(vb[:, 1], vb[:, 0]) + np.pi) % (2 * np.pi) - np.pi",
        "np.arctan2(va[:, 1], va[:, 0]) - np.arctan2(vb[:, 1], vb[:, 0])",
        MERGER,
        "Eq. 6: direction difference not wrapped to [-pi, pi]",
    ),
    Mutant(
        "R3",
        MERGE_KERNELS_PY,
        "t[run_start[b]] - eps_t2, np.inf)",
        "-np.inf, np.inf)",
        MERGER,
        "Eq. 6: A's detections not limited to the frame [s_B - eps_t2, tau]",
    ),
    Mutant(
        "R4",
        MERGE_KERNELS_PY,
        "tau = min(t[run_end[b] - 1], start_b + eps_t2)",
        "tau = t[run_end[b] - 1]",
        MERGER,
        "stage 2: decision time not capped at s_B + eps_t2 (uses B's future)",
    ),
    Mutant(
        "R5",
        MERGE_KERNELS_PY,
        "eps_d2 = eps_d * eps_d",
        "eps_d2 = eps_d",
        MERGER,
        "Eq. 6: d_min compared with eps_d instead of eps_d^2 (squared distances)",
    ),
    Mutant(
        "R6",
        MERGE_KERNELS_PY,
        "core = degree + 1 >= min_samples",
        "core = degree >= min_samples",
        MERGER,
        "stage 2 DBSCAN: a cluster does not count itself toward min_samples",
    ),
    # --- V-measure ----------------------------------------------------------------------------------------
    Mutant(
        "VM1",
        V_MEASURE_PY,
        "(beta * homogeneity + completeness)",
        "(homogeneity + beta * completeness)",
        V_MEASURE,
        "V-measure: beta weights completeness instead of homogeneity",
        original=True,
    ),
    Mutant(
        "VM2",
        V_MEASURE_PY,
        "objects = labels_true != -1",
        "objects = labels_true >= -1",
        V_MEASURE,
        "V-measure: completeness over all detections (clustering background penalised)",
    ),
    Mutant(
        "VM3",
        V_MEASURE_PY,
        "homogeneity, _, _ = homogeneity_completeness_v_measure(labels_true, labels_pred)",
        "homogeneity, _, _ = homogeneity_completeness_v_measure(labels_true[labels_true != -1], "
        "labels_pred[labels_true != -1])",
        V_MEASURE,
        "V-measure: homogeneity over object detections only (background in a cluster not penalised)",
    ),
    Mutant(
        "VM4",
        V_MEASURE_PY,
        "if groups is None:\n        return labels",
        "if True:\n        return labels",
        V_MEASURE,
        "V-measure: sequences ignored (equal ids of different sequences are one cluster)",
    ),
    # --- frame transform ----------------------------------------------------------------------------------
    Mutant(
        "FT1",
        FRAME_PY,
        'sensor_vx = c["ego_vx"] - c["ego_yaw_rate"] * c["sensor_y"]',
        'sensor_vx = c["ego_vx"] + c["ego_yaw_rate"] * c["sensor_y"]',
        FRAME,
        "frame transform: sign of the yaw-rate term of the sensor's x velocity",
        original=True,
    ),
    Mutant(
        "FT2",
        FRAME_PY,
        'sensor_vy = c["ego_yaw_rate"] * c["sensor_x"]',
        'sensor_vy = -c["ego_yaw_rate"] * c["sensor_x"]',
        FRAME,
        "frame transform: sign of the sensor's y velocity",
    ),
    Mutant(
        "FT3",
        FRAME_PY,
        "sensor_vx * cos_a + sensor_vy * sin_a",
        "sensor_vx * sin_a + sensor_vy * cos_a",
        FRAME,
        "frame transform: sin and cos swapped in the ego-motion compensation",
        original=True,
    ),
    Mutant(
        "FT4",
        FRAME_PY,
        'x, y = c["ego_x_seq"] + cos_e * x - sin_e * y, c["ego_y_seq"] + sin_e * x + cos_e * y',
        'x, y = c["ego_x_seq"] + cos_e * x + sin_e * y, c["ego_y_seq"] - sin_e * x + cos_e * y',
        FRAME,
        "frame transform: car-to-sequence rotation by -yaw",
    ),
    Mutant(
        "FT5",
        FRAME_PY,
        'angle = c["azimuth_sc"] + c["sensor_yaw"]',
        'angle = c["azimuth_sc"]',
        FRAME,
        "frame transform: sensor yaw left out of the line of sight",
    ),
    Mutant(
        "FT6",
        FRAME_PY,
        '"heading": c["ego_yaw_seq"] if self.frame == "frame" else np.zeros(len(x))',
        '"heading": c["ego_yaw_seq"]',
        FRAME,
        "frame transform: car-frame (CCS) heading = ego yaw instead of 0",
    ),
)

#: Statuses that count as caught.
CAUGHT = ("caught", "timeout")


def _status_of_snippet(package_root, mutant):
    path = package_root / mutant.file
    if not path.is_file():
        return "stale", None
    text = path.read_text(encoding="utf-8")
    count = text.count(mutant.snippet)
    if count == 0:
        return "stale", text
    if count > 1 and not mutant.every:
        return "ambiguous", text
    return "ok", text


def _numba_dependents(package, module_path):
    """Stems of the numba modules whose cached code may inline ``module_path``'s functions (itself included)."""
    stem = module_path.stem
    dependents = {stem}
    for path in package.rglob("*.py"):
        text = path.read_text(encoding="utf-8")
        if "numba" in text and re.search(rf"from \.+(\w+\.)*{re.escape(stem)} import", text):
            dependents.add(path.stem)
    return dependents


def _drop_cache(cache_dir, stems):
    for path in cache_dir.rglob("*"):
        if path.is_file() and path.name.split(".", 1)[0] in stems:
            path.unlink()


def _restore_cache(cache_dir, warm_dir, stems):
    _drop_cache(cache_dir, stems)
    for path in warm_dir.rglob("*"):
        if path.is_file() and path.name.split(".", 1)[0] in stems:
            target = cache_dir / path.relative_to(warm_dir)
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(path, target)


def _run_pytest(work, env, modules, timeout, select=None):
    command = [
        sys.executable,
        "-m",
        "pytest",
        "-x",
        "-q",
        "-p",
        "no:cacheprovider",
        "--import-mode=importlib",
        "-o",
        "addopts=",
        "-rf",
        *(("-k", select) if select else ()),
        *modules,
    ]
    started = time.monotonic()
    try:
        result = subprocess.run(command, cwd=work, env=env, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return "timeout", time.monotonic() - started, ""
    output = result.stdout + result.stderr
    return result.returncode, time.monotonic() - started, output


def _first_failure(output):
    for line in output.splitlines():
        if line.startswith(("FAILED ", "ERROR ")):
            return line[:160]
    return output.strip().splitlines()[-1][:160] if output.strip() else ""


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--package-root", type=Path, default=ROOT, help="folder holding sklearn_radar/ (default: this repo)"
    )
    parser.add_argument("--tests-root", type=Path, default=None, help="folder holding tests/ (default: --package-root)")
    parser.add_argument("-k", "--only", action="append", default=[], help="run only this mutant id (repeatable)")
    parser.add_argument("--list", action="store_true", help="list the mutants and whether their snippets match")
    parser.add_argument("--timeout", type=float, default=300.0, help="seconds per mutant before it counts as caught")
    parser.add_argument("--keep", action="store_true", help="keep the temporary folder")
    parser.add_argument(
        "--pytest-k",
        default=None,
        help="run only the tests matching this pytest -k expression (to see whether one test alone catches a mutant)",
    )
    args = parser.parse_args(argv)
    package_root = args.package_root.resolve()
    tests_root = (args.tests_root or package_root).resolve()

    mutants = [m for m in MUTANTS if not args.only or m.id in args.only]
    unknown = set(args.only) - {m.id for m in MUTANTS}
    if unknown:
        parser.error(f"unknown mutant id(s): {sorted(unknown)}")
    ids = [m.id for m in MUTANTS]
    assert len(ids) == len(set(ids)), "mutant ids must be unique"

    if args.list:
        for m in mutants:
            status, _ = _status_of_snippet(package_root, m)
            print(f"{m.id:5s} {status:9s} {m.file}: {m.description}{'  [original]' if m.original else ''}")
        return 0

    temp = Path(tempfile.mkdtemp(prefix="mutation-check-"))
    try:
        return _run(mutants, package_root, tests_root, temp, args.timeout, args.pytest_k)
    finally:
        if args.keep:
            print(f"kept {temp}")
        else:
            shutil.rmtree(temp, ignore_errors=True)


def _run(mutants, package_root, tests_root, temp, timeout, select=None):
    work = temp / "work"
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", ".hypothesis", "*.nbi", "*.nbc")
    shutil.copytree(package_root / "sklearn_radar", work / "sklearn_radar", ignore=ignore)
    shutil.copytree(tests_root / "tests", work / "tests", ignore=ignore)
    if (package_root / "pyproject.toml").is_file():
        shutil.copy2(package_root / "pyproject.toml", work / "pyproject.toml")
    cache_dir, warm_dir = temp / "numba-cache", temp / "numba-warm"
    env = {
        **os.environ,
        "PYTHONPATH": str(work) + os.pathsep + os.environ.get("PYTHONPATH", ""),
        "NUMBA_CACHE_DIR": str(cache_dir),
        "PYTHONDONTWRITEBYTECODE": "1",
        "PYTHONHASHSEED": "0",
    }
    print(f"package: {package_root / 'sklearn_radar'}\ntests:   {tests_root / 'tests'}\ncopy:    {work}")

    where = subprocess.run(
        [sys.executable, "-c", "import sklearn_radar; print(sklearn_radar.__file__)"],
        cwd=work,
        env=env,
        capture_output=True,
        text=True,
    )
    imported = Path(where.stdout.strip() or "?").resolve()
    if not imported.is_relative_to(work):
        print(f"the copy is not what gets imported: {imported}\n{where.stderr}")
        return 2

    statuses = {m.id: _status_of_snippet(work, m)[0] for m in mutants}
    wanted = sorted({module for m in mutants if statuses[m.id] == "ok" for module in m.tests})
    missing = {module for module in wanted if not (work / module).is_file()}
    if missing:  # e.g. older tests (--tests-root) that predate a module: run the others
        print(f"test modules not found, not run: {sorted(missing)}")
    tests_of = {m.id: tuple(module for module in m.tests if module not in missing) for m in mutants}
    for m in mutants:
        if statuses[m.id] == "ok" and not tests_of[m.id]:
            statuses[m.id] = "no tests"
    modules = sorted({module for m in mutants if statuses[m.id] == "ok" for module in tests_of[m.id]})
    started = time.monotonic()
    code, seconds, output = _run_pytest(work, env, modules, max(timeout, 900), select)
    print(f"baseline (unmutated copy, {len(modules)} modules): {'pass' if code == 0 else 'FAIL'} in {seconds:.0f} s")
    if code != 0:
        print(output[-5000:])
        return 2
    shutil.copytree(cache_dir, warm_dir)

    rows = []
    for m in mutants:
        if statuses[m.id] != "ok":
            reason = {"stale": "snippet not found", "ambiguous": "snippet occurs more than once"}.get(
                statuses[m.id], ""
            )
            rows.append((m, statuses[m.id], 0.0, reason))
            print(f"{m.id:5s} {statuses[m.id].upper():9s} {m.file}: {m.description}", flush=True)
            continue
        path = work / m.file
        original = path.read_text(encoding="utf-8")
        stat = path.stat()
        mutated = original.replace(m.snippet, m.replacement, -1 if m.every else 1)
        try:
            compile(mutated, str(path), "exec")
        except SyntaxError as error:
            rows.append((m, "invalid", 0.0, f"mutated file does not compile: {error}"))
            print(f"{m.id:5s} INVALID   {error}", flush=True)
            continue
        stems = _numba_dependents(work / "sklearn_radar", path)
        _drop_cache(cache_dir, stems)
        path.write_text(mutated, encoding="utf-8")
        try:
            code, seconds, output = _run_pytest(work, env, tests_of[m.id], timeout, select)
        finally:
            path.write_text(original, encoding="utf-8")
            os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns))
            _restore_cache(cache_dir, warm_dir, stems)
        if code == "timeout":
            status, detail = "timeout", f"tests ran longer than {timeout:.0f} s"
        elif code == 0:
            status, detail = "survived", ""
        elif code == 1:
            status, detail = "caught", _first_failure(output)
        else:
            status, detail = "caught", f"pytest exit {code}: {_first_failure(output)}"
        rows.append((m, status, seconds, detail))
        print(f"{m.id:5s} {status.upper():9s} {seconds:5.1f} s  {m.description}", flush=True)
        if detail:
            print(f"      {detail}", flush=True)

    total = time.monotonic() - started
    counted = [r for r in rows if r[1] in (*CAUGHT, "survived")]
    caught = [r for r in counted if r[1] in CAUGHT]
    originals = [r for r in counted if r[0].original]
    print()
    print(
        f"mutation score: {len(caught)}/{len(counted)} caught"
        + (f" ({len(rows) - len(counted)} stale/ambiguous/invalid, not counted)" if len(rows) > len(counted) else "")
    )
    print(f"issue 19's original kinds: {sum(r[1] in CAUGHT for r in originals)}/{len(originals)} caught")
    for m, status, _, detail in rows:
        if status not in CAUGHT:
            print(f"  {status}: {m.id} ({m.file}) {m.description}" + (f" -- {detail}" if detail else ""))
    print(f"total time {total:.0f} s (baseline included)")
    return 0 if len(caught) == len(counted) and len(counted) == len(rows) else 1


if __name__ == "__main__":
    sys.exit(main())
