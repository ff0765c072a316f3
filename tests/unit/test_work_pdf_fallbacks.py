"""work_pdf's large-deviation fallbacks are reported through recorded_fallbacks (no module
list that grows forever; issue 12)."""
from __future__ import annotations

import warnings

import numpy as np

from analogue import Model
from analogue.theory import work_statistics as ws

OU_A05 = Model(tau_m=1.0, delta=0.0, a=0.5, gamma=10.0)


def test_fallbacks_are_collected_only_inside_the_block() -> None:
    # w = 0.5 (the mean) is resolved by 32 modes; w = -4 (a density ~1e-157) is not
    w = np.array([0.5, -4.0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        with ws.recorded_fallbacks() as fb:
            ws.work_pdf(OU_A05, w, 1.0, modes=32, share=False)
        ws.work_pdf(OU_A05, w, 1.0, modes=32, share=False)  # outside: not recorded
    assert fb == [(-4.0, 1.0)]
    assert not hasattr(ws, "_FALLBACKS")
