// hapticrom-model.mjs: read a hapticrom model (card.json + model.onnx), check its integrity,
// encode designs, run the ONNX graph and decode the answer -- following docs/embedding.md only.
//
// The one JavaScript code path for both the Node example (node/predict.mjs, onnxruntime-node)
// and the browser explorer (explorer/, onnxruntime-web): the caller passes its onnxruntime
// module (`ort`) and the model's bytes; this module reads no files and loads no packages.
// Needs WebCrypto (globalThis.crypto.subtle: Node >= 19, every browser in a secure context).
//
//   const model = await HapticModel.load({ ort, cardText, files: { "model.onnx": bytes } });
//   const out = await model.predict([{ orientation: "forward", n_rings: 2, ... }]);
//   out.center_amplitude_um[0], out.profile_um[0], out.profile_distance_mm

export const FORMAT = "hapticrom-model";
export const CARD_VERSION = 1;
export const Z95 = 1.959964; // two-sided 95 % normal quantile (the planner's band, too)

/** A model directory that is malformed or fails its integrity check; `field` names the key. */
export class ModelFileError extends Error {
  constructor(field, message) {
    super(message);
    this.name = "ModelFileError";
    this.field = field;
  }
}

/** A bad design; `field` names the input, the message the allowed values. */
export class PredictorInputError extends Error {
  constructor(field, message) {
    super(message);
    this.name = "PredictorInputError";
    this.field = field;
  }
}

// ------------------------------------------------------------------ canonical JSON (sealing)

/** Python's repr of a float (shortest round-trip digits; exponent form below 1e-4 and from
 * 1e16 on: 3.0, 0.0001, 1e-05, 6.550000000000001, 1e+16). */
export function pythonFloat(x) {
  if (!Number.isFinite(x)) throw new ModelFileError("card", `non-finite number ${x} in the card`);
  if (x === 0) return Object.is(x, -0) ? "-0.0" : "0.0";
  const [mant, expText] = x.toExponential().split("e"); // shortest digits, d.ddd
  const e = Number(expText);
  const sign = mant.startsWith("-") ? "-" : "";
  const digits = mant.replace("-", "").replace(".", "");
  if (e < -4 || e >= 16) {
    const m = digits.length > 1 ? `${digits[0]}.${digits.slice(1)}` : digits;
    return `${sign}${m}e${e < 0 ? "-" : "+"}${String(Math.abs(e)).padStart(2, "0")}`;
  }
  if (e < 0) return `${sign}0.${"0".repeat(-e - 1)}${digits}`;
  const whole = digits.slice(0, e + 1).padEnd(e + 1, "0");
  const frac = digits.slice(e + 1);
  return `${sign}${whole}.${frac || "0"}`;
}

function codePointCompare(a, b) {
  const x = Array.from(a, (c) => c.codePointAt(0));
  const y = Array.from(b, (c) => c.codePointAt(0));
  for (let i = 0; i < Math.min(x.length, y.length); i++) if (x[i] !== y[i]) return x[i] - y[i];
  return x.length - y.length;
}

/** Parse JSON keeping every number's literal text: {num: "1.0"} tokens, so that integers and
 * floats re-serialise as Python's json module writes them. */
function parseLiteral(text) {
  let i = 0;
  const ws = () => { while (i < text.length && " \t\n\r".includes(text[i])) i++; };
  const fail = (what) => { throw new ModelFileError("card", `card.json: ${what} at character ${i}`); };
  function value() {
    ws();
    const c = text[i];
    if (c === "{") {
      i++; const obj = new Map(); ws();
      if (text[i] === "}") { i++; return obj; }
      for (;;) {
        ws(); if (text[i] !== '"') fail("expected a key");
        const k = string(); ws(); if (text[i] !== ":") fail("expected ':'"); i++;
        obj.set(k, value()); ws();
        if (text[i] === ",") { i++; continue; }
        if (text[i] === "}") { i++; return obj; }
        fail("expected ',' or '}'");
      }
    }
    if (c === "[") {
      i++; const arr = []; ws();
      if (text[i] === "]") { i++; return arr; }
      for (;;) {
        arr.push(value()); ws();
        if (text[i] === ",") { i++; continue; }
        if (text[i] === "]") { i++; return arr; }
        fail("expected ',' or ']'");
      }
    }
    if (c === '"') return string();
    for (const [word, v] of [["true", true], ["false", false], ["null", null]]) {
      if (text.startsWith(word, i)) { i += word.length; return v; }
    }
    const m = /^-?(0|[1-9]\d*)(\.\d+)?([eE][+-]?\d+)?/.exec(text.slice(i));
    if (!m) fail("unexpected text");
    i += m[0].length;
    return { num: m[0] };
  }
  function string() {
    const m = /^"(?:[^"\\\u0000-\u001f]|\\(?:["\\/bfnrt]|u[0-9a-fA-F]{4}))*"/.exec(text.slice(i));
    if (!m) fail("bad string");
    i += m[0].length;
    return JSON.parse(m[0]);
  }
  const v = value(); ws();
  if (i !== text.length) fail("trailing text");
  return v;
}

function canonical(v) {
  if (v === null || typeof v === "boolean") return JSON.stringify(v);
  if (typeof v === "string") return JSON.stringify(v); // escapes as Python's ensure_ascii=False
  if (Array.isArray(v)) return `[${v.map(canonical).join(",")}]`;
  if (v instanceof Map) {
    const keys = [...v.keys()].sort(codePointCompare);
    return `{${keys.map((k) => `${JSON.stringify(k)}:${canonical(v.get(k))}`).join(",")}}`;
  }
  const lit = v.num;
  if (/[.eE]/.test(lit)) return pythonFloat(Number(lit));
  return BigInt(lit).toString(); // an integer stays an integer ("-0" -> "0")
}

/** The canonical JSON text of a card without its `card_sha256` key (docs/embedding.md):
 * Python's json.dumps(card, sort_keys=True, separators=(",", ":"), ensure_ascii=False). */
export function canonicalCardText(cardText) {
  const tree = parseLiteral(cardText);
  if (!(tree instanceof Map)) throw new ModelFileError("card", "card.json is not an object");
  tree.delete("card_sha256");
  return canonical(tree);
}

/** Lower-case hex sha256 of bytes (Uint8Array) or of a string's UTF-8 encoding. */
export async function sha256Hex(data) {
  const bytes = typeof data === "string" ? new TextEncoder().encode(data) : data;
  if (!globalThis.crypto?.subtle) {
    throw new ModelFileError("card_sha256", "WebCrypto is not available, so the model cannot " +
      "be verified: serve the page from localhost or over https (Node >= 19 has it)");
  }
  const digest = await globalThis.crypto.subtle.digest("SHA-256", bytes);
  return Array.from(new Uint8Array(digest), (b) => b.toString(16).padStart(2, "0")).join("");
}

function plainName(name) {
  return typeof name === "string" && name !== "" && name !== "." && name !== ".." &&
    !/[/\\]/.test(name) && !/^[A-Za-z]:/.test(name);
}

/** Parse and verify a card and the files it lists (`files`: name -> Uint8Array). Checks, in
 * order: the format, card_sha256 over the canonical card, every listed name plain, every
 * listed file present with its sha256, and (when `present` names the directory's files) no
 * file the card does not list. Returns the parsed card; throws ModelFileError. */
export async function verifyModel(cardText, files, { present = null } = {}) {
  let card;
  try { card = JSON.parse(cardText); } catch (err) {
    throw new ModelFileError("card", `card.json: unreadable card: ${err.message}`);
  }
  if (card === null || typeof card !== "object" || card.format !== FORMAT) {
    throw new ModelFileError("format", `card.json: not a ${FORMAT} card`);
  }
  if (card.card_version !== CARD_VERSION) {
    throw new ModelFileError("card_version", `card.json: card_version ${card.card_version} is not ` +
      `${CARD_VERSION}, the version this reader knows`);
  }
  if (typeof card.card_sha256 !== "string") {
    throw new ModelFileError("card_sha256", "card.json: the card is not sealed (no card_sha256)");
  }
  const actual = await sha256Hex(canonicalCardText(cardText));
  if (actual !== card.card_sha256) {
    throw new ModelFileError("card_sha256", `card.json: card_sha256 ${card.card_sha256.slice(0, 12)}... ` +
      `does not match the card's content (${actual.slice(0, 12)}...): the card was changed`);
  }
  const listed = card.files;
  if (listed === null || typeof listed !== "object" || Object.keys(listed).length === 0) {
    throw new ModelFileError("files", "card.json: the card lists no files");
  }
  for (const [name, digest] of Object.entries(listed)) {
    if (!plainName(name)) throw new ModelFileError("files", `listed file '${name}' is not a plain file name`);
    if (!(name in files)) throw new ModelFileError("files", `listed file '${name}' is missing`);
    const got = await sha256Hex(files[name]);
    if (got !== digest) {
      throw new ModelFileError("files", `${name}: sha256 ${got.slice(0, 12)}... does not match ` +
        `the card's ${String(digest).slice(0, 12)}... (file changed)`);
    }
  }
  if (present !== null) {
    const extra = present.filter((n) => n !== "card.json" && !(n in listed)).sort();
    if (extra.length) {
      throw new ModelFileError("files", `file '${extra[0]}' is not listed in the card ` +
        "(refusing a directory that was changed)");
    }
  }
  return card;
}

// ------------------------------------------------------------------ inputs and encoding

/** Python's format(x, "g"): 6 significant digits, exponent form below 1e-4 and from 1e6. */
export function formatG(x) {
  if (Number.isNaN(x)) return "nan";
  if (!Number.isFinite(x)) return x > 0 ? "inf" : "-inf";
  if (x === 0) return Object.is(x, -0) ? "-0" : "0";
  const [mant, expText] = x.toExponential(5).split("e");
  const e = Number(expText);
  const strip = (s) => (s.includes(".") ? s.replace(/0+$/, "").replace(/\.$/, "") : s);
  if (e < -4 || e >= 6) {
    return `${strip(mant)}e${e < 0 ? "-" : "+"}${String(Math.abs(e)).padStart(2, "0")}`;
  }
  return strip(x.toFixed(5 - e));
}

/** Python's str() of a float as it appears in messages (repr; nan, inf). */
function pythonStr(x) {
  if (Number.isNaN(x)) return "nan";
  if (!Number.isFinite(x)) return x > 0 ? "inf" : "-inf";
  return pythonFloat(x);
}

/** The card's inputs as records with their code range (docs/embedding.md, "Inputs"). */
export function compileSpecs(card) {
  return card.inputs.map((d) => {
    const s = {
      name: d.name, type: d.type, unit: d.unit ?? "", scale: d.scale ?? "linear",
      choices: d.choices ?? [], encoding: d.encoding ?? "onehot", low: d.low, high: d.high,
      usedWhen: d.used_when ? { input: d.used_when.input, atLeast: d.used_when.at_least } : null,
      description: d.description ?? "",
    };
    s.lo = s.type === "categorical" ? 0 : s.low;
    s.hi = s.type === "categorical" ? s.choices.length - 1 : s.high;
    return s;
  });
}

/** Allowed values of an input, worded as the Python predictor words them. */
export function allowed(spec) {
  if (spec.type === "categorical") {
    const names = spec.choices.map((c) => `'${c}'`).join(", ");
    return `one of ${names} (or its index 0..${spec.choices.length - 1})`;
  }
  const unit = spec.unit ? ` ${spec.unit}` : "";
  return `${formatG(spec.low)} <= ${spec.name} <= ${formatG(spec.high)}${unit}`;
}

function asRows(designs) {
  if (Array.isArray(designs)) return designs;
  if (designs !== null && typeof designs === "object") return [designs];
  throw new PredictorInputError("X", "designs must be an object name -> value or a list of them");
}

/** Validate designs (a row object name -> value, or a list of them; a categorical by its
 * choice string or its index). Returns { codes: Float64Array (n * d, row-major), n,
 * extrapolated: boolean[] }; throws PredictorInputError naming the input. */
export function parseInputs(designs, specs, { extrapolate = false } = {}) {
  const rows = asRows(designs);
  const names = specs.map((s) => s.name);
  const n = rows.length;
  const d = specs.length;
  for (const row of rows) {
    const unknown = Object.keys(row).filter((k) => !names.includes(k)).sort();
    if (unknown.length) {
      throw new PredictorInputError(unknown[0], `unknown input '${unknown[0]}'; inputs are ${names.join(", ")}`);
    }
    const missing = names.filter((k) => !(k in row));
    if (missing.length) {
      throw new PredictorInputError(missing[0], `missing input '${missing[0]}'; inputs are ${names.join(", ")}`);
    }
  }
  const codes = new Float64Array(n * d);
  specs.forEach((s, j) => {
    rows.forEach((row, i) => {
      const v = row[s.name];
      if (s.type === "categorical" && typeof v === "string") {
        const k = s.choices.indexOf(v);
        if (k < 0) throw new PredictorInputError(s.name, `${s.name} = '${v}' is not allowed: ${allowed(s)}`);
        codes[i * d + j] = k;
      } else if (typeof v === "number") {
        codes[i * d + j] = v;
      } else {
        throw new PredictorInputError(s.name, `${s.name}: values are not numbers; allowed ${allowed(s)}`);
      }
    });
  });
  specs.forEach((s, j) => { // the predictor's order: per input, first the worst kind of fault
    const col = Array.from({ length: n }, (_, i) => codes[i * d + j]);
    let i = col.findIndex((v) => !Number.isFinite(v));
    if (i >= 0) throw new PredictorInputError(s.name, `${s.name}: row ${i} is ${pythonStr(col[i])} (not finite); allowed ${allowed(s)}`);
    if (s.type !== "continuous") {
      i = col.findIndex((v) => v !== Math.round(v));
      if (i >= 0) throw new PredictorInputError(s.name, `${s.name}: row ${i} = ${formatG(col[i])} is not an integer; allowed ${allowed(s)}`);
    }
    i = col.findIndex((v) => v < s.lo || v > s.hi);
    if (i >= 0 && (!extrapolate || s.type === "categorical")) {
      const hint = s.type === "categorical" ? "" : " (pass extrapolate=True to allow)";
      throw new PredictorInputError(s.name, `${s.name}: row ${i} = ${formatG(col[i])} is outside the trained range: ${allowed(s)}${hint}`);
    }
    if (s.type === "continuous" && s.scale === "log" && col.some((v) => v <= 0)) {
      throw new PredictorInputError(s.name, `${s.name}: a log-scale input must be > 0`);
    }
  });
  const extrapolated = Array.from({ length: n }, (_, i) =>
    specs.some((s, j) => codes[i * d + j] < s.lo || codes[i * d + j] > s.hi));
  return { codes, n, extrapolated };
}

/** Number of feature columns (one-hot categoricals: one per choice; everything else: one). */
export function nFeatures(specs) {
  return specs.reduce((a, s) => a + (s.type === "categorical" && s.encoding === "onehot" ? s.choices.length : 1), 0);
}

/** Encode validated codes to the graph's feature matrix (Float64Array n * F, row-major):
 * one-hot 1/0 per choice; ordinal categorical index / (n_choices - 1); integer and linear
 * (v - low) / (high - low); log (ln v - ln low) / (ln high - ln low); an input whose
 * used_when control is below its minimum encodes as 0. */
export function encode(codes, n, specs) {
  const d = specs.length;
  const F = nFeatures(specs);
  const out = new Float64Array(n * F);
  const index = Object.fromEntries(specs.map((s, j) => [s.name, j]));
  for (let i = 0; i < n; i++) {
    let f = 0;
    specs.forEach((s, j) => {
      const v = codes[i * d + j];
      if (s.type === "categorical" && s.encoding === "onehot") {
        for (let c = 0; c < s.choices.length; c++) out[i * F + f++] = v === c ? 1 : 0;
        return;
      }
      let a;
      let b;
      let x = v;
      if (s.type === "categorical") { a = 0; b = Math.max(s.choices.length - 1, 1); }
      else if (s.scale === "log") { a = Math.log(s.low); b = Math.log(s.high); x = Math.log(v); }
      else { a = s.low; b = s.high; }
      let feature = (x - a) / (b - a);
      if (s.usedWhen && codes[i * d + index[s.usedWhen.input]] < s.usedWhen.atLeast) feature = 0;
      out[i * F + f++] = feature;
    });
  }
  return out;
}

/** The unit's outer radius [mm] per row, from the card's edge_radius table. */
export function edgeRadius(card, specs, codes, n) {
  const rule = card.edge_radius;
  if (!rule || rule.method !== "table") {
    throw new ModelFileError("edge_radius", `edge_radius method '${rule?.method}' unknown (expected 'table')`);
  }
  const d = specs.length;
  const cols = rule.inputs.map((name) => specs.findIndex((s) => s.name === name));
  return Array.from({ length: n }, (_, i) => {
    const key = cols.map((j) => codes[i * d + j]);
    const k = rule.keys.findIndex((row) => row.every((v, c) => v === key[c]));
    if (k < 0) {
      const combo = rule.inputs.map((nm, c) => `'${nm}': ${pythonStr(key[c])}`).join(", ");
      throw new PredictorInputError(rule.inputs[0] ?? "X", `row ${i}: the combination {${combo}} of structural inputs was never trained`);
    }
    return rule.values_mm[k];
  });
}

// ------------------------------------------------------------------ the model

/** A verified model with an onnxruntime session (Node: onnxruntime-node; browser:
 * onnxruntime-web -- the same InferenceSession/Tensor API). */
export class HapticModel {
  constructor(card, session, ort) {
    this.card = card;
    this.session = session;
    this.ort = ort;
    this.specs = compileSpecs(card);
    this.profileDistanceMm = card.profile_distance_mm.slice();
    this.columns = card.log_output_columns;
  }

  /** Verify (see verifyModel) and open a model; `files` maps each listed name to its bytes. */
  static async load({ ort, cardText, files, present = null, sessionOptions = {} }) {
    const card = await verifyModel(cardText, files, { present });
    const graph = card.graph ?? {};
    if (!["float32", "float64"].includes(graph.dtype) || !(graph.file in files)) {
      throw new ModelFileError("graph", "card has no usable 'graph' entry");
    }
    const session = await ort.InferenceSession.create(files[graph.file], sessionOptions);
    return new HapticModel(card, session, ort);
  }

  /** Validated, encoded designs: { codes, n, extrapolated, features (Float64Array) }. */
  features(designs, { extrapolate = false } = {}) {
    const parsed = parseInputs(designs, this.specs, { extrapolate });
    return { ...parsed, features: encode(parsed.codes, parsed.n, this.specs) };
  }

  /** Predict every output for designs: per output name an array over rows (profile_um and
   * its band rows of arrays on profileDistanceMm); log_std per output; extrapolated when
   * `extrapolate` is set (out-of-range numeric inputs are refused otherwise). */
  async predict(designs, { extrapolate = false } = {}) {
    const { codes, n, extrapolated, features } = this.features(designs, { extrapolate });
    const graph = this.card.graph;
    const F = nFeatures(this.specs);
    const data = graph.dtype === "float32" ? Float32Array.from(features) : features;
    const x = new this.ort.Tensor(graph.dtype, data, [n, F]);
    const result = await this.session.run({ [graph.input]: x });
    const [meanName, stdName] = graph.outputs;
    return decode(this.card, result[meanName].data, result[stdName].data, n, {
      edge_radius_mm: edgeRadius(this.card, this.specs, codes, n),
      ...(extrapolate ? { extrapolated } : {}),
    });
  }
}

/** Decode the graph's (n, K) log_mean and log_std (docs/embedding.md, "Outputs"): column k is
 * the natural log of log_output_columns[k]; "name[j]" columns form the array output name. */
export function decode(card, logMean, logStd, n, extra = {}) {
  const cols = card.log_output_columns;
  const K = cols.length;
  // calibrated intervals (docs/embedding.md, section 6): log_std column k times its factor
  const scale = card.interval_calibration?.log_std_scale ?? null;
  if (scale !== null && (!Array.isArray(scale) || scale.length !== K ||
      !scale.every((f) => Number.isFinite(f) && f > 0))) {
    throw new ModelFileError("interval_calibration", `interval_calibration.log_std_scale must ` +
      `be ${K} positive factors, one per log output column (check: card values)`);
  }
  const sd = scale === null ? (i, k) => logStd[i * K + k] : (i, k) => logStd[i * K + k] * scale[k];
  const out = {};
  cols.forEach((col, k) => {
    const m = /^(.+)\[(\d+)\]$/.exec(col);
    const name = m ? m[1] : col;
    for (const [key, fn] of [[name, (i) => Math.exp(logMean[i * K + k])],
      [`${name}_log_std`, (i) => sd(i, k)],
      [`${name}_low95`, (i) => Math.exp(logMean[i * K + k] - Z95 * sd(i, k))],
      [`${name}_high95`, (i) => Math.exp(logMean[i * K + k] + Z95 * sd(i, k))]]) {
      if (!m) { out[key] = Array.from({ length: n }, (_, i) => fn(i)); continue; }
      out[key] ??= Array.from({ length: n }, () => []);
      for (let i = 0; i < n; i++) out[key][i][Number(m[2])] = fn(i);
    }
  });
  out.profile_distance_mm = card.profile_distance_mm.slice();
  return Object.assign(out, extra);
}
