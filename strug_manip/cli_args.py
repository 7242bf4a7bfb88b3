"""How the ``strug`` command line reads its arguments: value types, ``--set`` values, paths.

Decisions:

* Every argument error is one line on stderr, ``strug: error: argument --sims: ...``,
  with exit status 2 and no usage block (``strug CMD --help`` shows the usage); the
  messages name the flags a user typed (``--particles``, ``--time``), never the config
  fields behind them.
* Output paths are checked before any work starts: a directory flag (``bench --out``)
  must not name a file, a file flag (``run --rerun``, ``scene --out``) must not name a
  directory, and the folders they need must be creatable.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any, NoReturn

from planners.errors import ConfigError


class Parser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose errors are one line: ``strug: error: ...``, exit 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"strug: error: {message} (see: {self.prog} --help)\n")


def positive_int(text: str) -> int:
    """An integer >= 1, for argparse's ``type=``."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}")
    return value


def nonnegative_int(text: str) -> int:
    """An integer >= 0, for argparse's ``type=``."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}")
    return value


def positive_seconds(text: str) -> float:
    """A finite number of seconds > 0, for argparse's ``type=``."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seconds > 0, got {text!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"expected seconds > 0, got {text!r}")
    return value


def parse_value(text: str) -> Any:
    """A ``--set NAME=VALUE`` value: ``none``/``null``, booleans, ints, floats, else the string."""
    low = text.strip().lower()
    if low in ("none", "null"):
        return None
    if low in ("true", "false"):
        return low == "true"
    for cast in (int, float):
        try:
            return cast(text)
        except ValueError:
            pass
    return text


def parse_overrides(items: list[str] | None) -> dict[str, Any]:
    """``["depth=10", "c=50"]`` -> ``{"depth": 10, "c": 50}``.

    Raises:
        ConfigError: an item is not ``NAME=VALUE``.
    """
    out: dict[str, Any] = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise ConfigError(f"--set expects NAME=VALUE, got {item!r}")
        out[name.strip()] = parse_value(value)
    return out


def _file_in_the_way(path: Path) -> Path | None:
    """The nearest existing ancestor of ``path`` when it is a file (not a folder)."""
    for parent in path.parents:
        if parent.exists():
            return None if parent.is_dir() else parent
    return None


def _make_folder(folder: Path, flag: str, path: Path) -> None:
    blocker = _file_in_the_way(folder / "x")
    if blocker is not None:
        raise ConfigError(f"{flag} {path}: {blocker} is a file, so no folder can be made in it")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(
            f"{flag} {path}: cannot create the folder {folder} ({exc.strerror})"
        ) from None


def output_dir(path: Path, flag: str) -> Path:
    """``path`` as a directory for ``flag``, created if missing.

    Raises:
        ConfigError: ``path`` is a file, or it cannot be created (a parent is a file,
            no permission).
    """
    if path.exists() and not path.is_dir():
        raise ConfigError(f"{flag} {path} is a file; expected a directory (new or existing)")
    _make_folder(path, flag, path)
    return path


def output_file(path: Path, flag: str, suffixes: tuple[str, ...] = ()) -> Path:
    """``path`` as a file to write for ``flag``; its folder is created if missing.

    Args:
        path: the file.
        flag: the option's name, for messages.
        suffixes: accepted file name endings (lower case, with the dot); empty: any.

    Raises:
        ConfigError: ``path`` is a directory, has another ending, or its folder cannot
            be created.
    """
    if path.is_dir():
        example = f"{path}/out{suffixes[0] if suffixes else ''}"
        raise ConfigError(f"{flag} {path} is a directory; expected a file path like {example}")
    if suffixes and path.suffix.lower() not in suffixes:
        raise ConfigError(f"{flag} {path}: expected a file ending in {' or '.join(suffixes)}")
    _make_folder(path.parent, flag, path)
    return path
