"""Lines of JSON records that long runs append as they go, read back to resume."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from planners.errors import ConfigError


def read_jsonl(path: Path) -> list[Any]:
    """The records of ``path``, one JSON value per line ([] if it does not exist); a
    torn last line (a run killed mid-write) is dropped.

    Raises:
        ConfigError: a line before the last is not JSON.
    """
    if not path.exists():
        return []
    records, lines = [], path.read_text().splitlines()
    for i, line in enumerate(lines):
        try:
            records.append(json.loads(line))
        except json.JSONDecodeError:
            if i == len(lines) - 1:
                break  # killed mid-write: that record simply did not finish
            raise ConfigError(f"{path}: line {i + 1} is not JSON; the file is corrupt") from None
    return records
