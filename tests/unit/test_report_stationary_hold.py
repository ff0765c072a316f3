"""``[report] stationary_hold_divisor`` (issue 18 item 7): the stationary runs hold the noise
for the circuit's hold over an integer, validated with the rest of the table."""
from __future__ import annotations

import pytest

from analogue.report.plan import (MAX_HOLD_DIVISOR, ReportSettings, RunOptions,
                                  report_settings_from_dict, stationary_noise_dt)


def test_default_keeps_the_hold_and_quick_keeps_the_divisor():
    assert report_settings_from_dict({}).stationary_hold_divisor == 1
    assert stationary_noise_dt(0.01, ReportSettings()) == 0.01
    s = report_settings_from_dict({"stationary_hold_divisor": 2})
    assert stationary_noise_dt(0.01, s) == 0.005
    assert s.for_options(RunOptions(quick=True)).stationary_hold_divisor == 2


@pytest.mark.parametrize("bad", [0, -1, MAX_HOLD_DIVISOR + 1, 1.5, 2.0, "2", True])
def test_bad_divisor_names_the_key(bad):
    with pytest.raises(ValueError, match=r"report\.stationary_hold_divisor must be an integer "
                                         rf"in \[1, {MAX_HOLD_DIVISOR}\]"):
        report_settings_from_dict({"stationary_hold_divisor": bad}, "stick.toml")
