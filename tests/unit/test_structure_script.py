"""scripts/structure.py counts what it says (issue 20's measurement of branches on model
features): a branch on a feature is counted in every form, other branches are not."""
from __future__ import annotations

import importlib.util
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "structure.py"


def _script():
    spec = importlib.util.spec_from_file_location("_structure", SCRIPT)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_feature_branches_counts_every_form(tmp_path):
    src = tmp_path / "m.py"
    src.write_text(
        "def f(model, spring, xs):\n"
        "    if model.shot is None:\n"          # 2: if on an attribute
        "        pass\n"
        "    elif model.is_paper:\n"            # 4: elif
        "        pass\n"
        "    y = 1 if spring else 2\n"          # 6: ternary on a name
        "    z = [x for x in xs if model.cubic]\n"  # 7: comprehension filter
        "    while model.stribeck:\n"           # 8: while
        "        break\n"
        "    if model.tau_m > 0 and xs:\n"      # 10: no feature: not counted
        "        pass\n"
        "    return model.spring + y + len(z)\n")  # 12: a use, not a branch
    assert _script().feature_branches(src) == [2, 4, 6, 7, 8]


def test_measure_reads_the_package():
    m = _script().measure()
    assert m["feature_branches_total"] == sum(m["feature_branches"].values()) > 0
    assert all(not f.startswith("analogue/variants/") for f in m["feature_branches"])
    assert m["longest_functions"] and m["longest_functions"][0][1] >= m["longest_functions"][-1][1]


def test_the_variants_own_modules_stay_free_of_feature_branches():
    """Issue 20: the model, its Monte Carlo and the netlist find what differs between members
    on the variants (analogue.variants).  What is left in model.py is the constructor's
    validation of the parameters, once."""
    import ast

    s = _script()
    root = SCRIPT.parent.parent / "analogue"
    for rel in ("montecarlo.py", "circuit/netlist.py", "theory/weak_noise_family.py"):
        assert s.feature_branches(root / rel) == [], rel
    tree = ast.parse((root / "model.py").read_text())
    model = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "Model")
    post_init = next(n for n in model.body
                     if isinstance(n, ast.FunctionDef) and n.name == "__post_init__")
    lines = range(post_init.lineno, (post_init.end_lineno or 0) + 1)
    assert all(line in lines for line in s.feature_branches(root / "model.py"))
