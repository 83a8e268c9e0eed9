"""The only module that imports scikit-optimize.

scikit-optimize is archived upstream; its last release, 0.10.2, comes from a
community fork and is pinned in ``pyproject.toml``.  Everything in
sklearn-radar that needs Bayesian optimisation imports it from here, so the
backend can be swapped (for example for a maintained fork) in one place.

:class:`BayesSearchCV` here is skopt's with one saving: when a step asks for
a single candidate, the optimiser returns the point that its last ``tell``
already chose (skopt's ask-and-tell protocol, as ``gp_minimize`` uses it)
instead of refitting the Gaussian process on a copy and then once more on a
discarded "constant liar" point.  A guided step fits one Gaussian process
instead of three (the time it saves: :ref:`performance`); the candidates
are chosen by the same model and acquisition, from different random draws.
Batches of ``n_points > 1`` keep skopt's constant-liar strategy.

:meth:`Optimizer.ask_random` (the random phase asked at once, which lets a
search evaluate those candidates concurrently) reads skopt's private
``Optimizer._n_initial_points`` and ``_initial_samples`` and relies on
``ask()`` drawing a random point from the random state alone.  That holds
for :data:`SUPPORTED_VERSION` (tested in ``tests/test_skopt.py``); with any
other release :data:`RELIES_ON_INTERNALS` is false, and a search asks its
random candidates one at a time: the same candidates, fewer at a time.
"""

import warnings

try:
    import skopt
    from skopt import BayesSearchCV as _SkoptBayesSearchCV
    from skopt import Optimizer as _SkoptOptimizer
    from skopt.space import Categorical, Integer, Real
    from skopt.utils import dimensions_aslist
except ImportError as error:  # pragma: no cover - exercised only on a broken install
    raise ImportError(
        "sklearn-radar needs scikit-optimize==0.10.2 for Bayesian optimisation: pip install 'scikit-optimize==0.10.2'"
    ) from error

#: The scikit-optimize release whose Optimizer internals :meth:`Optimizer.ask_random` relies on.
SUPPORTED_VERSION = "0.10.2"
#: Whether the installed skopt is that release: the one version check of the internals.
RELIES_ON_INTERNALS = skopt.__version__ == SUPPORTED_VERSION
if not RELIES_ON_INTERNALS:  # pragma: no cover - only with another skopt installed
    warnings.warn(
        f"scikit-optimize {skopt.__version__} is not {SUPPORTED_VERSION}: searches ask their random candidates "
        "one at a time (same candidates, less concurrency)",
        stacklevel=2,
    )


#: The start of skopt's warning when its model proposes a point it has evaluated before (it then takes a random
#: one): expected on a small or discrete space, and no fault of the caller's.
REPEATED_POINT_WARNING = "The objective has been evaluated at point"


class Optimizer(_SkoptOptimizer):
    """skopt's Optimizer; ``ask(n_points=1)`` returns the point of the last ``tell`` (no refit on a copy).

    ``ask`` silences skopt's warning that its model proposed a point
    evaluated before (:data:`REPEATED_POINT_WARNING`), and only that one.
    """

    def ask(self, n_points=None, strategy="cl_min"):
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message=REPEATED_POINT_WARNING, category=UserWarning)
            if n_points == 1:
                return [super().ask()]  # skopt's single point: the one its last tell chose
            return super().ask(n_points=n_points, strategy=strategy)

    @property
    def n_random_left(self):
        """Random points still to come before the Gaussian process guides (0 when it guides, or when unknown)."""
        if not RELIES_ON_INTERNALS or self.base_estimator_ is None:
            return 0
        return max(self._n_initial_points, 0)

    def ask_random(self, n_points):
        """The next ``n_points`` random points: those ``n_points`` single-point ``ask``/``tell`` rounds would get.

        Random points depend on the random state only, and ``tell`` draws
        nothing from it before the Gaussian process is fitted: so they can be
        evaluated all at once, then told one by one in this order.
        """
        if not RELIES_ON_INTERNALS or self._initial_samples is not None or n_points > self.n_random_left:
            raise ValueError(f"n_points={n_points} random points are not ahead (only {self.n_random_left})")
        return [_SkoptOptimizer.ask(self) for _ in range(n_points)]


class BayesSearchCV(_SkoptBayesSearchCV):
    """skopt's BayesSearchCV whose optimisers are :class:`Optimizer` (one GP fit per single-candidate step)."""

    def _make_optimizer(self, params_space):
        kwargs = self.optimizer_kwargs_.copy()
        kwargs["dimensions"] = dimensions_aslist(params_space)
        optimizer = Optimizer(**kwargs)
        names = sorted(params_space.keys())
        for i, dimension in enumerate(optimizer.space.dimensions):
            if dimension.name is None:
                dimension.name = names[i]
        return optimizer


__all__ = [
    "RELIES_ON_INTERNALS",
    "REPEATED_POINT_WARNING",
    "SUPPORTED_VERSION",
    "BayesSearchCV",
    "Categorical",
    "Integer",
    "Optimizer",
    "Real",
    "dimensions_aslist",
]
