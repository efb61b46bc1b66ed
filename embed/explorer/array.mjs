// Crosstalk of a small array of identical units from one unit's predicted profile: the same
// rules as the planner's planner/crosstalk.py (amplitude at a centre distance from the log
// envelope of the profile, the last quarter's log-slope beyond it; incoherent superposition).

/** One unit's field: amplitude [um] at centre distances r [mm] >= its edge radius. */
export function unitField(centerUm, edgeRadiusMm, distanceMm, profileUm) {
  const logP = profileUm.map(Math.log);
  const envelope = logP.slice();
  for (let k = envelope.length - 2; k >= 0; k--) envelope[k] = Math.max(envelope[k], envelope[k + 1]);
  const g = distanceMm;
  const last = g[g.length - 1];
  const tail = g.map((v, k) => k).filter((k) => g[k] >= last - 0.25 * (last - g[0]));
  let slope = 0;
  if (tail.length > 1) { // least-squares line through the tail of the envelope
    const mx = tail.reduce((a, k) => a + g[k], 0) / tail.length;
    const my = tail.reduce((a, k) => a + envelope[k], 0) / tail.length;
    const sxy = tail.reduce((a, k) => a + (g[k] - mx) * (envelope[k] - my), 0);
    const sxx = tail.reduce((a, k) => a + (g[k] - mx) ** 2, 0);
    slope = Math.min(sxy / sxx, 0);
  }
  function amplitude(r) {
    const d = r - edgeRadiusMm;
    if (d > last) return Math.exp(envelope[envelope.length - 1] + slope * (d - last));
    const x = Math.min(Math.max(d, g[0]), last);
    let k = 0;
    while (k < g.length - 2 && g[k + 1] < x) k++;
    const t = (x - g[k]) / (g[k + 1] - g[k]);
    return Math.exp(envelope[k] + t * (envelope[k + 1] - envelope[k]));
  }
  return { centerUm, edgeRadiusMm, amplitude };
}

/** Site centres [mm] of a rows x cols grid; "hex" offsets odd rows by half a pitch. */
export function sitePositions(rows, cols, pitchMm, grid) {
  const out = [];
  for (let i = 0; i < rows; i++) {
    for (let j = 0; j < cols; j++) {
      const x = j + (grid === "hex" ? 0.5 * (i % 2) : 0);
      const y = grid === "hex" ? (i * Math.sqrt(3)) / 2 : i;
      out.push([pitchMm * x, pitchMm * y]);
    }
  }
  return out;
}

/** Per site: leakage from all other units (root sum of squares) / its own amplitude. */
export function leakageRatios(field, positions) {
  return positions.map(([xi, yi], i) => {
    let sum = 0;
    positions.forEach(([xj, yj], j) => {
      if (i !== j) sum += field.amplitude(Math.hypot(xi - xj, yi - yj)) ** 2;
    });
    return Math.sqrt(sum) / field.centerUm;
  });
}
