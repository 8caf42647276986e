{% raw %}
// rigfem's offline 3-D view: the part's surface triangles painted (back to front) on a 2-D canvas,
// coloured by utilisation per crank angle; drag turns, wheel zooms, the slider steps the cycle.
(function () {
  "use strict";
  const parts = JSON.parse(document.getElementById("v-data").textContent);
  const cv = document.getElementById("v-canvas"), g = cv.getContext("2d");
  const sel = document.getElementById("v-part"), slider = document.getElementById("v-frame");
  const angle = document.getElementById("v-angle"), peak = document.getElementById("v-peak");
  const bytes = (b64) => Uint8Array.from(atob(b64), (c) => c.charCodeAt(0)).buffer;
  let P = null, yaw = 0.6, pitch = -0.5, zoom = 1, timer = null;
  function load(k) {
    const d = parts[k];
    const pos = new Float32Array(bytes(d.pos));
    const tri = d.tri_bytes === 2 ? new Uint16Array(bytes(d.tri)) : new Uint32Array(bytes(d.tri));
    const util = new Uint16Array(bytes(d.util));
    const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    for (let i = 0; i < pos.length; i++) { lo[i % 3] = Math.min(lo[i % 3], pos[i]); hi[i % 3] = Math.max(hi[i % 3], pos[i]); }
    const c = lo.map((v, i) => (v + hi[i]) / 2), r = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) / 2 || 1;
    const held = d.held ? new Uint8Array(bytes(d.held)) : null;  // per vertex: 0, or its support's number
    const fmax = Math.max(1e-9, ...(d.loads || []).flat().map((l) => Math.hypot(...l.force)));  // N, over the cycle
    P = { d, pos, tri, util, c, r, n: d.vertices, held, fmax };
    slider.max = String(d.angles.length - 1); slider.value = String(d.governing || 0);  // opens at the governing angle
    draw();
  }
  // utilisation (%) -> the report's one scale (rigfem/report/scale.py): its stops 0..100 %, its colour above
  const SCALE = JSON.parse(document.getElementById("util-scale").textContent);
  const LOAD = "#d81b60";  // the pin loads' colour, as in the report's pictures
  function colour(u) {
    if (u > SCALE.range_pct[1]) return SCALE.above;
    const s = SCALE.stops, t = Math.max(0, Math.min(1, u / SCALE.range_pct[1]));
    const x = t * (s.length - 1), i = Math.min(s.length - 2, Math.floor(x)), f = x - i;
    return s[i].map((v, j) => Math.round(v + f * (s[i + 1][j] - v)));
  }
  function draw() {
    const k = Number(slider.value), { pos, tri, util, c, r, n, d, held, fmax } = P;
    const cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
    const s = zoom * 0.45 * Math.min(cv.width, cv.height) / r;
    const proj = (px, py, pz) => {  // a point of the part frame (mm) -> canvas x, y and depth
      const x = px - c[0], y = py - c[1], z = pz - c[2], x1 = cy * x + sy * y, y1 = -sy * x + cy * y;
      return [cv.width / 2 + s * x1, cv.height / 2 - s * (cp * z - sp * y1), sp * z + cp * y1];
    };
    const X = new Float32Array(n), Y = new Float32Array(n), Z = new Float32Array(n);
    for (let i = 0; i < n; i++) [X[i], Y[i], Z[i]] = proj(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]);
    const m = tri.length / 3, order = new Uint32Array(m), depth = new Float32Array(m);
    for (let t = 0; t < m; t++) { order[t] = t; depth[t] = Z[tri[3 * t]] + Z[tri[3 * t + 1]] + Z[tri[3 * t + 2]]; }
    order.sort((a, b) => depth[b] - depth[a]);
    g.fillStyle = "#fff"; g.fillRect(0, 0, cv.width, cv.height);
    const base = k * n;
    for (const t of order) {
      const a = tri[3 * t], b = tri[3 * t + 1], e = tri[3 * t + 2];
      const u = (util[base + a] + util[base + b] + util[base + e]) / 300;
      const ux = X[b] - X[a], uy = Y[b] - Y[a], vx = X[e] - X[a], vy = Y[e] - Y[a];
      const ax = pos[3 * b] - pos[3 * a], ay = pos[3 * b + 1] - pos[3 * a + 1], az = pos[3 * b + 2] - pos[3 * a + 2];
      const bx = pos[3 * e] - pos[3 * a], by = pos[3 * e + 1] - pos[3 * a + 1], bz = pos[3 * e + 2] - pos[3 * a + 2];
      const nx = ay * bz - az * by, ny = az * bx - ax * bz, nz = ax * by - ay * bx, nl = Math.hypot(nx, ny, nz) || 1;
      const vz = (sp * nz + cp * (-sy * nx + cy * ny)) / nl;  // normal towards the viewer
      const light = 0.55 + 0.45 * Math.abs(vz);
      const sup = held && held[a] && held[a] === held[b] && held[b] === held[e];  // a support's face: dark
      const col = sup ? [48, 48, 48] : colour(u);
      g.fillStyle = typeof col === "string" ? col : `rgb(${col.map((v) => Math.round(v * light)).join(",")})`;
      g.beginPath(); g.moveTo(X[a], Y[a]); g.lineTo(X[b], Y[b]); g.lineTo(X[e], Y[e]); g.closePath(); g.fill();
      if (Math.abs(ux * vy - uy * vx) < 0.5) continue;
      g.strokeStyle = g.fillStyle; g.lineWidth = 0.5; g.stroke();
    }
    const labels = [];  // drawn last, each moved down until it overlaps none before it
    (d.supports || []).forEach((name, j) => {  // each support named at the middle of its surface
      let sx = 0, sy2 = 0, m = 0;
      for (let i = 0; i < n; i++) if (held[i] === j + 1) { sx += X[i]; sy2 += Y[i]; m++; }
      if (m) labels.push([sx / m, sy2 / m, `held: ${name}`, "#202020", "#fff"]);
    });
    for (const l of (d.loads || [])[k] || []) {  // each pin load: an arrow onto its hole, length ∝ force
      const f = Math.hypot(...l.force), len = 0.35 * r * f / fmax, u3 = l.force.map((v) => v / (f || 1));
      const [hx, hy] = proj(...l.at), [tx, ty] = proj(...l.at.map((v, i) => v - len * u3[i]));
      const ang = Math.atan2(hy - ty, hx - tx);
      g.strokeStyle = g.fillStyle = LOAD; g.lineWidth = 4;
      g.beginPath(); g.moveTo(tx, ty); g.lineTo(hx, hy); g.stroke();
      g.beginPath(); g.moveTo(hx, hy);
      g.lineTo(hx - 16 * Math.cos(ang - 0.4), hy - 16 * Math.sin(ang - 0.4));
      g.lineTo(hx - 16 * Math.cos(ang + 0.4), hy - 16 * Math.sin(ang + 0.4)); g.closePath(); g.fill();
      labels.push([tx, ty, `${l.name}: ${f.toFixed(0)} N`, LOAD, "#fff"]);
    }
    let top = 0;  // the peak of this crank angle: a ringed dot and its value
    for (let i = 1; i < n; i++) if (util[base + i] > util[base + top]) top = i;
    g.lineWidth = 3; g.strokeStyle = "#000"; g.fillStyle = "#fff";
    g.beginPath(); g.arc(X[top], Y[top], 7, 0, 2 * Math.PI); g.fill(); g.stroke();
    g.fillStyle = "#000"; g.beginPath(); g.arc(X[top], Y[top], 3, 0, 2 * Math.PI); g.fill();
    g.font = "bold 15px system-ui, sans-serif";
    const tag = `peak ${(util[base + top] / 100).toFixed(1)} %`, tw = g.measureText(tag).width;
    const tx = Math.min(X[top] + 12, cv.width - 100 - tw), ty = Math.max(Y[top] - 12, 20);
    g.fillStyle = "rgba(255,255,255,0.85)"; g.fillRect(tx - 4, ty - 15, tw + 8, 21);
    g.fillStyle = "#000"; g.fillText(tag, tx, ty);
    const taken = [[tx - 4, ty - 15, tw + 8, 21]];
    g.font = "14px system-ui, sans-serif";
    for (const [x, y, text, bg, fg] of labels) {
      const w = g.measureText(text).width + 8;
      let bx = Math.max(4, Math.min(x + 8, cv.width - 110 - w)), by = Math.max(4, Math.min(y + 8, cv.height - 24));
      while (taken.some(([a, b, c2, h]) => bx < a + c2 && a < bx + w && by < b + h && b < by + 20) && by < cv.height - 24) by += 22;
      taken.push([bx, by, w, 20]);
      g.fillStyle = bg; g.fillRect(bx, by, w, 20); g.fillStyle = fg; g.fillText(text, bx + 4, by + 15);
    }
    g.fillStyle = "#111";
    if (d.free_body) g.fillText("free body: no support (the pin loads balance its inertia)", 10, cv.height - 10);
    legend();
    const gov = k === (d.governing || 0) ? ", governing: the highest peak of the cycle" : "";
    angle.textContent = `${d.angles[k].toFixed(1)}° (${k + 1} of ${d.angles.length}${gov})`;
    peak.textContent = `peak at this angle: ${d.peak[k].toFixed(1)} % of the allowable`;
  }
  function legend() {
    const x = cv.width - 70, y0 = 40, h = 200;
    for (let i = 0; i < h; i++) { const m = colour(100 * (1 - i / h)); g.fillStyle = `rgb(${m.join(",")})`; g.fillRect(x, y0 + i, 18, 1); }
    g.fillStyle = SCALE.above; g.fillRect(x, y0 - 22, 18, 18);
    g.fillStyle = "#111"; g.font = "14px system-ui, sans-serif";
    g.fillText("> 100 %", x - 4, y0 - 28); g.fillText("100 %", x + 22, y0 + 5); g.fillText("50 %", x + 22, y0 + h / 2 + 5);
    g.fillText("0 %", x + 22, y0 + h + 5); g.fillText("utilisation", x - 20, y0 + h + 28);
    g.fillStyle = LOAD; g.fillRect(x - 20, y0 + h + 44, 18, 4); g.fillStyle = "#111"; g.fillText("pin load", x + 2, y0 + h + 51);
    g.fillStyle = "#303030"; g.fillRect(x - 20, y0 + h + 60, 18, 12); g.fillStyle = "#111"; g.fillText("support", x + 2, y0 + h + 71);
  }
  let drag = null;
  cv.addEventListener("pointerdown", (e) => { drag = [e.clientX, e.clientY]; cv.setPointerCapture(e.pointerId); });
  cv.addEventListener("pointerup", () => { drag = null; });
  cv.addEventListener("pointermove", (e) => {
    if (!drag) return;
    yaw += (e.clientX - drag[0]) * 0.01; pitch += (e.clientY - drag[1]) * 0.01; drag = [e.clientX, e.clientY]; draw();
  });
  cv.addEventListener("wheel", (e) => { e.preventDefault(); zoom *= e.deltaY < 0 ? 1.15 : 1 / 1.15; draw(); }, { passive: false });
  document.getElementById("v-zin").addEventListener("click", () => { zoom *= 1.25; draw(); });
  document.getElementById("v-zout").addEventListener("click", () => { zoom /= 1.25; draw(); });
  document.getElementById("v-reset").addEventListener("click", () => { yaw = 0.6; pitch = -0.5; zoom = 1; draw(); });
  slider.addEventListener("input", draw);
  sel.addEventListener("change", () => load(Number(sel.value)));
  document.getElementById("v-play").addEventListener("click", (e) => {
    if (timer) { clearInterval(timer); timer = null; e.target.textContent = "▶ play"; return; }
    e.target.textContent = "❚❚ pause";
    timer = setInterval(() => { slider.value = String((Number(slider.value) + 1) % (P.d.angles.length)); draw(); }, 400);
  });
  load(0);
})();
{% endraw %}
