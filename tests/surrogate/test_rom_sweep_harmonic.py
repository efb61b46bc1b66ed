"""The envelope model on a sweep-trained harmonic model: what the run time needs of its
harmonic model (a ``frequency_hz`` input over a band, the design inputs of the transient runs,
the ``attachment`` choices it groups by) a sweep NN has, so the fit and the run time take it
unchanged; the default harmonic of the fit is the defaults' ``envelope_harmonic``."""

from __future__ import annotations

import numpy as np
import pytest

from surrogate.envelope.fit import train
from surrogate.runtime import defaults
from surrogate.runtime.models import MODEL_PATH_ENV
from surrogate.runtime.predictor import load_predictor
from surrogate.runtime.rom import load_envelope_model
from tests.surrogate.rom_cases import DESIGN
from tests.surrogate.rom_cases import transient_subset as write_transient_subset


@pytest.fixture(scope="module")
def transient_subset(tmp_path_factory):
    """The shipped transient dataset's first three parts (its manifest listing only them)."""
    return write_transient_subset(tmp_path_factory.mktemp("transient") / "data")


def test_the_envelope_fit_takes_its_steady_part_from_the_default_sweep_model(
        transient_subset, sweep_model, monkeypatch, tmp_path):
    monkeypatch.setenv(MODEL_PATH_ENV, str(sweep_model.parent))
    monkeypatch.setattr(defaults, "DEFAULT_MODELS", {**defaults.DEFAULT_MODELS,
                                                     "envelope_harmonic": (sweep_model.name,)})
    out = tmp_path / "rom"
    card = train([transient_subset], out, max_nfev=2)  # no harmonic given: the default
    assert card["harmonic"]["card"]
    rom = load_envelope_model(out)
    harmonic = load_predictor(sweep_model)
    band = harmonic.input_ranges["frequency_hz"]
    assert (rom.grid_hz[0], rom.grid_hz[-1]) == band  # the sweep's band, every 2.5 Hz
    design = {k: v for k, v in DESIGN.items() if k in rom.input_names}
    amp = rom.steady_amplitudes(design)
    row = {k: np.full(rom.grid_hz.size, v) for k, v in design.items()
           if k in harmonic.input_names}
    want = harmonic.predict({**row, "frequency_hz": rom.grid_hz})
    np.testing.assert_allclose(amp["center"], want["center_amplitude_um"], rtol=1e-6)
    np.testing.assert_allclose(amp["edge"], want["edge_amplitude_um"], rtol=1e-6)
