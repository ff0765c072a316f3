"""Estimators: from an :class:`analogue.Ensemble` (circuit or Monte Carlo, same code) to
observables with honest error bars.

Replicas of an ensemble are independent; samples along one trajectory are not.  Every
estimator therefore gets its errors either from independent samples (one per replica:
binomial bands), from the spread across replicas (or batches), or from an integrated
autocorrelation time, and says which in its result.
"""
from .intervals import wilson_interval, clopper_pearson_interval, student_interval
from .density import DensityEstimate, transition_density, stationary_density
from .stationary import (AutocorrelationTime, Estimate, StationaryObservables,
                         integrated_autocorrelation_time, mean_estimate, stationary_observables)
from .work import (WorkDistribution, FluctuationRatio, RateFunctionEstimate, LineFit,
                   work_rate_samples, work_distribution, fluctuation_ratio,
                   empirical_rate_function)
from .stick import StickStatistics, stick_statistics, stick_fraction_theory
from .transport import TransportEstimate, transport
from .prehistory import Prehistory, prehistory, prehistory_count, stationary_prehistory

__all__ = [
    "wilson_interval", "clopper_pearson_interval", "student_interval",
    "DensityEstimate", "transition_density", "stationary_density",
    "AutocorrelationTime", "Estimate", "StationaryObservables",
    "integrated_autocorrelation_time", "mean_estimate", "stationary_observables",
    "WorkDistribution", "FluctuationRatio", "RateFunctionEstimate", "LineFit",
    "work_rate_samples", "work_distribution", "fluctuation_ratio", "empirical_rate_function",
    "StickStatistics", "stick_statistics", "stick_fraction_theory",
    "TransportEstimate", "transport",
    "Prehistory", "prehistory", "prehistory_count", "stationary_prehistory",
]
