"""The ``--seeds START:STOP`` argument of the evaluation and benchmark tools, and their
resumable runs over it (:func:`rows_per_seed`)."""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

from tqdm import tqdm

from strug_manip.experiments.records import read_jsonl


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


def rows_per_seed(
    seeds: range,
    evaluate: Callable[[int], dict[str, Any]],
    out: Path | None = None,
    desc: str = "seeds",
) -> list[dict[str, Any]]:
    """``evaluate(seed)`` for every seed of ``seeds``, in order, with a progress bar;
    each row (a JSON-able dict with its ``seed``) is appended to ``out/results.jsonl``
    as it is made, and a rerun with the same ``out`` reads the seeds already there
    instead of evaluating them again (the tools' resumable runs)."""
    done: dict[int, dict[str, Any]] = {}
    path = None
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        path = out / "results.jsonl"
        done = {r["seed"]: r for r in read_jsonl(path)}
    rows = []
    for seed in tqdm(seeds, desc=desc, unit="seed"):
        if seed in done:
            rows.append(done[seed])
            continue
        row = evaluate(seed)
        rows.append(row)
        if path is not None:
            with path.open("a") as f:
                f.write(json.dumps(row) + "\n")
    return rows


def seed_tool(
    argv: list[str] | None,
    description: str,
    evaluate: Callable[[int], dict[str, Any]],
    table: Callable[[list[dict[str, Any]]], str],
    title: str,
) -> int:
    """A per-seed evaluation tool's command line: ``--seeds A:B`` (generator seeds),
    ``--out DIR`` (resumable, :func:`rows_per_seed`), ``--json`` (print the rows);
    else ``title`` with the seeds and ``table(rows)``. Returns the exit status (0)."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--seeds", type=seed_range, required=True, help="A:B, generator seeds")
    ap.add_argument("--out", type=Path, default=None, help="results folder (resumable)")
    ap.add_argument("--json", action="store_true", help="print the rows as JSON")
    args = ap.parse_args(argv)
    rows = rows_per_seed(args.seeds, evaluate, args.out, ap.prog)
    if args.json:
        print(json.dumps(rows))
    else:
        print(f"{title}, seeds {args.seeds.start}:{args.seeds.stop}")
        print(table(rows))
    return 0
