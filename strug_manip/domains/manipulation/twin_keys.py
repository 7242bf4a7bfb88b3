"""How the real belief update weighs the real key's status against a twin's: the measured
confusion P(real status | twin status) (issue 37, part 4).

A particle's twin is the floating-hand planning twin (:mod:`strug_manip.control`), not
the full Fetch: on the same cabinet, from the same state, the two end a skill with
different statuses in about one run in ten (``docs/skills.md``: 90 % the same status).
The exact-match rule (:data:`.model.MISMATCH`: a different status costs log 0.05,
whatever the two statuses are) treats every disagreement alike. With
``twin_keys="confusion"`` the confusion replaces it in the *real* update only (inside
a search a twin's key is compared with another twin's, where the exact rule is right):
a particle whose twin predicted status ``t`` is weighed by ``P(real status | t)``,
estimated from full-robot/twin pairs on tuning cabinets
(``tools/measure_twin_confusion.py``: the oracle's episodes, where the belief's only
particle is the true cabinet standing as the real one stands, so its twin's key and
the real key come from the same cabinet and the same starting state).

The data (``twin_confusion.json``, shipped in this package) holds the *counts* per
(twin status, real status) and their provenance (git commit, episode seeds, domains,
episodes, pairs). :func:`smoothed` turns them into probabilities:

* **toward the exact-match rule**: each row gets :attr:`TwinConfusion.prior_strength`
  pseudo-pairs spread as the exact-match rule spreads them (the twin's own status
  weight 1, every other :attr:`TwinConfusion.prior_mismatch`, normalised). A row with
  few or no pairs (a status the twin of the true cabinet rarely predicts, e.g.
  ``not_applicable``) thus stays the rule the update used before, and a row with many
  follows the measurement;
* **a floor**: every pair keeps at least :attr:`TwinConfusion.floor` (then the row is
  normalised again), so no real status is ever impossible after any twin status: one
  surprising outcome must not remove a model for good (the real belief is never
  resampled).

The holding flag and the handle's motion keep the model's rules (:func:`.model.key_loglik`).
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from planners.errors import ConfigError, UnknownNameError
from strug_manip.domains.manipulation.state import STATUS_CODES

#: The real update's key rules: the measured confusion, or the exact match of before.
TWIN_KEYS: tuple[str, ...] = ("confusion", "match")
#: The rule a task uses unless told (``twin_keys=``, or the environment variable
#: :data:`TWIN_KEYS_ENV`), decided on tuning seeds 9100-9111 (``docs/manipulation-tasks.md``):
#: the shipped confusion (the true cabinet's twin agreed with the full robot on every
#: weighed status) is sharper than the exact match, and STRUG did no better with it
#: (OpenDrawer 9/12 against 10/12, OpenDoor 7/12 and 7/12).
DEFAULT_TWIN_KEYS = "match"
#: Environment variable naming the rule for tasks built without ``twin_keys=`` (how
#: ``tools/eval_manipulation.py --twin-keys`` reaches the bench's episodes).
TWIN_KEYS_ENV = "STRUG_TWIN_KEYS"
#: The shipped data's file name, in this package.
DATA_FILE = "twin_confusion.json"
#: The statuses, in the order of their codes in observation keys.
STATUSES: tuple[str, ...] = tuple(sorted(STATUS_CODES, key=STATUS_CODES.__getitem__))


def twin_keys_rule(twin_keys: str | None = None) -> str:
    """The key rule to use: ``twin_keys``, else :data:`TWIN_KEYS_ENV`'s value, else
    :data:`DEFAULT_TWIN_KEYS`.

    Raises:
        UnknownNameError: a rule that is none of :data:`TWIN_KEYS`.
    """
    rule = twin_keys or os.environ.get(TWIN_KEYS_ENV) or DEFAULT_TWIN_KEYS
    if rule not in TWIN_KEYS:
        raise UnknownNameError("twin keys rule", rule, list(TWIN_KEYS))
    return rule


def smoothed(counts: np.ndarray, strength: float, mismatch: float, floor: float) -> np.ndarray:
    """P(real status | twin status), (n, n) rows by twin status, from ``counts`` (n, n)
    (module docstring): ``strength`` pseudo-pairs per row spread as the exact-match
    rule (own status 1, others ``mismatch``), then every entry at least ``floor``,
    rows normalised."""
    c = np.asarray(counts, dtype=float)
    n = len(c)
    prior = np.full((n, n), mismatch) + (1.0 - mismatch) * np.eye(n)
    prior /= prior.sum(axis=1, keepdims=True)
    p = (c + strength * prior) / (c.sum(axis=1, keepdims=True) + strength)
    p = np.maximum(p, floor)
    return p / p.sum(axis=1, keepdims=True)


@dataclass(frozen=True)
class TwinConfusion:
    """The measured confusion of the twin's status with the full robot's.

    Attributes:
        statuses: the statuses, rows and columns of ``counts`` (:data:`STATUSES`).
        counts: pairs counted per (twin status, real status), (n, n).
        prior_strength: pseudo-pairs per row spread as the exact-match rule (>= 0).
        prior_mismatch: the exact-match rule's weight of another status (0..1).
        floor: the least probability of any pair (0 <= floor < 1 / n).
        provenance: where the counts come from (commit, seeds, domains, episodes, ...).
        p: P(real | twin), (n, n), computed (:func:`smoothed`); ``log_p`` its log.
    """

    statuses: tuple[str, ...]
    counts: np.ndarray
    prior_strength: float
    prior_mismatch: float
    floor: float
    provenance: Mapping[str, Any]
    p: np.ndarray = field(init=False, repr=False)
    log_p: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        n = len(self.statuses)
        if self.statuses != STATUSES:
            raise ConfigError(f"twin confusion: statuses {self.statuses} are not {STATUSES}")
        c = np.asarray(self.counts, dtype=float)
        if c.shape != (n, n) or not np.all(np.isfinite(c)) or np.any(c < 0):
            raise ConfigError(f"twin confusion: counts must be ({n}, {n}), finite, >= 0")
        if not (self.prior_strength >= 0 and 0 <= self.prior_mismatch <= 1):
            raise ConfigError("twin confusion: prior_strength >= 0, prior_mismatch in [0, 1]")
        if not 0 <= self.floor < 1 / n:
            raise ConfigError(f"twin confusion: floor must be in [0, 1/{n}), got {self.floor}")
        p = smoothed(c, self.prior_strength, self.prior_mismatch, self.floor)
        object.__setattr__(self, "counts", c)
        object.__setattr__(self, "p", p)
        object.__setattr__(self, "log_p", np.log(p))

    def loglik(self, twin_code: float, real_code: float) -> float:
        """log P(real status | twin status), the statuses by their key codes."""
        return float(self.log_p[int(twin_code), int(real_code)])

    def as_dict(self) -> dict[str, Any]:
        """The JSON-ready data (what :func:`load_confusion` reads)."""
        return {
            "what": "pairs (twin status, real status): rows the twin's, columns the full "
            "robot's, on the same cabinet from the same starting state",
            "statuses": list(self.statuses),
            "counts": {
                t: {r: int(self.counts[i, j]) for j, r in enumerate(self.statuses)}
                for i, t in enumerate(self.statuses)
            },
            "smoothing": {
                "rule": "row i: (counts[i] + prior_strength * prior[i]) / (n_i + "
                "prior_strength), prior[i] the exact-match rule (own status 1, others "
                "prior_mismatch) normalised; then every entry >= floor, rows normalised",
                "prior_strength": self.prior_strength,
                "prior_mismatch": self.prior_mismatch,
                "floor": self.floor,
                "why": "rows with few pairs stay the rule the update used before; no real "
                "status is ever impossible after any twin status (the real belief is never "
                "resampled: a model weighed to zero is gone for good)",
            },
            "provenance": dict(self.provenance),
        }


def from_dict(d: Mapping[str, Any]) -> TwinConfusion:
    """A :class:`TwinConfusion` from its JSON form (:meth:`TwinConfusion.as_dict`).

    Raises:
        ConfigError: a malformed document, naming what is wrong.
    """
    try:
        statuses = tuple(d["statuses"])
        counts = np.array([[d["counts"][t][r] for r in statuses] for t in statuses], float)
        s = d["smoothing"]
        return TwinConfusion(statuses, counts, float(s["prior_strength"]),
                             float(s["prior_mismatch"]), float(s["floor"]),
                             dict(d["provenance"]))  # fmt: skip
    except (KeyError, TypeError, ValueError) as e:
        raise ConfigError(f"twin confusion data: malformed ({e!r})") from e


def load_confusion(path: str | Path | None = None) -> TwinConfusion:
    """The confusion in ``path`` (default: the data shipped in this package)."""
    if path is None:
        text = resources.files(__package__).joinpath(DATA_FILE).read_text()
    else:
        text = Path(path).read_text()
    return from_dict(json.loads(text))


def count_pairs(pairs: Iterable[tuple[str, str]]) -> np.ndarray:
    """Counts (n, n) of (twin status, real status) pairs, by :data:`STATUSES`.

    Raises:
        UnknownNameError: a status that is none of :data:`STATUSES`.
    """
    n = len(STATUSES)
    out = np.zeros((n, n), dtype=int)
    for t, r in pairs:
        for s in (t, r):
            if s not in STATUS_CODES:
                raise UnknownNameError("status", s, list(STATUSES))
        out[STATUS_CODES[t], STATUS_CODES[r]] += 1
    return out


def table(counts: np.ndarray, p: np.ndarray | None = None) -> str:
    """A Markdown table of ``counts`` (rows: twin status, columns: real status), each
    cell ``count`` or ``count (P)`` with ``p``; all-zero rows and columns left out."""
    c = np.asarray(counts).astype(int)
    rows = [i for i in range(len(c)) if c[i].sum()] or list(range(len(c)))
    cols = [j for j in range(len(c)) if c[:, j].sum()] or list(range(len(c)))
    lines = ["| twin \\ real | " + " | ".join(STATUSES[j] for j in cols) + " | n |",
             "|---" * (len(cols) + 2) + "|"]  # fmt: skip
    for i in rows:
        cells = [f"{c[i, j]}" + ("" if p is None else f" ({p[i, j]:.2f})") for j in cols]
        lines.append(f"| {STATUSES[i]} | " + " | ".join(cells) + f" | {c[i].sum()} |")
    return "\n".join(lines)
