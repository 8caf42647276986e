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
    const status = D.status_names[D.status[i]], mounts = D.rules_ok[i] === "1", c = pos.get(i);
    const verdict = c !== undefined && D.verdict[c] >= 0 ? D.verdict_names[D.verdict[c]] : null;
    let v = mounts ? '<span class="ok">Mounts</span>: every rig rule holds.' : '<span class="no">Does not mount</span>: a rig rule is broken.';
    v += ` Status: ${esc(status)}`;
    if (D.note[i] >= 0) v += ` (${esc(D.note_names[D.note[i]])})`;
    if (verdict) v += `. Verdict <span class="badge ${esc(verdict)}">${esc(verdict.toUpperCase())}</span>`;
    $("verdict").innerHTML = v + ".";
    $("rules").innerHTML = "<tr><th>rig rule</th><th>value</th><th>limit</th><th>holds</th></tr>" + D.rules.map((r) =>
      `<tr><td>${esc(r.name)}</td><td class=num>${fmt(at(r.value, i), 1)} ${esc(r.unit)}</td>` +
      `<td class=num>${esc(r.relation)} ${fmt(at(r.limit, i), 1)} ${esc(r.unit)}</td>` +
      `<td class="${r.ok[i] === "1" ? "ok" : "no"}">${r.ok[i] === "1" ? "yes" : "no"}</td></tr>`).join("");
    const u = c === undefined ? null : D.max_util_pct[c], e = c === undefined ? null : D.error_pct[c];
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
  function maps() {
    const host = $("maps"); host.innerHTML = "";
    const pairs = kind === "four-bar" ? [["d", "b3"], ["b4", "b3"]] : [["b2", "b3"]];
    for (const [x, y] of pairs) {
      const cv = document.createElement("canvas"); cv.width = 520; cv.height = 420; host.appendChild(cv);
      const g = cv.getContext("2d"), xs = D.grid[x], ys = D.grid[y], L = 60, B = 50;
      const w = (cv.width - L - 20) / xs.length, h = (cv.height - B - 40) / ys.length;
      g.fillStyle = "#fff"; g.fillRect(0, 0, cv.width, cv.height);
      for (let a = 0; a < xs.length; a++) for (let b = 0; b < ys.length; b++) {
        const at = Object.assign({}, pick, { [x]: xs[a], [y]: ys[b] });
        const i = index.get(key(D.lengths.map((n) => at[n])));
        const c = i === undefined ? undefined : pos.get(i);
        g.fillStyle = i === undefined ? "#fff" : colour(c === undefined ? null : D.max_util_pct[c]);
        g.fillRect(L + a * w, 40 + (ys.length - 1 - b) * h, w + 0.5, h + 0.5);
      }
      const a = xs.indexOf(pick[x]), b = ys.indexOf(pick[y]);
      g.strokeStyle = "#fff"; g.lineWidth = 3; g.beginPath();
      g.arc(L + (a + 0.5) * w, 40 + (ys.length - 0.5 - b) * h, Math.max(6, Math.min(w, h) * 0.6), 0, 2 * Math.PI); g.stroke();
      g.strokeStyle = "#000"; g.lineWidth = 1; g.stroke();
      g.fillStyle = "#111"; g.font = "14px system-ui, sans-serif";
      const fixed = D.lengths.filter((n) => n !== x && n !== y).map((n) => `${n} = ${pick[n]}`).join(", ");
      g.fillText(`${y} over ${x} (mm)${fixed ? ", " + fixed + " mm" : ""}`, L, 24);
      for (let k = 0; k < xs.length; k += Math.ceil(xs.length / 8)) g.fillText(String(xs[k]), L + k * w, cv.height - B + 24);
      for (let k = 0; k < ys.length; k += Math.ceil(ys.length / 8)) g.fillText(String(ys[k]), 6, 40 + (ys.length - 0.5 - k) * h + 5);
      g.fillText(`${x} (mm)`, cv.width / 2, cv.height - 6);
      g.save(); g.translate(14, cv.height / 2); g.rotate(-Math.PI / 2); g.restore();
      cv.addEventListener("click", (ev) => {
        const r = cv.getBoundingClientRect(), px = (ev.clientX - r.left) * cv.width / r.width, py = (ev.clientY - r.top) * cv.height / r.height;
        const ia = Math.floor((px - L) / w), ib = ys.length - 1 - Math.floor((py - 40) / h);
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
