"""The report's summary names every circuit bias term of at least one statistical error with
its reason (issue 18: the comparisons with every bias term below one SE, or the few that are
not named in the summary with the reason)."""
from __future__ import annotations

from analogue.study.budget import CIRCUIT_BIAS_TERMS, terms_above_se, terms_above_se_text
from analogue.study.metrics import Budget, compare


def _comps():
    return [
        # |z| < 3 but a bandwidth term of 2.5 SE (and a smoothing term of 1.2 SE)
        compare("work", "P(v>0)", 0.709, 0.001, 0.711, "exact",
                Budget(smoothing=-0.0012, bandwidth=0.0025, integration=0.0001)),
        # the same observable against the weak-noise theory: named once
        compare("work", "P(v>0)", 0.709, 0.001, 0.712, "weak-noise",
                Budget(smoothing=-0.0012, bandwidth=0.0025, finite_noise=0.01)),
        # every circuit term below one SE; the finite-noise term is the theory's, not named
        compare("slip", "mean v", 0.5, 0.01, 0.5, "weak-noise",
                Budget(smoothing=0.009, bandwidth=0.005, finite_noise=0.2)),
        # a term of exactly one SE is named (at least one)
        compare("stick", "stick fraction", 0.221, 0.001, 0.2195, "exact", Budget(bandwidth=0.001)),
    ]


def test_terms_of_at_least_one_se_are_named_once_largest_first():
    found = terms_above_se(_comps())
    assert set(found) == {"work", "stick"}
    assert [(o, n) for o, n, _ in found["work"]] == [("P(v>0)", "bandwidth"),
                                                     ("P(v>0)", "smoothing")]
    assert abs(found["work"][0][2] - 2.5) < 1e-9 and abs(found["work"][1][2] - 1.2) < 1e-9
    assert [(o, n) for o, n, _ in found["stick"]] == [("stick fraction", "bandwidth")]


def test_summary_lines_give_the_reason():
    lines = terms_above_se_text(_comps())
    assert lines[0] == ("work: bias terms of at least 1 standard error: P(v>0) (bandwidth "
                        "2.5 SE); P(v>0) (smoothing 1.2 SE).")
    assert lines[-1].startswith("Reasons: bandwidth: " + CIRCUIT_BIAS_TERMS["bandwidth"])
    assert "smoothing: " + CIRCUIT_BIAS_TERMS["smoothing"] in lines[-1]
    assert not any("slip" in line for line in lines)
    assert terms_above_se_text(_comps()[2:3]) == []
