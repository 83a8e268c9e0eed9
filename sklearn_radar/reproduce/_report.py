"""The report of a reproduce run: report.md laid out like the paper's tables, and its figures."""

from __future__ import annotations

import io

import numpy as np
import pandas as pd

from ._io import atomic_write, atomic_write_text

_SHORT = {"eps_phi": "eps_phi (rad)"}


def _format_params(params):
    """``cluster__eps_xy=0.6`` -> ``eps_xy=0.60``; only what the experiment sets."""
    shown = []
    for key, value in (params or {}).items():
        name = key.split("__")[-1]
        if name in ("eps_t", "n_jobs", "mode"):
            continue
        if name == "metric":
            continue
        shown.append(f"{_SHORT.get(name, name)}={value:.3g}" if isinstance(value, (int, float)) else f"{name}={value}")
    return ", ".join(shown)


def _percent(value):
    return "-" if value is None or (isinstance(value, float) and np.isnan(value)) else f"{100 * value:.2f} %"


def _grid_markdown(split):
    frame = pd.DataFrame(split["data"], index=split["index"], columns=split["columns"])
    header = "| eta_1 (m/s) \\ d_xy (m) | " + " | ".join(f"{c:.1f}" for c in frame.columns) + " |"
    rule = "|---|" + "---|" * len(frame.columns)
    rows = [f"| {i:.2f} | " + " | ".join(f"{v:g}" for v in frame.loc[i]) + " |" for i in frame.index]
    return "\n".join([header, rule, *rows])


def write_report(out, results):
    """Write ``report.md`` from ``results`` (what results.json holds)."""
    meta = results["meta"]
    lines = [
        "# sklearn-radar: the experiments of Scheiner et al. (ITSC 2019), re-run",
        "",
        f"- data: {meta['data']['source']}; {meta['data']['n_detections']:,} detections in "
        f"{meta['data']['n_sequences']} sequences, split by sequence into a training half "
        f"({meta['data'].get('n_train', 0):,} detections) and a test half ({meta['data'].get('n_test', 0):,}).",
        f"- budget: {meta['budget']['label']}: {meta['budget']['n_iter']} Bayesian-optimisation iterations per "
        f"tuned experiment ({meta['budget']['n_initial_points']} random), {meta['budget']['cv_folds']}-fold CV "
        "grouped by sequence on the training half. The paper used 100 iterations (30 random) on about a million "
        "detections of real data: `sklearn-radar reproduce --full` uses that budget on about a million simulated ones. "
        "The paper's own setting is scored beside each search and kept when the search found nothing better.",
        f"- scores: radar V-measure (V1) on the test half against the pre-clustered target; seed {meta['seed']}; "
        f"sklearn-radar {meta['version']}; wall time {meta.get('wall_time_s', float('nan')):.0f} s.",
    ]
    if meta.get("interrupted"):
        lines.append(f"- **interrupted**: only {', '.join(meta['completed']) or 'nothing'} finished.")
    lines += _filter_section(results) + _stage_sections(results) + _effect_section(results)
    lines += _baseline_section(results) + _figure_section(results) + _comparison_section(results)
    atomic_write_text(out / "report.md", "\n".join(lines) + "\n")


def _filter_section(results):
    if "filter" not in results:
        return []
    f = results["filter"]
    lines = ["", "## Detection filtering (Tables I and II)", "",
             "Table I: (object, 150 ms window) cases in which a moving object kept less than 75 % of its "
             "detections, per filter setting, FCS:", "", _grid_markdown(f["table_i"]["frame"]["errors"]), "",
             "The same in CCS:", "", _grid_markdown(f["table_i"]["car"]["errors"]), ""]  # fmt: skip
    for frame, best in f["best_removal_with_zero_errors"].items():
        name = "FCS" if frame == "frame" else "CCS"
        lines.append(f"- best background removal with 0 errors, {name}: "
                     + (f"{_percent(best['background_removed'])} at eta_1 = {best['vr_threshold']:.2f} m/s, "
                        f"d_xy = {best['d_xy']:.1f} m" if best else "no grid cell has 0 errors"))  # fmt: skip
    lines += ["", "Table II: background removal rates of the paper's settings.", "",
              "| CS | eta_1 (m/s) | d_xy (m) | removal (ours) | errors (ours) | objects removed (ours) | removal (paper) | errors (paper) |",
              "|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for row in f["table_ii"]:
        lines.append(f"| {'FCS' if row['frame'] == 'frame' else 'CCS'} | {row['vr_threshold']:.2f} | {row['d_xy']:.1f} | "
                     f"{row['removal_rate']:.2f} % | {row['errors']} | {row['object_removal_rate']:.2f} % | "
                     f"{row['paper_removal_rate']:.2f} % | {row['paper_errors']} |")  # fmt: skip
    lines += ["", "![Table I as a heatmap](table1_heatmap.png)"]
    return lines


def _stage_sections(results):
    experiments = results.get("experiments", {})
    lines = []
    for stage, title in ((1, "Point clustering (Table III)"), (2, "Cluster merging (Table IV)")):
        rows = [e for e in experiments.values() if e["stage"] == stage]
        if not rows:
            continue
        lines += ["", f"## {title}", "",
                  "| # | method | CS | filtered | V1 (ours) | V1 (paper) | our parameters | paper's parameters |",
                  "|---|---|---|---|---|---|---|---|"]  # fmt: skip
        for e in sorted(rows, key=lambda e: e["number"]):
            lines.append(f"| {e['number']} | {e['method']} | {'FCS' if e['frame'] == 'frame' else 'CCS'} | "
                         f"{'yes' if e['filtered'] else 'no'} | {_percent(e['v1_test'])} | {e['paper_v1_percent']:.2f} % | "
                         f"{_format_params(e['params'])} | {_format_params(e['paper_params'])} |")  # fmt: skip
        if stage == 2:
            base = experiments.get("8")
            lines += ["", "Stage 1 of #12 and #13: " + _format_params(rows[0].get("stage1_params"))
                      + (f" (#8 scores {_percent(base['v1_test'])} alone)" if base else "")]  # fmt: skip
    return lines


def _effect_section(results):
    effect = results.get("filter_effect")
    if not effect:
        return []
    paper = effect["paper"]
    return ["", "## The filter's effect on clustering", "",
            f"At {effect['setting_source']}'s setting, on the test half: clustering takes "
            f"{effect['filtered']['clustering_s']:.3f} s filtered and {effect['unfiltered']['clustering_s']:.3f} s unfiltered "
            f"({effect['time_saving_percent']:.1f} % saved; paper: {paper['time_saving_percent']} %); filtering leaves "
            f"{effect['fewer_clusters_per_sequence_percent']:.1f} % fewer clusters per sequence "
            f"(paper: {paper['fewer_clusters_per_sequence_percent']} %) and {effect['fewer_clusters_overall_percent']:.1f} % "
            f"fewer overall (paper: {paper['fewer_clusters_overall_percent']} %)."]  # fmt: skip


def _baseline_section(results):
    baselines = results.get("baselines")
    if not baselines:
        return []
    lines = ["", "## Beyond the paper: the clusterers a user would otherwise pick", "",
             "Same FCS + filter input, same budget and split.", "",
             "| clusterer | V1 (test) | parameters | wall time |", "|---|---|---|---|"]  # fmt: skip
    for name, record in baselines.items():
        lines.append(f"| {name} | {_percent(record['v1_test'])} | {_format_params(record['params'])} | {record['wall_time_s']:.0f} s |")
    return lines


def _figure_section(results):
    lines = ["", "## Figures", ""]
    if results.get("figures", {}).get("scene"):
        lines += ["Fig. 6 analogue, one test sequence: raw data, target, baseline and best clustering.", "",
                  "![scene](fig6_scene.png)", ""]  # fmt: skip
    if results.get("figures", {}).get("convergence"):
        lines += ["Best cross-validated score so far, per tuned experiment:", "", "![convergence](convergence.png)"]
    if results.get("figures", {}).get("missing"):
        lines += [f"(figures not drawn: {results['figures']['missing']})"]
    return lines


def _comparison_section(results):
    e = {int(k): v["v1_test"] for k, v in results.get("experiments", {}).items()}
    checks = []

    def claim(text, numbers, holds):
        if all(n in e for n in numbers):
            values = ", ".join(f"#{n} {_percent(e[n])}" for n in numbers)
            checks.append(f"- {text}: **{'holds' if holds() else 'does not hold'}** here ({values}).")

    claim("a tuned baseline beats the expert setting (#2 > #1)", (1, 2), lambda: e[2] > e[1])
    claim("FCS is at least as good as CCS (#3 >= #2)", (2, 3), lambda: e[3] >= e[2])
    claim("the Euclidean criteria improve on the box (#5, #6 > #3)", (3, 5, 6), lambda: e[5] > e[3] and e[6] > e[3])
    claim("range-adaptive N_min improves on the baseline (#7 > #3)", (3, 7), lambda: e[7] > e[3])
    claim("the combined method is the best stage-1 setting (#8 >= #2-#7)", tuple(range(2, 9)),
          lambda: e[8] >= max(e[n] for n in range(2, 8)))
    claim("filtering helps the combined method (#8 > #9 and #8 > #10)", (8, 9, 10), lambda: e[8] > e[9] and e[8] > e[10])
    claim("#8's setting transferred to the box criterion is worse (#11 < #8)", (8, 11), lambda: e[11] < e[8])
    claim("merging by velocity estimates hurts (#12 < #8)", (8, 12), lambda: e[12] < e[8])
    claim("merging by continuation helps slightly (#13 > #8)", (8, 13), lambda: e[13] > e[8])
    if not checks:
        return []
    reduced = results["meta"]["budget"]["n_iter"] < 100
    return ["", "## The paper's findings, checked", "", *checks, "",
            "Absolute V1 values differ from the paper's: the data here are simulated (see the "
            "simulator's statistics), the target is our pre-clustering of its ground truth"
            + (", and this run used a reduced budget." if reduced else ".")]  # fmt: skip


# ----------------------------------------------------------------------------- figures


def write_figures(out, results, context):
    """Draw the Table I heatmap, the scene view (Fig. 6) and the convergence curves, atomically."""
    figures = results.setdefault("figures", {})
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        figures["missing"] = "matplotlib is not installed"
        return
    from ..evaluation import plot_filter_errors

    if "filter_grids" in context:
        fig, axes = plt.subplots(1, 2, figsize=(12, 5))
        for ax, frame in zip(axes, ("frame", "car")):
            plot_filter_errors(context["filter_grids"][frame].errors, ax=ax)
            ax.set_title(f"Table I errors, {'FCS' if frame == 'frame' else 'CCS'}")
        _save_figure(fig, out / "table1_heatmap.png")
        figures["table1_heatmap"] = "table1_heatmap.png"
    if context.get("labels"):
        _scene_figure(plt, out, results, context)
        figures["scene"] = "fig6_scene.png"
    curves = {k: v["convergence"] for k, v in results.get("experiments", {}).items() if "convergence" in v}
    curves.update({k: v["convergence"] for k, v in results.get("baselines", {}).items()})
    if curves:
        fig, ax = plt.subplots(figsize=(8, 5))
        for name, scores in curves.items():
            ax.plot(np.arange(1, len(scores) + 1), np.maximum.accumulate(scores), label=f"#{name}" if name.isdigit() else name)
        ax.set(xlabel="iteration", ylabel="best mean CV V1 so far", title="Bayesian optimisation convergence")
        ax.legend(fontsize=7, ncol=2)
        _save_figure(fig, out / "convergence.png")
        figures["convergence"] = "convergence.png"


def _scene_figure(plt, out, results, context):
    from ..preprocessing import FrameTransform

    scenes, test = context["scenes"], context["test"]
    data = FrameTransform().fit_transform(scenes.data.iloc[test])
    sequence = scenes.groups[test]
    first = sequence == sequence[0]
    scores = {int(k): v["v1_test"] for k, v in results["experiments"].items() if int(k) in context["labels"]}
    best = max(scores, key=scores.get)
    baseline = 3 if 3 in context["labels"] else min(context["labels"])
    panels = [("raw data", None), ("target (pre-clustered ground truth)", context["target"][test]),
              (f"baseline #{baseline}", context["labels"][baseline]), (f"best: #{best}", context["labels"][best])]  # fmt: skip
    fig, axes = plt.subplots(1, 4, figsize=(20, 5.5), sharex=True, sharey=True)
    x, y = data["x"].to_numpy()[first], data["y"].to_numpy()[first]
    for ax, (title, labels) in zip(axes, panels):
        if labels is None:
            ax.scatter(x, y, s=0.5, c="0.3")
        else:
            labels = np.asarray(labels)[first]
            noise = labels < 0
            ax.scatter(x[noise], y[noise], s=0.3, c="0.8")
            ax.scatter(x[~noise], y[~noise], s=1.5, c=labels[~noise] % 20, cmap="tab20", vmin=0, vmax=19)
        ax.set(title=title, xlabel="x (m, FCS)", aspect="equal")
    axes[0].set_ylabel("y (m, FCS)")
    fig.suptitle(f"test sequence {sequence[0]}: each cluster its own colour, noise grey")
    _save_figure(fig, out / "fig6_scene.png")


def _save_figure(fig, path):
    import matplotlib.pyplot as plt

    buffer = io.BytesIO()
    fig.tight_layout()
    fig.savefig(buffer, format="png", dpi=90)
    plt.close(fig)
    atomic_write(path, lambda stream: stream.write(buffer.getvalue()))


__all__ = ["write_figures", "write_report"]
