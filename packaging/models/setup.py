"""Stage models/* from the source tree into src/hapticrom_models/, then build (see pyproject)."""

import sys
from pathlib import Path

from setuptools import setup

HERE = Path(__file__).resolve().parent
INIT = '''"""The shipped hapticrom models as package data: one directory per model (card.json and
the files it lists). Load one with ``surrogate.runtime.load_model(NAME)``; :data:`MODELS_DIR` is
the directory that holds them."""

from pathlib import Path

MODELS_DIR = Path(__file__).resolve().parent
NAMES = tuple(sorted(p.name for p in MODELS_DIR.iterdir() if (p / "card.json").is_file()))
'''
if (HERE.parent / "stage.py").is_file():  # in the repository (an unpacked sdist has src/)
    sys.path.insert(0, str(HERE.parent))
    from stage import REPO, stage

    names = sorted(p.name for p in (REPO / "models").iterdir() if (p / "card.json").is_file())
    src = stage(HERE, [(f"models/{n}", f"hapticrom_models/{n}") for n in names])
    (src / "hapticrom_models" / "__init__.py").write_text(INIT)
setup()
