"""The package's structure, measured from its own source (issue 20, "must show"): no import
circles among the modules of ``analogue/`` and no import from a lower layer up to a higher one.

The graph is read with :mod:`ast` (nothing is imported): every ``import``/``from ... import`` of
the package's own modules, at module level (including under ``if TYPE_CHECKING:``, which a type
checker follows like any import) and inside functions.  An import names the most specific own
module it reaches (``from .. import checks`` reaches ``analogue.checks``, not the package).  A
package's ``__init__`` importing its own children is its table of contents, not a circle, and
the top-level ``analogue/__init__.py`` (the public names, loaded lazily) stands above every layer.

Layers, lowest first (:data:`LAYERS`): physics (the model, its theory, the estimators) below the
circuit and the Monte Carlo that produce ensembles, below the study layer (the experiment, its
settings, what it compares), below what is made for people (report pages, plots, the board,
exports), below the CLI.  Imports within a layer may go either way as long as they form no circle.

Imports made inside functions may close no circle either, and outside ``cli.py`` (start-up
time: ``analogue --help`` loads no command's modules) there are none: a heavy third-party
dependency (scipy, matplotlib, xarray, PySpice) may still be imported inside a function, the
package's own modules are imported at module level.  The one exemption is the lazy export of a
package's ``__init__`` (its table of contents, loaded on first use): the imports of its own
children inside ``__getattr__`` or ``__call__`` (``analogue.simulate``, ``analogue.report(...)``;
:func:`lazy_exports` lists them, and a test holds them to those two functions).  A lazy export
by ``importlib.import_module`` (``analogue.circuit``) is a child of the package too.
"""
from __future__ import annotations

import ast
from pathlib import Path

import analogue

ROOT = Path(analogue.__file__).resolve().parent
PKG = ROOT.name

# Lowest first.  A module belongs to the layer of the longest prefix listed for it.
LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("foundations", ("checks", "cores", "files", "paper", "noise_free", "netcdf_layout")),
    ("model", ("model", "ensemble", "variants")),
    ("theory", ("theory",)),
    ("estimators", ("estimators",)),
    ("runs", ("montecarlo", "circuit", "data")),
    # study/experiments.py is the experiment itself (a TOML file -> model, circuit, report
    # settings); ``analogue.circuit.experiments`` is an alias of it (circuit/__init__)
    ("study", ("study",)),
    ("pages", ("report", "plots", "board", "export")),
    ("cli", ("cli",)),
)


# own-package imports made inside functions outside cli.py: 105 when issue 20's study layer
# began, 44 after it, 0 since (each moved to module level; none closed a circle or ran up a
# layer except circuit.schematic's main(), which read an experiment: now `analogue schematic`).
IN_FUNCTION_CEILING = 0
# the functions of a package's __init__ that may import its children: its lazy exports
LAZY_LOADERS = ("__getattr__", "__call__")


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in sorted(ROOT.rglob("*.py"))}


def _owner(name: str, modules: dict[str, Path]) -> str | None:
    """The most specific own module that ``name`` (a dotted path) reaches."""
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name or None


def _base(module: str, node: ast.ImportFrom, is_package: bool) -> str:
    if node.level == 0:
        return node.module or ""
    bits = module.split(".")
    if not is_package:
        bits = bits[:-1]
    bits = bits[: len(bits) - (node.level - 1)]
    return ".".join(bits + ([node.module] if node.module else []))


def import_graph() -> tuple[dict[str, set[str]], list[tuple[str, str, int]]]:
    """(module-level edges, function-level own imports as (module, target, line))."""
    modules = _modules()
    edges: dict[str, set[str]] = {m: set() for m in modules}
    in_functions: list[tuple[str, str, int]] = []
    for module, path in modules.items():
        tree = ast.parse(path.read_text(), filename=str(path))
        inside = set()
        for f in ast.walk(tree):
            if isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
                inside.update(id(n) for n in ast.walk(f) if n is not f)
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                base = _base(module, node, path.name == "__init__.py")
                # an imported name that is a module reaches it; any other name, its base
                names = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base
                         for a in node.names]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            else:
                continue
            targets = {_owner(n, modules) for n in names if n.split(".")[0] == PKG}
            for t in sorted(targets - {None, module}):
                assert t is not None
                if t.startswith(module + "."):
                    continue  # a package's __init__ and its own children: the table of contents
                if id(node) in inside:
                    in_functions.append((module, t, node.lineno))
                else:
                    edges[module].add(t)
    return edges, in_functions


def layer_of(module: str) -> int | None:
    """Index into :data:`LAYERS` (None: the top-level package, above every layer)."""
    if module == PKG:
        return None
    rest = module[len(PKG) + 1:]
    best, best_len = None, -1
    for i, (_, prefixes) in enumerate(LAYERS):
        for p in prefixes:
            if (rest == p or rest.startswith(p + ".")) and len(p) > best_len:
                best, best_len = i, len(p)
    if best is None:
        raise AssertionError(f"{module} is in no layer: add it to LAYERS in {__file__}")
    return best


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = 0
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on.add(root)
        while work:
            v, children = work[-1]
            advanced = False
            for w in children:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(graph.get(w, ())))))
                    advanced = True
                    break
                if w in on:
                    low[v] = min(low[v], index[w])
            if advanced:
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    out.append(sorted(comp))
    return sorted(out)


def _function_level_note(in_functions: list[tuple[str, str, int]]) -> str:
    outside_cli = [f for f in in_functions if f[0] != f"{PKG}.cli"]
    up = [f"{m}:{line} -> {t}" for m, t, line in outside_cli
          if layer_of(m) is not None and (layer_of(t) or 0) > (layer_of(m) or 0)]
    return (f"(function-level own imports outside cli.py: {len(outside_cli)}; of them "
            f"{len(up)} reach a higher layer: {up})")


def test_the_graph_sees_the_package():
    # the measurement is only worth something if it reads every module and real imports
    edges, in_functions = import_graph()
    assert len(edges) > 50 and f"{PKG}.model" in edges and f"{PKG}.cli" in edges
    assert f"{PKG}.model" in edges[f"{PKG}.theory.stationary"]
    assert f"{PKG}.checks" in edges[f"{PKG}.model"]  # "from . import checks" reaches the module


def test_the_cycle_finder_finds_cycles():
    g = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": {"e2"}, "e2": set()}
    assert _cycles(g) == [["a", "b", "c"]]


def test_no_import_circles():
    edges, in_functions = import_graph()
    cycles = _cycles(edges)
    detail = [[f"{m} -> {t}" for m in c for t in sorted(edges[m]) if t in c] for c in cycles]
    assert not cycles, (f"module-level import circles: {detail} "
                        f"{_function_level_note(in_functions)}")


def test_no_import_circles_hidden_in_functions():
    """An import inside a function only postpones a circle to the first call: counted with
    the module-level ones there is none either (the circles issue 20 found were all closed
    that way)."""
    edges, in_functions = import_graph()
    full = {m: set(ts) for m, ts in edges.items()}
    for m, t, _ in in_functions:
        full[m].add(t)
    cycles = _cycles(full)
    detail = [[f"{m}:{line} -> {t}" for m, t, line in in_functions if m in c and t in c]
              for c in cycles]
    assert not cycles, f"import circles closed inside functions: {cycles}, through {detail}"


def test_every_module_has_a_layer():
    for module in _modules():
        layer_of(module)


def test_no_import_runs_up_a_layer():
    edges, in_functions = import_graph()
    back = sorted(f"{m} ({LAYERS[layer_of(m)][0]}) -> {t} ({LAYERS[layer_of(t)][0]})"  # type: ignore[index]
                  for m, ts in edges.items() for t in ts
                  if layer_of(m) is not None and layer_of(t) is not None
                  and layer_of(t) > layer_of(m))  # type: ignore[operator]
    assert not back, (f"{len(back)} module-level imports from a lower layer to a higher one: "
                      f"{back} {_function_level_note(in_functions)}")


def _in_functions_outside_cli() -> list[tuple[str, str, int]]:
    _, in_functions = import_graph()
    return [f for f in in_functions if f[0] != f"{PKG}.cli"]


def lazy_exports() -> list[tuple[str, str, str, int]]:
    """(package, child, function, line) for each import of a package's own child made inside a
    function of its ``__init__`` (which :func:`import_graph` leaves out as the table of
    contents)."""
    modules = _modules()
    found = []
    for module, path in modules.items():
        if path.name != "__init__.py":
            continue
        tree = ast.parse(path.read_text(), filename=str(path))
        for f in ast.walk(tree):
            if not isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            for node in ast.walk(f):
                if isinstance(node, ast.ImportFrom):
                    base = _base(module, node, True)
                    names = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base
                             for a in node.names]
                elif isinstance(node, ast.Import):
                    names = [a.name for a in node.names]
                else:
                    continue
                for n in names:
                    t = _owner(n, modules) if n.split(".")[0] == PKG else None
                    if t is not None and t.startswith(module + "."):
                        found.append((module, t, f.name, node.lineno))
    return sorted(set(found))


def test_the_in_function_count_sees_imports_inside_functions():
    # the count is only worth something if it finds them: cli.py keeps its own (start-up)
    _, in_functions = import_graph()
    assert any(m == f"{PKG}.cli" for m, _, _ in in_functions)


def test_no_own_imports_inside_functions_outside_the_cli():
    found = _in_functions_outside_cli()
    assert len(found) <= IN_FUNCTION_CEILING, (
        f"{len(found)} own imports inside functions outside cli.py (allowed: "
        f"{IN_FUNCTION_CEILING}; import at module level: a circle it would close, or a layer it "
        f"would run up, is a fault of the design): "
        f"{[f'{m}:{line} -> {t}' for m, t, line in found]}")


def test_lazy_exports_are_only_the_packages_loaders():
    found = lazy_exports()
    # the measurement sees them: analogue.simulate and analogue.report(...) are lazy
    assert (PKG, f"{PKG}.circuit.simulate", "__getattr__") in {f[:3] for f in found}
    assert (f"{PKG}.report", f"{PKG}.report.pipeline", "__call__") in {f[:3] for f in found}
    other = [f"{m}:{line} {fn}() -> {t}" for m, t, fn, line in found if fn not in LAZY_LOADERS]
    assert not other, (f"imports of a package's children inside functions of its __init__ "
                       f"other than its lazy loaders {LAZY_LOADERS}: {other}")
