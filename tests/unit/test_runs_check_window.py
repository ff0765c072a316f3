"""The stationary integration check's prefix window (analogue.study.runs, issue 10): the
plan's rule, the nominal counterpart on matched rows and times, and the coupling test."""
from types import SimpleNamespace

import numpy as np
import pytest

from analogue.ensemble import Ensemble
from analogue.study.runs import (
    ExperimentRuns,
    _check_coupled,
    check_plan,
    head,
    stationary_check_plan,
)


def _ens(replicas=6, n_t=101, dt=0.01, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(n_t) * dt
    v = rng.normal(size=(replicas, n_t)).cumsum(axis=1) * 0.1
    x = np.cumsum(v, axis=1) * dt
    return Ensemble(t, v, x, {})


@pytest.mark.parametrize("replicas, per_deck, want, t_end, burn_in, longest, workers", [
    (32, 16, 16, 50.0, 2.0, 0.0, 2),     # stick --quick: 2 decks of 16
    (64, 32, 16, 100.0, 2.0, 10.0, 2),   # work --quick: 2 decks of 32, work windows up to 10
    (256, 32, 64, 200.0, 2.0, 10.0, 2),  # work full size
    (33, 16, 16, 50.0, 2.0, 0.0, 2),     # 3 equal decks of 11
    (10, 4, 4, 20.0, 1.0, 0.0, 2),       # decks 4, 3, 3: only one of the leading size
    (128, 16, 64, 100.0, 2.0, 0.0, 1),   # one worker
    (8, 8, 64, 10.0, 0.5, 0.0, 2),       # fewer replicas than wanted: the whole run
])
def test_plan_covers_the_wanted_replica_time(replicas, per_deck, want, t_end, burn_in, longest,
                                             workers):
    dt = 0.01
    decks, size, window = stationary_check_plan(replicas, want, per_deck, t_end, burn_in=burn_in,
                                                longest_window=longest, sample_dt=dt,
                                                workers=workers)
    # the decks are leading decks of the nominal run, all of one size (check_plan's matching)
    n = -(-replicas // per_deck)
    sizes = [replicas // n + (1 if b < replicas % n else 0) for b in range(n)]
    assert decks >= 1 and all(s == size for s in sizes[:decks])
    # a whole number of samples, within the run, long enough for every observable
    assert window == pytest.approx(round(window / dt) * dt)
    assert burn_in + longest < window <= t_end + 1e-12
    lost = burn_in + longest
    if window < t_end - 1e-9:
        # usable replica-time at least that of `want` whole paths, and not a sample more
        assert decks * size * (window - lost) >= want * (t_end - lost) - 1e-9
        assert decks * size * (window - dt - lost) < want * (t_end - lost)
    # every worker has a deck where the run has enough equal leading decks
    equal = sum(s == size for s in sizes)
    assert decks == min(equal, max(workers, decks))
    if decks < equal:
        assert decks % workers == 0
    # never fewer replicas than the whole-path check would have re-run
    assert decks >= min(check_plan(replicas, want, per_deck)[0], equal)


def test_plan_windows_of_the_quick_reports():
    """By hand from the rule: stick --quick 2 + 16 * 48 / 32 = 26; work --quick 12 + 16 * 88
    / 64 = 34."""
    assert stationary_check_plan(32, 16, 16, 50.0, burn_in=2.0, longest_window=0.0,
                                 sample_dt=0.01, workers=2) == (2, 16, pytest.approx(26.0))
    assert stationary_check_plan(64, 16, 32, 100.0, burn_in=2.0, longest_window=10.0,
                                 sample_dt=0.01, workers=2) == (2, 32, pytest.approx(34.0))


def test_head_is_the_exact_prefix():
    e = _ens()
    h = head(e, 0.5, 4)
    assert h.v.shape == (4, 51) and h.t[-1] == pytest.approx(0.5)
    np.testing.assert_array_equal(h.v, e.v[:4, :51])
    np.testing.assert_array_equal(h.x, e.x[:4, :51])   # positions not re-zeroed
    assert head(e, 1.0).v.shape == e.v.shape


def _runs(nominal, check, v0=1.0):
    exp = SimpleNamespace(v0=[v0], name="t")
    return ExperimentRuns(exp=exp, settings=None, quick=True, transition={v0: nominal},
                          stationary=nominal, noise_free=nominal, check_transition=check,
                          check_stationary=check)


def test_check_pair_matches_rows_and_times():
    e = _ens()
    chk = head(e, 0.3, 2)
    chk = Ensemble(chk.t, chk.v + 1e-4, chk.x, {})
    for kind in ("stationary", "transition"):
        c, n = _runs(e, chk).check_pair(kind)
        assert c is chk
        assert n.v.shape == c.v.shape
        np.testing.assert_array_equal(n.t, c.t)
        np.testing.assert_allclose(c.v - n.v, 1e-4)
    with pytest.raises(ValueError, match="kind"):
        _runs(e, chk).check_pair("noise_free")


def test_check_coupled_accepts_the_prefix_and_refuses_other_paths():
    e = _ens(seed=1)
    _check_coupled(e, head(e, 0.4, 3), "stationary check")
    other = _ens(seed=2)
    with pytest.raises(RuntimeError, match="does not retrace"):
        _check_coupled(e, head(other, 0.4, 3), "stationary check")
    # the same paths shifted by one sample are not the prefix
    late = head(e, 0.41, 3)
    shifted = Ensemble(late.t[:-1], late.v[:, 1:], late.x[:, 1:], {})
    with pytest.raises(RuntimeError, match="does not retrace"):
        _check_coupled(e, shifted, "stationary check")
    with pytest.raises(RuntimeError, match="shape"):
        _check_coupled(head(e, 0.2), head(e, 0.4, 3), "stationary check")
