#!/usr/bin/env node
// Predict with a hapticrom model from Node.js (onnxruntime-node), following docs/embedding.md:
//
//   node node/predict.mjs MODEL_DIR DESIGNS.json [--extrapolate] [--out OUT.json]
//
// DESIGNS.json: one design (an object input name -> value, a categorical as its choice string
// or index) or a list of them. Prints (or writes) {"model", "rows", "outputs"}: per output an
// array over rows, the profile as rows of amplitudes on outputs.profile_distance_mm.
// Exit codes as the hapticrom command line: 0 ok, 2 bad input or a model that fails its check.
import { readFileSync, readdirSync, writeFileSync } from "node:fs";
import { join } from "node:path";
import * as ort from "onnxruntime-node";
import { HapticModel, ModelFileError, PredictorInputError } from "../lib/hapticrom-model.mjs";

function usage(message) {
  process.stderr.write(`predict: ${message}\nusage: node node/predict.mjs MODEL_DIR DESIGNS.json [--extrapolate] [--out OUT.json]\n`);
  process.exit(2);
}

async function main(argv) {
  const args = argv.filter((a) => !a.startsWith("--"));
  const extrapolate = argv.includes("--extrapolate");
  const outAt = argv.indexOf("--out");
  const out = outAt >= 0 ? argv[outAt + 1] : null;
  if (outAt >= 0) args.splice(args.indexOf(out), 1);
  if (args.length !== 2 || (outAt >= 0 && !out)) usage("expected MODEL_DIR and DESIGNS.json");
  const [dir, designsPath] = args;
  const cardText = readFileSync(join(dir, "card.json"), "utf8");
  const entries = readdirSync(dir, { withFileTypes: true });
  const present = entries.map((e) => e.name);
  const regular = new Set(entries.filter((e) => e.isFile()).map((e) => e.name)); // no symlinks
  const listed = Object.keys(JSON.parse(cardText).files ?? {});
  const files = {}; // only regular files of this directory; anything else is reported missing
  for (const name of listed) if (regular.has(name)) files[name] = new Uint8Array(readFileSync(join(dir, name)));
  const model = await HapticModel.load({
    ort, cardText, files, present,
    sessionOptions: { intraOpNumThreads: 1, interOpNumThreads: 1, executionMode: "sequential" },
  });
  const designs = JSON.parse(readFileSync(designsPath, "utf8"));
  const outputs = await model.predict(designs, { extrapolate });
  const text = JSON.stringify({ model: model.card.name, rows: outputs.center_amplitude_um.length, outputs });
  if (out) writeFileSync(out, text);
  else process.stdout.write(`${text}\n`);
}

main(process.argv.slice(2)).catch((err) => {
  if (err instanceof PredictorInputError || err instanceof ModelFileError) {
    process.stderr.write(`predict: error: ${err.message}\n${JSON.stringify({ error: err.name, field: err.field, message: err.message })}\n`);
    process.exit(2);
  }
  if (err?.code === "ENOENT" || err instanceof SyntaxError) {
    process.stderr.write(`predict: error: ${err.message}\n`);
    process.exit(2);
  }
  process.stderr.write(`predict: failed: ${err?.stack ?? err}\n`);
  process.exit(1);
});
