{% raw %}
// rigfem's design-space explorer: look up the picked configuration in the sweep table (embedded JSON),
// show its rules and verdict, animate it by closed-form position analysis, draw maps through it.
(function () {
  "use strict";
  const ALL = JSON.parse(document.getElementById("sweep-data").textContent);
  const FINAL = { "four-bar": { b2: 480, b3: 840, b4: 780, d: 1020 }, "slider-crank": { b2: 300, b3: 840, offset: 0 } };
  const $ = (id) => document.getElementById(id);
  const esc = (s) => String(s).replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" })[c]);
  const at = (col, i) => (Array.isArray(col) ? col[i] : col);  // a column, or one value for every row
  const fmt = (v, n = 1) => (v === null || v === undefined ? "–" : v.toFixed(n));
  let D = null, kind = null, index = null, pos = null, pick = {}, theta = 0, timer = null;
  const key = (vals) => vals.join("|");
  // utilisation (%) -> the report's one scale (rigfem/report/scale.py): its stops 0..100 %, its colour above
  const SCALE = JSON.parse(document.getElementById("util-scale").textContent);
  const WORDS = JSON.parse(document.getElementById("words").textContent);  // rigfem/rig/rules.py's vocabulary
  function colour(u) {
    if (u === null) return SCALE.none;
    if (u > SCALE.range_pct[1]) return SCALE.above;
    const s = SCALE.stops, x = Math.max(0, u) / SCALE.range_pct[1] * (s.length - 1);
    const i = Math.min(s.length - 2, Math.floor(x)), f = x - i;
    return `rgb(${s[i].map((v, j) => Math.round(v + f * (s[i + 1][j] - v))).join(",")})`;
  }
  function setKind(k) {
    kind = k; D = ALL[k]; index = new Map(D.keys.map((v, i) => [key(v), i]));
    pos = new Map(D.computed.map((r, j) => [r, j]));  // table row -> position in the result columns
    const f = FINAL[k] || {};
    $("pickers").innerHTML = D.lengths.map((n) => `<label>${esc(n)} <select data-l="${esc(n)}">` +
      D.grid[n].map((v) => `<option value="${v}">${v}</option>`).join("") + "</select></label>").join("");
    for (const s of $("pickers").querySelectorAll("select")) {
      const n = s.dataset.l, g = D.grid[n];
      pick[n] = g.includes(f[n]) ? f[n] : g[Math.floor(g.length / 2)];
      s.value = String(pick[n]);
      s.addEventListener("change", () => { pick[n] = Number(s.value); update(); });
    }
    update();
  }
  function row() { return index.get(key(D.lengths.map((n) => pick[n]))); }
  function update() {
    for (const s of $("pickers").querySelectorAll("select")) s.value = String(pick[s.dataset.l]);
    const i = row();
    if (i === undefined) {
      $("verdict").innerHTML = '<span class="no">Not on the rig</span>: these lengths do not fit the rails.';
      $("rules").innerHTML = ""; $("facts").innerHTML = "";
    } else { show(i); }
    maps(); drawLinkage();
  }
  function show(i) {
    const status = D.status_names[D.status[i]], meets = D.rules_ok[i] === "1", c = pos.get(i);
    const verdict = c !== undefined && D.verdict[c] >= 0 ? D.verdict_names[D.verdict[c]] : null;
    const assembles = status !== "cannot assemble", u = c === undefined ? null : D.max_util_pct[c];
    const say = (good, text) => `<span class="${good ? "ok" : "no"}">${esc(text[0].toUpperCase() + text.slice(1))}</span>`;
    const broken = D.rules.filter((r) => r.ok[i] !== "1").map((r) => r.name.split(" (")[0]);
    let v = say(assembles, WORDS.assembles[assembles ? 0 : 1]) +
      (assembles ? " (closes over a full turn)" : " (cannot close over a full turn)");
    if (status === "toggle") v += ", but passes a toggle (no stress number)";
    v += ". " + say(meets, WORDS.rules[meets ? 0 : 1]) + (meets ? "" : ": " + esc(broken.join(", "))) + ".";
    if (D.note[i] >= 0) v += ` (${esc(D.note_names[D.note[i]])})`;
    if (verdict) {
      v += ` ${say(verdict === "pass", WORDS.stress[verdict])}: <span class="badge ${esc(verdict)}">` +
        `${esc(verdict.toUpperCase())}</span> at ${fmt(u)} % of σu/2.`;
    }
    $("verdict").innerHTML = v;
    $("rules").innerHTML = "<tr><th>rig rule</th><th>value</th><th>limit</th><th>holds</th></tr>" + D.rules.map((r) =>
      `<tr><td>${esc(r.name)}</td><td class=num>${fmt(at(r.value, i), 1)} ${esc(r.unit)}</td>` +
      `<td class=num>${esc(r.relation)} ${fmt(at(r.limit, i), 1)} ${esc(r.unit)}</td>` +
      `<td class="${r.ok[i] === "1" ? "ok" : "no"}">${r.ok[i] === "1" ? "yes" : "no"}</td></tr>`).join("");
    const e = c === undefined ? null : D.error_pct[c];
    const facts = [];
    if (u !== null) {
      facts.push(["worst part (mode)", esc(D.limiting_part_names[D.limiting_part[c]])]);
      facts.push(["its utilisation", `${fmt(u)} % of σu/2, band ${fmt(u * (1 - e / 100))}–${fmt(u * (1 + e / 100))} % (±${fmt(e)} %)`]);
    } else {
      facts.push(["worst part", "not computed (" + esc(status) + ")"]);
    }
    if (c !== undefined && D.mu_min_deg) facts.push(["transmission angle", `${fmt(D.mu_min_deg[c])}° … ${fmt(D.mu_max_deg[c])}°`]);
    if (c !== undefined) for (const j of D.joints) if (D[`peak_${j}_N`]) facts.push([`peak reaction at ${esc(j)}`, `${fmt(D[`peak_${j}_N`][c], 0)} N`]);
    if (c !== undefined && D.peak_torque_Nm) facts.push(["peak driver torque", `${fmt(D.peak_torque_Nm[c], 2)} N·m`]);
    $("facts").innerHTML = facts.map(([k, x]) => `<tr><th>${k}</th><td>${x}</td></tr>`).join("");
  }
  function positions(t) {  // joint positions (mm) at crank angle t (rad); null where the loop cannot close
    const b2 = pick.b2, b3 = pick.b3, A = [b2 * Math.cos(t), b2 * Math.sin(t)];
    if (kind === "slider-crank") {
      const off = pick.offset || 0, h = off - A[1];
      if (Math.abs(h) > b3) return null;
      return { O2: [0, 0], A, B: [A[0] + Math.sqrt(b3 * b3 - h * h), off], ground: [[-b2, off], [b2 + b3 + 60, off]] };
    }
    const b4 = pick.b4, d = pick.d, O4 = [d, 0], ex = O4[0] - A[0], ey = O4[1] - A[1], e = Math.hypot(ex, ey);
    if (e > b3 + b4 || e < Math.abs(b3 - b4) || e === 0) return null;
    const a = (b3 * b3 - b4 * b4 + e * e) / (2 * e), h = Math.sqrt(Math.max(0, b3 * b3 - a * a));
    const B = [A[0] + a * ex / e - h * ey / e, A[1] + a * ey / e + h * ex / e];  // the open branch
    return { O2: [0, 0], A, B, O4, ground: [[0, 0], O4] };
  }
  function drawLinkage() {
    const cv = $("anim"), g = cv.getContext("2d");
    g.fillStyle = "#fff"; g.fillRect(0, 0, cv.width, cv.height);
    const span = kind === "slider-crank" ? pick.b2 * 2 + pick.b3 + 120 : Math.max(pick.d + pick.b2 + pick.b4, 2 * (pick.b2 + pick.b3));
    const s = (cv.width - 60) / span, ox = 30 + (kind === "slider-crank" ? pick.b2 * s : pick.b2 * s), oy = cv.height / 2;
    const P = (p) => [ox + s * p[0], oy - s * p[1]];
    const q = row() === undefined ? null : positions(theta * Math.PI / 180);
    g.font = "15px system-ui, sans-serif";
    $("theta-out").textContent = `${theta}°`;
    if (!q) { g.fillStyle = "#c62828"; g.fillText("this linkage cannot be assembled at this crank angle", 20, 30); return; }
    g.strokeStyle = "#999"; g.setLineDash([6, 4]); g.lineWidth = 2; g.beginPath();
    g.moveTo(...P(q.ground[0])); g.lineTo(...P(q.ground[1])); g.stroke(); g.setLineDash([]);
    const links = kind === "slider-crank" ? [["O2", "A", "#1565c0", "b2 crank"], ["A", "B", "#ef6c00", "b3 rod"]]
      : [["O2", "A", "#1565c0", "b2 crank"], ["A", "B", "#ef6c00", "b3 coupler"], ["O4", "B", "#2e7d32", "b4 rocker"]];
    g.lineWidth = 7; g.lineCap = "round";
    for (const [a, b, c, label] of links) {
      g.strokeStyle = c; g.beginPath(); g.moveTo(...P(q[a])); g.lineTo(...P(q[b])); g.stroke();
      const m = P([(q[a][0] + q[b][0]) / 2, (q[a][1] + q[b][1]) / 2]); g.fillStyle = c; g.fillText(label, m[0] + 8, m[1] - 8);
    }
    g.fillStyle = "#111";
    for (const n of Object.keys(q)) {
      if (n === "ground") continue;
      const p = P(q[n]); g.beginPath(); g.arc(p[0], p[1], 6, 0, 2 * Math.PI); g.fill(); g.fillText(n, p[0] + 8, p[1] + 18);
    }
    if (kind === "slider-crank") { const p = P(q.B); g.strokeRect(p[0] - 18, p[1] - 12, 36, 24); }
  }
  function ticks(lo, hi, n) {  // about n round tick values (mm) from lo to hi
    const step = [60, 120, 180, 300, 600].find((t) => (hi - lo) / t <= n) || 1200, out = [];
    for (let v = Math.ceil(lo / step) * step; v <= hi; v += step) out.push(v);
    return out;
  }
  function colourBar(g, x0, y0, w, h) {  // 0..100 % of σu/2 upwards, magenta above
    const top = y0 + 26, span = h - 26;
    for (let k = 0; k < span; k++) { g.fillStyle = colour(100 * (1 - k / span)); g.fillRect(x0, top + k, w, 1.5); }
    g.fillStyle = SCALE.above; g.fillRect(x0, y0, w, 14);
    g.fillStyle = "#111"; g.font = "12px system-ui, sans-serif"; g.textAlign = "left";
    g.fillText("> 100", x0 + w + 4, y0 + 11);
    for (let v = 0; v <= 100; v += 20) g.fillText(String(v), x0 + w + 4, top + span * (1 - v / 100) + 4);
    g.save(); g.translate(x0 + w + 52, y0 + h / 2); g.rotate(-Math.PI / 2); g.textAlign = "center";
    g.fillText("peak utilisation (% of σu/2)", 0, 0); g.restore();
  }
  function maps() {
    const host = $("maps"); host.innerHTML = "";
    const pairs = kind === "four-bar" ? [["d", "b3"], ["b4", "b3"]] : [["b2", "b3"]];
    for (const [x, y] of pairs) {
      const cv = document.createElement("canvas"); cv.width = 600; cv.height = 440; host.appendChild(cv);
      const g = cv.getContext("2d"), X = D.grid[x], Y = D.grid[y], L = 70, T = 40, R = 110, B = 56;
      const cell = (a, b) => {  // the table row with the picked lengths but X[a], Y[b] (undefined: not on the rig)
        const at = Object.assign({}, pick, { [x]: X[a], [y]: Y[b] });
        return index.get(key(D.lengths.map((n) => at[n])));
      };
      // crop to the cells with a number in this slice and the pick, with one cell of margin
      let a0 = X.indexOf(pick[x]), a1 = a0, b0 = Y.indexOf(pick[y]), b1 = b0;
      for (let a = 0; a < X.length; a++) for (let b = 0; b < Y.length; b++) {
        const i = cell(a, b);
        if (i !== undefined && pos.has(i)) { a0 = Math.min(a0, a); a1 = Math.max(a1, a); b0 = Math.min(b0, b); b1 = Math.max(b1, b); }
      }
      a0 = Math.max(0, a0 - 1); a1 = Math.min(X.length - 1, a1 + 1); b0 = Math.max(0, b0 - 1); b1 = Math.min(Y.length - 1, b1 + 1);
      const xs = X.slice(a0, a1 + 1), ys = Y.slice(b0, b1 + 1);
      const w = (cv.width - L - R) / xs.length, h = (cv.height - T - B) / ys.length;
      cv.dataset.cells = `${xs.length}x${ys.length}`;
      g.fillStyle = "#fff"; g.fillRect(0, 0, cv.width, cv.height);
      for (let a = 0; a < xs.length; a++) for (let b = 0; b < ys.length; b++) {
        const i = cell(a0 + a, b0 + b), c = i === undefined ? undefined : pos.get(i);
        const px = L + a * w, py = T + (ys.length - 1 - b) * h;
        g.fillStyle = i === undefined ? "#fff" : colour(c === undefined ? null : D.max_util_pct[c]);
        g.fillRect(px, py, w + 0.5, h + 0.5);
        if (c !== undefined && D.rules_ok[i] !== "1") {  // computed, does not meet the rig rules: hatched
          g.save(); g.beginPath(); g.rect(px, py, w, h); g.clip();
          g.strokeStyle = "rgba(255,255,255,0.85)"; g.lineWidth = 1; g.beginPath();
          for (let k = 0; k < w + h; k += 9) { g.moveTo(px + k, py + h); g.lineTo(px + k + h, py); g.moveTo(px - k, py + h); g.lineTo(px - k + h, py); }
          g.stroke(); g.restore();
        }
        if (c !== undefined && D.verdict[c] >= 0 && D.verdict_names[D.verdict[c]] !== "pass") {
          g.strokeStyle = "#d50000"; g.lineWidth = 1.5; g.strokeRect(px + 1, py + 1, w - 2, h - 2);
        }
      }
      const a = xs.indexOf(pick[x]), b = ys.indexOf(pick[y]);
      g.strokeStyle = "#fff"; g.lineWidth = 3; g.beginPath();
      g.arc(L + (a + 0.5) * w, T + (ys.length - 0.5 - b) * h, Math.max(6, Math.min(w, h, 60) * 0.4), 0, 2 * Math.PI); g.stroke();
      g.strokeStyle = "#000"; g.lineWidth = 1; g.stroke();
      g.fillStyle = "#111"; g.font = "14px system-ui, sans-serif"; g.textAlign = "left";
      const fixed = D.lengths.filter((n) => n !== x && n !== y).map((n) => `${n} = ${pick[n]} mm`).join(", ");
      g.fillText(fixed ? `${y} over ${x}, at ${fixed}` : `${y} over ${x}`, L, 24);
      g.font = "12px system-ui, sans-serif"; g.textAlign = "center";
      for (const v of ticks(xs[0], xs[xs.length - 1], 8)) g.fillText(String(v), L + (xs.indexOf(v) + 0.5) * w, cv.height - B + 18);
      g.textAlign = "right";
      for (const v of ticks(ys[0], ys[ys.length - 1], 8)) g.fillText(String(v), L - 6, T + (ys.length - 0.5 - ys.indexOf(v)) * h + 4);
      g.font = "14px system-ui, sans-serif"; g.textAlign = "center";
      g.fillText(`${x} (mm)`, L + (cv.width - L - R) / 2, cv.height - 12);
      g.save(); g.translate(20, T + (cv.height - T - B) / 2); g.rotate(-Math.PI / 2); g.fillText(`${y} (mm)`, 0, 0); g.restore();
      colourBar(g, cv.width - R + 14, T, 16, cv.height - T - B);
      g.textAlign = "left";
      cv.addEventListener("click", (ev) => {
        const r = cv.getBoundingClientRect(), px = (ev.clientX - r.left) * cv.width / r.width, py = (ev.clientY - r.top) * cv.height / r.height;
        const ia = Math.floor((px - L) / w), ib = ys.length - 1 - Math.floor((py - T) / h);
        if (ia >= 0 && ia < xs.length && ib >= 0 && ib < ys.length) { pick[x] = xs[ia]; pick[y] = ys[ib]; update(); }
      });
    }
  }
  $("theta").addEventListener("input", (e) => { theta = Number(e.target.value); drawLinkage(); });
  $("play").addEventListener("click", (e) => {
    if (timer) { clearInterval(timer); timer = null; e.target.textContent = "▶ play"; return; }
    e.target.textContent = "❚❚ pause"; start();
  });
  function start() { timer = setInterval(() => { theta = (theta + 3) % 360; $("theta").value = String(theta); drawLinkage(); }, 40); }
  $("kind").addEventListener("change", (e) => setKind(e.target.value));
  setKind($("kind").value);
  start();
})();
{% endraw %}
