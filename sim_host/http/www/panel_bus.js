/* DFP21B front panel: the "bus" page, what the bus monitor of dfp-sim sees on the line
 * (docs/api.md, GET /api/v1/bus): the live list, one station's details, the bus events (log
 * kind "bus" from the stream, newest first) and a plot of one slave's Data_Exchange cycle time.
 * It polls the document about once a second while the page is shown, every BUS_POLL_HIDDEN
 * turns while a card is (the plot goes on, a large line's document is not fetched for
 * nothing), and sends nothing but GETs. A process without a monitor answers 404: the page's
 * tab is then hidden. */
'use strict';

const BUS_POLL_MS = 1000;
const BUS_POLL_HIDDEN = 5;
const BUS_EVENTS_MAX = 200;
const BUS_PLOT_WINDOW_S = 60;
let busDoc = null;          /* the last document */
let busSel = null;          /* address of the station whose details are shown */
let busTimer = null;
let busTurn = 0;
let busEvents = [];         /* log events of kind "bus", newest first */
const busCycle = new Map(); /* slave address -> [{t, ms}]: mean cycle time between two polls */
const busLastSpan = new Map(); /* slave address -> the dx_cycle_ms span of the last poll */

function busShown() {
  return document.body.dataset.page === 'bus';
}

/* The bus page or the card pages; the URL's #bus says which, so it can be bookmarked. */
function showBusPage(on) {
  document.body.dataset.page = on ? 'bus' : 'cards';
  $('tab-bus').classList.toggle('active', on);
  if (on && location.hash !== '#bus') history.replaceState(history.state, '', '#bus');
  if (!on && location.hash === '#bus') history.replaceState(history.state, '', location.pathname + location.search);
  if (typeof render === 'function') render();
  if (on) { renderBus(); pollBus(); }
}

function span3(s, digits) {
  if (!s) return '–';
  const f = (v) => Number(v).toFixed(digits);
  return f(s.min) + ' / ' + f(s.mean) + ' / ' + f(s.max);
}
function spanMean(s, digits) {
  return s ? Number(s.mean).toFixed(digits) : '–';
}

/* "now": something is wrong at present (a DP slave out of data exchange); "past": counters say
 * something went wrong since the start (missing answers, repeats, late or refused answers). */
function busWarning(st) {
  const dp = st.dp;
  if (dp && dp.state !== 'Data_Exch') return ['now', 'not in data exchange (' + dp.state + ')'];
  const why = [];
  if (st.missing) why.push(st.missing + ' missing answers');
  if (st.repeats_received) why.push(st.repeats_received + ' repeats');
  if (st.tsdr_over_slot) why.push(st.tsdr_over_slot + ' answers later than the slot time');
  if (st.rs || st.ue) why.push('RS/UE answers');
  if (st.garbled) why.push(st.garbled + ' garbled');
  if (st.token_repeats) why.push(st.token_repeats + ' token repeats');
  return why.length ? ['past', why.join(', ')] : ['', ''];
}

function busRowCells(st) {
  const dp = st.dp || {};
  return [
    ['c-addr', String(st.address)],
    ['c-role', st.role + (st.in_ring ? ' (ring)' : '')],
    ['c-state', st.dp ? dp.state : '–'],
    ['c-master', st.dp && dp.master !== null && dp.master !== undefined ? String(dp.master) : '–'],
    ['c-ident', (st.dp && dp.ident) || '–'],
    ['c-cycle', st.dp ? spanMean(dp.dx_cycle_ms, 2) : '–'],
    ['c-tsdr', spanMean(st.tsdr_us, 1)],
    ['c-repeats', String((st.repeats_received || 0) + (st.repeats_sent || 0))],
    ['c-missing', String((st.missing || 0) + (st.unanswered_sent || 0))],
  ];
}

function busRow(st) {
  const tr = document.createElement('tr');
  tr.id = 'bus-st-' + st.address;
  tr.dataset.address = String(st.address);
  const [level, why] = busWarning(st);
  tr.dataset.warn = level;
  const mark = document.createElement('td');
  mark.className = 'c-warn';
  mark.textContent = level ? '⚠' : '';
  mark.title = why;
  tr.appendChild(mark);
  busRowCells(st).forEach(([cls, v]) => {
    const td = document.createElement('td');
    td.className = cls;
    td.textContent = v;
    tr.appendChild(td);
  });
  if (st.dp) tr.dataset.state = st.dp.state;
  if (st.address === busSel) tr.classList.add('sel');
  tr.addEventListener('click', () => { busSel = st.address; renderBus(); drawBusPlot(); });
  return tr;
}

function renderBusList(stations) {
  const tb = $('bus-stations').tBodies[0];
  const key = JSON.stringify(stations.map((s) => [busRowCells(s), busWarning(s)])) + '|' + busSel;
  if (tb.dataset.key === key) return;
  tb.dataset.key = key;
  tb.textContent = '';
  stations.forEach((st) => tb.appendChild(busRow(st)));
  $('bus-none').hidden = stations.length > 0;
}

/* One row of the details: a heading row when value is undefined. */
function busKv(tb, key, value, mono) {
  const tr = document.createElement('tr');
  tr.dataset.key = key;
  const th = document.createElement('th');
  th.textContent = key;
  tr.appendChild(th);
  if (value === undefined) {
    th.colSpan = 2;
    th.className = 'sub';
  } else {
    const td = document.createElement('td');
    td.textContent = (value === null || value === '') ? '–' : String(value);
    if (mono) td.className = 'mono';
    tr.appendChild(td);
  }
  tb.appendChild(tr);
}

function busDetailRows(tb, st) {
  busKv(tb, 'role', st.role + (st.in_ring ? ', in the token ring' : ''));
  busKv(tb, 'heard', st.seen ? st.first_s.toFixed(3) + ' s … ' + st.last_s.toFixed(3) + ' s' : 'only addressed');
  if (st.role === 'active') {
    busKv(tb, 'FDL status', st.fdl_status);
    busKv(tb, 'next station', st.next_station);
    busKv(tb, 'tokens (repeats)', st.tokens_sent + ' (' + st.token_repeats + ')');
    busKv(tb, 'rotation ms min/mean/max', span3(st.rotation_ms, 3), true);
    busKv(tb, 'rotations over TTR', st.rotations_over_ttr);
    busKv(tb, 'requests sent (repeats, unanswered)',
      st.requests_sent + ' (' + st.repeats_sent + ', ' + st.unanswered_sent + ')');
  }
  busKv(tb, 'requests received (answers, missing)',
    st.requests_received + ' (' + st.answers + ', ' + st.missing + ')');
  busKv(tb, 'repeats received', st.repeats_received);
  busKv(tb, 'RS / RR / UE / garbled', [st.rs, st.rr, st.ue, st.garbled].join(' / '));
  busKv(tb, 'TSDR µs min/mean/max', span3(st.tsdr_us, 1), true);
  busKv(tb, 'TSDR below min / over max / over slot',
    [st.tsdr_below_min, st.tsdr_over_max, st.tsdr_over_slot].join(' / '));
  const dp = st.dp;
  if (!dp) return;
  busKv(tb, 'DP slave');
  busKv(tb, 'state', dp.state);
  busKv(tb, 'master', dp.master);
  busKv(tb, 'ident', dp.ident, true);
  busKv(tb, 'diagnosis', dp.diag_text);
  busKv(tb, 'diagnosis octets', dp.diag, true);
  busKv(tb, 'diagnosis changes / Stat_Diag', dp.diag_changes + ' / ' + dp.stat_diag);
  busKv(tb, 'configuration (Chk_Cfg)', dp.cfg, true);
  busKv(tb, 'parameters (Set_Prm)', dp.prm, true);
  busKv(tb, 'watchdog', dp.watchdog_ms ? dp.watchdog_ms + ' ms' : 'off');
  busKv(tb, 'min TSDR / GSD max TSDR (bits)', dp.min_tsdr_bits + ' / ' + (dp.max_tsdr_bits || '–'));
  busKv(tb, 'outputs', dp.outputs, true);
  busKv(tb, 'inputs', dp.inputs, true);
  busKv(tb, 'Data_Exchange', dp.dx_count);
  busKv(tb, 'DX cycle ms min/mean/max', span3(dp.dx_cycle_ms, 3), true);
  const d = dp.dfp21b;
  if (!d) return;
  busKv(tb, 'DFP21B (ident 0x6003)');
  busKv(tb, 'PD configuration', d.pd_config);
  busKv(tb, 'parameter channel', d.param_channel ? 'yes (8 octets before the PD)' : 'no');
  busKv(tb, 'control word', d.control_word + ' ' + (d.control_text || ''));
  busKv(tb, 'status word', d.status_word + ' ' + (d.status_text || ''));
  busKv(tb, 'MOVILINK request', d.param_request);
  busKv(tb, 'MOVILINK answer', d.param_answer);
}

function renderBusDetail(st) {
  const tb = $('bus-detail').tBodies[0];
  text('bus-sel', st ? st.address : null);
  const key = JSON.stringify(st);
  if (tb.dataset.key === key) return;
  tb.dataset.key = key;
  tb.textContent = '';
  if (st) busDetailRows(tb, st);
  $('bus-detail-none').hidden = !!st;
}

function renderBus() {
  if (!busDoc || !busShown()) return;
  const mon = busDoc.monitor || {};
  const line = busDoc.line || {};
  const ring = busDoc.ring || {};
  text('bus-info', (mon.source || '') + (mon.baud ? ' · ' + baudText(mon.baud) : '') +
    ' · ring ' + ((ring.members || []).join(', ') || 'none') +
    ' · ' + (line.telegrams || 0) + ' telegrams' +
    (typeof line.load_pct === 'number' ? ' · load ' + line.load_pct.toFixed(1) + ' %' : '') +
    (mon.timing === false ? ' · TSDR not measurable on this medium' : ''));
  const stations = Array.isArray(busDoc.stations) ? busDoc.stations : [];
  if (busSel === null || !stations.some((s) => s.address === busSel)) {
    const slave = stations.find((s) => s.dp);
    busSel = slave ? slave.address : (stations.length ? stations[0].address : null);
  }
  renderBusList(stations);
  renderBusDetail(stations.find((s) => s.address === busSel) || null);
  drawBusPlot();
}

/* The mean cycle time since the last poll, from the running sums of two documents. */
function noteBusCycles(doc) {
  const t = (doc.monitor && doc.monitor.t_s) || 0;
  (doc.stations || []).forEach((st) => {
    const s = st.dp && st.dp.dx_cycle_ms;
    if (!s) return;
    const prev = busLastSpan.get(st.address);
    busLastSpan.set(st.address, s);
    if (!prev || s.n <= prev.n) return;
    /* From the sums: the rounded means times n would be off by n times their rounding. */
    const ms = (s.sum - prev.sum) / (s.n - prev.n);
    let a = busCycle.get(st.address);
    if (!a) { a = []; busCycle.set(st.address, a); }
    a.push({ t: t, ms: ms });
    while (a.length && a[0].t < t - BUS_PLOT_WINDOW_S - 5) a.shift();
  });
}

async function pollBus() {
  if (role === null) return;
  try {
    const doc = await api('GET', 'bus');
    $('tab-bus').hidden = false;
    const t = doc && doc.monitor ? doc.monitor.t_s : 0;
    if (busDoc && busDoc.monitor && t < busDoc.monitor.t_s) { busCycle.clear(); busLastSpan.clear(); }
    busDoc = doc;
    noteBusCycles(doc);
    renderBus();
  } catch (e) {
    if (e.status === 404) {
      /* this process runs no monitor: no page to show */
      $('tab-bus').hidden = true;
      if (busShown()) showBusPage(false);
      busStop();
    }
  }
}

function busStart() {
  busStop();
  pollBus();
  busTimer = setInterval(() => {
    busTurn++;
    if (busShown() || busTurn % BUS_POLL_HIDDEN === 0) pollBus();
  }, BUS_POLL_MS);
}
function busStop() {
  if (busTimer !== null) clearInterval(busTimer);
  busTimer = null;
}

function busEventItem(e) {
  const li = logItem(e);
  li.id = 'bus-ev-' + e.seq;
  return li;
}

/* A log event from GET /api/v1/log or the stream (panel_log.js passes every one). */
function busNoteLog(e) {
  if (!e || e.kind !== 'bus') return;
  if (busEvents.some((x) => x.seq === e.seq)) return;
  const ul = $('bus-events');
  if (busEvents.length && e.seq < busEvents[0].seq) {
    busEvents.push(e);
    busEvents.sort((a, b) => b.seq - a.seq);
    busEvents = busEvents.slice(0, BUS_EVENTS_MAX);
    ul.textContent = '';
    busEvents.forEach((x) => ul.appendChild(busEventItem(x)));
  } else {
    busEvents.unshift(e);
    ul.insertBefore(busEventItem(e), ul.firstChild);
    while (busEvents.length > BUS_EVENTS_MAX) { busEvents.pop(); ul.removeChild(ul.lastChild); }
  }
  text('bus-ev-count', busEvents.length + ' events');
}

function busClearEvents() {
  busEvents = [];
  $('bus-events').textContent = '';
  text('bus-ev-count', '');
}

function drawBusPlot() {
  if (!busShown()) return;
  const { g, w, h } = plotCanvas('bus-plot');
  const k = plotColours();
  g.fillStyle = k.bg;
  g.fillRect(0, 0, w, h);
  const L = 52, R = 14, T = 10, B = 22;
  const pw = w - L - R, ph = h - T - B;
  text('bus-plot-station', busSel);
  const data = busCycle.get(busSel) || [];
  const tEnd = busDoc && busDoc.monitor ? busDoc.monitor.t_s : 0;
  const tStart = tEnd - BUS_PLOT_WINDOW_S;
  const vis = data.filter((p) => p.t >= tStart);
  let vmax = 1;
  vis.forEach((p) => { vmax = Math.max(vmax, p.ms); });
  const step = niceStep(vmax * 1.1, 4);
  vmax = Math.ceil((vmax * 1.05) / step) * step;
  const X = (t) => L + ((t - tStart) / BUS_PLOT_WINDOW_S) * pw;
  const Y = (v) => T + ph - (v / vmax) * ph;
  g.font = '11px ui-monospace, SFMono-Regular, Menlo, Consolas, monospace';
  g.strokeStyle = k.grid;
  g.fillStyle = k.txt;
  g.textAlign = 'right';
  g.textBaseline = 'middle';
  for (let v = 0; v <= vmax + 1e-9; v += step) {
    const y = Math.round(Y(v)) + 0.5;
    g.beginPath(); g.moveTo(L, y); g.lineTo(L + pw, y); g.stroke();
    g.fillText(String(Math.round(v * 100) / 100), L - 6, y);
  }
  g.textAlign = 'center';
  g.textBaseline = 'top';
  for (let s = 0; s <= BUS_PLOT_WINDOW_S; s += 10) {
    const x = Math.round(L + (s / BUS_PLOT_WINDOW_S) * pw) + 0.5;
    g.beginPath(); g.moveTo(x, T); g.lineTo(x, T + ph); g.stroke();
    g.fillText(s === BUS_PLOT_WINDOW_S ? 'now' : '-' + (BUS_PLOT_WINDOW_S - s) + ' s', x, T + ph + 5);
  }
  g.strokeStyle = k.act;
  g.lineWidth = 2;
  g.beginPath();
  vis.forEach((p, i) => { if (i === 0) g.moveTo(X(p.t), Y(p.ms)); else g.lineTo(X(p.t), Y(p.ms)); });
  g.stroke();
  g.lineWidth = 1;
  g.strokeStyle = k.grid;
  g.strokeRect(L + 0.5, T + 0.5, pw, ph);
  if (!vis.length) {
    g.fillStyle = k.txt;
    g.textAlign = 'center';
    g.textBaseline = 'middle';
    g.fillText(busSel === null ? 'no station' : 'no Data_Exchange cycles of this station (yet)', L + pw / 2, T + ph / 2);
  }
}

function wireBus() {
  $('tab-bus').addEventListener('click', () => showBusPage(true));
  window.addEventListener('resize', drawBusPlot);
  if (location.hash === '#bus') showBusPage(true);
}
