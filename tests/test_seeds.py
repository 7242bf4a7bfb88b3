"""The tools' ``--seeds START:STOP`` parser."""

from __future__ import annotations

import argparse

import pytest

from strug_manip.experiments.seeds import evaluation_seeds, seed_range


def test_a_range_is_start_to_stop_minus_one() -> None:
    assert seed_range("1000:1030") == range(1000, 1030)
    assert evaluation_seeds("0:1") == range(0, 1)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("1000", "expected START:STOP"),
        ("a:b", "expected START:STOP"),
        ("5:3", "need 0 <= START < STOP"),
        ("-1:3", "need 0 <= START < STOP"),
    ],
)
def test_bad_ranges_name_the_value(text: str, message: str) -> None:
    with pytest.raises(argparse.ArgumentTypeError, match=message) as err:
        seed_range(text)
    assert repr(text) in str(err.value)


def test_evaluation_seeds_stay_below_10000() -> None:
    with pytest.raises(argparse.ArgumentTypeError, match="10,000"):
        evaluation_seeds("9990:10010")
