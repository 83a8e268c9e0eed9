"""Global configuration of sklearn-radar: one switch, ``check_plausibility``.

Modelled on :func:`sklearn.set_config` / :func:`sklearn.config_context`.
The setting is process-wide: every thread of the process sees it.  It does
not travel to other processes (joblib's ``loky`` workers, dask workers),
which start with the default.  The default is read once, at import, from the
environment variable :data:`ENVIRONMENT_VARIABLE`: set
``SKLEARN_RADAR_CHECK_PLAUSIBILITY=0`` before the workers start (it is
inherited by processes started afterwards), or call
``set_config(check_plausibility=False)`` inside the task, e.g. with dask's
``client.run(sklearn_radar.set_config, check_plausibility=False)``.  A value
of the variable that is neither on nor off (:data:`ENVIRONMENT_VALUES`) makes
:func:`get_config` raise a ValueError naming it, until :func:`set_config`
sets the switch.
"""

from __future__ import annotations

import os
from contextlib import contextmanager

from sklearn.utils._param_validation import validate_params

#: Environment variable giving the default of ``check_plausibility``: "0", "false", "no" or "off" turn it off.
ENVIRONMENT_VARIABLE = "SKLEARN_RADAR_CHECK_PLAUSIBILITY"
#: Its accepted values (any case, surrounding spaces ignored), as the setting they give; unset or empty is on.
ENVIRONMENT_VALUES = {
    **dict.fromkeys(("0", "false", "no", "off"), False),
    **dict.fromkeys(("1", "true", "yes", "on", ""), True),
}


def _default_check_plausibility():
    """The setting the environment variable gives; None when its value is not one of :data:`ENVIRONMENT_VALUES`."""
    return ENVIRONMENT_VALUES.get(os.environ.get(ENVIRONMENT_VARIABLE, "").strip().lower())


def _environment_error() -> ValueError:
    off = ", ".join(repr(value) for value, on in ENVIRONMENT_VALUES.items() if not on)
    on = ", ".join(repr(value) for value, on in ENVIRONMENT_VALUES.items() if on and value)
    return ValueError(
        f"the environment variable {ENVIRONMENT_VARIABLE}={os.environ.get(ENVIRONMENT_VARIABLE, '')!r} (read when "
        f"sklearn_radar was imported) is neither on nor off: accepted are {off} (the plausibility checks off) and "
        f"{on} or unset (on), in any case"
    )


#: None: the environment variable held an invalid value at import (get_config raises until set_config sets it).
_config = {"check_plausibility": _default_check_plausibility()}


@validate_params({}, prefer_skip_nested_validation=True)
def get_config() -> dict:
    """The current values of the sklearn-radar configuration.

    Returns
    -------
    config : dict
        ``{"check_plausibility": bool}``; a copy, changing it changes nothing.

    Raises
    ------
    ValueError
        If the environment variable ``SKLEARN_RADAR_CHECK_PLAUSIBILITY``
        held a value that is neither on nor off when sklearn_radar was
        imported, and :func:`set_config` has not set the switch since.

    See Also
    --------
    set_config : change the configuration.
    config_context : change it within a ``with`` block.

    Examples
    --------
    >>> import sklearn_radar
    >>> sklearn_radar.get_config()["check_plausibility"]
    True
    """
    if _config["check_plausibility"] is None:
        raise _environment_error()
    return dict(_config)


@validate_params({"check_plausibility": ["boolean", None]}, prefer_skip_nested_validation=True)
def set_config(check_plausibility=None) -> None:
    """Change the sklearn-radar configuration of this process.

    Parameters
    ----------
    check_plausibility : bool, default=None
        True (the default): every estimator, and
        :func:`~sklearn_radar.datasets.load_radarscenes`, checks that the
        columns it reads hold physically plausible values (ranges in m,
        angles in rad, speeds in m/s, yaw rates in rad/s, timestamps in µs,
        ``t`` in s) and raises a ValueError naming the column, the value and
        the likely wrong unit.  False skips these checks, for data outside
        the bounds of :data:`sklearn_radar._schema.PLAUSIBLE_VALUES` that is
        nevertheless right.  None leaves the setting unchanged.  NaN and
        infinity are rejected either way.

    See Also
    --------
    get_config : the current values.
    config_context : change the configuration within a ``with`` block.

    Notes
    -----
    The setting holds for the whole process (all threads), not for worker
    processes of joblib or dask: see :mod:`sklearn_radar._config`.

    Examples
    --------
    >>> import sklearn_radar
    >>> sklearn_radar.set_config(check_plausibility=False)
    >>> sklearn_radar.get_config()["check_plausibility"]
    False
    >>> sklearn_radar.set_config(check_plausibility=True)
    """
    if check_plausibility is not None:
        _config["check_plausibility"] = bool(check_plausibility)


@validate_params({"check_plausibility": ["boolean", None]}, prefer_skip_nested_validation=True)
@contextmanager
def config_context(*, check_plausibility=None):
    """Change the sklearn-radar configuration within a ``with`` block, then restore it.

    Parameters
    ----------
    check_plausibility : bool, default=None
        As in :func:`set_config`; None leaves it unchanged.

    Yields
    ------
    None
        The block runs with the changed configuration.

    See Also
    --------
    set_config : change the configuration for good.
    get_config : the current values.

    Notes
    -----
    The previous values come back when the block ends, also on an
    exception.  The block changes the setting of the whole process, so two
    threads that enter blocks at the same time see each other's values.

    Examples
    --------
    >>> import sklearn_radar
    >>> with sklearn_radar.config_context(check_plausibility=False):
    ...     sklearn_radar.get_config()["check_plausibility"]
    False
    >>> sklearn_radar.get_config()["check_plausibility"]
    True
    """
    previous = get_config()
    set_config(check_plausibility=check_plausibility)
    try:
        yield
    finally:
        set_config(**previous)
