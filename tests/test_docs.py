"""Every Python block of the documentation pages (``docs/*.md``) runs as written, as the
README's do (``tests/test_readme.py``). A block that needs a long run or a downloaded
object is written as ``bash`` or plain text, not ``python``."""

from __future__ import annotations

from pathlib import Path

import pytest
from test_readme import python_blocks

DOCS = Path(__file__).resolve().parents[1] / "docs"
BLOCKS = [
    (page.name, line, code)
    for page in sorted(DOCS.glob("*.md"))
    for line, code in python_blocks(page.read_text())
]


def test_the_docs_have_their_python_blocks() -> None:
    pages = {name for name, _, _ in BLOCKS}
    # a manipulation trial, your own POMDP, a loaded object, a skill, the initial belief
    assert {"getting-started.md", "planners.md", "robot-world.md"} <= pages
    assert {"skills.md", "perception.md"} <= pages
    assert len(BLOCKS) >= 6


@pytest.mark.parametrize(
    ("page", "line", "code"), BLOCKS, ids=[f"{name}:{n}" for name, n, _ in BLOCKS]
)
def test_docs_block_runs(
    page: str, line: int, code: str, capsys: pytest.CaptureFixture[str]
) -> None:
    exec(compile(code, f"docs/{page}:{line}", "exec"), {"__name__": f"docs_{page[:-3]}_{line}"})
    assert capsys.readouterr().out  # every block prints what it shows
