"""The circuit defaults chosen from the model travel with the run (issue 20 item 5)."""
import pytest

from analogue import Model

SLOW = {"tau_m": 4.0, "delta": 0.9, "a": 0.1, "gamma": 30.0}


@pytest.mark.requires_ngspice
def test_chosen_defaults_recorded_in_the_runs_provenance():
    """The choice and its reason travel with the run (Ensemble.meta["circuit_defaults"])."""
    import analogue
    ens = analogue.simulate(Model(**SLOW), v0=2.0, t_end=0.2, replicas=2, seed=1, workers=1,
                            store=False, replicas_per_deck=2,
                            circuit={"reltol": 1e-4, "trtol": 7.0, "method": "gear"})
    chosen = ens.meta["circuit_defaults"]
    assert set(chosen) == {"smoothing", "noise_dt"}
    assert ens.meta["noise_dt"] == chosen["noise_dt"]["value"] < SLOW["tau_m"] / 100
    assert "t_rel" in chosen["noise_dt"]["why"]
