// Drive the built explorer in a real headless chromium (playwright-core), offline:
//   node explorer/check.mjs --url http://127.0.0.1:PORT/ --designs designs.json --out result.json
//                           [--screenshot shot.png] [--chromium /usr/bin/chromium]
// Every request to another origin is refused and reported. Writes {offline, errors, slider,
// designs}: the page's numbers after a slider is moved with the keyboard, and for every
// design the numbers shown on the page and the predicted profile.
import { readFileSync, writeFileSync, mkdtempSync, rmSync } from "node:fs";
import { tmpdir } from "node:os";
import { join } from "node:path";
import { chromium } from "playwright-core";

const argv = process.argv.slice(2);
const opt = (name, fallback = null) => (argv.includes(name) ? argv[argv.indexOf(name) + 1] : fallback);
const url = opt("--url");
const designs = JSON.parse(readFileSync(opt("--designs"), "utf8"));
const profile = mkdtempSync(join(tmpdir(), "hapticrom-chromium-"));
const browser = await chromium.launchPersistentContext(profile, { // a fresh user-data-dir
  executablePath: opt("--chromium", "/usr/bin/chromium"),
  headless: true,
  viewport: { width: 1180, height: 860 },
  args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync"],
});
const result = { offline: [], errors: [], slider: null, designs: [] };
try {
  const page = await browser.newPage();
  const origin = new URL(url).origin;
  await page.route("**/*", (route) => {
    const u = route.request().url();
    if (u.startsWith(origin) || u.startsWith("data:") || u.startsWith("blob:")) return route.continue();
    result.offline.push(u);
    return route.abort();
  });
  page.on("pageerror", (e) => result.errors.push(String(e)));
  page.on("console", (m) => { if (m.type() === "error") result.errors.push(m.text()); });
  await page.goto(url, { waitUntil: "load" });
  await page.evaluate(() => window.hapticromExplorer.ready);
  const snapshot = () => page.evaluate(() => ({
    runs: window.hapticromExplorer.state.runs,
    mean: document.getElementById("mean")?.getAttribute("points"),
    band: document.getElementById("band")?.getAttribute("points"),
    center: Number(document.getElementById("center").dataset.value),
    frequency_hz: window.hapticromExplorer.state.design.frequency_hz,
    status: document.getElementById("status").textContent,
  }));
  const before = await snapshot();
  await page.focus("#ctl-frequency_hz");
  await page.keyboard.press("End"); // a user moving the slider to its end
  await page.waitForFunction((n) => window.hapticromExplorer.state.runs > n, before.runs);
  result.slider = { before, after: await snapshot() };
  for (const d of designs) {
    result.designs.push(await page.evaluate(async (design) => {
      const ex = window.hapticromExplorer;
      await ex.setDesign(design);
      const num = (id) => Number(document.getElementById(id).dataset.value);
      const o = ex.state.outputs;
      return {
        status: document.getElementById("status").textContent,
        center_amplitude_um: num("center"), edge_amplitude_um: num("edge"),
        normalized_edge: num("ratio"), edge_radius_mm: num("radius"),
        profile_um: o?.profile_um[0], profile_um_low95: o?.profile_um_low95[0],
        profile_um_high95: o?.profile_um_high95[0],
        array: { ...ex.state.array, neighbour_um: num("arr-neighbour"),
          worst_leakage: num("arr-crosstalk") },
      };
    }, d));
  }
  const shot = opt("--screenshot");
  if (shot) {
    await page.evaluate((d) => window.hapticromExplorer.setDesign(d), designs[designs.length - 1]);
    await page.screenshot({ path: shot, fullPage: true });
  }
} finally {
  await browser.close();
  rmSync(profile, { recursive: true, force: true });
}
writeFileSync(opt("--out"), JSON.stringify(result));
