"""Every Python block of the README runs as written (a user pastes them)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"


def python_blocks(text: str) -> list[tuple[int, str]]:
    """``(line number, code)`` of every fenced block opened with ```` ```python ````."""
    blocks = []
    for m in re.finditer(r"^```python\n(.*?)^```", text, flags=re.S | re.M):
        blocks.append((text.count("\n", 0, m.start()) + 1, m.group(1)))
    return blocks


BLOCKS = python_blocks(README.read_text())


def test_the_readme_has_its_python_blocks() -> None:
    assert len(BLOCKS) >= 5  # a manipulation trial, a skill, two own-POMDP examples, an object
    assert python_blocks("```bash\nls\n```\n```python\nx = 1\n```\n") == [(4, "x = 1\n")]


@pytest.mark.parametrize(("line", "code"), BLOCKS, ids=[f"README.md:{n}" for n, _ in BLOCKS])
def test_readme_block_runs(line: int, code: str, capsys: pytest.CaptureFixture[str]) -> None:
    exec(compile(code, f"README.md:{line}", "exec"), {"__name__": f"readme_{line}"})
    assert capsys.readouterr().out  # every block prints what it shows
