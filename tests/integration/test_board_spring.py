"""The spring on the board: feedback from the position integrator (noise off, against the ODE)."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from analogue import Model
from analogue.board.design import design_board
from analogue.board.netlist import build_board_deck, nominal_instance
from analogue.circuit import ngspice as ng

pytestmark = pytest.mark.slow
# circuits/spring.toml: released from x0 = 2 at rest, rings down, sticks where |k x - a| < Delta
SPRING = Model(tau_m=3.0, delta=0.5, a=0.0, gamma=20.0, spring=1.0, x0=2.0)


def test_spring_board_follows_the_noise_free_equations(tmp_path):
    d = design_board(SPRING, v0=[0.0])
    real = d.realised
    assert real.spring == pytest.approx(1.0, rel=0.02)       # E96 rounding of R_X, R_K
    t_end = 8.0
    deck = build_board_deck(d, nominal_instance(d), v0=[0.0], t_end=t_end, sample_dt=0.01, seed=1,
                            noise_dir=tmp_path, noise_off=True, reltol=1e-5)
    plot = ng.run_deck(deck.text, t_stop=t_end * d.theta, files=deck.noise_files).plot
    t = np.linspace(0.0, t_end, 801)
    v = ng.resample(plot, deck.vectors["v"], t * d.theta)[0] * deck.to_model_v
    x = ng.resample(plot, deck.vectors["x"], t * d.theta)[0] * deck.to_model_x

    def rhs(_, y):   # the realised model with the bridge's tanh law, integrated independently
        vv, xx = y
        return [-vv / real.tau_m - real.delta * np.tanh(vv / real.epsilon) - real.spring * xx + real.a, vv]

    ref = solve_ivp(rhs, (0.0, t_end), [0.0, SPRING.x0], t_eval=t, rtol=1e-9, atol=1e-11,
                    method="LSODA")
    # the mass swings through about one half period (pi/sqrt(k) = 3.1) and sticks near
    # x = 2 - 2 Delta/k = 1 (the friction band |x| < Delta/k = 0.5 is reached after the
    # second swing); velocities up to ~1.4
    assert np.max(np.abs(ref.y[0])) > 1.0
    assert np.max(np.abs(v - ref.y[0])) < 0.005   # measured 7e-4
    assert np.max(np.abs(x - ref.y[1])) < 0.005   # measured 4e-4
