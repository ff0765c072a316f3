"""Issue 20 item 6: a short Ensemble repr, and dir(analogue) lists the lazily loaded names."""
from __future__ import annotations

import numpy as np

import analogue
from analogue import Ensemble


def test_repr_is_one_short_line_with_shape_range_model_and_provenance():
    rng = np.random.default_rng(0)
    t = np.linspace(0.0, 8.0, 801)
    v = rng.normal(size=(1000, t.size))
    meta = {"source": "circuit", "seed": 11, "noise_dt": 0.01,
            "model": {"tau_m": 2.0, "delta": 0.5, "a": 0.3, "gamma": 15.0, "mass": 1.0,
                      "cubic": 0.0, "spring": 0.0, "stribeck": None, "shot": None},
            "deck_sha256": ["ab" * 32] * 50, "circuit": [["R", 1e4, "ohm", "x"]] * 20}
    e = Ensemble(t, v, np.cumsum(v, axis=1) * 0.01, meta, noise=rng.normal(size=(1000, 800)))
    text = repr(e)
    # the dataclass repr printed every array: megabytes here
    assert "\n" not in text and len(text) < 300, text
    for part in ("replicas=1000", "n_t=801", "t=[0, 8]", "dt=0.01", "tau_m=2", "delta=0.5",
                 "a=0.3", "gamma=15", "source='circuit'", "seed=11", "noise=(1000, 800)"):
        assert part in text, (part, text)
    # the model's switched-off extensions and the long provenance lists stay out
    assert "cubic" not in text and "deck_sha256" not in text and "ab" * 8 not in text
    assert "+2 meta keys" in text


def test_repr_of_bare_and_single_time_ensembles():
    assert repr(Ensemble(np.array([0.0]), np.zeros((3, 1)), np.zeros((3, 1)))) == \
        "Ensemble(replicas=3, n_t=1, t=[0])"
    shot = {"model": {"tau_m": 1.0, "delta": 0.5, "a": 0.2, "gamma": float("inf"),
                      "shot": {"rate": 2.5, "mean": 0.35, "two_sided": False}}}
    text = repr(Ensemble(np.arange(3.0), np.zeros((2, 3)), np.zeros((2, 3)), shot))
    assert "gamma=inf" in text and "rate=2.5" in text and "mean=0.35" in text, text


def test_dir_lists_the_lazily_loaded_names():
    names = dir(analogue)
    for lazy in ("simulate", "open_ensemble", "load_runs", "theory", "estimators", "circuit",
                 "report", "plots", "montecarlo"):
        assert lazy in names, lazy
        assert getattr(analogue, lazy) is not None
    for eager in ("Model", "Ensemble", "ShotNoise", "__version__"):
        assert eager in names
    assert names == sorted(names)
