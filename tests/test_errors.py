"""Error helpers: located messages, quoted user values."""

from __future__ import annotations

import pytest

from asbuilt.errors import QUOTE_LIMIT, located, quoted


def test_located_leaves_out_unknown_parts():
    assert located("a.csv", None, "bad") == "a.csv: bad"


@pytest.mark.parametrize(
    "value, shown",
    [
        ("4x", "'4x'"),
        ("", "''"),
        ("a" * QUOTE_LIMIT, repr("a" * QUOTE_LIMIT)),
        ("9" * 5000, "'" + "9" * QUOTE_LIMIT + "...' (5,000 characters)"),
        ("it's" + "x" * 60, "\"it's" + "x" * (QUOTE_LIMIT - 4) + '..." (64 characters)'),
        (12345, "'12345'"),
    ],
    ids=["short", "empty", "at-the-limit", "5000-digits", "quote-inside", "not-a-string"],
)
def test_quoted_shortens_long_values_with_their_length(value, shown):
    assert quoted(value) == shown


def test_quoted_takes_a_limit():
    assert quoted("abcdefgh", limit=3) == "'abc...' (8 characters)"
