"""The only module that imports scikit-optimize.

scikit-optimize is archived upstream; its last release, 0.10.2, comes from a
community fork and is pinned in ``pyproject.toml``.  Everything in
sklearn-radar that needs Bayesian optimisation imports it from here, so the
backend can be swapped (for example for a maintained fork) in one place.
"""

try:
    from skopt import BayesSearchCV
    from skopt.space import Categorical, Integer, Real
except ImportError as error:  # pragma: no cover - exercised only on a broken install
    raise ImportError(
        "sklearn-radar needs scikit-optimize==0.10.2 for Bayesian optimisation: pip install 'scikit-optimize==0.10.2'"
    ) from error

__all__ = ["BayesSearchCV", "Categorical", "Integer", "Real"]
