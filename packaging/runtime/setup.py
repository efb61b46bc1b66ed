"""Stage the run-time packages from the source tree into src/, then build (see pyproject)."""

import sys
from pathlib import Path

from setuptools import setup

HERE = Path(__file__).resolve().parent
if (HERE.parent / "stage.py").is_file():  # in the repository (an unpacked sdist has src/)
    sys.path.insert(0, str(HERE.parent))
    from stage import stage

    stage(HERE, [("surrogate/__init__.py", "surrogate/__init__.py"),
                 ("surrogate/runtime", "surrogate/runtime"),
                 ("planner", "planner"), ("fieldspec", "fieldspec"), ("figstyle", "figstyle"),
                 ("motorlaw", "motorlaw"), ("calibration", "calibration")])
setup()
