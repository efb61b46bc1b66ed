"""The README's "Embed the predictor" Python lines run as printed and give the answer
docs/embedding.md quotes for its worked example."""

from __future__ import annotations

import contextlib
import io

from embed_cases import REPO


def test_readme_python_lines_run():
    text = (REPO / "README.md").read_text()
    section = text.split("## Embed the predictor", 1)[1].split("\n## ", 1)[0]
    code = section.split("```python\n", 1)[1].split("```", 1)[0]
    assert len([line for line in code.splitlines() if line.strip()]) <= 10
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "README.md", "exec"), {})
    first = out.getvalue().splitlines()[0]
    assert first.startswith("[13.969") and "[4.55]" in first  # docs/embedding.md, section 6
    assert "13.969" in (REPO / "docs/embedding.md").read_text()
