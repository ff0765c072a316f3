"""What a report measures: the settings of an experiment's analysis and how its runs execute.

The settings (:class:`ReportSettings`, the ``[report]`` table) and :class:`RunOptions` live in
:mod:`analogue.study.settings`, below both the experiment that holds them and the report that
reads them (they were here first; every name is re-exported).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from ..study.settings import (MAX_HOLD_DIVISOR, MIN_CHECK_REPLICAS, MIN_QUICK_CHECK_REPLICAS,
                              MIN_QUICK_REPLICAS, MIN_STATIONARY_REPLICAS, QUICK_DIVISOR,
                              ReportSettings, RunOptions, report_settings_from_dict,
                              stationary_noise_dt)

if TYPE_CHECKING:
    from ..study.experiments import Experiment

__all__ = ["RunOptions", "ReportSettings", "report_settings", "report_settings_from_dict",
           "QUICK_DIVISOR", "MIN_STATIONARY_REPLICAS", "MIN_CHECK_REPLICAS",
           "MAX_HOLD_DIVISOR", "stationary_noise_dt"]
# also importable from here, as before
_REEXPORTED = (MIN_QUICK_REPLICAS, MIN_QUICK_CHECK_REPLICAS)


def report_settings(exp: Experiment) -> ReportSettings:
    """The experiment's ``[report]`` settings (parsed with the file when it was loaded)."""
    return exp.report
