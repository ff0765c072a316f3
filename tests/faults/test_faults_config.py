"""Fault injection into the configuration: one TOML document, validated whole when it is loaded.

Every circuit a command will build (the nominal one, the noise-free one behind paper Fig. 1 and
the tight-tolerance integration check) is validated at load time; cross-references between
[experiment] and [report] are checked before anything runs; no user string reaches a deck.
"""
import dataclasses
import math
import re
import tomllib
from pathlib import Path

import pytest

from analogue import Model
from analogue.circuit import experiments as E
from analogue.circuit.experiments import experiment_from_dict, load_experiment
from analogue.report.plan import RunOptions, report_settings
from conftest import toml_text

ROOT = Path(__file__).resolve().parents[2]
STICK = tomllib.loads((ROOT / "circuits" / "stick.toml").read_text())


PAYLOADS = ["<script>alert(1)</script>", "x;rm -rf /", "a\n.control\nshell touch /tmp/pwned\n.endc",
            ".include /etc/passwd", "\x00", "é" * 40, "${HOME}", "'\"", " stick", ""]


def doc(**changes):
    """The stick document with tables updated: doc(model={"gamma": 5}, report=None)."""
    d = tomllib.loads(toml_text(STICK))
    for table, upd in changes.items():
        if upd is None:
            d.pop(table, None)
        elif isinstance(upd, dict):
            d.setdefault(table, {}).update(upd)
        else:
            d[table] = upd
    return d


def write(tmp_path, d, name="mine.toml") -> Path:
    p = tmp_path / name
    p.write_text(toml_text(d))
    return p


def one_line(exc) -> str:
    msg = str(exc.value)
    assert "\n" not in msg, msg
    return msg


# ------------------------------------------------------------------ §1 real parts
@pytest.mark.parametrize("diode", ["1N4148", "BAT54"])
def test_real_part_noise_free_circuit_is_the_users_circuit_with_noise_off(diode):
    exp = experiment_from_dict(doc(circuit={"diode": diode}))
    nominal, quiet = exp.mapping(), exp.noise_free_mapping()
    # same components, same part
    for name in ("capacitance", "resistance", "i_delta", "i_force", "kappa", "theta", "g_x",
                 "cap_x", "noise_ts", "noise_gain"):
        assert getattr(quiet, name) == getattr(nominal, name), name
    assert quiet.part == nominal.part and quiet.part.name == diode
    assert quiet.noise_stddev == 0.0 and nominal.noise_stddev > 0
    # the deck is the nominal one without its noise source: every other line is the same
    a = exp.deck(replicas=2).text.splitlines()
    b = exp.noise_free_deck().text.splitlines()
    assert any("trrandom" in ln for ln in a)
    assert not any(re.search(r"trrandom\(2 \S+ 0 [^0]", ln) for ln in b)

    def core(lines):
        out = []
        for ln in lines:
            if "noise" in ln.lower() or ln.startswith((".save", ".tran")):
                continue  # the noise source, the saved vectors, the run length
            out.append(re.sub(r" nz\d*\b", "", ln))
        return out
    assert core(a) == core(b)
    # (the .tran line differs in its length only: min(t_end, 6 tau_m))
    tran_a, tran_b = ([ln.split() for ln in lines if ln.startswith(".tran")][0] for lines in (a, b))
    assert tran_a[1] == tran_b[1] and tran_a[3:] == tran_b[3:]


@pytest.mark.parametrize("diode", ["1N4148", "BAT54"])
def test_real_part_every_planned_circuit_is_built_at_load(diode):
    exp = experiment_from_dict(doc(circuit={"diode": diode}))
    plan = exp.planned_circuits()
    assert set(plan) >= {"nominal", "noise_free", "check"}
    # the nominal deck's reltol (the spec's, or the fixed value when left to measurement)
    assert plan["check"].reltol == pytest.approx(plan["nominal"].reltol / 100)
    assert plan["check"].part.name == diode


def test_a_check_circuit_that_cannot_be_built_is_refused_at_load():
    # abstol / 100 underflows to 0: the nominal circuit is fine, the integration check is not
    with pytest.raises(ValueError, match="abstol") as exc:
        experiment_from_dict(doc(circuit={"abstol": 1e-322}))
    assert "check" in one_line(exc)


# --------------------------------------------------------- §5 extreme circuit values
@pytest.mark.parametrize("key,value", [("time_scale", 1e300), ("time_scale", 1e-300),
                                       ("capacitance", 1e300), ("capacitance", 1e-300),
                                       ("volts_per_velocity", 1e300),
                                       ("volts_per_velocity", 1e-300), ("noise_dt", 1e-300),
                                       ("max_step", 1e-300)])
def test_extreme_circuit_values_are_refused_naming_the_parameter(key, value):
    with pytest.raises(ValueError) as exc:
        experiment_from_dict(doc(circuit={key: value}))
    assert key in one_line(exc)


# ----------------------------------------------------- §8 one configuration at load
def test_in_memory_experiment_keeps_its_report_table():
    d = doc(report={"prehistory": [[2.0, 0.5, 1.0]], "stationary_replicas": 40})
    exp = experiment_from_dict(d)  # no file behind it
    assert exp.source is None
    assert exp.report.prehistory == ((2.0, 0.5, 1.0),)
    assert exp.report.stationary_replicas == 40
    assert report_settings(exp) == exp.report


def test_report_table_is_read_from_the_document_not_from_disk(tmp_path):
    p = write(tmp_path, doc(report={"stationary_replicas": 48}))
    exp = load_experiment(p)
    p.write_text("garbage = [")  # the file changes after loading: the experiment does not
    assert exp.report.stationary_replicas == 48
    assert report_settings(exp).stationary_replicas == 48


@pytest.mark.parametrize("key", ["stationary_replica", "Prehistory", "check_replica", "seed"])
def test_misspelled_report_keys_are_errors(key):
    with pytest.raises(ValueError, match=f"report.{key}") as exc:
        experiment_from_dict(doc(report={key: 1}))
    one_line(exc)


@pytest.mark.parametrize("report,needle", [
    ({"prehistory": [[3.0, 0.5, 1.0]]}, "report.prehistory"),      # v0 = 3 is not in [2, -2]
    ({"prehistory": [[2.0, 0.5, 9.0]]}, "report.prehistory"),      # t = 9 > t_end = 8
    ({"prehistory": [[0.5, 9.0]]}, "report.prehistory"),           # (v, t) form, t > t_end
    ({"work_paths": [[0.1, 80.0]]}, "report.work_paths"),          # tau > quick window 50 - 2
    ({"stationary_replicas": 3}, "report.stationary_replicas"),    # too few for the jackknife
    ({"check_replicas": 1}, "report.check_replicas"),
    ({"stationary_burn_in": 60.0}, "report.stationary_burn_in"),   # >= quick length 50
    ("not a table", "[report]"),
])
def test_cross_references_are_checked_at_load(report, needle):
    d = doc(report=None)
    d["report"] = report
    with pytest.raises(ValueError) as exc:
        experiment_from_dict(d)
    assert needle in one_line(exc)


def test_work_taus_beyond_the_stationary_window_are_refused():
    d = doc(experiment={"work_taus": [1.0, 60.0], "t_end": 80.0},
            report={"stationary_t_end": 100.0, "stationary_burn_in": 2.0})
    with pytest.raises(ValueError, match="work_taus") as exc:
        experiment_from_dict(d)
    one_line(exc)


def test_time_grid_is_checked_at_load():
    # t_end not a whole number of sample_dt: refused at load, not after the first runs
    with pytest.raises(ValueError, match="sample_dt") as exc:
        experiment_from_dict(doc(experiment={"t_end": 8.0, "sample_dt": 0.03}))
    one_line(exc)


def test_check_replicas_sets_the_size_of_the_integration_check():
    from analogue.study.runs import check_plan
    exp = experiment_from_dict(doc(report={"check_replicas": 40}))
    decks, per_deck = check_plan(1000, exp.report.check_replicas)
    assert decks * per_deck >= 40
    # the check re-runs whole nominal decks (same seeds, same sizes) so the noise is shared
    exp2 = experiment_from_dict(doc(report={"check_replicas": 16}))
    assert check_plan(1000, exp2.report.check_replicas)[0] == 1


@pytest.mark.parametrize("name", sorted(p.stem for p in (ROOT / "circuits").glob("*.toml")))
def test_existing_files_keep_working(name):
    path = ROOT / "circuits" / f"{name}.toml"
    exp = load_experiment(path)
    data = tomllib.loads(path.read_text()).get("report", {})
    for key, value in data.items():
        got = getattr(exp.report, key)
        if isinstance(value, list):
            assert got == tuple(tuple(float(x) for x in p) for p in value), key
        else:
            assert got == value, key
    q = exp.report.for_options(RunOptions(quick=True))
    assert q.stationary_t_end == exp.report.stationary_t_end / 2


# --------------------------------------------------------- schema follows the dataclasses
def test_model_table_accepts_every_model_field():
    allowed = E.model_keys()
    assert allowed == {f.name for f in dataclasses.fields(Model) if f.init}
    with pytest.raises(ValueError) as exc:
        experiment_from_dict(doc(model={"taum": 1.0}))
    msg = one_line(exc)
    assert "model.taum" in msg and all(k in msg for k in allowed)


def test_circuit_table_accepts_every_spec_field():
    from analogue.circuit.mapping import CircuitSpec
    assert E.circuit_keys() == {f.name for f in dataclasses.fields(CircuitSpec) if f.init}
    for f in dataclasses.fields(CircuitSpec):
        if f.default is not dataclasses.MISSING and f.default is not None:
            exp = experiment_from_dict(doc(circuit={f.name: f.default}))
            assert getattr(exp.spec, f.name) == f.default


def test_gamma_inf_is_passed_to_model_not_refused_by_the_loader():
    try:
        Model(tau_m=1.0, delta=0.7, a=0.2, gamma=math.inf)
        model_error = None
    except (TypeError, ValueError) as exc:
        model_error = str(exc)
    d = tomllib.loads(toml_text(STICK).replace("gamma = 10.0", "gamma = inf"))
    assert d["model"]["gamma"] == math.inf
    if model_error is None:
        try:
            experiment_from_dict(d)
        except ValueError as exc:  # the circuit may refuse it; the loader must not
            assert "must be finite" not in str(exc) or "model.gamma" not in str(exc)
    else:
        with pytest.raises((TypeError, ValueError)) as exc:
            experiment_from_dict(d)
        assert model_error in str(exc.value)


def test_noise_free_toml_is_refused_at_load_not_after_the_runs(tmp_path, cli, monkeypatch):
    """gamma = inf and no [model.shot]: the noise-free model has no stationary law or
    propagator.  Before, `analogue run` simulated the circuit (8 decks per v0) and only then
    failed in the theory; now the file is refused when it is loaded, naming both keys."""
    from analogue.cli import main
    d = doc(model={"gamma": math.inf})
    assert "shot" not in d["model"]
    with pytest.raises(ValueError) as exc:
        experiment_from_dict(d, where="quiet.toml")
    msg = one_line(exc)
    assert msg.startswith("quiet.toml: ") and "model.gamma = inf" in msg and "[model.shot]" in msg
    assert "finite value > 0" in msg
    path = write(tmp_path, d, "quiet.toml")
    store = tmp_path / "store"
    monkeypatch.setenv("ANALOGUE_STORE", str(store))
    r = cli.invoke(main, ["run", str(path), "--quick", "--store", str(store)])
    assert r.exit_code == 2 and "model.gamma = inf" in r.output, r.output
    assert not store.exists() or not any(f.is_file() for f in store.rglob("*")), "nothing ran"
    # either noise on makes it an experiment again
    assert experiment_from_dict(doc(model={"gamma": 5.0})).model.gamma == 5.0
    shot = doc(model={"gamma": math.inf, "shot": {"rate": 1.0, "mean": 0.5}})
    assert experiment_from_dict(shot).model.is_noisy


def test_nested_shot_table_becomes_shot_noise():
    import analogue
    shot_cls = getattr(analogue, "ShotNoise", None)
    if shot_cls is None or "shot" not in E.model_keys():
        pytest.skip("analogue.ShotNoise / Model.shot not present yet")
    d = doc(model={"shot": {"rate": 1.0, "mean": 0.1, "two_sided": True}})
    try:
        exp = experiment_from_dict(d)
    except ValueError as exc:  # the circuit may not realise shot noise yet
        assert "shot" in str(exc)
        return
    assert isinstance(exp.model.shot, shot_cls)


@pytest.mark.parametrize("key", ["tau_m", "delta", "a", "gamma", "mass", "epsilon"])
@pytest.mark.parametrize("bad", ["1", True, [1.0], {"x": 1}])
def test_model_values_of_the_wrong_type_are_refused_naming_the_key(key, bad):
    with pytest.raises((TypeError, ValueError)) as exc:
        experiment_from_dict(doc(model={key: bad}))
    msg = one_line(exc)
    assert key in msg


# -------------------------------------------------- injection payloads in every string
STRING_FIELDS = [("name", None), ("circuit", "coulomb"), ("circuit", "diode"),
                 ("circuit", "method")]


@pytest.mark.parametrize("table,key", STRING_FIELDS)
@pytest.mark.parametrize("payload", PAYLOADS)
def test_payloads_in_string_fields_are_refused_in_one_line(table, key, payload):
    d = doc()
    if key is None:
        d[table] = payload
    else:
        d[table][key] = payload
    with pytest.raises(ValueError) as exc:
        experiment_from_dict(d)
    one_line(exc)


@pytest.mark.parametrize("payload", PAYLOADS)
def test_description_is_free_text_that_never_reaches_a_deck(payload):
    exp = experiment_from_dict(doc(description=payload))
    assert exp.description == payload
    text = exp.representative_deck().text + exp.noise_free_deck().text
    if payload.strip() and payload.strip() != "stick":  # " stick" is the deck's title
        assert payload not in text
    assert ".control" not in text and "shell" not in text and ".include" not in text


@pytest.mark.parametrize("table,key,bad", [
    ("experiment", "v0", ["2.0"]), ("experiment", "v0", "2.0"), ("experiment", "replicas", "10"),
    ("experiment", "seed", 1.5), ("experiment", "histogram_times", [True]),
    ("netlist", "replicas", "4"), ("report", "prehistory", [["2", 0.5, 1.0]]),
    ("report", "stationary_t_end", "100"), ("circuit", "smoothing", "0.02"),
    ("circuit", "allow_bias", "yes"),
])
def test_strings_where_numbers_belong_are_refused(table, key, bad):
    d = doc()
    d[table][key] = bad
    with pytest.raises((TypeError, ValueError)) as exc:
        experiment_from_dict(d)
    assert key in one_line(exc)


# ------------------------------------------------------------------- files and names
def test_non_utf8_file_names_the_file(tmp_path):
    p = tmp_path / "latin1.toml"
    p.write_bytes(toml_text(STICK).encode().replace(b"Stick regime", b"Stick r\xe9gime"))
    with pytest.raises(ValueError) as exc:
        load_experiment(p)
    msg = one_line(exc)
    assert str(p) in msg and "UTF-8" in msg


@pytest.mark.parametrize("content", [b"name = ", b"[model\n", b"\xff\xfe\x00", b"",
                                     b"name = 'x'\nname = 'y'\n"])
def test_malformed_files_name_the_file(tmp_path, content):
    p = tmp_path / "bad.toml"
    p.write_bytes(content)
    with pytest.raises(ValueError) as exc:
        load_experiment(p)
    assert str(p) in one_line(exc)


def test_a_directory_is_not_an_experiment_file(tmp_path):
    d = tmp_path / "x.toml"
    d.mkdir()
    with pytest.raises(ValueError, match="x.toml") as exc:
        load_experiment(d)
    one_line(exc)


def test_names_resolve_from_local_circuits_first(tmp_path, monkeypatch):
    local = doc(description="my own stick")
    (tmp_path / "circuits").mkdir()
    write(tmp_path / "circuits", local, "stick.toml")
    monkeypatch.chdir(tmp_path)
    assert load_experiment("stick").description == "my own stick"
    monkeypatch.chdir(tmp_path / "circuits")  # no ./circuits here: the standard one
    assert load_experiment("stick").description == STICK["description"]


def test_standard_circuits_come_from_package_data(tmp_path, monkeypatch):
    # an install outside the checkout: no ./circuits, no checkout circuits/, only package data
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "stick.toml").write_bytes((ROOT / "circuits" / "stick.toml").read_bytes())
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(E, "CIRCUITS_DIR", tmp_path / "no-checkout")
    monkeypatch.setattr(E, "PACKAGE_CIRCUITS_DIR", pkg)
    assert load_experiment("stick").description == STICK["description"]
    assert E.standard_circuit("stick") == pkg / "stick.toml"
    with pytest.raises(ValueError, match="slip") as exc:
        load_experiment("slip")
    one_line(exc)


@pytest.mark.slow
def test_wheel_ships_the_standard_circuits(tmp_path):
    """Build the wheel, unpack it outside the checkout and load every standard experiment."""
    import subprocess
    import sys
    import zipfile
    wheels = tmp_path / "wheels"
    p = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps",
                        "-q", "-w", str(wheels), str(ROOT)], capture_output=True, text=True,
                       timeout=600, cwd=tmp_path)
    assert p.returncode == 0, p.stderr[-2000:]
    (whl,) = wheels.glob("analogue-*.whl")
    site = tmp_path / "site"
    with zipfile.ZipFile(whl) as z:
        z.extractall(site)
    for src in (ROOT / "circuits").glob("*.toml"):
        assert (site / "analogue" / "circuits" / src.name).read_bytes() == src.read_bytes()
    code = (f"import analogue.circuit.experiments as E; assert str(E.__file__).startswith("
            f"{str(site)!r}); "
            "print(sorted(E.load_experiment(n).name for n in E.PAPER_EXPERIMENTS))")
    run = tmp_path / "elsewhere"
    run.mkdir()
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300,
                       cwd=run, env={"PYTHONPATH": str(site), "PATH": "/usr/bin:/bin"})
    assert p.returncode == 0, p.stderr[-2000:]
    assert "stick" in p.stdout


def test_paper_experiments_are_an_explicit_list():
    assert E.PAPER_EXPERIMENTS[:3] == ("stick", "slip", "work")
    for name in E.PAPER_EXPERIMENTS:
        assert E.standard_circuit(name).is_file()


@pytest.mark.parametrize("table", [None, "model", "circuit", "experiment", "netlist", "report"])
@pytest.mark.parametrize("payload", ["a\nb", "<script>x</script>", "x\r\n.control"])
def test_payload_keys_are_refused_in_one_line(table, payload):
    d = doc()
    (d if table is None else d[table])[payload] = 1.0
    with pytest.raises(ValueError) as exc:
        experiment_from_dict(d)
    assert repr(payload)[1:-1] in one_line(exc)


@pytest.mark.parametrize("path", ["/dev/zero", "/dev/null"])
def test_devices_are_not_read(path):
    with pytest.raises(ValueError, match="regular file") as exc:
        load_experiment(Path(path))
    one_line(exc)


def test_a_huge_file_is_not_read(tmp_path):
    p = tmp_path / "huge.toml"
    with open(p, "wb") as fh:
        fh.truncate(E.MAX_FILE_BYTES + 1)
    with pytest.raises(ValueError, match="larger than") as exc:
        load_experiment(p)
    assert str(p) in one_line(exc)
