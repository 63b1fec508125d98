#include "plotting/result_page_assets.h"

namespace tailsim {

const char* const kResultPageCss = R"CSS(
body{font-family:sans-serif;margin:0;color:#222;background:#fafafa}
header{background:#234;color:#fff;padding:.5em 1em;display:flex;gap:1em;align-items:center;flex-wrap:wrap}
header h1{font-size:1.2em;margin:0}header a{color:#9cf}header select{max-width:40em}
main{padding:0 1em 2em 1em;max-width:1400px}
section{margin:1em 0}h2{font-size:1.1em;border-bottom:1px solid #ccc;margin:.8em 0 .4em 0}
.notes li{color:#a40}.keys li{margin:.1em 0}
#overview{display:flex;gap:1em;align-items:flex-start;flex-wrap:wrap}
#map{border:1px solid #ccc;background:#fff;cursor:pointer}
.tablebox{position:relative;height:330px;overflow-y:auto;border:1px solid #ccc;background:#fff;font-size:13px}
.thead{display:flex;background:#eee;border:1px solid #ccc;border-bottom:0;font-size:13px;font-weight:bold}
.row{position:absolute;left:0;right:0;height:22px;display:flex;align-items:center;cursor:pointer;white-space:nowrap}
.row:nth-child(even){background:#f4f6f8}.row:hover{background:#dde8f4}.row.sel{background:#fde7b0}
.cell{flex:0 1 9em;min-width:5.5em;overflow:hidden;text-overflow:ellipsis;padding:0 .4em}.cell.name{flex:1 1 16em;min-width:10em}
.thead .cell{cursor:pointer;padding:.3em .4em}.bad{color:#b00}.warn{color:#a60}
#replay{display:flex;gap:.6em;flex-wrap:wrap;align-items:flex-start}
#view3d{width:600px;height:420px;border:1px solid #ccc;background:#fff;position:relative}
#view3d canvas{display:block}
#hud{position:absolute;left:6px;top:4px;font-size:12px;background:rgba(255,255,255,.8);padding:2px 4px;pointer-events:none}
#legend{position:absolute;right:6px;bottom:4px;font-size:12px;background:rgba(255,255,255,.8);padding:2px 4px;pointer-events:none}
#plots{border:1px solid #ccc;background:#fff;cursor:crosshair}
.controls{display:flex;gap:.6em;align-items:center;margin:.4em 0;flex-wrap:wrap}
.controls input[type=range]{width:420px}
.figs{display:flex;flex-wrap:wrap;gap:.6em}.figs img{width:420px;border:1px solid #ddd;background:#fff}
.muted{color:#777}#expdesc{overflow-wrap:anywhere;max-height:8em;overflow-y:auto}
)CSS";

const char* const kResultPageBody = R"HTML(<header><h1 id="title">tailsim results</h1>
<label>experiment <select id="expsel"></select></label><a id="figlink" href="figures.html" hidden>all figures (figures.html)</a></header>
<main>
<section><h2 id="exptitle"></h2><p id="expdesc"></p><ul id="keys" class="keys"></ul><ul id="notes" class="notes"></ul></section>
<section id="overviewsec"><h2>Results over the swept keys</h2><div id="overview"><canvas id="map" width="560" height="360"></canvas>
<div><label>model <select id="mapmodel"></select></label><p id="mapnote" class="muted"></p></div></div></section>
<section><h2>Cases</h2><div class="controls"><label>filter <input id="filter" size="30" placeholder="part of a case name"></label>
<label><input type="checkbox" id="onlybad"> only failed or warned</label><span id="count" class="muted"></span></div>
<div class="thead" id="thead"></div><div class="tablebox" id="tablebox"><div id="spacer"></div></div></section>
<section id="replaysec"><h2 id="replaytitle">Replay</h2><p id="replaynote" class="muted">Click a case, a heat-map cell or a point to open its replay.</p>
<div class="controls"><button id="play">play</button><input type="range" id="scrub" min="0" max="1000" value="0">
<span id="tlabel">t = 0.000 s</span><label>speed <select id="speed"><option>0.1</option><option>0.25</option>
<option>0.5</option><option selected>1</option><option>2</option></select></label></div>
<div id="replay"><div id="view3d"><div id="hud"></div><div id="legend"></div></div><canvas id="plots" width="520" height="420"></canvas></div></section>
<section><h2>Figures</h2><div id="figs" class="figs"></div></section>
</main>
)HTML";

// The page's script. Globals: THREE (three.min.js, OrbitControls.js) and window.tailsim, whose
// dataLoaded / caseLoaded receive data.js and the case files, and whose state / seek / openCase /
// clickMap let a test drive the page.
const char* const kResultPageJs = R"JS('use strict';
(function () {
  const T = window.tailsim = {};
  const $ = (id) => document.getElementById(id);
  const DEG = Math.PI / 180;
  let data = null, ei = 0, exp = null, order = [], mapModel = null, grid = null;
  const loaded = {};  // case id -> case data
  const view = { c: null, k: -1, t: 0, t0: 0, t1: 0, playing: false, speed: 1, applied: {}, three: null, lastFrame: 0 };

  function el(tag, attrs, text) {
    const e = document.createElement(tag);
    for (const a in attrs || {}) e.setAttribute(a, attrs[a]);
    if (text !== undefined) e.textContent = text;
    return e;
  }
  function fmt(v, d) {
    if (v === null || v === undefined || !isFinite(v)) return '';
    const s = (+v).toFixed(d === undefined ? 3 : d);
    return /^-0(\.0*)?$/.test(s) ? s.slice(1) : s;  // no "-0.00"
  }
  function clear(e) { while (e.firstChild) e.removeChild(e.firstChild); }

  // ------------------------------------------------------------------ the experiment
  T.dataLoaded = function (d) {
    data = d;
    document.title = 'tailsim: ' + d.folder;
    $('title').textContent = 'tailsim results: ' + d.folder;
    $('figlink').hidden = !d.figures_html;
    if (d.note) $('title').appendChild(el('small', { class: 'note' }, ' (' + d.note + ')'));
    const sel = $('expsel');
    d.experiments.forEach((e, i) => sel.appendChild(el('option', { value: i }, e.name)));
    sel.parentNode.hidden = d.experiments.length < 2;
    sel.onchange = () => selectExperiment(+sel.value);
    $('filter').oninput = applyFilter;
    $('onlybad').onchange = applyFilter;
    $('tablebox').onscroll = renderRows;
    $('mapmodel').onchange = () => { mapModel = $('mapmodel').value; drawMap(); };
    $('play').onclick = () => (view.playing ? T.pause() : T.play());
    $('scrub').oninput = () => T.seek(view.t0 + (view.t1 - view.t0) * $('scrub').value / 1000);
    $('speed').onchange = () => { view.speed = +$('speed').value; };
    $('map').onclick = (ev) => { const r = $('map').getBoundingClientRect(); T.clickMap(ev.clientX - r.left, ev.clientY - r.top); };
    $('plots').onclick = (ev) => {
      const r = $('plots').getBoundingClientRect(), p = plotFrame();
      if (view.c) T.seek(view.t0 + (ev.clientX - r.left - p.x0) / (p.x1 - p.x0) * (view.t1 - view.t0));
    };
    selectExperiment(0);
    requestAnimationFrame(tick);
  };

  T.experiments = () => data.experiments.map((e) => e.name);
  T.selectExperiment = (i) => selectExperiment(i);
  function selectExperiment(i) {
    ei = i; exp = data.experiments[i];
    $('expsel').value = i;
    $('exptitle').textContent = exp.name + (exp.kind === 'pose' ? ' (poses)' : '');
    $('expdesc').textContent = exp.description;
    const keys = $('keys'); clear(keys);
    exp.axes.forEach((a) => keys.appendChild(el('li', {}, 'swept: ' + a.label + ' (' + a.key + '): ' +
      (a.values.length > 12 ? a.values.slice(0, 6).join(', ') + ', ... (' + a.values.length + ' values)' : a.values.join(', ')))));
    if (!exp.axes.length) keys.appendChild(el('li', {}, 'no swept key'));
    const notes = $('notes'); clear(notes);
    exp.notes.forEach((n) => notes.appendChild(el('li', {}, n)));
    // Warnings: each distinct text with its number of runs, folded when there are many.
    const nw = {};
    let runs = 0;
    exp.models.forEach((m) => exp.cases.runs[m.name].warnings.forEach((w) => { if (w) { nw[w] = (nw[w] || 0) + 1; ++runs; } }));
    const texts = Object.keys(nw);
    if (texts.length) {
      const li = el('li'), det = el('details'), list = el('ul');
      det.appendChild(el('summary', {}, runs + ' run(s) with warnings (' + texts.length + ' distinct; "only failed or warned" below lists them)'));
      texts.slice(0, 200).forEach((w) => list.appendChild(el('li', {}, nw[w] + ' run(s): ' + w)));
      if (texts.length > 200) list.appendChild(el('li', {}, '... and ' + (texts.length - 200) + ' more'));
      det.appendChild(list); li.appendChild(det); notes.appendChild(li);
      det.open = texts.length <= 3;
    }
    const ms = $('mapmodel'); clear(ms);
    exp.models.forEach((m) => ms.appendChild(el('option', { value: m.name }, m.title)));
    mapModel = exp.models.length ? exp.models[0].name : null;
    buildGrid(); drawMap(); buildTable(); drawFigures();
    $('overviewsec').hidden = !exp.axes.length;
    if (exp.cases.name.length === 1 && exp.cases.replay[0] !== null) T.openCase(i, 0);  // one case: show it
  }

  // ------------------------------------------------------------------ heat map / line
  function buildGrid() {
    grid = null;
    const ax = exp.axes;
    if (ax.length < 1) return;
    const n = exp.cases.name.length;
    if (ax.length === 1) {
      grid = { kind: 'line', x: ax[0] };
      return;
    }
    // As the figures' heat map (plots.cc): the first swept key up, the second across.
    const nx = ax[1].values.length, ny = ax[0].values.length;
    const cell = new Int32Array(nx * ny).fill(-1);
    for (let k = 0; k < n; ++k) {
      let other = true;
      for (let a = 2; a < ax.length; ++a) if (ax[a].index[k] !== 0) other = false;
      const ix = ax[1].index[k], iy = ax[0].index[k];
      if (other && ix >= 0 && iy >= 0 && cell[iy * nx + ix] < 0) cell[iy * nx + ix] = k;
    }
    grid = { kind: 'map', x: ax[1], y: ax[0], nx: nx, ny: ny, cell: cell };
  }
  const MAP = { x0: 70, y0: 20, x1: 470, y1: 310 };
  // The figures' colour maps (style.h): sequential white - orange - dark orange when every value
  // has one sign (dark at the largest magnitude), diverging blue - white - vermillion centred on
  // zero when the values have both signs.
  const SEQ = [[255, 253, 247], [230, 159, 0], [122, 74, 0]];
  const DIV = [[0, 114, 178], [140, 191, 224], [247, 247, 247], [238, 173, 126], [213, 94, 0]];
  function ramp(s, u) {
    u = Math.max(0, Math.min(1, u)) * (s.length - 1); const i = Math.min(s.length - 2, Math.floor(u)), f = u - i;
    return 'rgb(' + s[i].map((c, j) => Math.round(c + f * (s[i + 1][j] - c))).join(',') + ')';
  }
  function mapScale(lo, hi) {
    if (lo < 0 && hi > 0) { const m = Math.max(-lo, hi); return { kind: 'diverging', lo: -m, hi: m }; }
    return { kind: 'sequential', lo: lo, hi: hi, dark_at_low: hi <= 0 && lo < 0 };
  }
  function darkness(sc, v) {  // 0 light .. 1 dark
    const u = (v - sc.lo) / (sc.hi - sc.lo);
    return sc.kind === 'diverging' ? Math.abs(2 * u - 1) : sc.dark_at_low ? 1 - u : u;
  }
  function colour(sc, v) {
    const u = (v - sc.lo) / (sc.hi - sc.lo);
    return sc.kind === 'diverging' ? ramp(DIV, u) : ramp(SEQ, sc.dark_at_low ? 1 - u : u);
  }
  T.mapScale = () => view.mapScale || null;
  function drawMap() {
    const cv = $('map'), g = cv.getContext('2d');
    g.clearRect(0, 0, cv.width, cv.height);
    g.font = '12px sans-serif'; g.fillStyle = '#222';
    $('mapnote').textContent = '';
    if (!grid || !mapModel) { g.fillText('no swept key: one case', 20, 30); return; }
    const phi = exp.cases.runs[mapModel].phi_net_deg;
    let lo = Infinity, hi = -Infinity;
    phi.forEach((v) => { if (v !== null) { lo = Math.min(lo, v); hi = Math.max(hi, v); } });
    if (!(hi >= lo)) { lo = 0; hi = 1; }
    if (hi === lo) hi = lo + 1;
    const W = MAP.x1 - MAP.x0, H = MAP.y1 - MAP.y0;
    if (grid.kind === 'map') {
      const sc = view.mapScale = mapScale(lo, hi);
      const cw = W / grid.nx, ch = H / grid.ny;
      for (let iy = 0; iy < grid.ny; ++iy) for (let ix = 0; ix < grid.nx; ++ix) {
        const k = grid.cell[iy * grid.nx + ix];
        const v = k < 0 ? null : phi[k];
        g.fillStyle = v === null ? '#ddd' : colour(sc, v);
        g.fillRect(MAP.x0 + ix * cw, MAP.y1 - (iy + 1) * ch, Math.ceil(cw), Math.ceil(ch));
        if (v !== null && cw >= 36 && ch >= 14) {
          g.fillStyle = darkness(sc, v) > 0.6 ? '#fff' : '#222';
          g.fillText(fmt(v, 2), MAP.x0 + (ix + 0.5) * cw - 12, MAP.y1 - (iy + 0.5) * ch + 4);
        }
        if (view.c && k === view.k) {
          g.strokeStyle = '#f00'; g.lineWidth = 2; g.strokeRect(MAP.x0 + ix * cw + 1, MAP.y1 - (iy + 1) * ch + 1, cw - 2, ch - 2);
        }
      }
      g.fillStyle = '#222';
      axisTicks(g, grid.x, MAP.x0, MAP.x1, true); axisTicks(g, grid.y, MAP.y1, MAP.y0, false);
      g.fillText(grid.x.label, MAP.x0 + W / 2 - 30, MAP.y1 + 34);
      g.save(); g.translate(14, MAP.y0 + H / 2 + 30); g.rotate(-Math.PI / 2); g.fillText(grid.y.label, 0, 0); g.restore();
      for (let i = 0; i <= 50; ++i) { g.fillStyle = colour(sc, sc.lo + i / 50 * (sc.hi - sc.lo)); g.fillRect(MAP.x1 + 20, MAP.y1 - (i + 1) * H / 51, 14, H / 51 + 1); }
      g.fillStyle = '#222';
      g.fillText(fmt(sc.hi, 2), MAP.x1 + 38, MAP.y0 + 8); g.fillText(fmt(sc.lo, 2), MAP.x1 + 38, MAP.y1);
      if (sc.kind === 'diverging') g.fillText('0', MAP.x1 + 38, (MAP.y0 + MAP.y1) / 2 + 4);
      g.fillText('φ_net [deg]', MAP.x1 + 20, MAP.y0 - 6);
      if (exp.axes.length > 2) $('mapnote').textContent = 'Other swept keys at their first value.';
    } else {
      const a = grid.x, xs = a.numbers;
      lo = Infinity; hi = -Infinity;  // every model is drawn: the range of them all
      exp.models.forEach((m) => exp.cases.runs[m.name].phi_net_deg.forEach((v) => {
        if (v !== null) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
      }));
      if (!(hi >= lo)) { lo = 0; hi = 1; }
      if (hi === lo) hi = lo + 1;
      let xl = Math.min.apply(null, xs), xh = Math.max.apply(null, xs); if (xh === xl) xh = xl + 1;
      const X = (x) => MAP.x0 + (x - xl) / (xh - xl) * W, Y = (v) => MAP.y1 - (v - lo) / (hi - lo) * H;
      g.strokeStyle = '#888'; g.strokeRect(MAP.x0, MAP.y0, W, H);
      exp.models.forEach((m) => {
        const p = exp.cases.runs[m.name].phi_net_deg, pts = [];
        for (let k = 0; k < p.length; ++k) if (a.index[k] >= 0 && p[k] !== null) pts.push([xs[a.index[k]], p[k], k]);
        pts.sort((u, v) => u[0] - v[0]);
        g.strokeStyle = m.color; g.fillStyle = m.color; g.lineWidth = 1.5; g.beginPath();
        pts.forEach((q, i) => (i ? g.lineTo(X(q[0]), Y(q[1])) : g.moveTo(X(q[0]), Y(q[1]))));
        g.stroke();
        pts.forEach((q) => { g.beginPath(); g.arc(X(q[0]), Y(q[1]), q[2] === view.k && view.c ? 5 : 3, 0, 7); g.fill(); });
      });
      g.fillStyle = '#222';
      axisTicks(g, { values: null, numbers: null, lo: xl, hi: xh }, MAP.x0, MAP.x1, true);
      axisTicks(g, { values: null, numbers: null, lo: lo, hi: hi }, MAP.y1, MAP.y0, false);
      g.fillText(a.label, MAP.x0 + W / 2 - 30, MAP.y1 + 34);
      g.save(); g.translate(14, MAP.y0 + H / 2 + 30); g.rotate(-Math.PI / 2); g.fillText('φ_net [deg]', 0, 0); g.restore();
      $('mapnote').textContent = 'Every model; click a point to open its case.';
    }
  }
  // Ticks at round numbers of a continuous range (lo, hi), or at the values of a grid axis.
  function niceTicks(lo, hi, n) {
    const span = hi - lo, raw = span / Math.max(1, n), p = Math.pow(10, Math.floor(Math.log10(raw)));
    const step = [1, 2, 5, 10].map((m) => m * p).find((s) => s >= raw) || raw;
    const out = [];
    for (let v = Math.ceil(lo / step) * step; v <= hi + 1e-9 * span; v += step) out.push(Math.abs(v) < 1e-12 * step ? 0 : v);
    return out;
  }
  function axisTicks(g, a, p0, p1, horizontal) {
    g.font = '11px sans-serif';
    if (a.values && a.numeric && a.values.length > 12) {
      // many numeric values (a range): ticks at round numbers, placed between the cell centres
      const n = a.values.length, lo = Math.min.apply(null, a.numbers), hi = Math.max.apply(null, a.numbers);
      niceTicks(lo, hi, 6).forEach((v) => {
        const p = p0 + ((v - lo) / (hi - lo) * (n - 1) + 0.5) / n * (p1 - p0), s = String(+v.toPrecision(6));
        if (horizontal) g.fillText(s, p - 8, MAP.y1 + 16); else g.fillText(s, 24, p + 4);
      });
      return;
    }
    if (a.values) {
      const n = a.values.length, every = Math.ceil(n / 8);
      for (let i = 0; i < n; i += every) {
        const p = p0 + (i + 0.5) / n * (p1 - p0);
        if (horizontal) g.fillText(a.values[i], p - 10, MAP.y1 + 16); else g.fillText(a.values[i], 4 + 20, p + 4);
      }
      return;
    }
    niceTicks(a.lo, a.hi, 6).forEach((v) => {
      const p = p0 + (v - a.lo) / (a.hi - a.lo) * (p1 - p0), s = String(+v.toPrecision(6));
      if (horizontal) g.fillText(s, p - 8, MAP.y1 + 16); else g.fillText(s, 24, p + 4);
    });
  }
  // The case under a point of the map canvas (CSS pixels), opened; returns its index or -1.
  T.clickMap = function (x, y) {
    if (!grid) return -1;
    const W = MAP.x1 - MAP.x0, H = MAP.y1 - MAP.y0;
    let k = -1;
    if (grid.kind === 'map') {
      const ix = Math.floor((x - MAP.x0) / W * grid.nx), iy = Math.floor((MAP.y1 - y) / H * grid.ny);
      if (ix >= 0 && ix < grid.nx && iy >= 0 && iy < grid.ny) k = grid.cell[iy * grid.nx + ix];
    } else {
      const a = grid.x, xs = a.numbers;
      lo = Infinity; hi = -Infinity;  // every model is drawn: the range of them all
      exp.models.forEach((m) => exp.cases.runs[m.name].phi_net_deg.forEach((v) => {
        if (v !== null) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
      }));
      if (!(hi >= lo)) { lo = 0; hi = 1; }
      if (hi === lo) hi = lo + 1;
      let xl = Math.min.apply(null, xs), xh = Math.max.apply(null, xs); if (xh === xl) xh = xl + 1;
      let best = 15;
      for (let c = 0; c < exp.cases.name.length; ++c) {
        if (a.index[c] < 0) continue;
        const d = Math.abs(MAP.x0 + (xs[a.index[c]] - xl) / (xh - xl) * W - x);
        if (d < best) { best = d; k = c; }
      }
    }
    if (k >= 0) T.openCase(ei, k);
    return k;
  };
  // Where the map draws case k (CSS pixels of the canvas), for tests.
  T.mapPoint = function (k) {
    const W = MAP.x1 - MAP.x0, H = MAP.y1 - MAP.y0;
    if (!grid || grid.kind !== 'map') return null;
    const ix = exp.axes[1].index[k], iy = exp.axes[0].index[k];
    return { x: MAP.x0 + (ix + 0.5) * W / grid.nx, y: MAP.y1 - (iy + 0.5) * H / grid.ny };
  };

  // ------------------------------------------------------------------ the table (virtualised)
  const ROW = 22;
  let columns = [], sortCol = -1, sortDir = 1, shown = [];
  function buildTable() {
    columns = [{ title: 'case', cls: 'name', get: (k) => exp.cases.name[k], text: true }];
    exp.axes.forEach((a) => columns.push({ title: a.label, get: (k) => (a.index[k] >= 0 ? (a.numeric ? a.numbers[a.index[k]] : a.values[a.index[k]]) : null),
      show: (k) => (a.index[k] >= 0 ? a.values[a.index[k]] : '') }));
    exp.models.forEach((m) => {
      const r = exp.cases.runs[m.name];
      // MuJoCo's phi_net with its own uncertainty, as the run's table prints it.
      const u = r.phi_net_uncertainty_deg || [];
      columns.push({ title: m.title + ' φ_net [deg]', get: (k) => r.phi_net_deg[k],
        show: (k) => fmt(r.phi_net_deg[k], 3) + (Number.isFinite(u[k]) ? ' ± ' + fmt(u[k], 3) : '') });
      columns.push({ title: m.title + ' t_stop [s]', get: (k) => r.t_stop_s[k], show: (k) => fmt(r.t_stop_s[k], 3) });
      columns.push({ title: m.title + ' status', text: true, get: (k) => (r.ok[k] === 0 ? 'failed: ' + r.error[k] : r.warnings[k] ? 'warning: ' + r.warnings[k] : r.ok[k] === 1 ? 'ok' : ''),
        cls: (k) => (r.ok[k] === 0 ? 'bad' : r.warnings[k] ? 'warn' : '') });
    });
    // The verdict across the models (experiments/verdict.h), where the run gave one.
    const verdict = exp.cases.verdict || [];
    if (verdict.some((v) => v)) columns.push({ title: 'verdict', text: true, get: (k) => verdict[k] || '' });
    const head = $('thead'); clear(head);
    columns.forEach((c, i) => {
      const h = el('div', { class: 'cell' + (c.cls === 'name' ? ' name' : '') }, c.title);
      h.onclick = () => { sortDir = sortCol === i ? -sortDir : 1; sortCol = i; applyFilter(); };
      head.appendChild(h);
    });
    sortCol = -1; applyFilter();
  }
  function applyFilter() {
    const n = exp.cases.name.length, f = $('filter').value.toLowerCase(), bad = $('onlybad').checked;
    const runs = exp.models.map((m) => exp.cases.runs[m.name]);
    shown = [];
    for (let k = 0; k < n; ++k) {
      if (f && exp.cases.name[k].toLowerCase().indexOf(f) < 0) continue;
      if (bad && !runs.some((r) => r.ok[k] === 0 || r.warnings[k])) continue;
      shown.push(k);
    }
    if (sortCol >= 0) {
      const c = columns[sortCol], key = shown.map((k) => c.get(k)), idx = shown.map((_, i) => i);
      idx.sort((a, b) => {
        const u = key[a], v = key[b];
        if (u === v) return a - b;
        if (u === null || u === undefined) return 1;
        if (v === null || v === undefined) return -1;
        return (u < v ? -1 : 1) * sortDir;
      });
      shown = idx.map((i) => shown[i]);
    }
    $('count').textContent = shown.length + ' of ' + n + ' cases';
    $('spacer').style.height = shown.length * ROW + 'px';
    $('tablebox').style.height = Math.min(330, Math.max(2, shown.length) * ROW + 4) + 'px';
    renderRows();
  }
  function renderRows() {
    const box = $('tablebox'), spacer = $('spacer');
    Array.from(box.querySelectorAll('.row')).forEach((r) => r.remove());
    const first = Math.max(0, Math.floor(box.scrollTop / ROW) - 2), last = Math.min(shown.length, first + Math.ceil(box.clientHeight / ROW) + 5);
    for (let i = first; i < last; ++i) {
      const k = shown[i], row = el('div', { class: 'row' + (view.c && k === view.k ? ' sel' : ''), 'data-case': k });
      row.style.top = i * ROW + 'px';
      columns.forEach((c) => {
        const v = c.show ? c.show(k) : c.get(k);
        const cls = typeof c.cls === 'function' ? c.cls(k) : c.cls === 'name' ? 'name' : '';
        row.appendChild(el('div', { class: 'cell ' + cls, title: String(v) }, String(v === null ? '' : v)));
      });
      row.onclick = () => T.openCase(ei, k);
      box.insertBefore(row, spacer);
    }
  }
  T.tableRows = () => $('tablebox').querySelectorAll('.row').length;

  function drawFigures() {
    const f = $('figs'); clear(f);
    exp.figures.forEach((src) => { const a = el('a', { href: src }); a.appendChild(el('img', { src: src, loading: 'lazy', alt: src })); f.appendChild(a); });
    if (!exp.figures.length) f.appendChild(el('p', { class: 'muted' }, 'No figures yet: tailsim plot draws them.'));
  }

  // ------------------------------------------------------------------ opening a case
  T.openCase = function (e, k) {
    if (e !== ei) selectExperiment(e);
    const src = exp.cases.replay[k];
    view.k = k;
    $('replaytitle').textContent = 'Replay: ' + exp.name + ' / ' + exp.cases.name[k];
    drawMap(); renderRows();
    if (src === null) {
      view.c = null;
      $('replaynote').textContent = 'This case kept no time series (output.time_series: none, or every run failed): its results are in the table.';
      return false;
    }
    const id = 'e' + e + 'c' + k;
    if (loaded[id]) { showCase(loaded[id]); return true; }
    $('replaynote').textContent = 'loading ' + src + ' ...';
    const s = el('script', { src: src });
    s.onerror = () => { $('replaynote').textContent = 'cannot load ' + src; };
    document.body.appendChild(s);
    return true;
  };
  T.caseLoaded = function (c) {
    loaded[c.id] = c;
    if ('e' + ei + 'c' + view.k === c.id) showCase(c);
  };

  function showCase(c) {
    view.c = c;
    view.t0 = Infinity; view.t1 = -Infinity;
    for (const m in c.models) { const t = c.models[m].t_s; view.t0 = Math.min(view.t0, t[0]); view.t1 = Math.max(view.t1, t[t.length - 1]); }
    $('replaynote').textContent = Object.keys(c.models).length + ' model(s); ' + (c.geometry ? 'drag to turn the camera, wheel to zoom; ' : 'no robot geometry; ') +
      'arrows: the ground\'s normal force on each foot (from below) and friction forces (along the ground); thin line: the COM path.';
    setupScene(c);
    T.pause();
    T.seek(view.t0);
    drawMap(); renderRows();
    document.getElementById('replaysec').scrollIntoView && null;
  }

  // ------------------------------------------------------------------ sampling
  function index(t, ts) {  // last i with ts[i] <= t
    let lo = 0, hi = ts.length - 1;
    if (t <= ts[0]) return 0;
    if (t >= ts[hi]) return hi;
    while (hi - lo > 1) { const m = (lo + hi) >> 1; if (ts[m] <= t) lo = m; else hi = m; }
    return lo;
  }
  function sample(series, name, t) {
    const v = series[name]; if (!v) return null;
    const ts = series.t_s, i = index(t, ts);
    if (i + 1 >= ts.length || ts[i] === t || ts[i + 1] === ts[i]) return v[i];
    const f = (t - ts[i]) / (ts[i + 1] - ts[i]);
    if (v[i] === null || v[i + 1] === null) return v[i];
    return v[i] + f * (v[i + 1] - v[i]);
  }

  // ------------------------------------------------------------------ 3D
  function quatMj(q) { return new THREE.Quaternion(q[1], q[2], q[3], q[0]); }
  function geomMesh(gm, material, outline) {
    const s = gm.size;
    let geos = [];
    // Outlines: few segments, so that the edges between faces (> 25 deg apart) draw the shape.
    const seg = outline ? 8 : 16;
    if (gm.type === 'box') geos.push([new THREE.BoxBufferGeometry(2 * s[0], 2 * s[1], 2 * s[2]), null]);
    else if (gm.type === 'sphere') geos.push([new THREE.SphereBufferGeometry(s[0], seg, outline ? 4 : 12), null]);
    else if (gm.type === 'ellipsoid') geos.push([new THREE.SphereBufferGeometry(1, seg, outline ? 4 : 12), [s[0], s[1], s[2]]]);
    else if (gm.type === 'cylinder' || gm.type === 'capsule') {
      const capsule = gm.type === 'capsule' && !outline;  // an outline capsule: its cylinder's edges
      const c = new THREE.CylinderBufferGeometry(s[0], s[0], 2 * s[1], seg, 1, capsule);
      c.rotateX(Math.PI / 2);  // three.js cylinders lie along y, MuJoCo's along z
      geos.push([c, null]);
      if (capsule) for (const z of [-s[1], s[1]]) { const e = new THREE.SphereBufferGeometry(s[0], 12, 8); e.translate(0, 0, z); geos.push([e, null]); }
    }
    const group = new THREE.Group();
    group.position.set(gm.pos[0], gm.pos[1], gm.pos[2]);
    group.quaternion.copy(quatMj(gm.quat));
    geos.forEach(([geo, scale]) => {
      const o = outline ? new THREE.LineSegments(new THREE.EdgesGeometry(geo, 25), material) : new THREE.Mesh(geo, material);
      if (scale) o.scale.set(scale[0], scale[1], scale[2]);
      group.add(o);
    });
    return group;
  }
  // The robot of geometry g as nested groups: body (pose in parent) > pivot (tail joint, about z
  // through the joint's position) > inner (geoms and child bodies).
  function buildRobot(g, color, outline) {
    const top = new THREE.Group(), inner = [], pivots = [], feet = {};
    const solid = (rgba) => new THREE.MeshPhongMaterial({ color: new THREE.Color(rgba[0], rgba[1], rgba[2]), transparent: rgba[3] < 1, opacity: rgba[3] });
    const line = new THREE.LineBasicMaterial({ color: color });
    g.bodies.forEach((b, i) => {
      const body = new THREE.Group(), pivot = new THREE.Group(), inn = new THREE.Group();
      body.position.set(b.pos[0], b.pos[1], b.pos[2]);
      body.quaternion.copy(quatMj(b.quat));
      pivot.position.set(b.jpos[0], b.jpos[1], b.jpos[2]);
      inn.position.set(-b.jpos[0], -b.jpos[1], -b.jpos[2]);
      body.add(pivot); pivot.add(inn);
      (b.parent < 0 ? top : inner[b.parent]).add(body);
      inner[i] = inn;
      if (b.tail >= 0) pivots[b.tail] = pivot;
      body.userData.body = i;
      if (i === g.root.body) top.userData.rootGroup = body;
    });
    // children are added before their parents only if the list is out of order: MuJoCo orders parents first
    g.geoms.forEach((gm) => {
      const mesh = geomMesh(gm, outline ? line : solid(gm.rgba), outline);
      inner[gm.body].add(mesh);
      if (gm.foot) feet[gm.foot] = mesh;
    });
    return { top: top, root: top.userData.rootGroup, pivots: pivots, feet: feet };
  }
  function poseRobot(r, g, s) {
    const phi = s.phi_deg * DEG, c = Math.cos(phi), sn = Math.sin(phi);
    const q = new THREE.Quaternion().setFromAxisAngle(new THREE.Vector3(0, 0, 1), phi).multiply(quatMj(g.root.quat0));
    r.root.quaternion.copy(q);
    if (g.root.free) {
      const cx = g.root.com[0], cy = g.root.com[1];
      r.root.position.set(s.x_m - (c * cx - sn * cy), s.y_m - (sn * cx + c * cy), g.root.pos0[2]);
    }
    s.theta_deg.forEach((th, i) => { if (r.pivots[i]) r.pivots[i].rotation.set(0, 0, th * DEG); });
    r.top.updateMatrixWorld(true);
  }

  function setupScene(c) {
    const box = $('view3d');
    if (view.three) { box.removeChild(view.three.renderer.domElement); view.three.renderer.dispose(); view.three = null; }
    if (!c.geometry || !window.THREE || !THREE.OrbitControls) return;
    let renderer;
    try {
      renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    } catch (err) {
      $('replaynote').textContent = 'This browser has no WebGL: the plots beside show the run.';
      return;
    }
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    const W = box.clientWidth, H = box.clientHeight;
    renderer.setSize(W, H);
    renderer.setClearColor(0xffffff);
    box.insertBefore(renderer.domElement, box.firstChild);
    const scene = new THREE.Scene();
    const camera = new THREE.PerspectiveCamera(40, W / H, 0.01, 50);
    camera.up.set(0, 0, 1);
    camera.position.set(-0.45, -0.85, 0.55);  // from behind and to the right: the tail in front of the body
    scene.add(new THREE.AmbientLight(0xffffff, 0.55));
    const sun = new THREE.DirectionalLight(0xffffff, 0.6); sun.position.set(1, -1, 2); scene.add(sun);
    const ground = new THREE.GridHelper(2, 20, 0x999999, 0xdddddd); ground.rotation.x = Math.PI / 2; scene.add(ground);
    const controls = new THREE.OrbitControls(camera, renderer.domElement);
    controls.target.set(-0.12, 0, 0.08); controls.update();
    const robots = {}, arrows = {}, legend = $('legend'); clear(legend);
    const names = Object.keys(c.models);
    const solidModel = names.indexOf('mujoco') >= 0 ? 'mujoco' : null;
    const weight = c.geometry.mass_kg * c.geometry.g;
    names.forEach((m) => {
      const info = exp.models.find((x) => x.name === m) || { title: m, color: '#000000' };
      const r = buildRobot(c.geometry, info.color, m !== solidModel);
      scene.add(r.top);
      robots[m] = r;
      const series = c.models[m];
      // the COM path on the ground
      const pts = [];
      for (let i = 0; i < series.t_s.length; i += Math.max(1, Math.floor(series.t_s.length / 600))) pts.push(new THREE.Vector3(series.x_m ? series.x_m[i] : 0, series.y_m ? series.y_m[i] : 0, 0.001));
      scene.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints(pts), new THREE.LineBasicMaterial({ color: info.color })));
      // forces: normal per foot (up), friction per foot or in all (along the ground)
      const a = { normal: {}, friction: {}, total: null, scale: 0.12 / (weight / 4) };
      for (let k = 1; k <= 4; ++k) {
        if (series['foot' + k + '_Fn_N'] || series['N' + k + '_N']) { a.normal[k] = new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), 0.1, info.color); scene.add(a.normal[k]); }
        if (series['F' + k + 'x_N']) { a.friction[k] = new THREE.ArrowHelper(new THREE.Vector3(1, 0, 0), new THREE.Vector3(), 0.1, info.color); scene.add(a.friction[k]); }
      }
      if (!Object.keys(a.friction).length && series.FFx_N) { a.total = new THREE.ArrowHelper(new THREE.Vector3(1, 0, 0), new THREE.Vector3(), 0.1, info.color); scene.add(a.total); }
      arrows[m] = a;
      const item = el('div', {}, (m === solidModel ? '■ ' : '□ ') + info.title + (m === solidModel ? ' (solid)' : ' (outline)'));
      item.style.color = info.color; legend.appendChild(item);
    });
    view.three = { renderer: renderer, scene: scene, camera: camera, controls: controls, robots: robots, arrows: arrows };
  }
  // An arrow for force v: from `at` along v, or (toward) ending at `at` (a ground reaction pushing a foot).
  function setArrow(a, at, v, scale, toward) {
    const len = Math.hypot(v.x, v.y, v.z) * scale;
    if (!(len > 1e-4)) { a.visible = false; return; }
    const dir = v.clone().normalize();
    a.visible = true; a.position.copy(toward ? at.clone().addScaledVector(dir, -len) : at); a.setDirection(dir);
    a.setLength(len, Math.min(0.03, 0.4 * len), Math.min(0.015, 0.2 * len));
  }

  function stateAt(series, t, links) {
    const s = { t_s: t, phi_deg: sample(series, 'phi_deg', t), x_m: sample(series, 'x_m', t) || 0, y_m: sample(series, 'y_m', t) || 0, theta_deg: [] };
    for (let i = 1; i <= links; ++i) s.theta_deg.push(sample(series, 'theta' + i + '_deg', t));
    return s;
  }

  // ------------------------------------------------------------------ time
  T.seek = function (t) {
    if (!view.c) return;
    view.t = Math.max(view.t0, Math.min(view.t1, t));
    const c = view.c;
    view.applied = {};
    for (const m in c.models) {
      const series = c.models[m], s = stateAt(series, view.t, c.links);
      view.applied[m] = s;
      const th = view.three;
      if (th && th.robots[m]) {
        const r = th.robots[m];
        poseRobot(r, c.geometry, s);
        const a = th.arrows[m], fw = new THREE.Vector3();
        for (const k in a.normal) {
          r.feet[k].getWorldPosition(fw);
          const fn = sample(series, 'foot' + k + '_Fn_N', view.t);
          setArrow(a.normal[k], fw, new THREE.Vector3(0, 0, fn !== null ? fn : sample(series, 'N' + k + '_N', view.t)), a.scale, true);
        }
        for (const k in a.friction) {
          r.feet[k].getWorldPosition(fw); fw.z = 0.002;
          setArrow(a.friction[k], fw, new THREE.Vector3(sample(series, 'F' + k + 'x_N', view.t), sample(series, 'F' + k + 'y_N', view.t), 0), a.scale);
        }
        if (a.total) setArrow(a.total, new THREE.Vector3(s.x_m, s.y_m, 0.002), new THREE.Vector3(sample(series, 'FFx_N', view.t), sample(series, 'FFy_N', view.t), 0), a.scale);
      }
    }
    $('scrub').value = Math.round((view.t - view.t0) / Math.max(1e-12, view.t1 - view.t0) * 1000);
    $('tlabel').textContent = 't = ' + view.t.toFixed(3) + ' s';
    const hud = [];
    for (const m in view.applied) hud.push((exp.models.find((x) => x.name === m) || { title: m }).title + ': φ = ' + fmt(view.applied[m].phi_deg, 2) + ' deg, θ = ' + view.applied[m].theta_deg.map((v) => fmt(v, 1)).join(', ') + ' deg');
    let phase = '';
    for (let i = 0; i + 2 < c.strokes.length; i += 3) {
      if (view.t >= c.strokes[i] && view.t <= c.strokes[i + 1]) { phase = 'tail accelerating'; break; }
      if (view.t > c.strokes[i + 1] && view.t <= c.strokes[i + 2]) phase = 'tail decelerating';
    }
    if (phase) hud.push(phase);
    $('hud').textContent = hud.join('\n'); $('hud').style.whiteSpace = 'pre';
    render(); drawPlots();
  };
  T.play = function () { if (!view.c) return; if (view.t >= view.t1) T.seek(view.t0); view.playing = true; view.lastFrame = 0; $('play').textContent = 'pause'; };
  T.pause = function () { view.playing = false; $('play').textContent = 'play'; };
  function tick(now) {
    if (view.playing && view.c) {
      if (view.lastFrame) {
        const t = view.t + (now - view.lastFrame) / 1000 * view.speed;
        T.seek(t);
        if (t >= view.t1) T.pause();
      }
      view.lastFrame = now;
    } else if (view.three) render();
    requestAnimationFrame(tick);
  }
  function render() { const th = view.three; if (th) { th.controls.update(); th.renderer.render(th.scene, th.camera); } }

  // What the page shows now: the case, the time, and per model the state applied to the scene,
  // with the drawn body's yaw and tail angles read back from the 3D objects.
  T.state = function () {
    const out = { experiment: exp ? exp.name : null, case: view.c ? view.k : -1, case_name: view.c ? view.c.name : null, t: view.t, playing: view.playing, models: {} };
    for (const m in view.applied) {
      const s = view.applied[m], o = { phi_deg: s.phi_deg, theta_deg: s.theta_deg.slice(), x_m: s.x_m, y_m: s.y_m };
      const th = view.three;
      if (th && th.robots[m]) {
        const r = th.robots[m], e = new THREE.Euler().setFromQuaternion(r.root.getWorldQuaternion(new THREE.Quaternion()), 'ZYX');
        o.drawn_yaw_deg = e.z / DEG;
        o.drawn_theta_deg = r.pivots.map((p) => p.rotation.z / DEG);
        const a = th.arrows[m], shown = (set) => Object.keys(set).filter((k) => set[k].visible).length;
        o.force_arrows = { normal: shown(a.normal), friction: shown(a.friction) + (a.total && a.total.visible ? 1 : 0) };
      }
      out.models[m] = o;
    }
    out.webgl = !!view.three;
    return out;
  };

  // ------------------------------------------------------------------ plots beside the replay
  function plotFrame() { return { x0: 52, x1: 508 }; }
  function drawPlots() {
    const cv = $('plots'), g = cv.getContext('2d'), c = view.c, p = plotFrame();
    g.clearRect(0, 0, cv.width, cv.height);
    if (!c) return;
    const panels = [{ title: 'body yaw φ [deg]', cols: [['phi_deg', []]], y0: 20, y1: 135 },
                    { title: 'tail angles θ_i [deg]', cols: [], y0: 162, y1: 265 },
                    { title: 'moments [N m]: M_zT (solid), M_zF (dashed)', cols: [['MzT_Nm', []], ['MzF_Nm', [5, 4]]], y0: 292, y1: 392 }];
    for (let i = 1; i <= c.links; ++i) panels[1].cols.push(['theta' + i + '_deg', i > 1 ? [2 + i, 3] : []]);
    const X = (t) => p.x0 + (t - view.t0) / Math.max(1e-12, view.t1 - view.t0) * (p.x1 - p.x0);
    g.font = '11px sans-serif';
    panels.forEach((pn) => {
      let lo = Infinity, hi = -Infinity;
      for (const m in c.models) pn.cols.forEach(([n]) => (c.models[m][n] || []).forEach((v) => { if (v !== null) { lo = Math.min(lo, v); hi = Math.max(hi, v); } }));
      if (!(hi >= lo)) { lo = 0; hi = 1; }
      if (hi - lo < 1e-9) { lo -= 1; hi += 1; }
      const pad = 0.05 * (hi - lo); lo -= pad; hi += pad;
      const Y = (v) => pn.y1 - (v - lo) / (hi - lo) * (pn.y1 - pn.y0);
      g.strokeStyle = '#999'; g.lineWidth = 1; g.setLineDash([]); g.strokeRect(p.x0, pn.y0, p.x1 - p.x0, pn.y1 - pn.y0);
      g.fillStyle = '#222'; g.fillText(pn.title, p.x0, pn.y0 - 5);
      niceTicks(lo, hi, 4).forEach((v) => { g.fillText(String(+v.toPrecision(6)), 4, Y(v) + 4); g.strokeStyle = '#eee'; g.beginPath(); g.moveTo(p.x0, Y(v)); g.lineTo(p.x1, Y(v)); g.stroke(); });
      for (const m in c.models) {
        const info = exp.models.find((x) => x.name === m) || { color: '#000' }, s = c.models[m];
        pn.cols.forEach(([n, dash]) => {
          const v = s[n]; if (!v) return;
          g.strokeStyle = info.color; g.setLineDash(dash); g.lineWidth = 1.4; g.beginPath();
          let started = false;
          const step = Math.max(1, Math.floor(v.length / 1200));
          for (let i = 0; i < v.length; i += step) { if (v[i] === null) { started = false; continue; } const x = X(s.t_s[i]), y = Y(v[i]); if (started) g.lineTo(x, y); else g.moveTo(x, y); started = true; }
          g.stroke();
        });
      }
      g.setLineDash([]);
    });
    niceTicks(view.t0, view.t1, 6).forEach((t) => g.fillText(String(+t.toPrecision(6)), X(t) - 8, 408));
    g.fillText('t [s]', p.x1 - 20, 418);
    g.strokeStyle = '#d00'; g.lineWidth = 1; g.beginPath(); g.moveTo(X(view.t), 10); g.lineTo(X(view.t), 395); g.stroke();
  }
})();
)JS";

}  // namespace tailsim
