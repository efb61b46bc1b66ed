// The design explorer: every input of the model as a slider or a choice; the predicted centre
// and edge amplitudes and the profile with its 95 % band redrawn on every change; a small
// array preview. The model runs in the page (onnxruntime-web, wasm bundled with the page).
import * as ort from "onnxruntime-web/wasm";
import { HapticModel, formatG } from "../lib/hapticrom-model.mjs";
import { leakageRatios, sitePositions, unitField } from "./array.mjs";

ort.env.wasm.wasmPaths = new URL("./ort/", document.baseURI).href;
ort.env.wasm.numThreads = 1; // no SharedArrayBuffer needed (plain file server)
ort.env.wasm.proxy = false;

const SVG = "http://www.w3.org/2000/svg";
const STEPS = 400; // slider positions across a continuous input's trained range
const $ = (id) => document.getElementById(id);
const state = { model: null, design: {}, outputs: null, response: null, array: { rows: 3, cols: 3, grid: "square", pitch: null }, runs: 0 };
let pending = Promise.resolve();

function el(tag, attrs = {}, parent = null, ns = null) {
  const e = ns ? document.createElementNS(ns, tag) : document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (parent) parent.appendChild(e);
  return e;
}

// slider position <-> value (log inputs move evenly in log)
function toValue(spec, pos) {
  const t = pos / STEPS;
  if (spec.scale === "log") return Math.exp(Math.log(spec.low) + t * (Math.log(spec.high) - Math.log(spec.low)));
  return spec.low + t * (spec.high - spec.low);
}
function toPos(spec, v) {
  if (spec.scale === "log") return Math.round((STEPS * Math.log(v / spec.low)) / Math.log(spec.high / spec.low));
  return Math.round((STEPS * (v - spec.low)) / (spec.high - spec.low));
}
const shown = (v) => formatG(Number(v.toPrecision(4)));

/** Axis ticks 0, step, ... covering max, step 1, 2, 2.5 or 5 times a power of ten. */
function niceTicks(max, n = 4) {
  const raw = max / n;
  const p = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 2.5, 5, 10].map((m) => m * p).find((v) => v >= raw);
  return Array.from({ length: Math.ceil(max / step - 1e-9) + 1 }, (_, k) => k * step);
}

function buildInputs(specs) {
  const box = $("inputs");
  for (const s of specs) {
    const row = el("div", { class: "input", id: `in-${s.name}` }, box);
    const label = el("label", { for: `ctl-${s.name}` }, row);
    const slug = (t) => t.toLowerCase().replace(/[^a-z0-9]/g, "");
    label.textContent = s.unit && !slug(s.name).endsWith(slug(s.unit)) ? `${s.name} [${s.unit}]` : s.name;
    const out = el("output", { id: `val-${s.name}` }, label);
    let ctl;
    if (s.type === "categorical") {
      ctl = el("select", { id: `ctl-${s.name}`, name: s.name }, row);
      s.choices.forEach((c) => { el("option", { value: c }, ctl).textContent = c; });
      ctl.addEventListener("change", () => change(s.name, ctl.value));
    } else {
      const integer = s.type === "integer";
      ctl = el("input", {
        type: "range", id: `ctl-${s.name}`, name: s.name,
        min: integer ? s.low : 0, max: integer ? s.high : STEPS, step: 1,
      }, row);
      ctl.addEventListener("input", () => change(s.name, integer ? Number(ctl.value) : toValue(s, Number(ctl.value))));
    }
    if (s.description) row.title = s.description;
    out.textContent = "";
  }
}

function showInputs() {
  for (const s of state.model.specs) {
    const v = state.design[s.name];
    const ctl = $(`ctl-${s.name}`);
    if (s.type === "categorical") ctl.value = v;
    else ctl.value = s.type === "integer" ? v : toPos(s, v);
    $(`val-${s.name}`).textContent = s.type === "categorical" ? "" : shown(v);
    const used = !s.usedWhen || state.design[s.usedWhen.input] >= s.usedWhen.atLeast;
    $(`in-${s.name}`).classList.toggle("unused", !used);
  }
}

function change(name, value) {
  state.design = { ...state.design, [name]: value };
  return update();
}

/** Predict the current design and redraw everything (changes are queued, never lost). */
function update() {
  pending = pending.then(async () => {
    showInputs();
    try {
      state.outputs = await state.model.predict([state.design]);
      state.response = await frequencyResponse();
      $("status").textContent = "";
    } catch (err) {
      state.outputs = null;
      $("status").textContent = err.message;
    }
    draw();
    state.runs += 1;
  });
  return pending;
}

/** Centre and edge amplitude at FREQS frequencies across the model's trained band (when the
 * model has a frequency input), everything else as the current design. */
const FREQS = 31;
async function frequencyResponse() {
  const spec = state.model.specs.find((s) => s.name === "frequency_hz");
  if (!spec) return null;
  const f = Array.from({ length: FREQS }, (_, k) => spec.low + ((spec.high - spec.low) * k) / (FREQS - 1));
  const o = await state.model.predict(f.map((v) => ({ ...state.design, frequency_hz: v })));
  return { f, center: o.center_amplitude_um, edge: o.edge_amplitude_um };
}

function setNumber(id, value, unit, digits = 4) {
  const e = $(id);
  e.dataset.value = String(value);
  e.textContent = `${Number(value.toPrecision(digits))} ${unit}`.trim();
}

function draw() {
  const o = state.outputs;
  if (!o) return;
  setNumber("center", o.center_amplitude_um[0], "µm");
  setNumber("edge", o.edge_amplitude_um[0], "µm");
  setNumber("ratio", o.normalized_edge[0], "");
  setNumber("radius", o.edge_radius_mm[0], "mm", 3);
  drawProfile(o);
  drawResponse(state.response);
  drawArray(o);
}

function drawResponse(r) {
  const svg = $("response");
  svg.replaceChildren();
  if (!r) return;
  const W = 640, H = 220, L = 56, R = 16, T = 14, B = 38;
  const yt = niceTicks(Math.max(...r.center, ...r.edge));
  const ymax = yt[yt.length - 1];
  const x = (v) => L + ((v - r.f[0]) / (r.f[r.f.length - 1] - r.f[0])) * (W - L - R);
  const y = (v) => T + (1 - v / ymax) * (H - T - B);
  const pts = (ys) => r.f.map((v, k) => `${x(v).toFixed(2)},${y(ys[k]).toFixed(2)}`).join(" ");
  el("polyline", { id: "resp-center", points: pts(r.center), fill: "none", stroke: "#08519c", "stroke-width": "2" }, svg, SVG);
  el("polyline", { id: "resp-edge", points: pts(r.edge), fill: "none", stroke: "#e6550d", "stroke-width": "2", "stroke-dasharray": "5 3" }, svg, SVG);
  const f0 = state.design.frequency_hz;
  el("line", { x1: x(f0), y1: T, x2: x(f0), y2: H - B, stroke: "#999", "stroke-dasharray": "2 2" }, svg, SVG);
  el("line", { x1: L, y1: H - B, x2: W - R, y2: H - B, stroke: "#444" }, svg, SVG);
  el("line", { x1: L, y1: T, x2: L, y2: H - B, stroke: "#444" }, svg, SVG);
  for (const v of yt) el("text", { x: L - 6, y: y(v) + 4, "text-anchor": "end", "font-size": "11" }, svg, SVG).textContent = shown(v);
  for (let k = 0; k <= 4; k++) {
    const fv = r.f[0] + ((r.f[r.f.length - 1] - r.f[0]) * k) / 4;
    el("text", { x: x(fv), y: H - B + 16, "text-anchor": "middle", "font-size": "11" }, svg, SVG).textContent = shown(fv);
  }
  el("text", { x: (L + W - R) / 2, y: H - 4, "text-anchor": "middle", "font-size": "12" }, svg, SVG).textContent = "frequency [Hz]";
  el("text", { x: 14, y: (T + H - B) / 2, "text-anchor": "middle", "font-size": "12", transform: `rotate(-90 14 ${(T + H - B) / 2})` }, svg, SVG).textContent = "amplitude [µm]";
  el("text", { x: W - R - 4, y: H - B - 8, "text-anchor": "end", "font-size": "11", fill: "#08519c" }, svg, SVG).textContent = "centre (solid), edge (dashed); dotted: this design";
}

function drawProfile(o) {
  const svg = $("profile");
  svg.replaceChildren();
  const d = o.profile_distance_mm;
  const lo = o.profile_um_low95[0];
  const hi = o.profile_um_high95[0];
  const mid = o.profile_um[0];
  const W = 640, H = 300, L = 56, R = 16, T = 16, B = 40;
  const yt = niceTicks(Math.max(...hi, o.center_amplitude_um[0]));
  const ymax = yt[yt.length - 1];
  const x = (v) => L + ((v - d[0]) / (d[d.length - 1] - d[0])) * (W - L - R);
  const y = (v) => T + (1 - v / ymax) * (H - T - B);
  const pts = (xs, ys) => xs.map((v, k) => `${x(v).toFixed(2)},${y(ys[k]).toFixed(2)}`).join(" ");
  el("polygon", { id: "band", points: `${pts(d, hi)} ${pts([...d].reverse(), [...lo].reverse())}`, fill: "#9ecae1", opacity: "0.6" }, svg, SVG);
  el("polyline", { id: "mean", points: pts(d, mid), fill: "none", stroke: "#08519c", "stroke-width": "2" }, svg, SVG);
  el("line", { x1: L, y1: H - B, x2: W - R, y2: H - B, stroke: "#444" }, svg, SVG);
  el("line", { x1: L, y1: T, x2: L, y2: H - B, stroke: "#444" }, svg, SVG);
  for (const v of yt) el("text", { x: L - 6, y: y(v) + 4, "text-anchor": "end", "font-size": "11" }, svg, SVG).textContent = shown(v);
  for (let k = 0; k <= 4; k++) {
    const dv = d[0] + ((d[d.length - 1] - d[0]) * k) / 4;
    el("text", { x: x(dv), y: H - B + 16, "text-anchor": "middle", "font-size": "11" }, svg, SVG).textContent = shown(dv);
  }
  el("text", { x: (L + W - R) / 2, y: H - 6, "text-anchor": "middle", "font-size": "12" }, svg, SVG).textContent = "distance from the unit's edge [mm]";
  el("text", { x: 14, y: (T + H - B) / 2, "text-anchor": "middle", "font-size": "12", transform: `rotate(-90 14 ${(T + H - B) / 2})` }, svg, SVG).textContent = "amplitude [µm]";
  el("text", { x: W - R, y: T + 12, "text-anchor": "end", "font-size": "11", fill: "#08519c" }, svg, SVG).textContent = "mean, shaded: 95 % band";
}

function arrayControls() {
  const box = $("array-controls");
  const add = (name, label, attrs, read) => {
    const row = el("div", { class: "input" }, box);
    const lab = el("label", { for: `arr-${name}` }, row);
    lab.textContent = label;
    el("output", { id: `arrval-${name}` }, lab);
    const ctl = el(attrs.tag ?? "input", { id: `arr-${name}`, ...attrs.attrs }, row);
    (attrs.options ?? []).forEach((c) => { el("option", { value: c }, ctl).textContent = c; });
    ctl.addEventListener(attrs.tag === "select" ? "change" : "input", () => { state.array[name] = read(ctl.value); drawArray(state.outputs); });
    return ctl;
  };
  add("pitch", "pitch [mm]", { attrs: { type: "range", min: 8, max: 40, step: 0.5, value: 20 } }, Number);
  add("rows", "rows x cols", { attrs: { type: "range", min: 2, max: 5, step: 1, value: 3 } }, (v) => { state.array.cols = Number(v); return Number(v); });
  add("grid", "grid", { tag: "select", options: ["square", "hex"] }, String);
  state.array.pitch = 20;
}

function drawArray(o) {
  if (!o) return;
  const a = state.array;
  const r0 = o.edge_radius_mm[0];
  const pitch = Math.max(a.pitch, 2 * r0);
  $("arrval-pitch").textContent = shown(pitch);
  $("arrval-rows").textContent = `${a.rows} x ${a.cols}`;
  const field = unitField(o.center_amplitude_um[0], r0, o.profile_distance_mm, o.profile_um[0]);
  const pos = sitePositions(a.rows, a.cols, pitch, a.grid);
  const leak = leakageRatios(field, pos);
  const svg = $("array");
  svg.replaceChildren();
  const xs = pos.map((p) => p[0]), ys = pos.map((p) => p[1]);
  const span = Math.max(Math.max(...xs) - Math.min(...xs), Math.max(...ys) - Math.min(...ys)) + 2 * r0 + 4;
  const s = 280 / span;
  const cx = (150 - (s * (Math.max(...xs) + Math.min(...xs))) / 2), cy = (150 - (s * (Math.max(...ys) + Math.min(...ys))) / 2);
  const worst = Math.max(...leak);
  pos.forEach(([px, py], i) => {
    const shade = Math.round(230 - 180 * Math.min(leak[i] / 0.5, 1));
    el("circle", { cx: cx + s * px, cy: cy + s * py, r: s * r0, fill: `rgb(255,${shade},${shade})`, stroke: "#444" }, svg, SVG);
  });
  const nb = field.amplitude(pitch);
  const box = $("array-numbers");
  box.innerHTML = "";
  const line = (id, text, value) => { const p = el("p", { id }, box); p.textContent = text; p.dataset.value = String(value); };
  line("arr-neighbour", `one neighbour at ${shown(pitch)} mm: ${shown(nb)} µm (${shown(100 * nb / field.centerUm)} % of the centre)`, nb);
  line("arr-crosstalk", `worst site leakage (all others, incoherent): ${shown(100 * worst)} %`, worst);
  line("arr-note", "darker: more leakage at that site; the planner's rules (planner/crosstalk.py)", worst);
}

async function fetchBytes(url) {
  const r = await fetch(url);
  if (!r.ok) throw new Error(`${url}: HTTP ${r.status}`);
  return new Uint8Array(await r.arrayBuffer());
}

async function main() {
  const cardText = await (await fetch("model/card.json")).text();
  const listed = Object.keys(JSON.parse(cardText).files ?? {});
  const files = Object.fromEntries(await Promise.all(listed.map(async (n) => [n, await fetchBytes(`model/${n}`)])));
  const model = await HapticModel.load({ ort, cardText, files, sessionOptions: { executionProviders: ["wasm"] } });
  state.model = model;
  $("model-line").textContent = `${model.card.name} (${model.card.kind}): ${model.card.predicts}`;
  buildInputs(model.specs);
  arrayControls();
  const design = {}; // the middle of every range (geometric middle of log inputs), first choices
  for (const s of model.specs) {
    if (s.type === "categorical") design[s.name] = s.choices[0];
    else if (s.type === "integer") design[s.name] = Math.round((s.low + s.high) / 2);
    else design[s.name] = toValue(s, STEPS / 2);
  }
  state.design = design;
  await update();
}

// For tests and scripts: the page's state, and a way to set a whole design at once.
window.hapticromExplorer = {
  state,
  ready: main().then(() => true, (err) => { $("status").textContent = `the model failed to load: ${err.message}`; throw err; }),
  setDesign: (design) => { state.design = { ...design }; return update(); },
};
