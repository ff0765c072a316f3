"""Standard circuits and experiments, defined in ``circuits/*.toml``.

Schema (every table and key optional unless marked; unknown keys are errors)::

    name = "stick"                 # required, ^[A-Za-z][A-Za-z0-9_]{0,31}$, the file's stem
    description = "..."            # free text (never reaches a deck)

    [model]                        # analogue.Model: every field of the dataclass is a key;
    tau_m = 1.0                    # those without a default are required
    delta = 0.7
    a = 0.2
    gamma = 10.0
    mass = 1.0

    [circuit]                      # analogue.circuit.CircuitSpec: every field is a key
    coulomb = "diode-bridge"
    diode = "ideal"
    smoothing = 0.02

    [experiment]
    v0 = [2.0, -2.0]               # required: initial velocities (model units)
    replicas = 200                 # replicas per initial velocity
    t_end = 8.0                    # required, model time
    sample_dt = 0.01               # required, model time
    seed = 1                       # ngspice .options seed
    burn_in = 0.0                  # time discarded before stationary measurements
    histogram_times = [0.5, 1.0]   # times at which to histogram v (each <= t_end)
    work_taus = [1.0, 2.0]         # work windows tau (each <= t_end - burn_in)

    [netlist]                      # the representative deck committed in netlists/
    replicas = 4                   # total replicas in that deck (v0 values cycled)

    [report]                       # what the report measures: analogue.study.settings

The whole document is validated when it is loaded, before anything runs: the tables, the
cross-references between ``[experiment]`` and ``[report]``, the time grids of every run and
every circuit a command will build (the nominal one, the noise-free one of paper Fig. 1 and the
tight-tolerance integration check; :meth:`Experiment.planned_circuits`).

The ``[model]`` and ``[circuit]`` keys are the fields of :class:`analogue.Model` and
:class:`~analogue.circuit.mapping.CircuitSpec` (read from the dataclasses, so new fields are
accepted as they are added); the values are validated by those classes.  A nested table
(``[model.shot]``) becomes the dataclass its field is annotated with (e.g. ``ShotNoise``).
An experiment needs noise: ``gamma = inf`` (TOML ``inf``) switches the Gaussian noise off and
is accepted only together with a ``[model.shot]`` table; without one the file is refused when
it is loaded, naming both keys.

Experiment names resolve from ``./circuits/<name>.toml`` first, then from the standard
circuits shipped with the package (``analogue/circuits/`` in an installed wheel, copied from
the checkout's top-level ``circuits/`` at build time; the checkout's ``circuits/`` itself when
running from a source tree).
"""
from __future__ import annotations

import dataclasses
import math
import re
import sys
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import model as _model_module
from ..model import Model
from .. import checks
from .figure_layout import fig5_layout
from .settings import ReportSettings, report_settings_from_dict
from ..theory import weak_noise
from ..circuit.mapping import (FIXED_TRTOL, CircuitMapping, CircuitSpec, check_mapping_values,
                      check_spec_ranges, map_model)
from ..circuit.netlist import Deck, build_deck

__all__ = ["Experiment", "load_experiment", "experiment_from_dict", "regenerate_netlists",
           "netlist_path", "experiment_names", "standard_circuit", "resolve_experiment",
           "model_keys", "circuit_keys", "PAPER_EXPERIMENTS", "PAPER_FIGURE_TAGS",
           "FIG1_EXPERIMENTS", "OPEN_QUESTION_EXPERIMENTS", "CIRCUITS_DIR",
           "PACKAGE_CIRCUITS_DIR", "NETLISTS_DIR"]

REPO_ROOT = Path(__file__).resolve().parents[2]
CIRCUITS_DIR = REPO_ROOT / "circuits"        # the checkout's standard circuits (fixed layout)
NETLISTS_DIR = REPO_ROOT / "netlists"
# In an installed wheel the standard circuits are package data (setup.py copies circuits/
# into analogue/circuits/ when it builds); a source tree has none and uses CIRCUITS_DIR.
PACKAGE_CIRCUITS_DIR = Path(__file__).resolve().parents[1] / "circuits"

# The experiments of `analogue paper`, in the paper's order: stick (Figs. 2, 5, 6), slip
# (Figs. 3, 4), work (Figs. 7-9).  The one list: `paper` runs these and nothing else.  The
# model-family experiments (issue 9: cubic, stribeck, spring, shot) join here once the report
# supports them ("Beyond the paper").
PAPER_EXPERIMENTS = ("stick", "slip", "work")
# Which of the paper's figures an experiment reproduces, where that is not read off its model:
# the figure number in the file name of its prehistory figure (Fig. 2: stick, Figs. 3-4:
# slip), the experiments whose noise-free motion makes up Fig. 1, and the experiment whose
# work statistics open the paper's open question (Section V) in any report.
PAPER_FIGURE_TAGS = {"stick": "2", "slip": "3-4"}
FIG1_EXPERIMENTS = ("stick", "slip")
OPEN_QUESTION_EXPERIMENTS = ("work",)

_TOP_KEYS = {"name", "description", "model", "circuit", "experiment", "netlist", "report"}
_EXPERIMENT_KEYS = {"v0", "replicas", "t_end", "sample_dt", "seed", "burn_in",
                    "histogram_times", "work_taus"}
_EXPERIMENT_REQUIRED = {"v0", "t_end", "sample_dt"}
_NETLIST_KEYS = {"replicas"}
# Longest run / shortest solver step (noise hold or max_step): beyond this a deck would not
# finish (ngspice takes at least one step per hold; measured ~20 us per replica-step).
MAX_STEPS_PER_RUN = 10_000_000
# Noise-free runs (paper Fig. 1) last six relaxation times: the motion has settled by then.
NOISE_FREE_TAUS = 6.0


def _init_fields(cls) -> dict:
    return {f.name: f for f in dataclasses.fields(cls) if f.init}


def model_keys() -> set:
    """Keys of the ``[model]`` table: the fields of :class:`analogue.Model`."""
    return set(_init_fields(Model))


def circuit_keys() -> set:
    """Keys of the ``[circuit]`` table: the fields of :class:`CircuitSpec`."""
    return set(_init_fields(CircuitSpec))


def _required(cls) -> set:
    return {n for n, f in _init_fields(cls).items()
            if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING}


@dataclass(frozen=True)
class Experiment:
    """One experiment: the model, the circuit choice, what to run and what to measure
    (``report``: the ``[report]`` table, parsed with the rest of the file)."""

    name: str
    description: str
    model: Model
    spec: CircuitSpec
    v0: tuple
    replicas: int
    t_end: float
    sample_dt: float
    seed: int
    burn_in: float
    histogram_times: tuple
    work_taus: tuple
    netlist_replicas: int
    source: Path | None = None
    report: ReportSettings = field(default_factory=ReportSettings)

    def mapping(self) -> CircuitMapping:
        return map_model(self.model, self.spec)

    def noise_free_mapping(self) -> CircuitMapping:
        """The user's own circuit (same components, same parts) with the noise source off."""
        return self.mapping().without_noise()

    def check_spec(self, spec: CircuitSpec | None = None) -> CircuitSpec:
        """The integration check's circuit: the same, 100x tighter tolerances, a quarter of the
        step (the held noise is the same realisation, so the path-by-path difference measures
        the integration error).  ``spec``: the nominal run's circuit with its tolerances as
        chosen (analogue.circuit.tolerances); default this experiment's, unset tolerances at
        their fixed values.  The check integrates with the nominal run's method at ngspice's
        default trtol: measured against a further 100x tighter run (gear 3e-9) on the work
        experiment's stationary deck (32 x 30, nominal trap 3e-5), a gear check kept 21 % of
        the nominal's stick-fraction error (-4.8e-4 of -2.2e-3 path spreads), so the measured
        difference fell 21 % short of it, a trap check 8 % (-1.8e-4), and cost 7.6 against
        9.0 CPU-s."""
        spec = self.spec if spec is None else spec
        m = map_model(self.model, spec)
        max_step = spec.max_step if spec.max_step is not None else m.noise_dt
        return spec.replace(reltol=m.reltol / 100, abstol=spec.abstol / 100, trtol=FIXED_TRTOL,
                            method=m.method, vntol=m.vntol / 100, max_step=max_step / 4)

    def planned_circuits(self) -> dict:
        """Every circuit a run of this experiment builds: ``{"nominal", "noise_free",
        "check"}`` -> CircuitMapping (each raises ValueError if it cannot be built)."""
        nominal = self.mapping()
        try:
            check = map_model(self.model, self.check_spec())
        except ValueError as exc:
            raise ValueError(f"the integration check's circuit (100x tighter tolerances, a "
                             f"quarter of the step) cannot be built: {exc}") from None
        return {"nominal": nominal, "noise_free": nominal.without_noise(), "check": check}

    def noise_free_t_end(self) -> float:
        """Length of the noise-free run: ``min(t_end, 6 tau_m)`` on the sample grid."""
        n = max(1, math.floor(min(self.t_end, NOISE_FREE_TAUS * self.model.tau_m)
                              / self.sample_dt + 1e-9))
        return n * self.sample_dt

    def initial_velocities(self) -> np.ndarray:
        """(len(v0) * replicas,) initial velocities: each v0 value repeated ``replicas`` times."""
        return np.repeat(np.asarray(self.v0, dtype=float), self.replicas)

    def deck(self, *, replicas: int | None = None, seed: int | None = None) -> Deck:
        """The deck of this experiment (default: all replicas); with ``replicas`` given, the v0
        values are cycled over that many replicas."""
        if replicas is None:
            v0 = self.initial_velocities()
        else:
            v0 = np.resize(np.asarray(self.v0, dtype=float), replicas)
        return build_deck(self.mapping(), replicas=len(v0), v0=v0, t_end=self.t_end,
                          seed=self.seed if seed is None else seed, sample_dt=self.sample_dt,
                          title=self.name)

    def noise_free_deck(self, seed: int | None = None) -> Deck:
        """The noise-free deck: one replica per v0, the user's circuit with zero noise."""
        v0 = np.asarray(self.v0, dtype=float)
        return build_deck(self.noise_free_mapping(), replicas=len(v0), v0=v0,
                          t_end=self.noise_free_t_end(), sample_dt=self.sample_dt,
                          seed=self.seed if seed is None else seed, title=self.name)

    def representative_deck(self) -> Deck:
        """The small deck committed as ``netlists/<name>.cir``."""
        return self.deck(replicas=self.netlist_replicas)


def shown_key(key) -> str:
    """A TOML key as it may appear in a one-line message (quoted when it is not plain)."""
    return key if isinstance(key, str) and re.fullmatch(r"[A-Za-z0-9_-]{1,64}", key) else repr(key)


def _table(data, key: str, allowed: set, where: str) -> dict:
    section = data.get(key, {})
    if not isinstance(section, dict):
        raise ValueError(f"{where}: [{key}] must be a table, got {type(section).__name__}")
    unknown = sorted(set(section) - allowed)
    if unknown:
        raise ValueError(f"{where}: unknown key {key}.{shown_key(unknown[0])} (allowed: "
                         f"{', '.join(sorted(allowed))})")
    return section


def _require(section: dict, required: set, prefix: str, where: str) -> None:
    missing = sorted(required - set(section))
    if missing:
        raise ValueError(f"{where}: missing required key {prefix}.{missing[0]}")


def _floats(what: str, value, *, allow_empty: bool = True) -> tuple:
    if not isinstance(value, list) or (not allow_empty and not value):
        raise ValueError(f"{what} must be a {'non-empty ' if not allow_empty else ''}list of numbers")
    return tuple(checks.finite(f"{what}[{i}]", x) for i, x in enumerate(value))


def _nested_class(cls, key: str):
    """The dataclass a field of ``cls`` is annotated with (``shot: ShotNoise | None``)."""
    annotation = str(_init_fields(cls)[key].type)
    for token in re.findall(r"[A-Za-z_][A-Za-z0-9_]*", annotation):
        for home in (sys.modules.get(cls.__module__), _model_module):
            found = getattr(home, token, None) if home is not None else None
            if isinstance(found, type) and (dataclasses.is_dataclass(found)
                                            or hasattr(found, "from_mapping")):
                return found  # a dataclass, or a kind chosen by its table (noise = {kind=...})
    return None


def _field_value(cls, table: str, key: str, value, where: str):
    """A TOML value for field ``key`` of ``cls``: nested tables become the field's dataclass;
    text or booleans where the field is a number are refused (TypeError)."""
    what = f"{where}: {table}.{key}"
    annotation = str(_init_fields(cls)[key].type)
    if isinstance(value, dict):
        sub = _nested_class(cls, key)
        if sub is None:
            raise TypeError(f"{what} must be a value, not a table")
        try:
            build = getattr(sub, "from_mapping", None)
            return build(value) if build is not None else sub(**value)
        except TypeError as exc:
            if not dataclasses.is_dataclass(sub):
                raise TypeError(f"{what}: {exc}") from None
            allowed = ", ".join(sorted(_init_fields(sub)))
            raise TypeError(f"{what}: {exc} (keys of [{table}.{key}]: {allowed})") from None
        except ValueError as exc:
            raise ValueError(f"{what}: {exc}") from None
    shape = re.search(r"\btuple\[([^\]]*)\]", annotation)
    if isinstance(value, list) and shape:
        # a TOML array for a tuple field (stribeck = [delta_s, v_s]): the count is a value error
        items = [t.strip() for t in shape.group(1).split(",")]
        if "..." not in items and len(value) != len(items):
            raise ValueError(f"{what} must be a list of {len(items)} values, got {value!r}")
        return tuple(value)
    numeric = re.search(r"\b(float|int|Real)\b", annotation) is not None
    if numeric and re.search(r"\bstr\b", annotation) is None and isinstance(value, (str, bool, list)) \
            and not ("bool" in annotation and isinstance(value, bool)):
        raise TypeError(f"{what} must be a number, got {value!r}")
    return value


def _build(cls, table: str, data: dict, where: str):
    kwargs = {k: _field_value(cls, table, k, v, where) for k, v in data.items()}
    try:
        return cls(**kwargs)
    except TypeError as exc:
        raise TypeError(f"{where}: [{table}]: {exc}") from None
    except (ValueError, OverflowError) as exc:
        raise ValueError(f"{where}: [{table}]: {exc}") from None


def _grid(t_end: float, sample_dt: float, what: str, where: str) -> None:
    n = round(t_end / sample_dt)
    if n < 1 or abs(n * sample_dt - t_end) > 1e-6 * t_end:
        raise ValueError(f"{where}: {what}={t_end:g} must be a whole number of "
                         f"experiment.sample_dt={sample_dt:g} intervals (t/sample_dt = "
                         f"{t_end / sample_dt:.6g})")


def _prehistory_targets(report: ReportSettings, v0s: tuple, where: str) -> tuple:
    """``report.prehistory`` as ``(v0, v, t)`` triples: a pair ``[v, t]`` starts from
    ``experiment.v0[0]``.  A pair whose first number is itself one of experiment.v0 is refused:
    it reads as well as ``[v0, v]`` with the time left out (``[2.0, 0.2]`` in the stick
    experiment was taken as "v0 = 2 to v = 2 at t = 0.2" without a word, issue 20 item 2)."""
    out = []
    for p in report.prehistory:
        if len(p) == 2:
            if any(math.isclose(p[0], u, rel_tol=1e-12, abs_tol=1e-12) for u in v0s):
                raise ValueError(
                    f"{where}: report.prehistory entry {list(p)} is ambiguous: a pair is read "
                    f"as [v, t] from experiment.v0[0] = {v0s[0]:g} (target v = {p[0]:g} at "
                    f"t = {p[1]:g}), but {p[0]:g} is also one of experiment.v0 = {list(v0s)}; "
                    f"write the three numbers [v0, v, t], e.g. [{v0s[0]:g}, {p[0]:g}, {p[1]:g}]")
            p = (v0s[0],) + tuple(p)
        out.append(tuple(p))
    return tuple(out)


def _check_figures(exp: Experiment, where: str) -> None:
    """What the paper's figures of this experiment draw, computed from its model when the
    file is loaded (closed forms, ~10 ms per target), so that a figure that cannot be drawn
    is refused here, with the key to change, not after the circuit has run (issue 20 item 1:
    Fig. 5's example time was a constant before the stick time of a user's model).  Family
    members draw their own figures (analogue.report.family_figures) from exact numerics."""
    m = exp.model
    if not m.is_paper:
        return
    if m.regime == "stick":
        v0s = exp.v0[:2] if len(exp.v0) > 1 else (exp.v0[0], -exp.v0[0])
        for v0 in v0s:
            try:
                fig5_layout(m, v0)
            except (ValueError, ArithmeticError) as exc:
                raise ValueError(f"{where}: paper Fig. 5 (boundaries) from v0 = {v0:g} cannot be "
                                 f"drawn for this model ({exc}): change experiment.v0 or the "
                                 f"[model] values") from None
    for v0, v, t in exp.report.prehistory:
        try:
            weak_noise.optimal_path(m, v, t, v0, n=64)
        except (ValueError, ArithmeticError) as exc:
            raise ValueError(f"{where}: report.prehistory entry [{v0:g}, {v:g}, {t:g}]: the "
                             f"optimal path to it cannot be computed ({exc}): choose another "
                             f"target") from None
    if exp.report.work_paths and m.a == 0:
        raise ValueError(f"{where}: report.work_paths {[list(p) for p in exp.report.work_paths]} "
                         f"needs a force: with model.a = 0 the work W = F x is zero; remove "
                         f"report.work_paths or set model.a != 0")


def _check_plan(exp: Experiment, where: str) -> None:
    """Cross-references and everything the runs will build, before anything runs."""
    st_full, st_quick = exp.report.variants()
    v0s = exp.v0
    for p in exp.report.prehistory:
        v0, t = p[0], p[-1]
        if not any(math.isclose(v0, u, rel_tol=1e-12, abs_tol=1e-12) for u in v0s):
            raise ValueError(f"{where}: report.prehistory entry {list(p)} starts from v0={v0:g}, "
                             f"which is not one of experiment.v0={list(v0s)}")
        if not 0 < t <= exp.t_end:
            raise ValueError(f"{where}: report.prehistory entry {list(p)} has time t={t:g} "
                             f"outside (0, experiment.t_end={exp.t_end:g}]")
    for st, size in ((st_full, "full"), (st_quick, "--quick")):
        window = st.stationary_t_end - st.stationary_burn_in
        for w, tau in st.work_paths:
            if tau > window:
                raise ValueError(f"{where}: report.work_paths entry [{w:g}, {tau:g}]: tau={tau:g} "
                                 f"exceeds the stationary window stationary_t_end - "
                                 f"stationary_burn_in = {window:g} ({size} size; --quick halves "
                                 f"stationary_t_end)")
        for tau in exp.work_taus:
            if tau > window + 1e-9:
                raise ValueError(f"{where}: experiment.work_taus entry {tau:g} exceeds the "
                                 f"stationary window report.stationary_t_end - "
                                 f"report.stationary_burn_in = {window:g} ({size} size; --quick "
                                 f"halves stationary_t_end)")
        _grid(st.stationary_t_end, exp.sample_dt, f"report.stationary_t_end ({size} size)", where)
    _grid(exp.t_end, exp.sample_dt, "experiment.t_end", where)

    # every circuit the runs build, and the decks' numbers
    try:
        plan = exp.planned_circuits()
        exp.representative_deck()
        exp.noise_free_deck()
    except OverflowError as exc:
        raise ValueError(f"{where}: the circuit's values overflow ({exc}); check circuit."
                         f"time_scale, circuit.capacitance, circuit.volts_per_velocity and the "
                         f"[model] values") from None
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None
    for kind, m in plan.items():
        try:
            check_mapping_values(m, kind)
        except ValueError as exc:
            raise ValueError(f"{where}: {exc}") from None
    longest = max(exp.t_end, st_full.stationary_t_end)
    m = plan["check"]
    step = min(m.noise_dt, m.spec.max_step)
    if longest / step > MAX_STEPS_PER_RUN:
        name = "max_step" if exp.spec.max_step is not None and \
            exp.spec.max_step <= m.noise_dt else "noise_dt"
        raise ValueError(f"{where}: circuit.{name}={getattr(exp.spec, name) or m.noise_dt:.3g} "
                         f"means {longest / step:.3g} solver steps over the longest run "
                         f"({longest:g} model time units, integration check at a quarter of "
                         f"the step); the limit is {MAX_STEPS_PER_RUN:.0e}: raise it")


def experiment_from_dict(data: dict, where: str = "experiment", source: Path | None = None) -> Experiment:
    """Validate a parsed TOML document (see the module docstring for the schema)."""
    if not isinstance(data, dict):
        raise ValueError(f"{where}: the document must be a table")
    unknown = sorted(set(data) - _TOP_KEYS)
    if unknown:
        raise ValueError(f"{where}: unknown key {shown_key(unknown[0])} (allowed: "
                         f"{', '.join(sorted(_TOP_KEYS))})")
    if "name" not in data:
        raise ValueError(f"{where}: missing required key name")
    name = checks.identifier(f"{where}: name", data["name"])
    description = data.get("description", "")
    if not isinstance(description, str):
        raise ValueError(f"{where}: description must be a string")

    mdata = _table(data, "model", model_keys(), where)
    _require(mdata, _required(Model), "model", where)
    model = _build(Model, "model", mdata, where)
    if not model.is_noisy:
        # Refused here, not after the circuit has run: an experiment compares noisy runs with
        # the stationary law and the propagator, which the noise-free model does not have (its
        # motion is the noise-free run every experiment already makes, paper Fig. 1).
        raise ValueError(f"{where}: model.gamma = inf with no [model.shot] table is the "
                         f"noise-free model (no stationary law or propagator to compare the "
                         f"circuit with): set model.gamma to a finite value > 0 or add a "
                         f"[model.shot] table (rate > 0, mean > 0)")

    cdata = _table(data, "circuit", circuit_keys(), where)
    spec = _build(CircuitSpec, "circuit", cdata, where)
    check_spec_ranges(spec, f"{where}: circuit")

    edata = _table(data, "experiment", _EXPERIMENT_KEYS, where)
    _require(edata, _EXPERIMENT_REQUIRED, "experiment", where)
    v0 = _floats(f"{where}: experiment.v0", edata["v0"], allow_empty=False)
    replicas = checks.integer(f"{where}: experiment.replicas", edata.get("replicas", 100), minimum=1, maximum=100_000)
    t_end = checks.positive(f"{where}: experiment.t_end", edata["t_end"])
    sample_dt = checks.positive(f"{where}: experiment.sample_dt", edata["sample_dt"])
    if sample_dt > t_end:
        raise ValueError(f"{where}: experiment.sample_dt must be <= t_end={t_end}, got {sample_dt}")
    seed = checks.integer(f"{where}: experiment.seed", edata.get("seed", 1), minimum=0, maximum=2**31 - 1)
    burn_in = checks.nonnegative(f"{where}: experiment.burn_in", edata.get("burn_in", 0.0))
    if burn_in >= t_end:
        raise ValueError(f"{where}: experiment.burn_in must be < t_end={t_end}, got {burn_in}")
    times = _floats(f"{where}: experiment.histogram_times", edata.get("histogram_times", []))
    for t in times:
        if not 0 < t <= t_end:
            raise ValueError(f"{where}: experiment.histogram_times must lie in (0, t_end={t_end}], got {t}")
    taus = _floats(f"{where}: experiment.work_taus", edata.get("work_taus", []))
    for tau in taus:
        if not 0 < tau <= t_end - burn_in:
            raise ValueError(f"{where}: experiment.work_taus must lie in (0, t_end - burn_in="
                             f"{t_end - burn_in}], got {tau}")

    ndata = _table(data, "netlist", _NETLIST_KEYS, where)
    netlist_replicas = checks.integer(f"{where}: netlist.replicas", ndata.get("replicas", 4), minimum=1, maximum=64)

    report = report_settings_from_dict(data.get("report"), where)
    report = dataclasses.replace(report, prehistory=_prehistory_targets(report, v0, where))

    exp = Experiment(name=name, description=description, model=model, spec=spec, v0=v0,
                     replicas=replicas, t_end=t_end, sample_dt=sample_dt, seed=seed,
                     burn_in=burn_in, histogram_times=times, work_taus=taus,
                     netlist_replicas=netlist_replicas, source=source, report=report)
    _check_plan(exp, where)
    _check_figures(exp, where)
    return exp


def _names_in(directory: Path) -> list[str]:
    if not directory.is_dir():
        return []
    return sorted(p.stem for p in directory.glob("*.toml") if checks.NAME_PATTERN.fullmatch(p.stem))


def _standard_dir() -> Path:
    """Where the standard circuits are: package data in an installed wheel, else the checkout."""
    return PACKAGE_CIRCUITS_DIR if _names_in(PACKAGE_CIRCUITS_DIR) else CIRCUITS_DIR


def experiment_names() -> list[str]:
    """Names of the standard experiments (shipped with the package), sorted."""
    return _names_in(_standard_dir())


def standard_circuit(name: str) -> Path:
    """The TOML file of the standard experiment ``name`` (package data or the checkout)."""
    name = checks.identifier("experiment name", name)
    path = _standard_dir() / f"{name}.toml"
    if not path.is_file():
        raise ValueError(f"experiment name must be one of {experiment_names()}, got {name!r}")
    return path


def resolve_experiment(name: str) -> Path:
    """``./circuits/<name>.toml`` if it exists, else the standard experiment ``name``."""
    name = checks.identifier("experiment name", name)
    local = Path.cwd() / "circuits" / f"{name}.toml"
    if local.is_file():
        return local
    try:
        return standard_circuit(name)
    except ValueError:
        local_names = _names_in(Path.cwd() / "circuits")
        raise ValueError(f"experiment name must be one of {sorted(set(experiment_names()) | set(local_names))} "
                         f"(./circuits, then the standard circuits), got {name!r}") from None


# An experiment file is a page of text (the standard ones are ~1 kB); a bound keeps a wrong
# path (a data file, /dev/zero) from being read into memory.
MAX_FILE_BYTES = 1 << 20


def _read_document(path: Path) -> dict:
    try:
        if path.exists() and not path.is_dir() and not path.is_file():
            raise ValueError(f"{path}: not a regular file (a device, pipe or socket), not an "
                             f"experiment file")
        size = path.stat().st_size
        if size > MAX_FILE_BYTES:
            raise ValueError(f"{path}: {size} bytes, larger than an experiment file can be "
                             f"({MAX_FILE_BYTES} bytes); is it the right file?")
        raw = path.read_bytes()
    except IsADirectoryError:
        raise ValueError(f"{path}: is a directory, not an experiment file") from None
    except OSError as exc:
        raise ValueError(f"{path}: cannot read the experiment file ({exc.strerror or exc})") from None
    try:
        # one byte-order mark at the start is what some editors (Windows Notepad) write:
        # the same document (TOML itself refuses it)
        text = raw.decode("utf-8").removeprefix("\ufeff")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{path}: not a UTF-8 text file (byte {exc.start}: "
                         f"{raw[exc.start:exc.start + 1]!r}); TOML files are UTF-8") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        msg = " ".join(str(exc).split())
        raise ValueError(f"{path}: not valid TOML: {msg}") from None


def load_experiment(path_or_name) -> Experiment:
    """Load an experiment: a bare name (``./circuits/<name>.toml``, else the standard
    experiment) or a TOML file path."""
    by_name = False
    if isinstance(path_or_name, Path):
        path = path_or_name
    elif isinstance(path_or_name, str):
        if checks.NAME_PATTERN.fullmatch(path_or_name):
            path, by_name = resolve_experiment(path_or_name), True
        else:
            path = Path(path_or_name)
    else:
        raise ValueError(f"path_or_name must be a path or an experiment name, got {path_or_name!r}")
    if not path.exists():
        raise ValueError(f"no experiment file at {path}")
    data = _read_document(path)
    exp = experiment_from_dict(data, where=str(path), source=path)
    if (by_name or path.parent.resolve() == CIRCUITS_DIR.resolve()) and exp.name != path.stem:
        raise ValueError(f"{path}: name must equal the file stem {path.stem!r}, got {exp.name!r}")
    return exp


def netlist_text(exp: Experiment) -> str:
    """The committed representative deck: a provenance comment after the title line."""
    text = exp.representative_deck().text
    title, rest = text.split("\n", 1)
    where = f"circuits/{exp.name}.toml"
    if exp.source is not None and Path(exp.source).resolve().parent != CIRCUITS_DIR.resolve():
        where = Path(exp.source).name
    header = (f"* Generated by analogue.circuit.experiments from {where} "
              f"({exp.netlist_replicas} replicas; regenerate with `analogue netlist`). Do not edit.\n")
    return f"{title}\n{header}{rest}"


def _write_atomic(path: Path, text: str) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text)
    tmp.replace(path)


def netlist_path(exp: Experiment) -> Path:
    """Where the representative deck of ``exp`` lives: ``netlists/<name>.cir`` for the standard
    experiments, ``<toml stem>.cir`` beside any other experiment file."""
    if exp.source is not None and Path(exp.source).resolve().parent != CIRCUITS_DIR.resolve():
        return Path(exp.source).with_suffix(".cir")
    return NETLISTS_DIR / f"{exp.name}.cir"


def regenerate_netlists(check: bool = False, experiments=None) -> list[Path]:
    """Write the representative deck of every experiment in ``circuits/`` (or of
    ``experiments``: names or TOML paths) to :func:`netlist_path`; return the paths written.
    With ``check=True`` write nothing and return the decks that are missing or stale."""
    out = []
    for item in (experiment_names() if experiments is None else experiments):
        exp = load_experiment(item)
        path = netlist_path(exp)
        text = netlist_text(exp)
        current = path.read_text() if path.exists() else None
        if check:
            if current != text:
                out.append(path)
            continue
        path.parent.mkdir(exist_ok=True)
        if current != text:
            _write_atomic(path, text)
        out.append(path)
    return out
