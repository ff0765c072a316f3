"""The package's structure, measured from its source (issue 20, "must show"): ``python
scripts/structure.py`` prints

* per file, the branches on model features: ``if``/``elif``/``while`` statements, ternaries
  (``a if t else b``) and comprehension filters whose test reads one of :data:`FEATURES` (as
  an attribute, ``model.spring``, or a name, ``spring``) -- outside the variants' own modules
  (:data:`OWN`), which are where such a difference is meant to live;
* the import circles and the imports that run back up a layer (the graph and the layers of
  ``tests/unit/test_import_layers.py``, read with :mod:`ast`, nothing imported), module level
  and, separately, the own imports made inside functions (and the lazy exports of a package's
  ``__init__``, which the layering test exempts);
* the longest functions (lines from ``def`` to the last line of the body).

``--json`` prints the same as one JSON object (for a closing note or a comparison).
"""
from __future__ import annotations

import argparse
import ast
import importlib.util
import json
import sys
from collections import Counter
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
PKG_DIR = REPO / "analogue"

#: The model features whose tests the issue counts (126 in 21 files when it was filed).
FEATURES = frozenset({"spring", "shot", "cubic", "stribeck", "is_paper", "is_gradient"})
#: Where a variant's own difference lives: branches there are the variant's, not a test on it.
OWN = ("analogue/variants/",)


def _layers():
    """tests/unit/test_import_layers.py, loaded by path (tests/ is no package)."""
    path = REPO / "tests" / "unit" / "test_import_layers.py"
    spec = importlib.util.spec_from_file_location("_import_layers", path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.path.insert(0, str(REPO))  # it imports analogue (for its path): this checkout's
    spec.loader.exec_module(mod)
    return mod


def _reads_feature(test: ast.AST) -> bool:
    for n in ast.walk(test):
        if isinstance(n, ast.Attribute) and n.attr in FEATURES:
            return True
        if isinstance(n, ast.Name) and n.id in FEATURES:
            return True
    return False


def feature_branches(path: Path) -> list[int]:
    """Line numbers of the branches on :data:`FEATURES` in one file."""
    tree = ast.parse(path.read_text(), filename=str(path))
    lines = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.If, ast.IfExp, ast.While)):
            if _reads_feature(node.test):
                lines.append(node.lineno)
        elif isinstance(node, ast.comprehension):
            lines.extend(c.lineno for c in node.ifs if _reads_feature(c))
    return sorted(lines)


def branch_table() -> dict[str, int]:
    out = {}
    for path in sorted(PKG_DIR.rglob("*.py")):
        rel = path.relative_to(REPO).as_posix()
        if rel.startswith(OWN):
            continue
        n = len(feature_branches(path))
        if n:
            out[rel] = n
    return out


def longest_functions(top: int = 10) -> list[tuple[str, int]]:
    found = []
    for path in sorted(PKG_DIR.rglob("*.py")):
        rel = path.relative_to(REPO).as_posix()
        tree = ast.parse(path.read_text(), filename=str(path))
        stack: list[tuple[ast.AST, str]] = [(tree, "")]
        while stack:
            node, prefix = stack.pop()
            for child in ast.iter_child_nodes(node):
                if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                    name = f"{prefix}{child.name}"
                    if not isinstance(child, ast.ClassDef):
                        end = child.end_lineno or child.lineno
                        found.append((f"{rel}:{name}", end - child.lineno + 1))
                    stack.append((child, name + "."))
                else:
                    stack.append((child, prefix))
    return sorted(found, key=lambda f: (-f[1], f[0]))[:top]


def import_structure() -> dict:
    layers = _layers()
    edges, in_functions = layers.import_graph()
    lay = layers.layer_of
    cycles = layers._cycles(edges)
    full = {m: set(ts) for m, ts in edges.items()}
    for m, t, _ in in_functions:
        full[m].add(t)
    back = sorted(f"{m} -> {t}" for m, ts in edges.items() for t in ts
                  if lay(m) is not None and lay(t) is not None and lay(t) > lay(m))
    back_fn = sorted(f"{m}:{line} -> {t}" for m, t, line in in_functions
                     if lay(m) is not None and lay(t) is not None and lay(t) > lay(m))
    outside_cli = [f for f in in_functions if f[0] != "analogue.cli"]
    return {"circles": cycles, "circles_with_function_imports": layers._cycles(full),
            "back_arrows": back, "back_arrows_in_functions": back_fn,
            "function_level_own_imports": len(in_functions),
            "function_level_own_imports_outside_cli": len(outside_cli),
            "lazy_exports": [f"{m}.{fn} -> {t}" for m, t, fn, _ in layers.lazy_exports()]}


def measure() -> dict:
    table = branch_table()
    return {"feature_branches": table, "feature_branches_total": sum(table.values()),
            "feature_branch_files": len(table), **import_structure(),
            "longest_functions": longest_functions()}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--json", action="store_true", help="print one JSON object")
    args = p.parse_args(argv)
    m = measure()
    if args.json:
        print(json.dumps(m, indent=1))
        return 0
    print(f"Branches on model features {sorted(FEATURES)} outside {OWN}:")
    width = max((len(f) for f in m["feature_branches"]), default=10)
    for f, n in sorted(m["feature_branches"].items(), key=lambda kv: (-kv[1], kv[0])):
        print(f"  {f:<{width}}  {n:4d}")
    print(f"  {'total':<{width}}  {m['feature_branches_total']:4d}  in "
          f"{m['feature_branch_files']} files")
    print(f"\nImport circles (module level): {len(m['circles'])}")
    for c in m["circles"]:
        print("  " + " <-> ".join(c))
    print(f"Import circles counting imports inside functions: "
          f"{len(m['circles_with_function_imports'])}")
    for c in m["circles_with_function_imports"]:
        print("  " + " <-> ".join(c))
    print(f"Back-arrows (module level): {len(m['back_arrows'])}")
    for b in m["back_arrows"]:
        print("  " + b)
    print(f"Back-arrows inside functions: {len(m['back_arrows_in_functions'])}")
    for b in m["back_arrows_in_functions"]:
        print("  " + b)
    print(f"Own imports inside functions: {m['function_level_own_imports']} "
          f"({m['function_level_own_imports_outside_cli']} outside cli.py)")
    print(f"Lazy exports (a package's __init__ loading its children on first use, exempt): "
          f"{len(m['lazy_exports'])}")
    for e in m["lazy_exports"]:
        print("  " + e)
    print("\nLongest functions (lines):")
    for name, n in m["longest_functions"]:
        print(f"  {n:4d}  {name}")
    counts: Counter[str] = Counter()
    for f, n in m["feature_branches"].items():
        counts[f.split("/")[1]] += n
    print("\nFeature branches by package: "
          + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
    return 0


if __name__ == "__main__":
    sys.exit(main())
