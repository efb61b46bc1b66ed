"""The thigh layout requests of ``examples/`` as dicts, with the model paths made absolute so
that tests run from any directory."""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
THIGH = ROOT / "examples" / "thigh-layout.toml"
THIGH_PERCEPTUAL = ROOT / "examples" / "thigh-layout-perceptual.toml"


def thigh(perceptual: bool = False) -> dict[str, Any]:
    """The example request (6 x 6 hex, 100-170 Hz) with absolute model paths."""
    d = tomllib.loads((THIGH_PERCEPTUAL if perceptual else THIGH).read_text())
    d["model"]["path"] = str(ROOT / "models" / "nn-default")
    d["timing"]["model"] = str(ROOT / "models" / "rom-default")
    return d


def toml_text(perceptual: bool = False) -> str:
    """The example file's text with absolute model paths, planned on ``nn-default`` as
    :func:`thigh` is (the example leaves the path out, so it would take the default model)."""
    text = (THIGH_PERCEPTUAL if perceptual else THIGH).read_text()
    nn = repr(str(ROOT / "models" / "nn-default"))
    assert '# path = "models/nn-default"' in text
    return (text.replace('# path = "models/nn-default"', f"path = {nn}", 1)
            .replace('"models/rom-default"', repr(str(ROOT / "models" / "rom-default"))))
