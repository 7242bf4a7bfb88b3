"""The ``--seeds START:STOP`` argument of the evaluation and benchmark tools."""

from __future__ import annotations

import argparse


def seed_range(text: str, below: int | None = None) -> range:
    """Generator seeds START..STOP-1 from ``"START:STOP"`` (0 <= START < STOP, and
    STOP <= ``below`` when given), for argparse's ``type=``.

    Raises:
        argparse.ArgumentTypeError: ``text`` is not such a range (argparse then exits 2
            with the message).
    """
    try:
        lo, hi = (int(x) for x in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected START:STOP (integers) like 1000:1030, got {text!r}"
        ) from None
    if not 0 <= lo < hi:
        raise argparse.ArgumentTypeError(f"need 0 <= START < STOP, got {text!r}")
    if below is not None and hi > below:
        raise argparse.ArgumentTypeError(f"STOP must be <= {below:,}, got {text!r}")
    return range(lo, hi)


def evaluation_seeds(text: str) -> range:
    """:func:`seed_range` below 10,000: the generated cabinets the evaluations use."""
    return seed_range(text, below=10_000)


def training_seeds(text: str) -> range:
    """:func:`seed_range` at or above
    :data:`~strug_manip.world.perception_data.TRAIN_SEED_START`: the generated cabinets
    of the training split."""
    from strug_manip.world.perception_data import TRAIN_SEED_START

    seeds = seed_range(text)
    if seeds.start < TRAIN_SEED_START:
        raise argparse.ArgumentTypeError(
            f"training seeds start at {TRAIN_SEED_START:,}, got {text!r}"
        )
    return seeds
