"""analogue.checks: one argument order (name, value), keywords, strict types, messages that
name the parameter and the allowed range."""
import math

import numpy as np
import pytest

from analogue import checks
from analogue.checks import ArgumentTypeError


def test_name_first_and_keywords_give_the_same_result():
    assert checks.positive("t_end", 2) == checks.positive(name="t_end", value=2) == 2.0
    assert checks.identifier(name="prefix", value="Xa_1") == "Xa_1"
    assert checks.integer(name="n", value=np.int64(3), minimum=1) == 3
    assert checks.spice_number(name="R", value=1e3) == "1000"


@pytest.mark.parametrize("check", [checks.real, checks.finite, checks.positive, checks.nonnegative,
                                   checks.spice_number])
@pytest.mark.parametrize("bad", [True, np.bool_(False), "1.0", b"1", None, [1.0, 2.0], object()])
def test_numbers_refuse_non_numbers_with_a_type_error_naming_the_parameter(check, bad):
    with pytest.raises(TypeError, match=r"^speed must be a real number, got ") as exc:
        check("speed", bad)
    assert isinstance(exc.value, ArgumentTypeError) and isinstance(exc.value, ValueError)


@pytest.mark.parametrize("value", [3, 3.0, np.float32(3.0), np.int8(3), np.asarray(3.0)])
def test_numbers_accept_numeric_types(value):
    x = checks.positive("speed", value)
    assert type(x) is float and x == 3.0


@pytest.mark.parametrize("check, value, message", [
    (checks.finite, math.nan, "x must be finite, got nan"),
    (checks.finite, math.inf, "x must be finite, got inf"),
    (checks.finite, 10**400, "x must be finite, got inf"),
    (checks.positive, 0.0, "x must be > 0, got 0.0"),
    (checks.positive, -math.inf, "x must be finite, got -inf"),
    (checks.nonnegative, -1e-300, "x must be >= 0, got -1e-300"),
])
def test_value_errors_name_the_parameter_and_the_range(check, value, message):
    with pytest.raises(ValueError) as exc:
        check("x", value)
    assert str(exc.value) == message and not isinstance(exc.value, TypeError)


def test_allow_inf_admits_plus_infinity_only():
    assert checks.positive("gamma", math.inf, allow_inf=True) == math.inf
    assert checks.real("gamma", math.inf, allow_inf=True) == math.inf
    for bad in (-math.inf, math.nan):
        with pytest.raises(ValueError, match="gamma must be finite"):
            checks.positive("gamma", bad, allow_inf=True)


def test_in_range_is_closed_and_says_why():
    assert checks.in_range("c", 1e-15, 1e-15, 1e3) == 1e-15
    assert checks.in_range("c", 1e3, 1e-15, 1e3) == 1e3
    with pytest.raises(ValueError, match=r"^c must be in \[1e-15, 1000\], got 1001.0 \(too big\)$"):
        checks.in_range("c", 1001, 1e-15, 1e3, why="too big")


def test_in_range_open_interval():
    assert checks.in_range("confidence", 0.95, 0, 1, closed=False) == 0.95
    for bad in (0, 1, 1.5):
        with pytest.raises(ValueError, match=r"^confidence must be in \(0, 1\), got "):
            checks.in_range("confidence", bad, 0, 1, closed=False)


def test_instance_names_the_parameter_and_the_type():
    from analogue import Model
    m = Model(1.0, 0.5, 0.2, 10.0)
    assert checks.instance("model", m, Model, description="an analogue.Model") is m
    with pytest.raises(TypeError, match=r"^model must be an analogue.Model, got dict$") as exc:
        checks.instance("model", {"tau_m": 1.0}, Model, description="an analogue.Model")
    assert isinstance(exc.value, ValueError)


@pytest.mark.parametrize("value, kwargs, error, message", [
    (2.0, dict(minimum=1), TypeError, "n must be an integer >= 1, got 2.0"),
    (True, dict(minimum=0), TypeError, "n must be an integer >= 0, got True"),
    ("3", {}, TypeError, "n must be an integer, got '3'"),
    (0, dict(minimum=1), ValueError, "n must be an integer >= 1, got 0"),
    (17, dict(minimum=1, maximum=16), ValueError, "n must be an integer in [1, 16], got 17"),
    (-1, dict(maximum=5, minimum=0), ValueError, "n must be an integer in [0, 5], got -1"),
    (6, dict(maximum=5), ValueError, "n must be an integer <= 5, got 6"),
])
def test_integer_messages(value, kwargs, error, message):
    with pytest.raises(error) as exc:
        checks.integer("n", value, **kwargs)
    assert str(exc.value) == message


def test_flags_refuse_numbers_and_none_unless_none_means_something():
    assert checks.flag("x", np.bool_(True)) is True and checks.flag("x", False) is False
    assert checks.optional_flag("progress", None, none_means="auto") is None
    assert checks.optional_flag("progress", True, none_means="auto") is True
    for bad in (0, 1, None, "yes"):
        with pytest.raises(TypeError, match=r"^x must be True or False, got "):
            checks.flag("x", bad)
    with pytest.raises(TypeError, match=r"^progress must be True, False or None \(auto\), got 1$"):
        checks.optional_flag("progress", 1, none_means="auto")


@pytest.mark.parametrize("bad", ["", "1abc", "a b", "a;rm", "x" * 33, "é", "a\n.control", None, 3])
def test_identifier_refuses_anything_but_a_safe_spice_name(bad):
    with pytest.raises(ValueError, match=r"^node must match \^\[A-Za-z\]"):
        checks.identifier("node", bad)
    assert checks.identifier("node", "x" * 32) == "x" * 32


def test_spice_number_round_trips_and_never_copies_text():
    for x in (1.0, -2.5e-13, 1 / 3, 6.02214076e23, 0.0, -0.0):
        text = checks.spice_number("v", x)
        assert float(text) == x or abs(float(text) - x) <= 1e-15 * abs(x)
        assert set(text) <= set("0123456789.e+-")
    assert checks.spice_number("v", 0.0) == "0"


def test_finite_array():
    np.testing.assert_array_equal(checks.finite_array("w", [1, 2.5]), [1.0, 2.5])
    with pytest.raises(ValueError, match="^w must be finite$"):
        checks.finite_array("w", [1.0, math.nan])
    with pytest.raises(ValueError, match="^w must be real numbers"):
        checks.finite_array("w", ["a"])


def test_every_public_check_takes_name_then_value():
    import inspect
    for fname in checks.__all__:
        f = getattr(checks, fname)
        if inspect.isfunction(f):
            params = list(inspect.signature(f).parameters.values())
            assert [p.name for p in params[:2]] == ["name", "value"], fname
            positional = ("low", "high", "kind")  # in_range's interval, instance's type
            assert all(p.kind is p.KEYWORD_ONLY for p in params[2:] if p.name not in positional), fname
