// Build the design explorer into a static directory (default explorer/dist):
//   node explorer/build.mjs [--model MODEL_DIR] [--out DIR]
// bundles app.mjs with onnxruntime-web (esbuild), copies the page, the onnxruntime wasm
// binary and the model (card.json + the files it lists) -- nothing is fetched from a CDN.
import { cpSync, mkdirSync, readFileSync, rmSync, writeFileSync } from "node:fs";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath } from "node:url";
import * as esbuild from "esbuild";

const HERE = dirname(fileURLToPath(import.meta.url));
const argv = process.argv.slice(2);
const opt = (name, fallback) => (argv.includes(name) ? argv[argv.indexOf(name) + 1] : fallback);
const model = resolve(opt("--model", join(HERE, "..", "..", "models", "nn-default")));
const out = resolve(opt("--out", join(HERE, "dist")));

const card = JSON.parse(readFileSync(join(model, "card.json"), "utf8"));
rmSync(out, { recursive: true, force: true });
mkdirSync(join(out, "model"), { recursive: true });
await esbuild.build({
  entryPoints: [join(HERE, "app.mjs")], bundle: true, format: "esm", platform: "browser",
  target: "es2022", minify: true, outfile: join(out, "app.js"), logLevel: "warning",
});
for (const f of ["index.html", "style.css"]) cpSync(join(HERE, f), join(out, f));
const ortDist = join(HERE, "..", "node_modules", "onnxruntime-web", "dist");
mkdirSync(join(out, "ort"));
for (const f of ["ort-wasm-simd-threaded.wasm", "ort-wasm-simd-threaded.mjs"]) cpSync(join(ortDist, f), join(out, "ort", f));
for (const f of ["card.json", ...Object.keys(card.files ?? {})]) cpSync(join(model, f), join(out, "model", f));
writeFileSync(join(out, "build.json"), JSON.stringify({ model, name: card.name, card_sha256: card.card_sha256 ?? null }, null, 1));
console.log(`explorer built (model ${card.name}, ${model})`);
