"""The run-time predictor: a model directory in, named amplitudes out (numpy + onnxruntime).

    >>> p = load_predictor("models/default-nn")
    >>> out = p.predict({"orientation": ["forward"], "attachment": ["glued"], ...})
    >>> out["center_amplitude_um"], out["profile_um"], out["edge_radius_mm"]

Outputs per row: ``center_amplitude_um``, ``edge_amplitude_um``, ``normalized_edge``,
``profile_um`` (n, m) on ``profile_distance_mm`` (distance from the unit's outer edge [mm]),
``edge_radius_mm`` (the unit's outer radius [mm]) and ``<output>_log_std`` (predictive std of
the natural log of each amplitude output, times the card's ``interval_calibration`` factors when
it has them, so that exp(ln value +- 1.96 log_std) covers 95 % of held-out rows;
``load_predictor(path, calibrated=False)`` reports the graph's raw spread). A model trained on
more profiles returns them too, by the names of its card's ``log_output_columns`` (``NAME[j]``
columns form the (n, m) output ``NAME``), e.g. ``profile_normal_um``, the normal component
|u_z| of the skin surface. Inputs are validated (:class:`PredictorInputError` names the
input); out-of-range points raise unless ``extrapolate=True``, which adds a boolean
``extrapolated`` array instead.

This module must stay importable without torch, scikit-learn or the FE solver.
"""

from __future__ import annotations

import re
import threading
from pathlib import Path
from typing import Any

import numpy as np
import onnxruntime as ort

from surrogate.runtime.card import CARD_NAME, ModelFileError, read_card, read_model_file
from surrogate.runtime.compiled import compile_specs, encode_row, row_codes
from surrogate.runtime.encoding import (
    InputSpec,
    PredictorInputError,
    encode,
    n_features,
    parse_inputs,
)

__all__ = ["ModelFileError", "Predictor", "PredictorInputError", "load_predictor",
           "make_session"]

SCALAR_OUTPUTS = ("center_amplitude_um", "edge_amplitude_um", "normalized_edge")
_ARRAY_COLUMN = re.compile(r"^(.+)\[(\d+)\]$")


def output_layout(columns: list[str], m: int) -> dict[str, slice | int]:
    """The graph's log-output columns by output name: an index for a scalar output, a slice
    of ``m`` columns for an array output ``NAME[0]`` .. ``NAME[m-1]`` (in order, contiguous).
    ValueError for any other layout; the scalar outputs of :data:`SCALAR_OUTPUTS` and
    ``profile_um`` must lead, as every exported graph writes them."""
    out: dict[str, slice | int] = {}
    k = 0
    while k < len(columns):
        match = _ARRAY_COLUMN.match(columns[k])
        name = match.group(1) if match else columns[k]
        if name in out:
            raise ValueError(f"log_output_columns: {name!r} appears twice")
        if not match:
            out[name] = k
            k += 1
            continue
        want = [f"{name}[{j}]" for j in range(m)]
        if columns[k:k + m] != want:
            raise ValueError(f"log_output_columns: {name}[...] must be {m} columns "
                             f"{want[0]} .. {want[-1]} in order")
        out[name] = slice(k, k + m)
        k += m
    if list(out)[:4] != [*SCALAR_OUTPUTS, "profile_um"]:
        raise ValueError(f"log_output_columns must start with {', '.join(SCALAR_OUTPUTS)}, "
                         "profile_um[...]")
    return out
_DTYPES = {"float32": np.float32, "float64": np.float64}
_GRAPH_OUTPUTS = ["log_mean", "log_std"]
#: Card key of the interval calibration (surrogate.intervals): its ``log_std_scale`` (one
#: factor per log output column) multiplies the graph's ``log_std``; absent: factor 1.
CALIBRATION_KEY = "interval_calibration"
#: Rows per graph call of a large batch: encoding, graph and decoding of a chunk stay in the
#: cache (measured on nn-default at 10,000 rows, one thread: 17 % less graph time than one
#: call). 512 rather than 1,024 for the sweep models' decode, whose per-row gathered tables
#: then stay in the cache: ``bench/runtime/predict.py --models nn-default SWEEP_MODEL gp-default
#: --chunk-rows 256,512,1024 --rounds 5``, 10,000 designs: nn-default 48 / 43 / 40 ms, a sweep
#: model (150 modes) 423 / 419 / 461 ms, gp-default 964 / 926 / 961 ms
CHUNK_ROWS = 512


def make_session(model: bytes | str | Path, threads: int = 1) -> ort.InferenceSession:
    """An onnxruntime CPU session tuned for small calls from one thread: ``threads`` intra-op
    threads, no inter-op pool, no busy-wait spinning between calls."""
    opts = ort.SessionOptions()
    opts.intra_op_num_threads = threads
    opts.inter_op_num_threads = 1
    opts.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
    opts.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
    opts.add_session_config_entry("session.intra_op.allow_spinning", "0")
    opts.log_severity_level = 4  # a failure is raised (and named by the loader), not logged
    src = model if isinstance(model, bytes) else str(model)
    return ort.InferenceSession(src, sess_options=opts, providers=["CPUExecutionProvider"])


class EdgeRadius:
    """The unit's outer radius [mm], an exact function of the discrete design inputs stored
    in the card as a table (every combination seen in training -> its radius), held as a
    dense lookup array over the inputs' integer codes (NaN where a combination was never
    trained)."""

    def __init__(self, rule: dict[str, Any], specs: list[InputSpec]) -> None:
        names = [s.name for s in specs]
        if rule.get("method") != "table":
            raise ModelFileError("edge_radius", f"edge_radius method {rule.get('method')!r} "
                                 "unknown (expected 'table')")
        self.columns = [names.index(n) for n in rule["inputs"]]
        self.inputs = list(rule["inputs"])
        self.keys = np.asarray(rule["keys"], dtype=float).reshape(-1, len(self.columns))
        self.values = np.asarray(rule["values_mm"], dtype=float)
        self._lookup = self._dense()
        self._by_key = {tuple(k): float(v) for k, v in zip(self.keys.tolist(),
                                                          self.values.tolist(), strict=True)}
        if len(self.columns) == 1:  # the usual rule (the radius follows the ring count)
            self._by_key = {k[0]: v for k, v in self._by_key.items()}

    def row(self, row: list[float]) -> float | None:
        """The radius of one design given as its codes (None: a combination never trained)."""
        if len(self.columns) == 1:
            return self._by_key.get(row[self.columns[0]])
        return self._by_key.get(tuple([row[j] for j in self.columns]))

    def _dense(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
        """(columns, lowest key, strides, table) of the dense form; None when the keys are
        not small non-negative integers (then every call takes the general path)."""
        if self.keys.size == 0 or not np.all(self.keys == np.round(self.keys)):
            return None
        low = self.keys.min(axis=0)
        shape = (self.keys.max(axis=0) - low + 1).astype(np.intp)
        if int(np.prod(shape)) > 1 << 16:
            return None
        strides = np.cumprod(np.r_[shape[1:], 1][::-1])[::-1].astype(float)
        table = np.full(int(np.prod(shape)), np.nan)
        table[((self.keys - low) @ strides).astype(np.intp)] = self.values
        return np.asarray(self.columns, dtype=np.intp), low, strides, table

    def __call__(self, codes: np.ndarray) -> np.ndarray:
        if self._lookup is not None:
            cols, low, strides, table = self._lookup
            flat = (codes[:, cols] - low) @ strides
            if flat.size == 0 or (flat.min() >= 0 and flat.max() < table.size):
                found = table[flat.astype(np.intp)]
                if not np.isnan(found).any():  # integral codes: validated by the caller
                    return found
        return self._general(codes)

    def _general(self, codes: np.ndarray) -> np.ndarray:
        sub = codes[:, self.columns]
        match = np.all(sub[:, None, :] == self.keys[None, :, :], axis=2)
        found = match.any(axis=1)
        if not found.all():
            i = int(np.argmin(found))
            combo = dict(zip(self.inputs, sub[i].tolist(), strict=True))
            raise PredictorInputError(self.inputs[0] if self.inputs else "X",
                                      f"row {i}: the combination {combo} of structural inputs "
                                      "was never trained")
        return self.values[np.argmax(match, axis=1)]


class Predictor:
    """A loaded model: validated inputs in, named outputs out. Build with
    :func:`load_predictor`. The ONNX session is made once, with one thread; the checks and
    the encoding are compiled from the card once (:func:`compile_specs`), so a call costs a
    few array operations beyond the graph."""

    def __init__(self, card: dict[str, Any], session: ort.InferenceSession, *,
                 calibrated: bool = True) -> None:
        self.card = card
        self.specs = [InputSpec.from_dict(d) for d in card["inputs"]]
        self.input_names: tuple[str, ...] = tuple(s.name for s in self.specs)
        self.input_ranges: dict[str, tuple[float, float]] = {s.name: s.range
                                                             for s in self.specs}
        self.profile_distance_mm = np.asarray(card["profile_distance_mm"], dtype=float)
        m = self.profile_distance_mm.size
        self._layout = output_layout(list(card.get("log_output_columns") or
                                          [*SCALAR_OUTPUTS, *(f"profile_um[{j}]"
                                                              for j in range(m))]), m)
        self.n_log_outputs = sum(1 if isinstance(v, int) else m for v in self._layout.values())
        self.output_names: tuple[str, ...] = (*self._layout, "edge_radius_mm")
        #: profile outputs beyond ``profile_um`` (e.g. ``profile_normal_um``), in column order
        self.extra_outputs: tuple[str, ...] = tuple(list(self._layout)[4:])
        self.kind = str(card.get("kind", ""))
        self.session = session
        self._dtype = _DTYPES[card["graph"]["dtype"]]
        self._edge = EdgeRadius(card["edge_radius"], self.specs)
        self._plan = compile_specs(self.specs)
        self._local = threading.local()  # per-thread buffers of the one-design path
        self._std_scale = _std_scale(card, self.n_log_outputs) if calibrated \
            else None

    def uncalibrated(self) -> Predictor:
        """This model reporting the graph's raw ``log_std`` (no ``interval_calibration``
        factors), sharing its session."""
        if self._std_scale is None:
            return self
        return Predictor(self.card, self.session, calibrated=False)

    def features(self, X: Any, *, extrapolate: bool = False) -> tuple[np.ndarray, np.ndarray,
                                                                       np.ndarray]:
        """(codes, encoded features in the graph's dtype, extrapolated mask)."""
        codes, outside = parse_inputs(X, self.specs, extrapolate=extrapolate, plan=self._plan)
        return codes, encode(codes, self.specs, plan=self._plan, dtype=self._dtype), outside

    def predict(self, X: Any, *, extrapolate: bool = False) -> dict[str, np.ndarray]:
        """Predict every output for design points ``X`` (see the module docstring)."""
        row = row_codes(X, self._plan)
        if row is not None:
            out = self._predict_one(row)
            if out is not None:
                if extrapolate:
                    out["extrapolated"] = np.zeros(1, dtype=bool)
                return out
        codes, outside = parse_inputs(X, self.specs, extrapolate=extrapolate, plan=self._plan)
        n = codes.shape[0]
        amp, std = np.empty((n, self.n_log_outputs)), np.empty((n, self.n_log_outputs))
        for i in range(0, max(n, 1), CHUNK_ROWS):  # a chunk's arrays stay in the cache
            j = min(i + CHUNK_ROWS, n)
            feats = encode(codes[i:j], self.specs, plan=self._plan, dtype=self._dtype)
            log_mean, log_std = self.session.run(_GRAPH_OUTPUTS, {"x": feats})
            np.exp(log_mean, out=amp[i:j], dtype=float)
            std[i:j] = log_std
        out = self._decode(amp, std)
        out["edge_radius_mm"] = self._edge(codes)
        if extrapolate:
            out["extrapolated"] = outside
        return out

    def _predict_one(self, row: list[float]) -> dict[str, np.ndarray] | None:
        """One design inside the trained range, checked and encoded in Python scalars
        (:func:`encode_row`; the same arithmetic as the batch path) and decoded into views of
        one array per output kind; None hands it to the batch path (a value outside the
        range, a combination the edge-radius table lacks), which explains a refusal."""
        radius = self._edge.row(row)
        if radius is None:
            return None
        one = getattr(self._local, "one", None) or self._bind_one()
        one.x[0] = encode_row(row, self._plan)
        self.session.run_with_iobinding(one.binding)
        amp = np.exp(one.log_mean, dtype=float)  # new arrays: nothing returned aliases a buffer
        std = one.log_std.astype(float)
        out = self._decode(amp, std)
        out["edge_radius_mm"] = np.array([radius])
        return out

    def _decode(self, amp: np.ndarray, std: np.ndarray) -> dict[str, np.ndarray]:
        """Named outputs of (n, n_out) amplitudes and log-stds (the stds calibrated in place):
        a scalar output as a contiguous (n,) array, an array output as (n, m)."""
        if self._std_scale is not None:
            std *= self._std_scale
        out: dict[str, np.ndarray] = {}
        for name, cols in self._layout.items():  # contiguous arrays (a copy beyond one row)
            out[name] = np.ascontiguousarray(amp[:, cols])
            out[f"{name}_log_std"] = np.ascontiguousarray(std[:, cols])
        return out

    def _bind_one(self) -> _OneRow:
        """This thread's buffers for one design (an onnxruntime IOBinding of preallocated
        input and output arrays: at batch 1 it saves the allocation of three arrays per call,
        a quarter of the graph's time)."""
        width = int(self._plan.source.size)
        one = _OneRow(self.session, width, self.n_log_outputs, self._dtype)
        self._local.one = one
        return one


class _OneRow:
    """Preallocated (1, width) input and (1, n_out) outputs bound to a session."""

    def __init__(self, session: ort.InferenceSession, width: int, n_out: int,
                 dtype: Any) -> None:
        self.x = np.zeros((1, width), dtype=dtype)
        self.log_mean = np.zeros((1, n_out), dtype=dtype)
        self.log_std = np.zeros((1, n_out), dtype=dtype)
        self.binding = session.io_binding()
        self.binding.bind_cpu_input("x", self.x)
        for name, buf in zip(_GRAPH_OUTPUTS, (self.log_mean, self.log_std), strict=True):
            self.binding.bind_output(name, "cpu", 0, dtype, buf.shape, buf.ctypes.data)


def _std_scale(card: dict[str, Any], n_out: int) -> np.ndarray | None:
    """The card's per-column log-std factors (None without a calibration); a malformed entry
    is a ModelFileError naming the key."""
    entry = card.get(CALIBRATION_KEY)
    if entry is None:
        return None
    try:
        scale = np.asarray(entry["log_std_scale"], dtype=float)
    except (KeyError, TypeError, ValueError):
        scale = np.zeros(0)
    if scale.shape != (n_out,) or not np.all(np.isfinite(scale) & (scale > 0)):
        raise ModelFileError(CALIBRATION_KEY, f"{CALIBRATION_KEY}.log_std_scale must be "
                             f"{n_out} positive factors, one per log output column "
                             "(check: card values)")
    return scale


def _session(path: Path, name: str, data: bytes) -> ort.InferenceSession:
    """An onnxruntime session of the graph bytes ``data`` (never a path: a graph's external
    data or custom-op library cannot be fetched from elsewhere); any failure is a refusal
    naming the file."""
    try:
        return make_session(data)
    except Exception as err:  # onnxruntime raises its own classes (InvalidProtobuf, Fail, ...)
        text = str(err).strip().splitlines()[0][:300] if str(err).strip() else ""
        raise ModelFileError(name, f"{path / name}: not an ONNX graph this runtime can run "
                             f"(check: graph; {type(err).__name__}: {text})") from None


def _check_graph(path: Path, name: str, card: dict[str, Any],
                 session: ort.InferenceSession, width: int, n_out: int) -> None:
    """The graph's contract: one input ``x`` (batch, width) of the card's dtype and outputs
    ``log_mean`` and ``log_std`` of (batch, n_out), checked on one row."""
    where = f"{path / name}: the graph does not match the card (check: graph contract; "
    inputs = session.get_inputs()
    if [i.name for i in inputs] != ["x"]:
        raise ModelFileError(name, where + f"inputs {[i.name for i in inputs]}, expected "
                             "['x'])")
    outs = {o.name for o in session.get_outputs()}
    if not {"log_mean", "log_std"} <= outs:
        raise ModelFileError(name, where + f"outputs {sorted(outs)}, expected log_mean and "
                             "log_std)")
    try:
        mean, std = session.run(["log_mean", "log_std"],
                                {"x": np.zeros((1, width), _DTYPES[card["graph"]["dtype"]])})
    except Exception as err:
        raise ModelFileError(name, where + f"one row of {width} features fails: "
                             f"{type(err).__name__})") from None
    for label, arr in (("log_mean", mean), ("log_std", std)):
        if np.shape(arr) != (1, n_out):
            raise ModelFileError(name, where + f"{label} has shape {np.shape(arr)} for one "
                                 f"row, expected (1, {n_out}))")


def load_predictor(path: str | Path, *, calibrated: bool = True) -> Predictor:
    """Load ``models/NAME/`` as a :class:`Predictor`, after verifying the directory as a whole
    (:func:`surrogate.runtime.card.verify_model_dir`) and the graph against the card; any
    failure is a :class:`ModelFileError` naming the file and the check. ``calibrated=False``
    reports the graph's raw ``log_std`` (what a calibration is computed from)."""
    root = Path(path)
    card = read_card(root)
    if "graph" not in card:  # the steady-state contract, whatever the kind's name
        raise ModelFileError("kind", f"{root / CARD_NAME}: a {card.get('kind')!r} model, not "
                             "a steady-state predictor (no ONNX graph)")
    graph = card["graph"]
    if not isinstance(graph, dict) or not isinstance(graph.get("dtype"), str) \
            or graph["dtype"] not in _DTYPES:
        raise ModelFileError("graph", f"{root / CARD_NAME}: graph.dtype must be one of "
                             f"{sorted(_DTYPES)} (check: keys)")
    name = graph["file"]
    session = _session(root, name, read_model_file(root, card, name))
    try:
        predictor = Predictor(card, session, calibrated=calibrated)
        width = n_features(predictor.specs)
    except ModelFileError:
        raise
    except (KeyError, TypeError, ValueError, IndexError, AttributeError) as err:
        raise ModelFileError(CARD_NAME, f"{root / CARD_NAME}: malformed card "
                             f"(check: card values; {type(err).__name__}: {err})") from None
    _check_graph(root, name, card, session, width, predictor.n_log_outputs)
    return predictor
