"""The paper's theory figures: files are written, and the curves drawn are the theory's."""
import numpy as np
import pytest
from matplotlib.figure import Figure

from analogue import Model
from analogue.plots import paper_theory
from analogue.theory.weak_noise_work import fluctuation_relation, rate_function

EXPECTED = [f"fig{i}_{name}.png" for i, name in enumerate(
    ["deterministic", "paths_stick", "paths_slip_up", "paths_slip_down", "boundaries",
     "propagator", "work_paths", "rate_function", "fluctuation_relation"], start=1)]


@pytest.mark.slow
def test_draw_all_writes_every_figure_as_png(tmp_path):
    written = paper_theory.draw_all(tmp_path / "figs")
    assert [p.name for p in written] == EXPECTED
    for p in written:
        data = p.read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n"
        assert len(data) > 20_000  # a drawn figure, not an empty canvas


def test_module_entry_point_usage(tmp_path, capsys):
    assert paper_theory.main([]) == 2
    assert "usage" in capsys.readouterr().err


def test_figures_draw_on_given_axes_and_show_the_theory():
    fig = Figure()
    axes = fig.subplots(1, 2)
    out = paper_theory.fig8_rate_function(axes)
    assert out[0] is axes[0] and out[1] is axes[1]
    m = Model(tau_m=1.0, delta=1.0, a=0.5, gamma=10.0)
    # the first line of panel (a) is the w < 0 branch of eq. (64), never joined across w = 0
    line = axes[0].get_lines()[0]
    w, y = line.get_xdata(), line.get_ydata()
    assert np.all(w < 0)
    assert np.allclose(y, rate_function(m, w))

    fig = Figure()
    ax = fig.subplots()
    paper_theory.fig9_fluctuation_relation(ax)
    for line in ax.get_lines()[:2]:
        w, y = line.get_xdata(), line.get_ydata()
        assert np.allclose(y, fluctuation_relation(m, w))


def test_deterministic_figure_matches_the_model():
    fig = Figure()
    axes = fig.subplots(1, 2)
    paper_theory.fig1_deterministic(axes)
    m = Model(tau_m=1.0, delta=0.7, a=0.3, gamma=10.0)
    line = axes[0].get_lines()[0]
    assert np.allclose(line.get_ydata(), m.deterministic(2.0, line.get_xdata()))
    assert line.get_ydata()[-1] == 0.0  # stuck (a < Delta)
