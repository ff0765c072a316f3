"""Standard circuits and experiments, defined in ``circuits/*.toml``.

Schema (every table and key optional unless marked; unknown keys are errors)::

    name = "stick"                 # required, ^[A-Za-z][A-Za-z0-9_]{0,31}$, the file's stem
    description = "..."            # free text (never reaches a deck)

    [model]                        # analogue.Model; tau_m, delta, a, gamma required
    tau_m = 1.0
    delta = 0.7
    a = 0.2
    gamma = 10.0
    mass = 1.0

    [circuit]                      # analogue.circuit.CircuitSpec fields
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
"""
from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..model import Model
from . import validation as val
from .mapping import CircuitMapping, CircuitSpec, map_model
from .netlist import Deck, build_deck

__all__ = ["Experiment", "load_experiment", "regenerate_netlists", "experiment_names",
           "CIRCUITS_DIR", "NETLISTS_DIR"]

REPO_ROOT = Path(__file__).resolve().parents[2]
CIRCUITS_DIR = REPO_ROOT / "circuits"
NETLISTS_DIR = REPO_ROOT / "netlists"

_TOP_KEYS = {"name", "description", "model", "circuit", "experiment", "netlist", "report"}
# [report] is read by analogue.report.plan (what the report measures; never reaches a deck).
_MODEL_KEYS = {"tau_m", "delta", "a", "gamma", "mass", "epsilon",
               "cubic", "stribeck", "spring", "x0", "shot"}  # (the last five: issue 9)
_MODEL_REQUIRED = {"tau_m", "delta", "a", "gamma"}
_EXPERIMENT_KEYS = {"v0", "replicas", "t_end", "sample_dt", "seed", "burn_in",
                    "histogram_times", "work_taus"}
_EXPERIMENT_REQUIRED = {"v0", "t_end", "sample_dt"}
_NETLIST_KEYS = {"replicas"}


@dataclass(frozen=True)
class Experiment:
    """One standard experiment: the model, the circuit choice and what to measure."""

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

    def mapping(self) -> CircuitMapping:
        return map_model(self.model, self.spec)

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

    def representative_deck(self) -> Deck:
        """The small deck committed as ``netlists/<name>.cir``."""
        return self.deck(replicas=self.netlist_replicas)


def _table(data, key: str, allowed: set, where: str) -> dict:
    section = data.get(key, {})
    if not isinstance(section, dict):
        raise ValueError(f"{where}: [{key}] must be a table")
    unknown = sorted(set(section) - allowed)
    if unknown:
        raise ValueError(f"{where}: unknown key {key}.{unknown[0]} (allowed: {', '.join(sorted(allowed))})")
    return section


def _require(section: dict, required: set, prefix: str, where: str) -> None:
    missing = sorted(required - set(section))
    if missing:
        raise ValueError(f"{where}: missing required key {prefix}.{missing[0]}")


def _int(value, what: str, lo: int, hi: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
        raise ValueError(f"{what} must be an integer in [{lo}, {hi}], got {value!r}")
    return value


def _floats(value, what: str, allow_empty: bool = True) -> tuple:
    if not isinstance(value, list) or (not allow_empty and not value):
        raise ValueError(f"{what} must be a {'non-empty ' if not allow_empty else ''}list of numbers")
    return tuple(val.finite(x, f"{what}[{i}]") for i, x in enumerate(value))


def experiment_from_dict(data: dict, where: str = "experiment", source: Path | None = None) -> Experiment:
    """Validate a parsed TOML document (see the module docstring for the schema)."""
    if not isinstance(data, dict):
        raise ValueError(f"{where}: the document must be a table")
    unknown = sorted(set(data) - _TOP_KEYS)
    if unknown:
        raise ValueError(f"{where}: unknown key {unknown[0]} (allowed: {', '.join(sorted(_TOP_KEYS))})")
    if "name" not in data:
        raise ValueError(f"{where}: missing required key name")
    name = val.check_name(data["name"], f"{where}: name")
    description = data.get("description", "")
    if not isinstance(description, str):
        raise ValueError(f"{where}: description must be a string")

    mdata = _table(data, "model", _MODEL_KEYS, where)
    _require(mdata, _MODEL_REQUIRED, "model", where)
    mdata = dict(mdata)
    for key, value in mdata.items():
        if key == "gamma" and value == float("inf"):
            continue  # gamma = inf: no Gaussian noise (shot noise alone)
        if key not in ("stribeck", "shot"):
            val.finite(value, f"{where}: model.{key}")
    if "stribeck" in mdata:  # [delta_s, v_s]
        st = mdata["stribeck"]
        if not isinstance(st, list) or len(st) != 2:
            raise ValueError(f"{where}: model.stribeck must be a list [delta_s, v_s]")
        mdata["stribeck"] = tuple(val.finite(x, f"{where}: model.stribeck[{i}]") for i, x in enumerate(st))
    if "shot" in mdata:  # [model.shot] rate, mean, two_sided
        from ..model import ShotNoise
        sh = mdata["shot"]
        if not isinstance(sh, dict) or not {"rate", "mean"} <= set(sh) <= {"rate", "mean", "two_sided"}:
            raise ValueError(f"{where}: [model.shot] must be a table with rate, mean and optional two_sided")
        mdata["shot"] = ShotNoise(**sh)
    model = Model(**mdata)

    cdata = _table(data, "circuit", set(CircuitSpec.__dataclass_fields__), where)
    spec = CircuitSpec(**cdata)

    edata = _table(data, "experiment", _EXPERIMENT_KEYS, where)
    _require(edata, _EXPERIMENT_REQUIRED, "experiment", where)
    v0 = _floats(edata["v0"], f"{where}: experiment.v0", allow_empty=False)
    replicas = _int(edata.get("replicas", 100), f"{where}: experiment.replicas", 1, 100_000)
    t_end = val.positive(edata["t_end"], f"{where}: experiment.t_end")
    sample_dt = val.positive(edata["sample_dt"], f"{where}: experiment.sample_dt")
    if sample_dt > t_end:
        raise ValueError(f"{where}: experiment.sample_dt must be <= t_end={t_end}, got {sample_dt}")
    seed = _int(edata.get("seed", 1), f"{where}: experiment.seed", 0, 2**31 - 1)
    burn_in = val.nonnegative(edata.get("burn_in", 0.0), f"{where}: experiment.burn_in")
    if burn_in >= t_end:
        raise ValueError(f"{where}: experiment.burn_in must be < t_end={t_end}, got {burn_in}")
    times = _floats(edata.get("histogram_times", []), f"{where}: experiment.histogram_times")
    for t in times:
        if not 0 < t <= t_end:
            raise ValueError(f"{where}: experiment.histogram_times must lie in (0, t_end={t_end}], got {t}")
    taus = _floats(edata.get("work_taus", []), f"{where}: experiment.work_taus")
    for tau in taus:
        if not 0 < tau <= t_end - burn_in:
            raise ValueError(f"{where}: experiment.work_taus must lie in (0, t_end - burn_in="
                             f"{t_end - burn_in}], got {tau}")

    ndata = _table(data, "netlist", _NETLIST_KEYS, where)
    netlist_replicas = _int(ndata.get("replicas", 4), f"{where}: netlist.replicas", 1, 64)

    exp = Experiment(name=name, description=description, model=model, spec=spec, v0=v0,
                     replicas=replicas, t_end=t_end, sample_dt=sample_dt, seed=seed,
                     burn_in=burn_in, histogram_times=times, work_taus=taus,
                     netlist_replicas=netlist_replicas, source=source)
    exp.mapping()  # refuse experiments the circuit cannot do (ratings, bias) at load time
    return exp


def experiment_names() -> list[str]:
    """Names of the experiments in ``circuits/``, sorted."""
    return sorted(p.stem for p in CIRCUITS_DIR.glob("*.toml"))


def load_experiment(path_or_name) -> Experiment:
    """Load ``circuits/<name>.toml`` (given a bare name) or a TOML file path."""
    if isinstance(path_or_name, Path):
        path = path_or_name
    elif isinstance(path_or_name, str):
        if val.NAME_PATTERN.fullmatch(path_or_name):
            path = CIRCUITS_DIR / f"{path_or_name}.toml"
            if not path.exists():
                raise ValueError(f"experiment name must be one of {experiment_names()}, "
                                 f"got {path_or_name!r}")
        else:
            path = Path(path_or_name)
    else:
        raise ValueError(f"path_or_name must be a path or an experiment name, got {path_or_name!r}")
    if not path.is_file():
        raise ValueError(f"no experiment file at {path}")
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: not valid TOML: {exc}") from None
    exp = experiment_from_dict(data, where=str(path), source=path)
    if path.parent.resolve() == CIRCUITS_DIR.resolve() and exp.name != path.stem:
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
            path.write_text(text)
        out.append(path)
    return out
