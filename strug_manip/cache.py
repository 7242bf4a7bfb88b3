"""The project's caches: the one bounded in-memory cache, a dict that keeps its most
recently used entries and counts its hits (the control context's motion planners and
placements, the planning twin's programs, an episode's outcomes, worlds and clouds), and
the one folder of files derived from code or data (collision pieces, textures)."""

from __future__ import annotations

import os
from collections import OrderedDict
from collections.abc import Hashable
from pathlib import Path
from typing import Any

import platformdirs


def cache_root() -> Path:
    """The folder of derived files: ``$STRUG_MANIP_CACHE`` if that variable is set, else
    ``platformdirs.user_cache_dir("strug-manip")``."""
    return Path(os.environ.get("STRUG_MANIP_CACHE") or platformdirs.user_cache_dir("strug-manip"))


class LRU(OrderedDict):
    """A dict that keeps its ``size`` most recently used entries and counts hits.

    Args:
        size: entries kept; the least recently used is dropped beyond it.
    """

    def __init__(self, size: int) -> None:
        super().__init__()
        self.size, self.hits, self.misses = size, 0, 0

    def lookup(self, key: Hashable) -> Any:
        """The value under ``key`` (marked used), or None."""
        v = self.get(key)
        if v is None:
            self.misses += 1
            return None
        self.hits += 1
        self.move_to_end(key)
        return v

    def store(self, key: Hashable, value: Any) -> None:
        """Keep ``value`` under ``key`` as the most recently used entry."""
        self[key] = value
        self.move_to_end(key)
        while len(self) > self.size:
            self.popitem(last=False)

    @property
    def hit_rate(self) -> float:
        """Hits over lookups (0 before any)."""
        n = self.hits + self.misses
        return self.hits / n if n else 0.0
