/* DFP21B front panel: the speed and current plot of the selected card's drive over the last
 * 20 s, drawn on a canvas from the state events (panel.js feeds it). */
'use strict';

const PLOT_WINDOW_US = 20e6;
const plotData = new Map(); /* card address -> [{t, sp, act, cur}] */
let lastT = -1;

function addSamples(s) {
  if (typeof s.t_us !== 'number') return;
  if (s.t_us < lastT) restarted();
  lastT = s.t_us;
  (s.cards || []).forEach((c) => {
    if (!c.drive) return;
    let a = plotData.get(c.address);
    if (!a) { a = []; plotData.set(c.address, a); }
    a.push({ t: s.t_us, sp: c.drive.speed_setpoint_rpm, act: c.drive.speed_actual_rpm, cur: c.drive.current_pct });
    while (a.length && a[0].t < s.t_us - PLOT_WINDOW_US - 1e6) a.shift();
  });
}

function niceStep(range, n) {
  const raw = range / n;
  const p = Math.pow(10, Math.floor(Math.log10(raw)));
  const f = raw / p;
  return (f <= 1 ? 1 : f <= 2 ? 2 : f <= 5 ? 5 : 10) * p;
}

/* The canvas (id, default the drive's plot) at the device's pixel ratio; returns its size in CSS
 * pixels and the context. The bus page draws its cycle times with it too. */
function plotCanvas(id) {
  const cv = $(id || 'plot');
  const dpr = window.devicePixelRatio || 1;
  const w = Math.max(200, cv.clientWidth);
  const h = Math.max(120, cv.clientHeight);
  if (cv.width !== Math.round(w * dpr) || cv.height !== Math.round(h * dpr)) {
    cv.width = Math.round(w * dpr);
    cv.height = Math.round(h * dpr);
  }
  const g = cv.getContext('2d');
  g.setTransform(dpr, 0, 0, dpr, 0, 0);
  return { g: g, w: w, h: h };
}

function plotColours() {
  const css = getComputedStyle(document.body);
  const col = (n, d) => (css.getPropertyValue(n) || d).trim();
  return {
    bg: col('--plot-bg', '#0d1117'), grid: col('--plot-grid', '#263040'), txt: col('--muted', '#8b96a5'),
    sp: col('--c-setpoint', '#e3b341'), act: col('--c-actual', '#3fb950'), cur: col('--c-current', '#58a6ff'),
  };
}

/* Speed axis: includes 0, at least +-100 rpm of room; current axis 0..max(20 %, peak). */
function plotScales(vis) {
  let smin = 0, smax = 100;
  vis.forEach((p) => {
    [p.sp, p.act].forEach((v) => { if (typeof v === 'number') { smin = Math.min(smin, v); smax = Math.max(smax, v); } });
  });
  const sstep = niceStep((smax - smin) * 1.1 || 100, 5);
  smin = Math.floor(smin / sstep) * sstep;
  smax = Math.ceil((smax * 1.05) / sstep) * sstep;
  if (smax <= smin) smax = smin + sstep;
  let cmax = 20;
  vis.forEach((p) => { if (typeof p.cur === 'number') cmax = Math.max(cmax, p.cur); });
  const cstep = niceStep(cmax * 1.1, 4);
  cmax = Math.ceil((cmax * 1.05) / cstep) * cstep;
  return { smin: smin, smax: smax, sstep: sstep, cmax: cmax, cstep: cstep };
}

/* Grid, axis labels and the time scale; fr is the frame (L, T, pw, ph, YS, YC). */
function drawAxes(g, fr, sc, k) {
  const { L, T, pw, ph, YS, YC } = fr;
  g.font = '11px ui-monospace, SFMono-Regular, Menlo, Consolas, monospace';
  g.lineWidth = 1;
  g.strokeStyle = k.grid;
  g.fillStyle = k.txt;
  g.textBaseline = 'middle';
  g.textAlign = 'right';
  for (let v = sc.smin; v <= sc.smax + 1e-9; v += sc.sstep) {
    const y = Math.round(YS(v)) + 0.5;
    g.beginPath(); g.moveTo(L, y); g.lineTo(L + pw, y); g.stroke();
    g.fillText(String(Math.round(v * 10) / 10), L - 6, y);
  }
  g.textAlign = 'left';
  g.fillStyle = k.cur;
  for (let v = 0; v <= sc.cmax + 1e-9; v += sc.cstep) g.fillText(v + '%', L + pw + 6, YC(v));
  g.fillStyle = k.txt;
  g.textAlign = 'center';
  g.textBaseline = 'top';
  for (let s = 0; s <= 20; s += 5) {
    const x = Math.round(L + (s / 20) * pw) + 0.5;
    g.beginPath(); g.moveTo(x, T); g.lineTo(x, T + ph); g.stroke();
    g.fillText(s === 20 ? 'now' : '-' + (20 - s) + ' s', x, T + ph + 5);
  }
  g.save();
  g.translate(12, T + ph / 2);
  g.rotate(-Math.PI / 2);
  g.textBaseline = 'middle';
  g.fillText('rpm', 0, 0);
  g.restore();
  if (sc.smin < 0) {
    g.strokeStyle = k.txt;
    const y0 = Math.round(YS(0)) + 0.5;
    g.beginPath(); g.moveTo(L, y0); g.lineTo(L + pw, y0); g.stroke();
  }
}

/* Current, setpoint and actual speed, clipped to the frame. */
function drawTraces(g, fr, vis, k) {
  g.save();
  g.beginPath();
  g.rect(fr.L, fr.T, fr.pw, fr.ph);
  g.clip();
  const line = (key, Y, color, width, dash) => {
    g.strokeStyle = color;
    g.lineWidth = width;
    g.setLineDash(dash || []);
    g.beginPath();
    let started = false;
    vis.forEach((p) => {
      const v = p[key];
      if (typeof v !== 'number') { started = false; return; }
      const x = fr.X(p.t), y = Y(v);
      if (!started) { g.moveTo(x, y); started = true; } else g.lineTo(x, y);
    });
    g.stroke();
  };
  line('cur', fr.YC, k.cur, 1.5);
  line('sp', fr.YS, k.sp, 1.5, [5, 3]);
  line('act', fr.YS, k.act, 2);
  g.restore();
  g.setLineDash([]);
}

function drawPlot() {
  const { g, w, h } = plotCanvas();
  const k = plotColours();
  g.fillStyle = k.bg;
  g.fillRect(0, 0, w, h);

  const L = 52, R = 44, T = 10, B = 22;
  const pw = w - L - R, ph = h - T - B;
  const data = plotData.get(selected) || [];
  const tEnd = data.length ? data[data.length - 1].t : (state ? state.t_us : 0);
  const tStart = tEnd - PLOT_WINDOW_US;
  const vis = data.filter((p) => p.t >= tStart - 2e5);
  const sc = plotScales(vis);
  const fr = {
    L: L, T: T, pw: pw, ph: ph,
    X: (t) => L + ((t - tStart) / PLOT_WINDOW_US) * pw,
    YS: (v) => T + ph - ((v - sc.smin) / (sc.smax - sc.smin)) * ph,
    YC: (v) => T + ph - (v / sc.cmax) * ph,
  };
  drawAxes(g, fr, sc, k);
  drawTraces(g, fr, vis, k);
  g.strokeStyle = k.grid;
  g.strokeRect(L + 0.5, T + 0.5, pw, ph);
  if (!vis.length) {
    g.fillStyle = k.txt;
    g.textAlign = 'center';
    g.textBaseline = 'middle';
    g.fillText(currentCard() && !currentCard().drive ? 'no drive on this card' : 'waiting for data…', L + pw / 2, T + ph / 2);
  }
}
