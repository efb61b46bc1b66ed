"""The predictor's Python lines as printed run and give the answer docs/embedding.md quotes
for its worked example: the README's "Predict" example and the "Embed the predictor" section
of docs/surrogates.md (where the README's section of that name moved)."""

from __future__ import annotations

import contextlib
import io

import pytest
from embed_cases import REPO


def _block(path: str, marker: str) -> str:
    """The first ```python block after ``marker`` in ``path``."""
    text = (REPO / path).read_text().split(marker, 1)[1]
    return text.split("```python\n", 1)[1].split("```", 1)[0]


@pytest.mark.parametrize("path, marker, centre", [
    ("README.md", "**Predict**", "13.984"),  # nn-sweep, the default network
    ("docs/surrogates.md", "## Embed the predictor", "13.969")])  # nn-default
def test_readme_python_lines_run(path, marker, centre):
    code = _block(path, marker)
    assert len([line for line in code.splitlines() if line.strip()]) <= 10
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, path, "exec"), {})
    first = out.getvalue().splitlines()[0]
    assert first.startswith(f"[{centre}") and "[4.55]" in first  # docs/embedding.md, section 6
    assert f"centre {centre} µm" in (REPO / "docs/embedding.md").read_text()
