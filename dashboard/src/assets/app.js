// dicstream dashboard: receives snapshots over server-sent events (/events) and draws them on
// canvases by hand (no chart library: a few line and bar charts do not need one). Read-only:
// the page never sends anything but GET requests.
'use strict';

// Counters the browser tests read: they must grow while the instance runs.
// `points`: the points each chart drew (by canvas id); `charts`: what each chart drew last (the
// CSV export); `exported`: the size of what each export button produced last.
const dash = { snapshots: 0, imagesDrawn: 0, chartsDrawn: 0, last: null, points: {}, charts: {}, exported: {}, paused: false, zoom: {} };
window.dash = dash;

const $ = (id) => document.getElementById(id);
const fmt = (v, d = 3) => (v === null || v === undefined || !isFinite(v)) ? '-' : Number(v).toFixed(d);
const sci = (v) => (v === null || v === undefined || !isFinite(v)) ? '-' : Number(v).toExponential(3);
const esc = (s) => String(s).replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' }[c]));

const STATUS_COLORS = ['#00000000', '#ff00ff', '#808080', '#ffffff', '#ff8c00', '#ffff00', '#00ffff'];
const SERIES_COLORS = ['#d64545', '#2b6cb0', '#2f8132', '#8e44ad', '#c65d07'];

// ---- colour maps: the figures' own (wire::colour_map, served as /colour_maps.js) ----
function mapColour(name, t) {
  const table = COLOUR_MAPS[name];
  t = isFinite(t) ? Math.min(1, Math.max(0, t)) : 0.5;
  const x = t * (table.length - 1), i = Math.min(table.length - 2, Math.floor(x)), f = x - i;
  return [0, 1, 2].map((k) => Math.round(table[i][k] + f * (table[i + 1][k] - table[i][k])));
}
// Where a value falls on a scale {map, lo, hi}: the diverging map is centred on zero.
function scaleT(s, v) {
  if (s.map === 'diverging') {
    return 0.5 + Math.min(s.hi, Math.max(s.lo, v)) / (2 * Math.max(Math.abs(s.lo), Math.abs(s.hi)));
  }
  return (v - s.lo) / (s.hi - s.lo);
}
const scaleColour = (s, v) => mapColour(s.map, scaleT(s, v));

// ---- charts ----
function niceTicks(lo, hi, n) {
  if (!(hi > lo)) { hi = lo + 1; }
  const raw = (hi - lo) / n;
  const mag = Math.pow(10, Math.floor(Math.log10(raw)));
  const step = [1, 2, 5, 10].map((m) => m * mag).find((s) => s >= raw) || raw;
  const ticks = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) ticks.push(v);
  return ticks;
}

function tickLabel(v, span) {
  if (Math.abs(v) < span * 1e-9) return '0';
  if (span < 0.01 || Math.abs(v) >= 1e4) return v.toExponential(1);
  const d = Math.max(0, 2 - Math.floor(Math.log10(span)));
  return v.toFixed(Math.min(d, 4));
}

// series: [{x: [], y: [], color, label, dots}]
// opts: {xlabel, ylabel (with units), yZero, empty}. Paused, a chart already drawn stays
// (`redraw`: a zoom's change draws it anyway). Zoomed (`dash.zoom[id]`: an x range), the y
// range fits the points inside it.
function lineChart(canvas, series, opts, redraw) {
  if (dash.paused && dash.charts[canvas.id] && !redraw) return;
  dash.charts[canvas.id] = { series, opts };
  const ctx = canvas.getContext('2d');
  const W = canvas.width, H = canvas.height, L = 70, R = 10, T = 10, B = 30;
  ctx.clearRect(0, 0, W, H);
  ctx.font = '11px system-ui, sans-serif';
  let xs = [], ys = [];
  for (const s of series) {
    if (s.noBounds) continue; // drawn clipped to the others' range (a wild early fit)
    for (let i = 0; i < s.x.length; i++) {
      if (s.x[i] !== null && s.y[i] !== null && isFinite(s.x[i]) && isFinite(s.y[i])) { xs.push(s.x[i]); ys.push(s.y[i]); }
    }
  }
  ctx.fillStyle = '#52606d';
  dash.points[canvas.id] = xs.length;
  if (opts.ylabel) {
    ctx.save(); ctx.translate(11, (H - B + T) / 2); ctx.rotate(-Math.PI / 2);
    ctx.textAlign = 'center'; ctx.fillText(opts.ylabel, 0, 0); ctx.restore();
  }
  if (xs.length === 0) { ctx.fillText(opts.empty || 'no data yet', L + 10, H / 2); return; }
  let x0 = Math.min(...xs), x1 = Math.max(...xs), y0 = Math.min(...ys), y1 = Math.max(...ys);
  const z = dash.zoom[canvas.id];
  if (z) {
    [x0, x1] = z;
    const inside = ys.filter((_, i) => xs[i] >= x0 && xs[i] <= x1);
    if (inside.length) { y0 = Math.min(...inside); y1 = Math.max(...inside); }
  }
  if (opts.yZero) { y0 = Math.min(y0, 0); y1 = Math.max(y1, 0); }
  if (x1 === x0) { x1 = x0 + 1; }
  if (y1 === y0) { y1 = y0 + (Math.abs(y0) || 1) * 0.1; y0 -= (Math.abs(y0) || 1) * 0.1; }
  dash.charts[canvas.id].frame = { left: L, right: W - R, x0, x1 };
  const px = (x) => L + (x - x0) / (x1 - x0) * (W - L - R);
  const py = (y) => H - B - (y - y0) / (y1 - y0) * (H - T - B);
  ctx.strokeStyle = '#e4e7eb'; ctx.lineWidth = 1;
  for (const t of niceTicks(y0, y1, 5)) {
    ctx.beginPath(); ctx.moveTo(L, py(t)); ctx.lineTo(W - R, py(t)); ctx.stroke();
    ctx.fillText(tickLabel(t, y1 - y0), 16, py(t) + 4);
  }
  for (const t of niceTicks(x0, x1, 6)) {
    ctx.beginPath(); ctx.moveTo(px(t), T); ctx.lineTo(px(t), H - B); ctx.stroke();
    ctx.fillText(tickLabel(t, x1 - x0), px(t) - 10, H - B + 13);
  }
  ctx.strokeStyle = '#52606d'; ctx.strokeRect(L, T, W - L - R, H - T - B);
  ctx.textAlign = 'center'; ctx.fillText(opts.xlabel || '', (L + W - R) / 2, H - 3); ctx.textAlign = 'start';
  let lx = L + 8;
  ctx.save();
  ctx.beginPath(); ctx.rect(L, T, W - L - R, H - T - B); ctx.clip();
  for (const s of series) {
    ctx.strokeStyle = s.color; ctx.fillStyle = s.color; ctx.lineWidth = 1.6;
    if (s.dots) {
      for (let i = 0; i < s.x.length; i++) {
        if (s.y[i] === null || !isFinite(s.y[i])) continue;
        ctx.fillRect(px(s.x[i]) - 1.5, py(s.y[i]) - 1.5, 3, 3);
      }
    } else {
      ctx.beginPath();
      let pen = false;
      for (let i = 0; i < s.x.length; i++) {
        if (s.y[i] === null || !isFinite(s.y[i])) { pen = false; continue; }
        if (pen) ctx.lineTo(px(s.x[i]), py(s.y[i])); else ctx.moveTo(px(s.x[i]), py(s.y[i]));
        pen = true;
      }
      ctx.stroke();
    }
    if (s.label) { ctx.fillRect(lx, T + 6, 10, 3); ctx.fillText(s.label, lx + 13, T + 11); lx += 20 + ctx.measureText(s.label).width; }
  }
  ctx.restore();
  dash.chartsDrawn++;
}

function barChart(canvas, groups, edges) {
  if (dash.paused && dash.points[canvas.id] !== undefined) return;
  dash.points[canvas.id] = groups.filter((g) => g.bins).length;
  const ctx = canvas.getContext('2d');
  const W = canvas.width, H = canvas.height, L = 40, B = 30, T = 18;
  ctx.clearRect(0, 0, W, H);
  ctx.font = '11px system-ui, sans-serif';
  ctx.fillStyle = '#52606d';
  const present = groups.filter((g) => g.bins);
  if (present.length === 0) { ctx.fillText('no latency yet', L, H / 2); return; }
  const n = edges.length + 1, slot = (W - L - 10) / n, bw = slot / (present.length + 0.5);
  present.forEach((g, k) => {
    const total = g.bins.reduce((a, b) => a + b, 0) || 1;
    const top = Math.max(...g.bins) / total || 1;
    ctx.fillStyle = g.color;
    g.bins.forEach((c, i) => {
      const h = (c / total) / top * (H - T - B);
      ctx.fillRect(L + i * slot + k * bw, H - B - h, bw - 1, h);
    });
    ctx.fillRect(L + 10 + k * 190, 4, 10, 8);
    ctx.fillText(g.label, L + 24 + k * 190, 12);
  });
  ctx.fillStyle = '#52606d';
  edges.forEach((e, i) => { if (i % 2 === 0) ctx.fillText('≤' + e, L + i * slot, H - B + 13); });
  ctx.fillText('> ' + edges[edges.length - 1], L + edges.length * slot - 10, H - B + 13);
  ctx.fillText('latency (ms), share of the samples', W / 2 - 80, H - 3);
  dash.chartsDrawn++;
}

// ---- the specimen: image, strain map, mesh ----
const img = new Image();
let imgVersion = -1, imgReady = false;
img.onload = () => { imgReady = true; drawSpecimen(); };

// The map's scale: automatic or symmetric, the server's (`ranges`, resolved per measure and
// component by wire::colour_range::choose, the figures' own: dashboard/src/map_ranges.rs);
// fixed, the user's two numbers, a minimum not below the maximum refused: {error}.
function colourScale(f, measureName, comp) {
  const mode = $('range-mode').value;
  if (mode === 'fixed') {
    const lo = parseFloat($('range-min').value), hi = parseFloat($('range-max').value);
    if (!isFinite(lo) || !isFinite(hi)) return { error: 'fixed range: min and max must be numbers' };
    if (!(lo < hi)) return { error: `fixed range refused: min ${lo} is not below max ${hi}` };
    return { map: lo < 0 && hi > 0 ? 'diverging' : 'viridis', lo, hi };
  }
  const r = f.ranges && f.ranges[measureName] && f.ranges[measureName][comp];
  return r ? r[mode] : { error: `no ${measureName} range` };
}

function drawColorbar(scale, label) {
  const c = $('colorbar'), ctx = c.getContext('2d');
  ctx.clearRect(0, 0, c.width, c.height);
  ctx.fillStyle = '#222'; ctx.font = '11px system-ui, sans-serif';
  ctx.fillText(label, 0, 10);
  const T = 24, B = 14, h = c.height - T - B;
  if (scale.error) {
    dash.rangeError = scale.error;
    ctx.fillStyle = '#b00'; ctx.fillText('range', 0, T + 10); ctx.fillText('refused', 0, T + 24);
    return;
  }
  dash.rangeError = null;
  const { lo, hi } = scale;
  for (let i = 0; i < h; i++) {
    const [r, g, b] = scaleColour(scale, hi - (hi - lo) * i / (h - 1));
    ctx.fillStyle = `rgb(${r},${g},${b})`;
    ctx.fillRect(0, T + i, 16, 1);
  }
  ctx.fillStyle = '#222';
  for (let k = 0; k <= 4; k++) {
    const v = hi - (hi - lo) * k / 4;
    ctx.fillText(Math.abs(v) < 1e-3 && v !== 0 ? v.toExponential(1) : v.toFixed(4), 19, T + h * k / 4 + 4);
  }
}

// Seth-Hill strain measures are functions of the principal stretches on the same axes: log
// ln λ, Green-Lagrange (λ² − 1)/2, nominal λ − 1. A node's strain in one of them gives its
// stretches, hence the others. Small strain (sym ∇u) carries no rotation: it converts to none.
// (The server converts the same way for the ranges it sends: stretch_states::convert_strain;
// tests/processes/dashboard.rs holds the two equal.)
const STRETCH_OF = { log: (e) => Math.exp(e), green: (e) => Math.sqrt(1 + 2 * e), nominal: (e) => 1 + e };
const STRAIN_OF = { log: (l) => Math.log(l), green: (l) => (l * l - 1) / 2, nominal: (l) => l - 1 };
function convertStrain(exx, eyy, exy, from, to) {
  if (from === to) return [exx, eyy, exy];
  const mean = (exx + eyy) / 2, radius = Math.hypot((exx - eyy) / 2, exy);
  const theta = 0.5 * Math.atan2(2 * exy, exx - eyy), c = Math.cos(theta), s = Math.sin(theta);
  const [a, b] = [mean + radius, mean - radius].map((e) => STRAIN_OF[to](STRETCH_OF[from](e)));
  return [a * c * c + b * s * s, a * s * s + b * c * c, (a - b) * c * s];
}

// The map's values of component `comp` in the chosen measure (null where the node has none),
// and the measure's name; null values when the conversion is impossible.
const finiteOrNull = (v) => (isFinite(v) ? v : null);
function mapValues(f, comp) {
  const want = $('map-measure').value;
  if (want === 'measured' || want === f.measure) return [f[comp], f.measure];
  if (!(f.measure in STRETCH_OF)) return [null, `${want}: not from ${f.measure} strain`];
  const k = { exx: 0, eyy: 1, exy: 2 }[comp];
  return [f.exx.map((v, i) => (v === null || f.eyy[i] === null || f.exy[i] === null) ? null
    : finiteOrNull(convertStrain(v, f.eyy[i], f.exy[i], f.measure, want)[k])), want];
}

function drawSpecimen() {
  const s = dash.last;
  const canvas = $('image'), ctx = canvas.getContext('2d');
  if (!s || !s.image || !imgReady) return;
  const im = s.image;
  if (canvas.width !== im.width_px || canvas.height !== im.height_px) {
    canvas.width = im.width_px; canvas.height = im.height_px;
  }
  ctx.drawImage(img, 0, 0);
  dash.imagesDrawn++;
  const f = s.field;
  if (f && f.x.length > 0) {
    const comp = $('component').value, [converted, measureName] = mapValues(f, comp);
    const values = converted || f[comp].map(() => null);
    const scale = colourScale(f, measureName, comp);
    // What the map was drawn with, for the browser test: the scale, the field, the quantity.
    Object.assign(dash, { mapScale: scale, mapField: f, mapMeasure: measureName, mapComp: comp });
    const cell = Math.max(1, f.step_px * f.stride / im.factor);
    if ($('show-map').checked && !scale.error) {
      ctx.globalAlpha = 0.55;
      for (let i = 0; i < f.x.length; i++) {
        const v = values[i];
        if (v === null) continue;
        const [r, g, b] = scaleColour(scale, v);
        ctx.fillStyle = `rgb(${r},${g},${b})`;
        ctx.fillRect(f.x[i] / im.factor - cell / 2, f.y[i] / im.factor - cell / 2, cell, cell);
      }
      ctx.globalAlpha = 1;
    }
    for (let i = 0; i < f.x.length; i++) {
      const x = f.x[i] / im.factor, y = f.y[i] / im.factor;
      if (f.status[i] !== 0) {
        // Lost or refused: a cross in the colour of its status.
        ctx.strokeStyle = STATUS_COLORS[f.status[i]] || '#ff00ff'; ctx.lineWidth = 1.5;
        ctx.beginPath(); ctx.moveTo(x - 3, y - 3); ctx.lineTo(x + 3, y + 3);
        ctx.moveTo(x + 3, y - 3); ctx.lineTo(x - 3, y + 3); ctx.stroke();
      } else if ($('show-mesh').checked) {
        ctx.fillStyle = '#000'; ctx.fillRect(x - 1, y - 1, 2, 2);
      }
    }
    drawColorbar(scale, `${comp} (${measureName})`);
  }
}

// ---- the snapshot ----
function setText(id, text) { const e = $(id); if (e.textContent !== String(text)) e.textContent = text; }

function latencyText(l) {
  return l ? `p50 ${fmt(l.p50, 1)} ms, p90 ${fmt(l.p90, 1)} ms, p99 ${fmt(l.p99, 1)} ms, max ${fmt(l.max, 1)} ms (${l.count})` : '-';
}

function update(s) {
  dash.snapshots++;
  dash.last = s;
  setText('instance', s.instance);
  setText('mode', s.mode === 'run' ? 'dicstream run' : 'dicstream monitor');
  setText('viewers', s.viewers);
  setText('uptime', `${fmt(s.t_s, 0)} s`);
  setText('test-time', s.test_time_s === null || s.test_time_s === undefined ? '-' : `${fmt(s.test_time_s, 1)} s`);

  // Image and field.
  if (s.image && s.image.version !== imgVersion) {
    imgVersion = s.image.version;
    img.src = `/image.png?v=${imgVersion}`;
  } else {
    drawSpecimen();
  }
  setText('image-info', s.image
    ? `frame ${s.image.frame_id}, shown ${s.image.width_px}x${s.image.height_px} px (1/${s.image.factor} of ${s.frames.width_px}x${s.frames.height_px}, ${s.frames.bit_depth} bit)`
    : (s.image_error || 'no image yet'));
  const f = s.field;
  setText('field-info', f ? `field of frame ${f.frame_id}: ${f.valid_nodes}/${f.nodes} nodes ok, ${f.measure} strain, ZOI ${f.zoi_px} px every ${f.step_px} px${f.stride > 1 ? `, every ${f.stride}th node shown` : ''}` : 'no field yet');
  if (f) {
    $('status-legend').innerHTML = f.status_counts.filter((c) => c.code !== 0)
      .map((c) => `<span class="swatch" style="background:${STATUS_COLORS[c.code]}"></span>${esc(c.status)} ${c.count}`).join('') +
      ' &nbsp;(crosses: nodes lost or refused by the final check)';
  }

  // Gauge strains.
  const m = s.gauge.measures[$('measure').value];
  const clock = s.gauge.clock === 'test' ? 'test time (s)' : 'time since the dashboard started (s)';
  lineChart($('gauge-chart'), ['exx', 'eyy', 'exy'].map((k, i) => ({ x: s.gauge.t_s, y: m[k], color: SERIES_COLORS[i], label: k })),
    { xlabel: clock, ylabel: `${$('measure').value} strain (-)`, yZero: true, empty: 'no field yet' });
  setText('gauge-clock', s.gauge.clock === 'test' ? "the test's time (the rig's)" : 'the time since the dashboard started (no rig seen)');
  setText('gauge-points', s.gauge.t_s.length);
  updateUserGauges(s.user_gauges);

  // Stress-stretch.
  const id = s.identification, series = [];
  [['uniaxial', 0], ['equibiaxial', 1]].forEach(([k, i]) => {
    const c = id[k];
    series.push({ x: c.stretch, y: c.nominal_mpa, color: SERIES_COLORS[i], label: k, dots: true });
    if (c.fit) series.push({ x: c.fit.stretch, y: c.fit.nominal_mpa, color: SERIES_COLORS[i + 3], label: `fit ${k}`, noBounds: c.stretch.length > 0 });
  });
  lineChart($('stress-chart'), series, { xlabel: 'stretch λ (-)', ylabel: 'nominal stress (MPa)', yZero: true, empty: 'no test data yet' });

  drawInvariantFunctions(id);
  updateRig(s.rig);
  updateForces(s.forces);
  updateStates(s.stretch_states);
  updatePipeline(s);
  updateProcesses(s.processes, s.mode);
  updateIdentification(id);
}

// f(I1) and g(I2) of the identified law (paper Figs. 8 and 14), each over the invariant range
// its load case reached (uniaxial: I1 = λ² + 2/λ; equibiaxial: I2 = λ⁴ + 2/λ²), once shown.
function drawInvariantFunctions(id) {
  const series = [];
  const curve = (c, top, label, color) => {
    if (!c || !(top > 3)) return;
    const x = [], y = [];
    for (let k = 0; k <= 40; k++) {
      const inv = 3 + (top - 3) * k / 40;
      x.push(inv);
      y.push(Math.exp(c.values.reduce((sum, a, i) => sum + a * Math.pow(inv - 3, i), 0)));
    }
    series.push({ x, y, color, label });
  };
  const maxStretch = (c) => c && c.stretch.length ? Math.max(...c.stretch) : 1;
  const lu = maxStretch(id.uniaxial), le = maxStretch(id.equibiaxial);
  curve(id.f_coefficients, lu * lu + 2 / lu, 'f(I1) against I1', SERIES_COLORS[0]);
  curve(id.g_coefficients, le ** 4 + 2 / (le * le), 'g(I2) against I2', SERIES_COLORS[1]);
  // The route's experimental points (eqs. 19/20 and 23) from this run's stresses.
  [[id.f_points, 'f points (uniaxial)', SERIES_COLORS[3]], [id.g_points, 'g points (equibiaxial)', SERIES_COLORS[4]]]
    .forEach(([p, label, color]) => {
      if (p && p.invariant.length) series.push({ x: p.invariant, y: p.value_mpa, color, label, dots: true });
    });
  lineChart($('fg-chart'), series, { xlabel: 'invariant I1 or I2 (-)', ylabel: 'f, g (MPa)', yZero: true, empty: 'no coefficient identified yet' });
}

// The user's named gauges ([correlator] gauges), one chart each against the test's time, with
// their unit; created once the run sends them (a monitor has no gauges' shapes: none).
function updateUserGauges(gauges) {
  if (!Array.isArray(gauges) || gauges.length === 0) return;
  const box = $('user-gauges');
  gauges.forEach((g, i) => {
    const id = `user-gauge-${i}`;
    let canvas = document.getElementById(id);
    if (!canvas) {
      if (i === 0) box.textContent = '';
      const title = document.createElement('h3');
      title.className = 'small gauge-name';
      title.textContent = `${g.name}: ${g.kind}, ${g.quantity} (${g.unit})`;
      canvas = document.createElement('canvas');
      canvas.id = id; canvas.className = 'chart'; canvas.width = 560; canvas.height = 200;
      box.append(title, canvas);
    }
    // The gauge strains' colours (exx, eyy, exy), whatever the JSON's key order.
    const keys = ['exx', 'eyy', 'exy', 'elongation'].filter((k) => k in g.series);
    const series = keys.map((k, j) => ({ x: g.t_s, y: g.series[k], color: SERIES_COLORS[j], label: k }));
    lineChart(canvas, series, { xlabel: 'test time (s)', ylabel: `${g.name}: ${g.quantity} (${g.unit})`, yZero: true, empty: 'no reading yet' });
  });
}

// Strain control: target against the newest field's gauge log strains, per axis.
function strainText(st) {
  if (!st) return '';
  const axis = (k, name) => `ln λ${name} target ${fmt(st.target_log[k], 4)}` +
    (st.measured_log ? `, measured ${fmt(st.measured_log[k], 4)} (${st.error_log[k] >= 0 ? '+' : ''}${fmt(st.error_log[k], 4)})` : '');
  return ` <span id="rig-strain">${axis(0, 'x')}; ${axis(1, 'y')}</span>`;
}

function updateRig(r) {
  const body = $('actuators').tBodies[0];
  if (!r) { setText('rig-info', 'no rig sample yet'); return; }
  setText('rig-info', `t_sim ${fmt(r.t_sim_s, 2)} s, ${r.rate_hz.toFixed(0)} samples/s`);
  body.innerHTML = r.actuators.map((a) => `<tr><td class="text">${esc(a.name)}</td><td class="text">${esc(a.mode)}</td>` +
    `<td>${fmt(a.position_mm, 3)}</td><td>${fmt(a.command, 3)} ${a.unit}</td><td>${fmt(a.error, 4)} ${a.unit}</td>` +
    `<td>${fmt(a.force_n, 1)}</td><td class="text ${a.limits.length ? 'bad' : ''}">${a.limits.length ? esc(a.limits.join(', ')) : 'none'}</td></tr>`).join('');
  const drift = r.axis_centre_mm.map((c) => fmt(c, 3)).join(' / ');
  $('rig-more').innerHTML = `program <b id="rig-program">${esc(r.program)}</b>, test ${r.test_index} (${esc(r.load_case)}), ` +
    `hydraulics <b class="${r.hydraulics_on ? 'good' : 'bad'}">${r.hydraulics_on ? 'on' : 'off'}</b>, ` +
    `limits <b class="${r.limits_tripped ? 'bad' : 'good'}">${r.limits_tripped ? 'TRIPPED' : 'none tripped'}</b>; ` +
    `stretch ${fmt(r.stretch[0], 4)} x ${fmt(r.stretch[1], 4)}, rotation ${fmt(r.rotation_deg, 3)}°, ` +
    `centre drift X/Y/Z ${drift} mm, specimen offset ${fmt(r.centre_offset_mm[0], 3)}, ${fmt(r.centre_offset_mm[1], 3)} mm; ` +
    `control <b id="rig-control" class="${r.control === 'held' ? 'bad' : ''}">${esc(r.control)}</b>` + strainText(r.strain);
  const h = r.history;
  lineChart($('rig-chart'), [
    { x: h.t_sim_s, y: h.stretch_x, color: SERIES_COLORS[0], label: 'λx' },
    { x: h.t_sim_s, y: h.stretch_y, color: SERIES_COLORS[1], label: 'λy' },
  ], { xlabel: 'test time (s)', ylabel: 'stretch (-)' });
}

// Each loaded actuator's force against the test's time and against its grip's displacement.
function updateForces(f) {
  const a = f ? f.actuators : [];
  setText('forces-info', a.length ? `loaded: ${a.map((x) => x.name).join(', ')}; ${f.t_sim_s.length} points` : 'no load yet');
  lineChart($('force-time-chart'), a.map((x, i) => ({ x: f.t_sim_s, y: x.force_n, color: SERIES_COLORS[i % 5], label: x.name })),
    { xlabel: 'test time (s)', ylabel: 'force (N)', yZero: true, empty: 'no loaded actuator yet' });
  lineChart($('force-grip-chart'), a.map((x, i) => ({ x: x.grip_mm, y: x.force_n, color: SERIES_COLORS[i % 5], label: x.name })),
    { xlabel: 'grip displacement (mm)', ylabel: 'force (N)', yZero: true, empty: 'no loaded actuator yet' });
}

// The latest field's node states in the (λ1, λ2) plane and the canonical paths (paper Fig. 5).
function updateStates(st) {
  if (dash.paused && dash.charts['states-chart']) return;
  dash.statePoints = st ? st.shown : 0;
  setText('states-info', st ? `field of frame ${st.frame_id}: ${st.shown} of ${st.valid} valid nodes` : 'no field yet');
  const series = [];
  if (st && st.shown > 0) {
    series.push({ x: st.l1, y: st.l2, color: SERIES_COLORS[1], label: 'nodes', dots: true });
    const top = Math.max(1.1, ...st.l1), x = [];
    for (let k = 0; k <= 40; k++) x.push(1 + (top - 1) * k / 40);
    series.push({ x, y: x.map((l) => 1 / Math.sqrt(l)), color: SERIES_COLORS[0], label: 'uniaxial' });
    series.push({ x, y: x, color: SERIES_COLORS[2], label: 'equibiaxial' });
    series.push({ x, y: x.map(() => 1), color: SERIES_COLORS[4], label: 'pure shear' });
  }
  lineChart($('states-chart'), series, { xlabel: 'λ1 (larger principal stretch, -)', ylabel: 'λ2 (-)', empty: 'no field yet' });
}

function updatePipeline(s) {
  setText('frames-seen', s.frames.seen);
  setText('frame-id', s.frames.last_id ?? '-');
  setText('frame-rate', `${fmt(s.frames.rate_hz, 1)} /s`);
  const c = s.correlator;
  setText('fields-seen', c.fields_seen);
  setText('field-rate', `${fmt(c.rate_hz, 1)} /s`);
  setText('correlate-ms', c.correlate_ms === null ? '-' : `${fmt(c.correlate_ms, 1)} ms`);
  setText('skipped', c.frames_skipped ?? '-');
  setText('missed', s.frames.missed_by_dashboard);
  setText('lat-field', latencyText(c.latency_ms));
  setText('lat-ident', latencyText(s.identification.latency_ms));
  setText('restarts-seen', `camera ${s.frames.camera_restarts_seen}, correlator ${c.restarts_seen}, rig ${s.rig ? s.rig.restarts_seen : 0} (ids going back)`);
  const edges = (c.latency_ms || s.identification.latency_ms || { bin_edges_ms: [] }).bin_edges_ms;
  barChart($('latency-chart'), [
    { label: 'capture → field', bins: c.latency_ms && c.latency_ms.bins, color: SERIES_COLORS[1] },
    { label: 'capture → identification', bins: s.identification.latency_ms && s.identification.latency_ms.bins, color: SERIES_COLORS[4] },
  ], edges);
}

function updateProcesses(p, mode) {
  const el = $('processes');
  if (!p || !p.roles) {
    el.innerHTML = mode === 'monitor'
      ? '<p class="small">Attached with <code>dicstream monitor</code>: this dashboard sees the services only. CPU per process, deaths and restarts with their reason are known to <code>dicstream run</code> and shown on its own dashboard; here a restart shows as ids going back (Pipeline).</p>'
      : '<p class="small">no process report yet</p>';
    return;
  }
  const rows = p.roles.map((r) => `<tr><td class="text">${esc(r.role)}</td><td>${r.pid ?? '-'}</td>` +
    `<td class="text ${r.alive ? 'good' : 'bad'}">${r.alive ? 'running' : 'not running'}</td><td>${fmt(r.cpu_s, 1)}</td>` +
    `<td>${fmt(100 * r.cpu_share, 0)} %</td><td id="restarts-${esc(r.role)}">${r.restarts}</td></tr>`).join('');
  const list = (items, empty) => items.length ? `<ul>${items.map((x) => `<li>${esc(x)}</li>`).join('')}</ul>` : `<p class="small">${empty}</p>`;
  el.innerHTML = `<table><thead><tr><th class="text">process</th><th>pid</th><th class="text">state</th><th>CPU s</th><th>CPU (one core)</th><th>restarts</th></tr></thead><tbody>${rows}</tbody></table>` +
    `<h3 class="small">deaths and stale processes (<span id="fault-count">${p.faults.length}</span>)</h3>${list(p.faults, 'none')}` +
    `<h3 class="small">restarts (<span id="restart-count">${p.restarts.length}</span>)</h3>${list(p.restarts, 'none')}`;
}

function updateIdentification(id) {
  if (!id.reports) { setText('ident-info', 'no identification yet'); $('coefficients').innerHTML = ''; return; }
  setText('ident-info', `${id.reports} reports, last at frame ${id.frame_id}; points uniaxial ${id.points.uniaxial}, equibiaxial ${id.points.equibiaxial}, pure shear ${id.points.pure_shear}`);
  const table = (name, law, c, waiting) => {
    if (!c) return `<p class="small">${name}: <i>${waiting}</i></p>`;
    const cells = c.values.map((v, i) => `<tr><td class="text">${law}<sub>${i}</sub></td><td>${sci(v)}</td><td>± ${sci(c.sigma[i])}</td></tr>`).join('');
    return `<table class="coef"><thead><tr><th class="text">${name}</th><th>value</th><th>σ</th></tr></thead><tbody>${cells}</tbody></table>`;
  };
  $('coefficients').innerHTML = `<div style="display:flex;gap:24px">` +
    table('f(I1) = exp Σ a_i (I1 − 3)^i', 'a', id.f_coefficients, 'waiting for uniaxial data') +
    table('g(I2) = exp Σ b_i (I2 − 3)^i', 'b', id.g_coefficients, 'waiting for equibiaxial data') +
    `</div><p class="small">Lambert-Diani-Rey fit, RMS ${fmt(id.rms_mpa, 4)} MPa</p>`;
  $('ranking').tBodies[0].innerHTML = id.ranking.map((m, i) => `<tr><td>${i + 1}</td><td class="text">${esc(m.name)}</td><td>${fmt(m.aic, 1)}</td><td>${fmt(m.rms_mpa, 4)}</td></tr>`).join('');
}

// ---- connection ----
function connect() {
  const es = new EventSource('/events');
  es.onopen = () => { $('conn').textContent = 'live'; $('conn').className = 'good'; };
  es.onerror = () => { $('conn').textContent = 'reconnecting'; $('conn').className = 'bad'; };
  es.addEventListener('snapshot', (e) => {
    try { update(JSON.parse(e.data)); } catch (err) { console.error(err); }
  });
  // The server is stopping (the run is over): no reconnecting, and what ended.
  es.addEventListener('end', () => {
    es.close();
    const finished = dash.last && dash.last.rig && dash.last.rig.program === 'finished';
    $('conn').textContent = finished ? 'test finished' : 'run ended';
    $('conn').className = finished ? 'good' : 'warn';
  });
}
// ---- pause and export ----
const CHART_IDS = ['gauge-chart', 'stress-chart', 'rig-chart', 'force-time-chart', 'force-grip-chart', 'states-chart', 'fg-chart', 'latency-chart'];
const csvCell = (v) => (v === null || v === undefined) ? '' : (typeof v === 'number' ? String(v) : `"${String(v).replace(/"/g, '""')}"`);
// The line charts' series as drawn: one row per point (chart, series, axis labels with units).
function chartsCsv() {
  const rows = ['chart,series,x_name,y_name,x,y'];
  for (const [id, c] of Object.entries(dash.charts)) {
    for (const s of c.series) {
      for (let i = 0; i < s.x.length; i++) {
        rows.push([id, s.label || '', c.opts.xlabel || '', c.opts.ylabel || '', s.x[i], s.y[i]].map(csvCell).join(','));
      }
    }
  }
  return rows.join('\n') + '\n';
}
function chartsPng() {
  const out = {};
  for (const id of CHART_IDS) out[id] = $(id).toDataURL('image/png');
  return out;
}
function snapshotJson() { return JSON.stringify(dash.last, null, 1); }
dash.exportCsv = chartsCsv; dash.exportPng = chartsPng; dash.exportJson = snapshotJson;

function download(name, url) {
  const a = document.createElement('a');
  a.href = url; a.download = name; document.body.appendChild(a); a.click(); a.remove();
}
const stamp = () => `${dash.last ? dash.last.instance : 'dicstream'}_${new Date().toISOString().replace(/[:.]/g, '-')}`;
const blobUrl = (text, type) => URL.createObjectURL(new Blob([text], { type }));
$('export-csv').addEventListener('click', () => {
  const text = chartsCsv(); dash.exported.csv = text.length;
  download(`${stamp()}_charts.csv`, blobUrl(text, 'text/csv'));
});
$('export-json').addEventListener('click', () => {
  const text = snapshotJson(); dash.exported.json = text.length;
  download(`${stamp()}_snapshot.json`, blobUrl(text, 'application/json'));
});
$('export-png').addEventListener('click', () => {
  const pngs = chartsPng();
  dash.exported.png = Object.values(pngs).reduce((n, u) => n + u.length, 0);
  for (const [id, url] of Object.entries(pngs)) download(`${stamp()}_${id}.png`, url);
});
$('pause').addEventListener('click', () => {
  dash.paused = !dash.paused;
  $('pause').textContent = dash.paused ? 'resume' : 'pause';
  $('pause').className = dash.paused ? 'on' : '';
  if (!dash.paused && dash.last) update(dash.last);
});

// ---- zoom: drag across a line chart selects its x range, a double click resets it ----
function zoomTo(id, range) {
  if (range) dash.zoom[id] = range; else delete dash.zoom[id];
  const c = dash.charts[id];
  if (c) lineChart($(id), c.series, c.opts, true);
}
dash.zoomTo = zoomTo;
for (const id of CHART_IDS.filter((c) => c !== 'latency-chart')) {
  const canvas = $(id);
  canvas.title = 'drag across to zoom on x; double-click to reset';
  const dataX = (e) => {
    const f = dash.charts[id] && dash.charts[id].frame;
    if (!f) return null;
    const x = e.offsetX * canvas.width / canvas.clientWidth;
    return f.x0 + (x - f.left) / (f.right - f.left) * (f.x1 - f.x0);
  };
  let from = null;
  canvas.addEventListener('mousedown', (e) => { from = dataX(e); });
  canvas.addEventListener('mouseup', (e) => {
    const to = dataX(e), f = dash.charts[id] && dash.charts[id].frame;
    if (from !== null && to !== null && f && Math.abs(to - from) > 0.02 * (f.x1 - f.x0)) {
      zoomTo(id, [Math.min(from, to), Math.max(from, to)]);
    }
    from = null;
  });
  canvas.addEventListener('dblclick', () => zoomTo(id, null));
}

for (const id of ['component', 'map-measure', 'range-mode', 'range-min', 'range-max', 'show-mesh', 'show-map']) {
  $(id).addEventListener('change', drawSpecimen);
}
$('measure').addEventListener('change', () => dash.last && update(dash.last));
connect();
