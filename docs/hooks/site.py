"""mkdocs hooks of the documentation site (mkdocs.yml ``hooks``).

* Before the build, every ```python block of README.md runs, each in a fresh interpreter from
  the repository root; one that fails stops the build naming the block's first line and the
  error (so a README example that no longer works fails ``make docs`` and ``make test``).
* A link from a page to a file of the repository outside docs/ (``../bench/fem/accuracy.py``)
  becomes that path in code type: the site has no page for it, and the text still says
  where to look. A link to a file that exists nowhere is left for mkdocs to report.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

from mkdocs.exceptions import PluginError
from mkdocs.plugins import get_plugin_logger

log = get_plugin_logger(__name__)

REPO = Path(__file__).resolve().parents[2]
EXAMPLES_FROM = (REPO / "README.md", REPO / "docs" / "getting-started.md")
BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)
LINK = re.compile(r"(?<!!)\[([^\]]+)\]\((?!https?:|mailto:|#)([^)\s]+)\)")


def python_blocks(path: Path) -> list[tuple[int, str]]:
    """(line number, code) of every ```python block of ``path``."""
    text = path.read_text(encoding="utf-8")
    return [(text.count("\n", 0, m.start()) + 2, m.group(1)) for m in BLOCK.finditer(text)]


def run_block(code: str, timeout_s: float = 300.0) -> subprocess.CompletedProcess:
    """``code`` run by this interpreter in a new process from the repository root."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(REPO), *filter(None, [os.environ.get("PYTHONPATH")])])}
    return subprocess.run([sys.executable, "-c", code], cwd=REPO, env=env, text=True,
                          capture_output=True, timeout=timeout_s)


def on_pre_build(config: Any) -> None:
    blocks = [(path, line, code) for path in EXAMPLES_FROM for line, code in python_blocks(path)]

    def run(block: tuple[Path, int, str]) -> tuple[Path, int, float, Any]:
        t0 = time.perf_counter()
        done = run_block(block[2])
        return block[0], block[1], time.perf_counter() - t0, done

    with ThreadPoolExecutor(max_workers=2) as pool:  # each is its own process
        for path, line, seconds, done in pool.map(run, blocks):
            if done.returncode != 0:
                raise PluginError(f"{path.name}:{line}: the Python example failed "
                                  f"(exit {done.returncode}):\n{done.stderr[-2000:]}")
            log.info(f"{path.name}:{line}: Python example ran ({seconds:.1f} s)")


def on_page_markdown(markdown: str, page: Any, config: Any, files: Any) -> str:
    here = Path(page.file.abs_src_path).parent
    docs = Path(config["docs_dir"]).resolve()

    def outside(m: re.Match) -> str:
        target = m.group(2).split("#")[0]
        full = (here / target).resolve()
        if not target or full.is_relative_to(docs) or not full.exists():
            return m.group(0)
        shown = full.relative_to(REPO).as_posix()
        text = m.group(1)
        return f"`{shown}`" if text.strip("`") == shown else f"{text} (`{shown}`)"

    return LINK.sub(outside, markdown)
