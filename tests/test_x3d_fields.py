"""X3D field text -> numbers: the bulk converter reads what XML numbers allow
and names the first word it cannot read, as the word-by-word reader did."""

from __future__ import annotations

import numpy as np
import pytest

from shadowgeo.io.x3d.fields import parse


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("1 2 3", [1.0, 2.0, 3.0]),
        ("1,2,3", [1.0, 2.0, 3.0]),  # commas separate as white space does
        ("1, 2 ,3", [1.0, 2.0, 3.0]),
        (" \t1\n2\r\n 3 ", [1.0, 2.0, 3.0]),
        ("1e3 -2.5E-2 +4e+0", [1000.0, -0.025, 4.0]),
        (".5 -.5 5.", [0.5, -0.5, 5.0]),
        ("007 0.0 1e-300", [7.0, 0.0, 1e-300]),
    ],
)
def test_vectors_read_as_written(text, expected):
    assert parse(text, "SFVec3f").tolist() == expected


def test_minus_zero_keeps_its_sign():
    value = parse("-0 0 -0.0", "SFVec3f")
    assert np.signbit(value).tolist() == [True, False, True]


@pytest.mark.parametrize("text", ["", "   ", "\n\t", ",", " , , "])
def test_blank_text_is_no_numbers(text):
    # (np.fromstring alone reads blank text as [-1.0])
    assert parse(text, "MFFloat").shape == (0,)
    assert parse(text, "MFVec3f").shape == (0, 3)
    assert parse(text, "MFInt32").shape == (0,)


@pytest.mark.parametrize(
    ("text", "bad"),
    [
        ("1 abc 3", "abc"),
        ("1 2-3 4", "2-3"),  # no separator between two numbers
        ("1 1.5.5 2", "1.5.5"),
        ("0x10 1 2", "0x10"),  # XML numbers have no hexadecimal
        ("1_000 2 3", "1_000"),  # nor digit groups (which float() accepts)
        ("1 2 1e", "1e"),
        ("1;2;3", "1;2;3"),
    ],
)
def test_a_bad_word_is_named(text, bad):
    with pytest.raises(ValueError, match=rf"^is not numbers \(SFVec3f: '{bad}' is not a number\)$"):
        parse(text, "SFVec3f")


def test_not_finite_and_out_of_range_values():
    with pytest.raises(ValueError, match="not finite"):
        parse("1 nan 2", "SFVec3f")
    with pytest.raises(ValueError, match="not finite"):
        parse("1 2 1e400", "SFVec3f")
    with pytest.raises(ValueError, match=r"the value -1e\+80, outside"):
        parse("1 -1e80 2", "SFVec3f")


def test_integers():
    value = parse("0 1 2 -1, 3 4 5 -1", "MFInt32")
    assert value.dtype == np.int64 and value.tolist() == [0, 1, 2, -1, 3, 4, 5, -1]
    assert parse("1.0 2", "MFInt32").tolist() == [1, 2]  # integral numbers read as before
    assert parse(" 7 ", "SFInt32") == 7
    with pytest.raises(ValueError, match="not an integer"):
        parse("1.5 2", "MFInt32")
    with pytest.raises(ValueError, match="'x' is not a number"):
        parse("1 x", "MFInt32")
    with pytest.raises(ValueError, match="32-bit integer range"):
        parse("1 2147483648", "MFInt32")
    with pytest.raises(ValueError, match="32-bit integer range"):
        parse("99999999999999999999", "MFInt32")  # (numpy saturates it at 2**63 - 1)
    assert parse("-2147483648 2147483647", "MFInt32").tolist() == [-(2**31), 2**31 - 1]
    with pytest.raises(ValueError, match="not an integer"):
        parse("1 2", "SFInt32")


def test_a_long_list_matches_python_float():
    rng = np.random.default_rng(7)
    values = rng.normal(scale=1e3, size=30_000)
    text = " ".join(map(repr, values.tolist()))
    assert np.array_equal(parse(text, "MFVec3f"), values.reshape(-1, 3))
