"""Order of the examples in the gallery: a reading order, not the alphabet.

Used by ``docs/conf.py`` as sphinx-gallery's ``within_subsection_order``.
Examples not listed here come after the listed ones, by file name.
"""

ORDER = (
    "plot_quick_start.py",
    "plot_simulated_scene.py",
    "plot_simulator_difficulty.py",
    "plot_ccs_vs_fcs.py",
    "plot_filter_grid.py",
    "plot_stage1_criteria.py",
    "plot_range_adaptive_min_points.py",
    "plot_merging_modes.py",
    "plot_tuning.py",
    "plot_sequence_search.py",
    "plot_streaming.py",
    "plot_classification.py",
    "plot_learned_grouping.py",
    "plot_radarscenes_io.py",
)


class ExampleOrder:
    """Sort key: position in :data:`ORDER`, then the file name."""

    def __init__(self, src_dir):
        self.src_dir = src_dir

    def __call__(self, filename):
        position = ORDER.index(filename) if filename in ORDER else len(ORDER)
        return f"{position:03d}_{filename}"

    def __repr__(self):
        # sphinx-gallery compares configurations by repr between builds.
        return f"<{self.__class__.__name__}>"
