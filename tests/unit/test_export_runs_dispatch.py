"""Every shipped experiment's export reads the runs from the function its report runs them
with (issue 20 item 4): the paper's model through study.runs.run_experiment_runs, a family
member through study.members.member_runs (which analyse_member calls), with the same size;
and the line export prints before it starts names that size's replica counts.  No ngspice:
the two runners are replaced by recorders."""
import pytest

from analogue import export
from analogue.circuit.experiments import PAPER_EXPERIMENTS, load_experiment, standard_circuit
from analogue.study import members as beyond
from analogue.report.plan import RunOptions

SHIPPED = (*PAPER_EXPERIMENTS, *beyond.MEMBERS)


@pytest.mark.parametrize("name", SHIPPED)
@pytest.mark.parametrize("quick", [True, False])
def test_export_uses_the_reports_runner(name, quick, monkeypatch):
    calls = []
    monkeypatch.setattr(export, "run_experiment_runs",
                        lambda exp, opts: calls.append(("paper", exp.name, opts.quick)))
    monkeypatch.setattr(export, "member_runs",
                        lambda exp, opts: calls.append(("member", exp.name, opts.quick)))
    exp = load_experiment(standard_circuit(name))
    export.experiment_runs(exp, RunOptions(quick=quick))
    kind = "paper" if name in PAPER_EXPERIMENTS else "member"
    assert calls == [(kind, name, quick)]

    line = export.size_line(exp, quick)
    assert line.startswith(f"{name}: the {'--quick' if quick else 'full (no --quick)'} size")
    if kind == "member":
        s = beyond.member_sizes(exp, quick)
        assert f"{s.transition_replicas} " in line
    else:
        opts = RunOptions(quick=quick)
        assert f"({opts.scaled(exp.replicas)} replicas per v0, " \
               f"{exp.report.for_options(opts).stationary_replicas} stationary)" in line


def test_analyse_member_reads_member_runs(monkeypatch):
    """The member's report section gets its circuit runs from member_runs (the function
    export reads), at the report's size."""
    seen = []

    class Stop(Exception):
        pass

    def fake(exp, opts, *, quick=None, progress=None):
        seen.append((exp.name, quick))
        raise Stop
    monkeypatch.setattr(beyond, "member_runs", fake)
    with pytest.raises(Stop):
        beyond.analyse_member("shot", RunOptions(quick=True))
    assert seen == [("shot", True)]
