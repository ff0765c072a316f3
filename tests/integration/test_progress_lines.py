"""Progress: a bar labelled with its run on a terminal; with stderr a file or pipe, one plain
line per run instead (and nothing when progress is off)."""
import io
import shutil

import pytest

import analogue
from analogue import Model
from analogue.circuit import simulate as S

MODEL = Model(tau_m=1.0, delta=0.7, a=0.2, gamma=10.0)


class _Tty(io.StringIO):
    def isatty(self):
        return True


@pytest.mark.parametrize("progress, tty, n, mode", [
    (True, True, 1, "bar"), (True, False, 1, "line"), (False, True, 5, None),
    (False, False, 5, None), (None, True, 5, "bar"), (None, True, 1, None),
    (None, False, 5, None)])
def test_progress_mode(monkeypatch, progress, tty, n, mode):
    monkeypatch.setattr(S.sys, "stderr", _Tty() if tty else io.StringIO())
    assert S._progress_mode(progress, n) == mode


def test_progress_mode_refuses_other_values():
    with pytest.raises(ValueError, match="progress must be True"):
        S._progress_mode("yes", 1)


@pytest.fixture
def ngspice():
    if shutil.which("ngspice") is None:
        pytest.skip("ngspice not installed")


def test_plain_line_per_run_when_stderr_is_not_a_terminal(ngspice, tmp_path, capsys):
    kw = dict(v0=1.0, t_end=0.2, replicas=3, seed=5, store=tmp_path, workers=1)
    analogue.simulate(MODEL, progress=True, label="stick: transition v0=1", **kw)
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith("stick: transition v0=1: 1 decks (0 from the store, 1 run) in ")
    analogue.simulate(MODEL, progress=True, **kw)               # default label, from the store
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [err[0]] and err[0].startswith("stick, gamma=10, v0=1, seed 5: 1 decks (1 from")
    analogue.simulate(MODEL, progress=False, **kw)
    analogue.simulate(MODEL, **kw)                              # auto: silent off a terminal
    assert capsys.readouterr().err == ""


def test_bar_is_labelled_with_the_run(ngspice, tmp_path, monkeypatch):
    tty = _Tty()
    monkeypatch.setattr(S.sys, "stderr", tty)
    import tqdm.auto
    seen = {}
    real = tqdm.auto.tqdm

    def spy(*args, **kwargs):
        seen.update(kwargs)
        kwargs["file"] = tty
        return real(*args, **kwargs)
    monkeypatch.setattr(tqdm.auto, "tqdm", spy)
    analogue.simulate(MODEL, v0=1.0, t_end=0.2, replicas=3, seed=6, store=tmp_path, workers=1,
                      progress=True, label="slip: stationary")
    assert seen["desc"] == "slip: stationary"


def test_label_is_validated():
    with pytest.raises(ValueError, match="label must be a printable str"):
        analogue.simulate(MODEL, v0=1.0, t_end=0.2, replicas=1, seed=1, label="a\nb")
