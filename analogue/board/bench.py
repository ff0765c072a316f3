"""The bench checks of one board design, run by the board job (issue 21) and shown on its
page: every op-amp inside its guaranteed input common-mode range, the residual friction with
the enable low at the worst-case MOSFET threshold and servo swing, a transient started by
the reset switch against the ``.ic`` start on the same noise, every part inside its absolute
maximum ratings over all of these runs (:func:`analogue.board.ratings.part_stresses`), and
the inputs' currents with the bench supply off (:func:`analogue.board.ratings.unpowered_inputs`).  Each is one short ngspice run
of one replica; the tests in ``tests/integration/test_board_bench.py`` and
``test_board_ratings.py`` assert the same quantities."""
from __future__ import annotations

from typing import Any

import numpy as np

from ..circuit import ngspice as ng
from . import opamp
from .design import BoardDesign
from .netlist import RESET_TIME, BoardInstance, build_board_deck
from .components import board_components
from .ratings import common_mode_margins, part_stresses, unpowered_inputs, worst_stresses

__all__ = ["WORST_VTO", "bench_checks"]

WORST_VTO = 0.8       # the MOSFETs' lowest datasheet threshold (2N7002, BSS84)


def _run(design, board, noise_dir, *, v0, t_end, seed=1, **kw):
    deck = build_board_deck(design, board, v0=v0, t_end=t_end, sample_dt=0.01, seed=seed,
                            noise_dir=noise_dir, save_all=True, **kw)
    plot = ng.run_deck(deck.text, t_stop=t_end * design.theta + deck.t_offset,
                       files=deck.noise_files).plot
    return deck, plot


def bench_checks(design: BoardDesign, board: BoardInstance, noise_dir, *, seed: int,
                 v_test: float = 10.0) -> dict:
    """(see module docstring) ``board``: the nominal board; ``v_test``: the calibration's
    force voltage."""
    out: dict[str, Any] = {}
    deck, plot = _run(design, board, noise_dir, v0=[2.0, -2.0], t_end=1.0, seed=seed)
    cm = common_mode_margins(design, board, deck.text, plot)
    out["common_mode"] = {"instances": cm,
                          "min_margin": min(min(r["margin_low"], r["margin_high"]) for r in cm.values())}
    servo = opamp.get_opamp(design.spec.servo_opamp).guaranteed.replace(vos=0.0, ib=0.0, ios=0.0)
    worst = board.replace(mosfet_vto=WORST_VTO, enable=False,
                          opamps={**board.opamps, "st": servo, "sb": servo})
    stress = {"run (.ic start)": part_stresses(design, board, deck.text, plot)}
    res, peak = [], []
    for vt in (v_test, -v_test):
        cal_board = worst.replace(v_force=vt)
        d_cal, p = _run(design, cal_board, noise_dir, v0=[0.0], t_end=4.0, noise_off=True)
        stress[f"calibration step, force {vt:+g} V, enable low"] = part_stresses(
            design, cal_board, d_cal.text, p)
        # settled part of the step (t > 3 tau_m): before it the switch channels' 9 pF at the
        # floating bridge nodes carry C dV/dt, an inertia term (0.2 % of C) the tau_m step
        # absorbs, not a friction
        settled = p["time"] > 3.0 * design.theta
        i = np.abs(p["i(vb0ia)"])
        res.append(float(np.max(i[settled])))
        peak.append(float(np.max(i)))
    out["residual_friction"] = {"max_A": max(res), "relative_to_I0": max(res) / design.i_delta,
                                "capacitive_peak_A": max(peak),
                                "mosfet_vto": WORST_VTO, "servo": servo.name}
    paths = {}
    # the .ic start is the common-mode run above (same deck): not run twice
    reset = _run(design, board, noise_dir, v0=[2.0, -2.0], t_end=1.0, seed=seed, start="reset")
    stress["reset start (reset, release, enable toggled)"] = part_stresses(design, board,
                                                                          reset[0].text, reset[1])
    for start, (d, p) in (("ic", (deck, plot)), ("reset", reset)):
        grid = d.t_offset + np.linspace(0.0, 1.0, 101) * design.theta
        paths[start] = np.array([np.interp(grid, p["time"], p[f"v(o{j})"]) * design.to_model_v
                                 for j in range(2)])
    out["reset_start"] = {"reset_time_s": RESET_TIME,
                          "initial": paths["reset"][:, 0].tolist(),
                          "rms_vs_ic_start": float(np.sqrt(np.mean((paths["reset"] - paths["ic"]) ** 2)))}
    out["stresses"] = {**worst_stresses(stress), "modes": list(stress)}
    out["unpowered_inputs"] = unpowered_inputs(board_components(design))
    return out
