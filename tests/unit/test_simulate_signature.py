"""analogue.simulate has an explicit, documented, keyword-only signature (issue 12), and the
SDE producer shares the keywords that mean the same thing."""
from __future__ import annotations

import concurrent.futures as cf
import inspect

import pytest

import analogue
from analogue import Model
from analogue.circuit import simulate as S
from analogue.montecarlo import simulate_sde

MODEL = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)
BASE = dict(v0=0.0, t_end=1.0, replicas=2, seed=0, store=False, progress=False)
KEYWORDS = ("replicas_per_deck", "store", "progress", "timeout", "scheduler", "return_noise",
            "return_records", "label", "workers", "executor", "circuit", "sample_dt")


def test_simulate_has_no_var_keyword_and_only_keyword_options() -> None:
    params = inspect.signature(analogue.simulate).parameters
    kinds = {p.kind for p in params.values()}
    assert inspect.Parameter.VAR_KEYWORD not in kinds
    assert inspect.Parameter.VAR_POSITIONAL not in kinds
    assert list(params)[0] == "model"
    for name in list(params)[1:]:
        assert params[name].kind is inspect.Parameter.KEYWORD_ONLY, name
    assert set(KEYWORDS) <= set(params)


def test_every_simulate_parameter_is_annotated_and_documented() -> None:
    sig = inspect.signature(analogue.simulate)
    doc = analogue.simulate.__doc__ or ""
    for name, p in sig.parameters.items():
        assert p.annotation is not inspect.Parameter.empty, name
        assert f"\n    {name} :" in doc, name
    assert sig.return_annotation is not inspect.Signature.empty


def test_shared_keywords_have_the_same_names_in_the_sde_producer() -> None:
    circuit = inspect.signature(analogue.simulate).parameters
    sde = inspect.signature(simulate_sde).parameters
    for name in ("v0", "t_end", "replicas", "seed", "sample_dt"):
        assert name in sde and sde[name].kind is inspect.Parameter.KEYWORD_ONLY, name
        assert circuit[name].kind is inspect.Parameter.KEYWORD_ONLY, name


def test_scheduler_and_executor_together_are_refused() -> None:
    with cf.ThreadPoolExecutor(1) as pool, pytest.raises(ValueError, match="executor"):
        analogue.simulate(MODEL, scheduler="tcp://127.0.0.1:8786", executor=pool, **BASE)


@pytest.mark.parametrize("bad", ["tcp://127.0.0.1:8786", 4, object()])
def test_executor_must_be_an_executor(bad: object) -> None:
    with pytest.raises(TypeError, match="executor"):
        analogue.simulate(MODEL, executor=bad, **BASE)


def test_scheduler_string_is_an_address_not_an_executor() -> None:
    with pytest.raises(TypeError, match="scheduler"):
        analogue.simulate(MODEL, scheduler=cf.ThreadPoolExecutor, **BASE)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="scheduler"):
        analogue.simulate(MODEL, scheduler="inproc:/", **BASE)


def test_injected_executor_is_used_and_left_open() -> None:
    class Counting(cf.ThreadPoolExecutor):
        submitted = 0

        def submit(self, fn, /, *args, **kwargs):  # type: ignore[no-untyped-def, override]
            Counting.submitted += 1
            return super().submit(fn, *args, **kwargs)

    pool = Counting(2)
    ex, closer, client = S._executor(1, None, 3, pool)
    assert ex is pool and closer is None and client is None
    pool.submit(int, 1).result()  # still open: the caller owns it
    pool.shutdown()


def test_sde_ensemble_carries_the_noise_that_drove_it() -> None:
    import numpy as np
    z = np.random.default_rng(1).standard_normal((3, 100))
    ens = simulate_sde(MODEL, v0=0.0, t_end=1.0, replicas=3, seed=0, dt=0.01, noise=z)
    assert isinstance(ens, analogue.Ensemble)
    np.testing.assert_array_equal(ens.noise, z)
    assert ens.meta["noise_dt"] == 0.01 and ens.meta["t_end"] == 1.0
    again = simulate_sde(MODEL, v0=0.0, t_end=1.0, replicas=3, seed=0, dt=0.01, noise=ens.noise)
    np.testing.assert_array_equal(again.v, ens.v)
    assert simulate_sde(MODEL, v0=0.0, t_end=1.0, replicas=3, seed=0, dt=0.01).noise is None
