"""The shipped envelope model and one realistic design the envelope-model tests share."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "models" / "rom-default"
TRANSIENT = ROOT / "datasets" / "transient"


def transient_subset(data: Path, parts: int = 3) -> Path:
    """Write into the new directory ``data`` the shipped transient dataset's first ``parts``
    parts, with its manifest listing only them (digest recomputed); returns ``data``."""
    from surrogate.data.integrity import manifest_digest

    data.mkdir()
    manifest = json.loads((TRANSIENT / "_manifest.json").read_text())
    keep = sorted(manifest["parts"])[:parts]
    for name in keep:
        shutil.copy(TRANSIENT / name, data)
    manifest["parts"] = {k: manifest["parts"][k] for k in keep}
    manifest["digest"] = manifest_digest(manifest)
    (data / "_manifest.json").write_text(json.dumps(manifest))
    return data
#: A glued unit with two rings on the default forearm, with the motor's time constants [ms].
DESIGN = {"orientation": "reverse", "attachment": "glued", "n_rings": 2,
          "ring_1_E_kPa": 150.0, "ring_2_E_kPa": 150.0, "ring_3_E_kPa": 150.0,
          "ring_density_kg_m3": 1070.0, "ring_nu": 0.47, "ring_loss_factor": 0.08,
          "skin_E_kPa": 49.0, "fat_thickness_mm": 10.0, "tissue_loss_factor": 0.3,
          "tau_spinup_ms": 20.0, "tau_spindown_ms": 35.0}
