"""What the paper's figures draw, derived from an experiment's model alone (issue 20 item 1:
every time, range and target a figure uses follows from the model).  The study layer's: the
experiment checks it when its file is loaded (a figure that cannot be drawn is refused there)
and :mod:`analogue.plots.paper_theory` draws with it (and re-exports it)."""
from __future__ import annotations

from ..model import Model
from ..theory import weak_noise

__all__ = ["FIG5_EXAMPLE_TAUS", "FIG5_END_TAUS", "FIG5_MARGIN", "fig5_layout"]

# Fig. 5's times, in relaxation times tau_m after the stick time t_a(v0) of the panel: the
# boundaries w, u open at t_a and then grow like e^{(t - t_a)/tau_m}, so the example paths
# sit at t_a + 1.4 tau_m and the panel ends at t_a + 2.4 tau_m (3.0 and 4.0 for the paper's
# panel (a): tau_m = 1, t_a+ = ln 5).  The example paths end |v0| * 0.4 beyond the stick band
# (0.8 for the paper's v0 = 2).  Fixed times (t = 3) failed for a user's model whose t_a is
# later (tau_m = 2, Delta = 0.5, a = 0.3: t_a+ = 2 ln 6 = 3.58; issue 20 item 1).
FIG5_EXAMPLE_TAUS = 1.4
FIG5_END_TAUS = 2.4
FIG5_MARGIN = 0.4


def fig5_layout(model: Model, v0: float) -> dict:
    """What a Fig. 5 panel from ``v0`` draws, from the model alone: ``t_a`` (the stick time,
    where the boundaries start), ``t_example`` (where the example paths end), ``t_max`` (the
    panel's end), ``margin`` (how far beyond the stick band the direct examples end) and
    ``v_lim`` (the velocity axis, symmetric, holding v0 and every example end).  Raises
    ValueError outside the stick regime (no boundaries: :func:`weak_noise.boundaries`)."""
    if not abs(model.a) <= model.delta:
        raise ValueError(f"Fig. 5 needs the stick regime |a| <= Delta (boundaries w, u exist "
                         f"only there), got a={model.a:g}, Delta={model.delta:g}")
    t_a = float(model.stick_time(v0))
    t_example = t_a + FIG5_EXAMPLE_TAUS * model.tau_m
    t_max = t_a + FIG5_END_TAUS * model.tau_m
    if v0 != 0:
        margin = FIG5_MARGIN * abs(v0)
    else:  # from rest: the band's own width sets the scale
        b = weak_noise.boundaries(model, t_example, v0)
        margin = FIG5_MARGIN * abs(float(b["w"]) - float(b["u"]))
    ends = weak_noise.boundary_examples(model, t_example, v0, margin)
    v_lim = 1.15 * max([abs(v0)] + [abs(x) for x in ends.values()])
    return {"t_a": t_a, "t_example": t_example, "t_max": t_max, "margin": margin,
            "v_lim": v_lim, "examples": ends}
