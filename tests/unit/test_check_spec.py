"""The integration check's circuit (Experiment.check_spec) and the tolerance calibration's
reference (tolerances.reference_spec): 100x tighter, a quarter of the step, the nominal's
integration method (a gear check of a trap run kept 21 % of the error it was to measure)."""
from __future__ import annotations

import pytest

from analogue.circuit.experiments import load_experiment, standard_circuit
from analogue.circuit.mapping import map_model
from analogue.circuit.tolerances import Tolerances, reference_spec


@pytest.mark.parametrize("method", ["trap", "gear"])
def test_check_spec_is_100x_tighter_with_the_nominal_method(method):
    exp = load_experiment(standard_circuit("stick"))
    nominal = exp.spec.replace(reltol=3e-5, trtol=20.0, method=method)
    m = map_model(exp.model, nominal)
    chk = exp.check_spec(nominal)
    cm = map_model(exp.model, chk)
    assert chk.method == method
    assert cm.reltol == pytest.approx(m.reltol / 100)
    assert cm.vntol == pytest.approx(m.vntol / 100)
    assert chk.abstol == pytest.approx(nominal.abstol / 100)
    assert chk.max_step == pytest.approx(m.noise_dt / 4)


def test_check_spec_of_unset_tolerances_uses_the_fixed_method():
    exp = load_experiment(standard_circuit("stick"))
    assert exp.check_spec().method == map_model(exp.model, exp.spec).method


def test_reference_spec_keeps_the_tightest_candidates_method():
    exp = load_experiment(standard_circuit("work"))
    m = map_model(exp.model, exp.spec.replace(reltol=1e-4, trtol=7.0, method="gear"))
    ref = reference_spec(exp.spec, m, Tolerances(3e-5, 7.0, "trap"))
    assert ref.method == "trap" and ref.reltol == pytest.approx(3e-7)
