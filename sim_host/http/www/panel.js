/* DFP21B front panel for dfp-sim. Plain ES2017, no library, no build step: it reads the control
 * API of docs/api.md (GET /api/v1/state once, then the SSE stream /api/v1/events) and sends the
 * actions the API offers. URLs are relative so the panel also works behind a path prefix.
 * Classic scripts sharing one global scope, loaded in this order by index.html: panel_util.js,
 * panel_auth.js, panel_plot.js, panel_log.js, panel_params.js, panel_bus.js (the bus page), then
 * this file (state, rendering, controls). panel_auth.js decides between its login form and the
 * panel (panelStart). */
'use strict';

const STALE_MS = 3000; /* no state event for this long: the stream is considered dropped */
const CW_BITS = [
  [0, 'controller inhibit'], [1, 'enable / rapid stop'], [2, 'enable / stop'], [3, 'hold control'],
  [4, 'ramp set 2'], [5, 'param set 2'], [6, 'fault reset']];

let state = null;          /* the last /api/v1/state object */
let selected = null;       /* address of the card shown */
let shownCard = null;      /* address the card-bound fields were last filled for */
let readOnly = false;
let es = null;
let lastStateAt = 0;
let tabsKey = '';
const pending = {};        /* control id -> true while its request runs */

/* An action from a control: shows what it does and how it ended in the status line. */
async function act(label, method, path, body, key) {
  if (key) pending[key] = true;
  setStatus(label + ' …', 'busy');
  try {
    const r = await api(method, path, body);
    if (r && r.ok === false) {
      setStatus(label + ': ' + (r.error || 'refused'), 'error');
    } else {
      setStatus(label + ': ok', 'ok');
    }
    return r;
  } catch (e) {
    setStatus(label + ': ' + e.message, 'error');
    return null;
  } finally {
    if (key) delete pending[key];
  }
}

function currentCard() {
  if (!state || !Array.isArray(state.cards)) return null;
  return state.cards.find((c) => c.address === selected) || null;
}
function masterSlave(addr) {
  const m = state && state.master;
  if (!m || !Array.isArray(m.slaves)) return null;
  return m.slaves.find((s) => s.address === addr) || null;
}

/* ---------- rendering ---------- */

function buildDip() {
  const box = $('dip-switches');
  box.textContent = '';
  const labels = ['2⁰', '2¹', '2²', '2³', '2⁴', '2⁵', '2⁶', 'nc'];
  labels.forEach((l, i) => {
    const sw = document.createElement('div');
    sw.className = 'dsw';
    sw.id = 'dip-' + i;
    sw.dataset.on = '0';
    sw.title = i < 7 ? 'address bit ' + i + ' (' + (1 << i) + ')' : 'not connected';
    const slot = document.createElement('div');
    slot.className = 'dsw-slot';
    const knob = document.createElement('div');
    knob.className = 'dsw-knob';
    slot.appendChild(knob);
    const lab = document.createElement('span');
    lab.textContent = l;
    sw.appendChild(slot);
    sw.appendChild(lab);
    box.appendChild(sw);
  });
}

function buildCwBits() {
  const box = $('cw-bits');
  CW_BITS.forEach(([bit, name]) => {
    const l = document.createElement('label');
    l.className = 'chk';
    const cb = document.createElement('input');
    cb.type = 'checkbox';
    cb.className = 'ctl';
    cb.id = 'cw-bit-' + bit;
    cb.dataset.bit = String(bit);
    cb.addEventListener('change', cwFromBits);
    l.appendChild(cb);
    l.appendChild(document.createTextNode(' ' + bit + ' ' + name));
    box.appendChild(l);
  });
}

function renderTabs() {
  const cards = (state && state.cards) || [];
  const onCards = !busShown();
  const key = cards.map((c) => c.address).join(',') + '|' + selected + '|' + onCards;
  const nav = $('card-tabs');
  if (key !== tabsKey) {
    tabsKey = key;
    nav.textContent = '';
    cards.forEach((c) => {
      const b = document.createElement('button');
      b.className = 'tab' + (onCards && c.address === selected ? ' active' : '');
      b.id = 'tab-card-' + c.address;
      b.dataset.address = String(c.address);
      const dot = document.createElement('i');
      dot.className = 'tabdot';
      b.appendChild(dot);
      b.appendChild(document.createTextNode('card ' + c.address));
      b.addEventListener('click', () => { selected = c.address; showBusPage(false); });
      nav.appendChild(b);
    });
    if (!cards.length) {
      const s = document.createElement('span');
      s.className = 'dim';
      s.textContent = 'no card';
      nav.appendChild(s);
    }
  }
  cards.forEach((c) => {
    const b = $('tab-card-' + c.address);
    if (b) b.dataset.dp = (c.dp && c.dp.state) || '';
  });
}

function renderLedsAndDip(c) {
  const leds = c.leds || {};
  const runEl = $('led-run');
  const bfEl = $('led-bus-fault');
  runEl.dataset.mode = leds.run || 'off';
  bfEl.dataset.mode = leds.bus_fault || 'off';
  runEl.title = 'RUN: ' + (leds.run || 'off') + (leds.run_pattern ? ' (' + leds.run_pattern + ')' : '');
  bfEl.title = 'BUS FAULT: ' + (leds.bus_fault || 'off') +
    (leds.bus_fault_pattern ? ' (' + leds.bus_fault_pattern + ')' : '');

  const dip = c.dip || {};
  for (let i = 0; i < 8; i++) {
    const sw = $('dip-' + i);
    if (sw) sw.dataset.on = (i < 7 && ((dip.address >> i) & 1)) ? '1' : '0';
  }
  text('card-address', c.address);
  $('subd').dataset.cable = c.cable ? 'true' : 'false';
  const hint = $('dip-hint');
  const nextMsg = (dip.next_address !== undefined && dip.next_address !== dip.address)
    ? 'DIP switches set to ' + dip.next_address + ': takes effect at the next power-cycle'
    : 'DIP switches: ' + dip.address + ' (read at power-up)';
  if (hint.textContent !== nextMsg) hint.textContent = nextMsg;
}

function renderDp(c) {
  const dp = c.dp || {};
  const dpEl = $('dp-state');
  text('dp-state', dp.state);
  dpEl.dataset.state = dp.state || '';
  text('dp-master', dp.master === null || dp.master === undefined ? 'none' : dp.master);
  text('dp-baud', dp.baud === null || dp.baud === undefined ? '– (searching)' : baudText(dp.baud));
  text('dp-baud-state', dp.baud_state);
  text('dp-watchdog', dp.watchdog_ms ? dp.watchdog_ms + ' ms' : 'off');
  text('dp-config', dp.config);
  text('dp-on-bus', c.on_bus ? 'yes' : 'no');
  const diag = dp.diag || {};
  text('diag-text', diag.text);
  text('diag-ext-text', diag.ext_text || diag.ext || 'none');
  $('diag-ext').textContent = diag.ext && diag.ext_text ? diag.ext : '';
  $('diag-hex').textContent = diag.hex || '';
}

function renderMonitorAndNvm(c) {
  const mon = c.monitor || {};
  text('mon-p090', mon.P090);
  text('mon-po', words(mon.po));
  text('mon-pi', words(mon.pi));

  const notes = [];
  const nvm = c.nvm || {};
  if (nvm.eeprom_note) notes.push('EEPROM: ' + nvm.eeprom_note);
  if (nvm.card_nvm_note) notes.push('card NVM: ' + nvm.card_nvm_note);
  if (nvm.note) notes.push(nvm.note);
  const nv = $('nvm-notes');
  const nkey = notes.join('\n');
  if (nv.dataset.key !== nkey) {
    nv.dataset.key = nkey;
    nv.textContent = '';
    notes.forEach((n) => {
      const d = document.createElement('div');
      d.className = 'note';
      d.textContent = n;
      nv.appendChild(d);
    });
  }
  $('drive-eeprom').textContent = nvm.eeprom ? 'EEPROM ' + nvm.eeprom : '';
}

function renderDrive(c) {
  const d = c.drive;
  if (d) {
    text('speed-actual', fmt1(d.speed_actual_rpm));
    text('speed-setpoint', fmt1(d.speed_setpoint_rpm));
    text('current', fmt1(d.current_pct));
    text('fault-name', d.fault ? 'F' + d.fault + ' ' + d.fault_name : d.fault_name);
    $('fault-name').dataset.fault = d.fault ? '1' : '0';
    text('control-text', d.control_text);
    text('status-text', d.status_text);
    const ins = d.inputs || {};
    text('drive-inputs', Object.keys(ins).map((k) => k + ' = ' + (ins[k] ? '+24 V' : '0 V')).join(', ') +
      (d.enabled ? ' · enabled' : ' · not enabled'));
    text('drive-ramps', 'up ' + d.ramp_up_ms + ' ms, down ' + d.ramp_down_ms + ' ms');
    if (!pending.di00) $('di00').checked = !!ins.DI00;
  } else {
    ['speed-actual', 'speed-setpoint', 'current', 'control-text', 'status-text', 'drive-inputs',
      'drive-ramps'].forEach((id) => text(id, null));
    text('fault-name', 'no drive');
  }
  if (!pending.cable) $('cable').checked = !!c.cable;
}

function renderDpv1(c) {
  const v1 = c.dpv1 || {};
  text('dpv1-enabled', v1.enabled ? 'enabled' : 'off');
  text('dpv1-msac1', v1.msac1 ? 'open' : 'closed');
  const m2 = Array.isArray(v1.msac2) ? v1.msac2 : [];
  for (let i = 0; i < 2; i++) {
    const x = m2[i];
    text('dpv1-msac2-' + i, !x ? '–' : (x.open ? 'open (master ' + x.master + ')' : 'closed'));
    const el = $('dpv1-msac2-' + i);
    el.dataset.open = x && x.open ? '1' : '0';
  }
  $('dpv1-msac1').dataset.open = v1.msac1 ? '1' : '0';
}

function renderCard(c) {
  renderLedsAndDip(c);
  renderDp(c);
  renderMonitorAndNvm(c);
  renderDrive(c);
  renderDpv1(c);

  const dip = c.dip || {};
  /* fields the user edits: filled when another card is shown, not on every update */
  if (shownCard !== c.address) {
    shownCard = c.address;
    $('dip-next').value = dip.next_address !== undefined ? dip.next_address : dip.address;
    $('ps-slave').value = c.address;
    text('po-slave', c.address);
    loadPo();
    if (paramSel) readParam();
  }
}

function renderMaster() {
  const m = state.master;
  const tb = $('master-slaves').tBodies[0];
  if (!m) {
    text('master-info', 'none in this process');
    tb.textContent = '';
    return;
  }
  text('master-info', 'address ' + m.address + ' · ' + (m.running ? 'RUN' : 'STOP') +
    (m.baud ? ' · ' + baudText(m.baud) : ''));
  if (!pending['master-run']) $('master-run').checked = !!m.running;
  const rows = (m.slaves || []).map((s) =>
    [s.address, s.phase, s.cycles, words(s.po), words(s.pi)]);
  const key = JSON.stringify(rows);
  if (tb.dataset.key !== key) {
    tb.dataset.key = key;
    tb.textContent = '';
    rows.forEach((r) => {
      const tr = document.createElement('tr');
      r.forEach((v, i) => {
        const td = document.createElement('td');
        td.textContent = String(v);
        if (i >= 3) td.className = 'mono';
        tr.appendChild(td);
      });
      tb.appendChild(tr);
    });
  }
}

function updateEnabled() {
  const c = currentCard();
  const hasMaster = !!(state && state.master);
  const hasDrive = !!(c && c.drive);
  document.querySelectorAll('.ctl').forEach((el) => {
    let on = !readOnly && !!c;
    const id = el.id || '';
    if (id === 'di00' || id === 'fault-number' || id === 'fault-inject') on = on && hasDrive;
    if (el.closest('#cw-bits') || /^po[0-9]|^po-|^ps-/.test(id) || id === 'master-run') on = on && hasMaster;
    if (/^pd-/.test(id)) on = on && hasDrive && !!paramSel && !paramSel.read_only;
    if (el.disabled === on) el.disabled = !on;
  });
  $('pd-read').disabled = !(c && hasDrive && paramSel);
}

function render() {
  if (!state) return;
  try {
    /* replay serves read-only; a viewer may read but not act (the server refuses with 403) */
    readOnly = !!state.read_only || role === 'viewer';
    document.body.classList.toggle('read-only', readOnly);
    text('ro-badge', role === 'viewer' ? 'read-only (viewer)' : 'read-only');
    $('ro-badge').hidden = !readOnly;
    text('sim-mode', state.mode);
    const med = state.medium || {};
    text('sim-medium', (med.name || med.kind || '–') + (med.baud ? ' · ' + baudText(med.baud) : ''));
    text('sim-time', secs(state.t_us));
    const cards = Array.isArray(state.cards) ? state.cards : [];
    if (!cards.some((c) => c.address === selected)) selected = cards.length ? cards[0].address : null;
    renderTabs();
    const c = currentCard();
    document.body.classList.toggle('no-card', !c);
    if (c) renderCard(c);
    renderMaster();
    updateEnabled();
  } catch (e) {
    setStatus('panel: cannot show this state: ' + e.message, 'error');
    console.error(e);
  }
}


/* dfp-sim was started again behind the same address: its clock and log numbers begin anew. */
function restarted() {
  plotData.clear();
  logEntries = [];
  logSeqs.clear();
  renderLog();
  busClearEvents();
  shownCard = null;
  setStatus('dfp-sim restarted: plot and log begin again', 'info');
  api('GET', 'log?since=0&limit=' + LOG_MAX).then(addLogs).catch(() => {});
}

/* ---------- the event stream ---------- */

function setConn(s, label) {
  const el = $('conn-status');
  el.dataset.state = s;
  el.textContent = label || s;
}

/* The browser gave up on the stream (it does on any answer but 200, e.g. the 401 of a dfp-sim
 * started again): reconnect while the session holds, else the login form. */
async function reconnect() {
  if (role === null) return;
  let valid;
  try {
    valid = await sessionStillValid();
  } catch (e) {
    setTimeout(reconnect, 2000);  /* dfp-sim not answering (yet) */
    return;
  }
  if (role === null) return;
  if (valid) connect();
  else showLogin('the session ended (was dfp-sim started again?): log in again');
}

function connect() {
  if (es) es.close();
  setConn('connecting', 'connecting');
  const src = new EventSource(API + 'events');  /* same origin: the session cookie goes along */
  es = src;
  src.onopen = () => { setConn('connected', 'connected'); lastStateAt = Date.now(); };
  src.onerror = () => {
    if (src !== es) return;
    setConn('disconnected', 'disconnected');
    if (src.readyState === EventSource.CLOSED) setTimeout(reconnect, 2000);
  };
  src.addEventListener('state', (m) => {
    let s;
    try { s = JSON.parse(m.data); } catch (e) { return; }
    lastStateAt = Date.now();
    if ($('conn-status').dataset.state !== 'connected') setConn('connected', 'connected');
    state = s;
    addSamples(s);
    render();
    drawPlot();
  });
  src.addEventListener('log', (m) => {
    try { addLog(JSON.parse(m.data)); } catch (e) { /* a malformed line is skipped */ }
  });
}

/* A stream that stays open but carries nothing (a half-open TCP connection) counts as dropped. */
setInterval(() => {
  if (es && es.readyState === EventSource.OPEN && Date.now() - lastStateAt > STALE_MS) {
    setConn('disconnected', 'disconnected');
    connect();
  }
}, 1000);

/* ---------- controls ---------- */

function cwFromBits() {
  let w = parseWord($('po1').value);
  if (w === null) w = 0;
  document.querySelectorAll('#cw-bits input').forEach((cb) => {
    const b = 1 << Number(cb.dataset.bit);
    w = cb.checked ? (w | b) : (w & ~b);
  });
  $('po1').value = '0x' + hex4(w);
}
function bitsFromCw() {
  const w = parseWord($('po1').value);
  if (w === null) return;
  document.querySelectorAll('#cw-bits input').forEach((cb) => {
    cb.checked = !!(w & (1 << Number(cb.dataset.bit)));
  });
}
function rpmFromPo2() {
  const w = parseWord($('po2').value);
  if (w !== null) $('po-rpm').value = (int16(w) * 0.2).toFixed(1);
}
function po2FromRpm() {
  const r = Number($('po-rpm').value);
  if (isNaN(r)) return;
  $('po2').value = String(Math.max(-32768, Math.min(32767, Math.round(r / 0.2))));
}
function loadPo() {
  const c = currentCard();
  const s = c ? masterSlave(c.address) : null;
  const po = (s && s.po) || (c && c.monitor && c.monitor.po) || [0, 0, 0];
  $('po1').value = '0x' + hex4(po[0] || 0);
  $('po2').value = String(int16(po[1] || 0));
  $('po3').value = String(po[2] || 0);
  bitsFromCw();
  rpmFromPo2();
  if (s && s.outputs) $('po-hex').value = s.outputs;
}

function wire() {
  $('di00').addEventListener('change', (ev) => {
    const c = currentCard();
    if (!c) return;
    const on = ev.target.checked;
    act('DI00 = ' + (on ? '+24 V (enable)' : '0 V (controller inhibit)'), 'POST',
      'cards/' + c.address + '/inputs', { DI00: on }, 'di00');
  });
  $('fault-inject').addEventListener('click', () => {
    const c = currentCard();
    const f = Number($('fault-number').value);
    if (!c) return;
    if (!Number.isInteger(f) || f < 1 || f > 255) { setStatus('fault number: 1..255', 'error'); return; }
    act('inject fault ' + f, 'POST', 'cards/' + c.address + '/fault', { fault: f });
  });
  $('cable').addEventListener('change', (ev) => {
    const c = currentCard();
    if (!c) return;
    const on = ev.target.checked;
    act(on ? 'plug the bus cable' : 'pull the bus cable', 'POST', 'cards/' + c.address + '/cable',
      { connected: on }, 'cable');
  });
  $('power-cycle').addEventListener('click', () => {
    const c = currentCard();
    if (c) act('power-cycle card ' + c.address, 'POST', 'cards/' + c.address + '/power-cycle', {});
  });
  $('dip-set').addEventListener('click', () => {
    const c = currentCard();
    const a = Number($('dip-next').value);
    if (!c) return;
    if (!Number.isInteger(a) || a < 0 || a > 127) { setStatus('DIP address: 0..127', 'error'); return; }
    act('DIP switches = ' + a + ' (next power-up)', 'POST', 'cards/' + c.address + '/dip', { address: a });
  });
  $('master-run').addEventListener('change', (ev) => {
    const on = ev.target.checked;
    act('master ' + (on ? 'RUN' : 'STOP'), 'POST', 'master/run', { running: on }, 'master-run');
  });

  $('po1').addEventListener('input', bitsFromCw);
  $('po2').addEventListener('input', rpmFromPo2);
  $('po-rpm').addEventListener('input', po2FromRpm);
  $('po-load').addEventListener('click', loadPo);
  $('po-send').addEventListener('click', () => {
    const c = currentCard();
    if (!c) return;
    const po = ['po1', 'po2', 'po3'].map((id) => parseWord($(id).value));
    const bad = po.findIndex((v) => v === null);
    if (bad >= 0) { setStatus('PO' + (bad + 1) + ': a word, 0..65535, -32768..-1 or 0x0000..0xFFFF', 'error'); return; }
    act('PO ' + po.map(hex4).join(' '), 'POST', 'master/slaves/' + c.address + '/outputs', { po: po });
  });
  $('po-hex-send').addEventListener('click', () => {
    const c = currentCard();
    const h = $('po-hex').value.replace(/\s+/g, '');
    if (!c) return;
    if (!/^([0-9a-fA-F]{2})+$/.test(h)) { setStatus('output image: hex octets', 'error'); return; }
    act('output image ' + h, 'POST', 'master/slaves/' + c.address + '/outputs', { hex: h });
  });

  wireParams();
  wireLog();
  wireBus();

  window.addEventListener('resize', drawPlot);
}


/* ---------- start ---------- */

/* Logged in (or no login needed): the state, the stream, the log and the parameter list. Runs
 * again after each login. */
async function panelStart() {
  let since = 0;
  try {
    state = await api('GET', 'state');
    addSamples(state);
    render();
    drawPlot();
    since = Math.max(0, ((state.events && state.events.next_seq) || 0) - LOG_MAX);
    setStatus('connected to dfp-sim (' + state.mode + ')', 'ok');
  } catch (e) {
    setStatus('cannot read the state: ' + e.message, 'error');
  }
  connect();
  busStart();
  try {
    addLogs(await api('GET', 'log?since=' + since + '&limit=' + LOG_MAX));
  } catch (e) {
    setStatus('cannot read the log: ' + e.message, 'error');
  }
  searchParams();
}

/* Logged out or the session gone: no stream (it would only answer 401). */
function panelStop() {
  if (es) es.close();
  es = null;
  busStop();
  setConn('disconnected', 'logged out');
}

function start() {
  buildDip();
  buildCwBits();
  LOG_KINDS.forEach(noteKind);
  wire();
  drawPlot();
  authStart();
}

if (document.readyState === 'loading') document.addEventListener('DOMContentLoaded', start);
else start();
