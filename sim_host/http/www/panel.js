/* DFP21B front panel for dfp-sim. Plain ES2017, no library, no build step: it reads the control
 * API of docs/api.md (GET /api/v1/state once, then the SSE stream /api/v1/events) and sends the
 * actions the API offers. URLs are relative so the panel also works behind a path prefix. */
'use strict';

(function () {
  const API = 'api/v1/';
  const LOG_MAX = 500;
  const PLOT_WINDOW_US = 20e6;
  const STALE_MS = 3000; /* no state event for this long: the stream is considered dropped */
  const LOG_KINDS = ['dp_state', 'baud', 'watchdog', 'prm', 'cfg', 'diag', 'led', 'param', 'drive',
    'fault', 'speed', 'master', 'action', 'nvm', 'lost'];
  const LEVEL_RANK = { error: 0, warn: 1, info: 2, debug: 3 };
  const CW_BITS = [
    [0, 'controller inhibit'], [1, 'enable / rapid stop'], [2, 'enable / stop'], [3, 'hold control'],
    [4, 'ramp set 2'], [5, 'param set 2'], [6, 'fault reset']];

  const $ = (id) => document.getElementById(id);

  let state = null;          /* the last /api/v1/state object */
  let selected = null;       /* address of the card shown */
  let shownCard = null;      /* address the card-bound fields were last filled for */
  let readOnly = false;
  let es = null;
  let lastStateAt = 0;
  let tabsKey = '';
  const pending = {};        /* control id -> true while its request runs */
  const plotData = new Map(); /* card address -> [{t, sp, act, cur}] */
  let lastT = -1;
  let logEntries = [];       /* newest first */
  const logSeqs = new Set();
  let paramSel = null;       /* selected entry of the parameter browser */

  /* ---------- helpers ---------- */

  function text(id, v) {
    const el = $(id);
    const s = (v === null || v === undefined || v === '') ? '–' : String(v);
    if (el && el.textContent !== s) el.textContent = s;
  }
  function fmt1(v) {
    return (v === null || v === undefined || isNaN(Number(v))) ? '–' : Number(v).toFixed(1);
  }
  function hex4(w) {
    return (Number(w) & 0xFFFF).toString(16).toUpperCase().padStart(4, '0');
  }
  function words(a) {
    return Array.isArray(a) ? a.map(hex4).join(' ') : '–';
  }
  function baudText(b) {
    if (b === null || b === undefined) return null;
    if (b >= 1e6) return (b / 1e6) + ' MBd';
    if (b >= 1e3) return (b / 1e3) + ' kBd';
    return b + ' Bd';
  }
  function secs(t) {
    return (t === null || t === undefined) ? '–' : (t / 1e6).toFixed(3) + ' s';
  }
  function int16(w) {
    w = Number(w) & 0xFFFF;
    return w >= 0x8000 ? w - 0x10000 : w;
  }
  /* "0x0006", "6", "-1500" -> 0..65535, or null */
  function parseWord(s) {
    s = String(s).trim();
    if (s === '') return 0;
    let v;
    if (/^0x[0-9a-f]{1,4}$/i.test(s)) v = parseInt(s, 16);
    else if (/^-?\d+$/.test(s)) v = parseInt(s, 10);
    else return null;
    if (v < -32768 || v > 65535) return null;
    return v & 0xFFFF;
  }
  /* A value typed by the user: an integer stays a number (the raw value); anything else ("FIELDBUS",
   * "1.5", "2000 ms") goes as text for the drive's own parser. */
  function valueOf(s) {
    s = String(s).trim();
    return /^-?\d+$/.test(s) ? Number(s) : s;
  }

  function setStatus(msg, level) {
    const el = $('status-line');
    const now = new Date();
    const ts = now.toTimeString().slice(0, 8);
    el.textContent = ts + '  ' + msg;
    el.dataset.level = level || 'info';
  }

  /* One API call. Resolves to the parsed JSON body; an HTTP error rejects with the server's
   * {"error": ...} text. */
  async function api(method, path, body) {
    const opt = { method: method, headers: { Accept: 'application/json' } };
    if (body !== undefined) {
      opt.headers['Content-Type'] = 'application/json';
      opt.body = JSON.stringify(body);
    }
    let res;
    try {
      res = await fetch(API + path, opt);
    } catch (e) {
      throw new Error('no answer from dfp-sim (' + e.message + ')');
    }
    let data = null;
    try { data = await res.json(); } catch (e) { data = null; }
    if (!res.ok) {
      const msg = (data && data.error) ? data.error : res.statusText;
      throw new Error('HTTP ' + res.status + ': ' + msg);
    }
    return data;
  }

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
    const key = cards.map((c) => c.address).join(',') + '|' + selected;
    const nav = $('card-tabs');
    if (key !== tabsKey) {
      tabsKey = key;
      nav.textContent = '';
      cards.forEach((c) => {
        const b = document.createElement('button');
        b.className = 'tab' + (c.address === selected ? ' active' : '');
        b.id = 'tab-card-' + c.address;
        b.dataset.address = String(c.address);
        const dot = document.createElement('i');
        dot.className = 'tabdot';
        b.appendChild(dot);
        b.appendChild(document.createTextNode('card ' + c.address));
        b.addEventListener('click', () => { selected = c.address; render(); });
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

  function renderCard(c) {
    const dp = c.dp || {};
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
      readOnly = !!state.read_only;
      document.body.classList.toggle('read-only', readOnly);
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

  /* ---------- plot ---------- */

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

  function drawPlot() {
    const cv = $('plot');
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(200, cv.clientWidth);
    const h = Math.max(120, cv.clientHeight);
    if (cv.width !== Math.round(w * dpr) || cv.height !== Math.round(h * dpr)) {
      cv.width = Math.round(w * dpr);
      cv.height = Math.round(h * dpr);
    }
    const g = cv.getContext('2d');
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    const css = getComputedStyle(document.body);
    const col = (n, d) => (css.getPropertyValue(n) || d).trim();
    const cBg = col('--plot-bg', '#0d1117'), cGrid = col('--plot-grid', '#263040');
    const cTxt = col('--muted', '#8b96a5');
    const cSp = col('--c-setpoint', '#e3b341'), cAct = col('--c-actual', '#3fb950');
    const cCur = col('--c-current', '#58a6ff');
    g.fillStyle = cBg;
    g.fillRect(0, 0, w, h);

    const L = 52, R = 44, T = 10, B = 22;
    const pw = w - L - R, ph = h - T - B;
    const data = plotData.get(selected) || [];
    const tEnd = data.length ? data[data.length - 1].t : (state ? state.t_us : 0);
    const tStart = tEnd - PLOT_WINDOW_US;
    const vis = data.filter((p) => p.t >= tStart - 2e5);

    /* speed axis: includes 0, at least +-100 rpm of room; current axis 0..max(20 %, peak) */
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

    const X = (t) => L + ((t - tStart) / PLOT_WINDOW_US) * pw;
    const YS = (v) => T + ph - ((v - smin) / (smax - smin)) * ph;
    const YC = (v) => T + ph - (v / cmax) * ph;

    g.font = '11px ui-monospace, SFMono-Regular, Menlo, Consolas, monospace';
    g.lineWidth = 1;
    g.strokeStyle = cGrid;
    g.fillStyle = cTxt;
    g.textBaseline = 'middle';
    g.textAlign = 'right';
    for (let v = smin; v <= smax + 1e-9; v += sstep) {
      const y = Math.round(YS(v)) + 0.5;
      g.beginPath(); g.moveTo(L, y); g.lineTo(L + pw, y); g.stroke();
      g.fillText(String(Math.round(v * 10) / 10), L - 6, y);
    }
    g.textAlign = 'left';
    g.fillStyle = cCur;
    for (let v = 0; v <= cmax + 1e-9; v += cstep) g.fillText(v + '%', L + pw + 6, YC(v));
    g.fillStyle = cTxt;
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
    if (smin < 0) {
      g.strokeStyle = cTxt;
      const y0 = Math.round(YS(0)) + 0.5;
      g.beginPath(); g.moveTo(L, y0); g.lineTo(L + pw, y0); g.stroke();
    }

    g.save();
    g.beginPath();
    g.rect(L, T, pw, ph);
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
        const x = X(p.t), y = Y(v);
        if (!started) { g.moveTo(x, y); started = true; } else g.lineTo(x, y);
      });
      g.stroke();
    };
    line('cur', YC, cCur, 1.5);
    line('sp', YS, cSp, 1.5, [5, 3]);
    line('act', YS, cAct, 2);
    g.restore();
    g.setLineDash([]);
    g.strokeStyle = cGrid;
    g.strokeRect(L + 0.5, T + 0.5, pw, ph);
    if (!vis.length) {
      g.fillStyle = cTxt;
      g.textAlign = 'center';
      g.textBaseline = 'middle';
      g.fillText(currentCard() && !currentCard().drive ? 'no drive on this card' : 'waiting for data…', L + pw / 2, T + ph / 2);
    }
  }

  /* dfp-sim was started again behind the same address: its clock and log numbers begin anew. */
  function restarted() {
    plotData.clear();
    logEntries = [];
    logSeqs.clear();
    renderLog();
    shownCard = null;
    setStatus('dfp-sim restarted: plot and log begin again', 'info');
    api('GET', 'log?since=0&limit=' + LOG_MAX).then(addLogs).catch(() => {});
  }

  /* ---------- log ---------- */

  function logMatches(e) {
    const kind = $('log-kind').value;
    const lvl = $('log-level').value;
    const txt = $('log-text').value.trim().toLowerCase();
    if (kind && e.kind !== kind) return false;
    if (lvl && (LEVEL_RANK[e.level] === undefined ? 2 : LEVEL_RANK[e.level]) > LEVEL_RANK[lvl]) return false;
    if (txt && (e.source + ' ' + e.kind + ' ' + e.text).toLowerCase().indexOf(txt) < 0) return false;
    return true;
  }

  function logItem(e) {
    const li = document.createElement('li');
    li.dataset.level = e.level || 'info';
    li.dataset.kind = e.kind || '';
    li.dataset.seq = String(e.seq);
    const parts = [
      ['l-t', (e.t_us / 1e6).toFixed(6)],
      ['l-src', e.source || ''],
      ['l-lvl', e.level || ''],
      ['l-kind', e.kind || ''],
      ['l-text', e.text || ''],
    ];
    parts.forEach(([cls, s]) => {
      const sp = document.createElement('span');
      sp.className = cls;
      sp.textContent = s;
      li.appendChild(sp);
    });
    return li;
  }

  function renderLog() {
    const ul = $('log');
    ul.textContent = '';
    const frag = document.createDocumentFragment();
    logEntries.forEach((e) => { if (logMatches(e)) frag.appendChild(logItem(e)); });
    ul.appendChild(frag);
    text('log-count', ul.children.length + ' of ' + logEntries.length + ' lines');
  }

  function trimLog() {
    while (logEntries.length > LOG_MAX) logSeqs.delete(logEntries.pop().seq);
  }

  /* The kind filter offers the kinds of docs/api.md and any other kind the log has shown. */
  function noteKind(k) {
    if (!k) return;
    const sel = $('log-kind');
    if (Array.prototype.some.call(sel.options, (o) => o.value === k)) return;
    const o = document.createElement('option');
    o.value = k;
    o.textContent = k;
    sel.appendChild(o);
  }

  function addLog(e) {
    if (!e || typeof e.seq !== 'number' || logSeqs.has(e.seq)) return;
    logSeqs.add(e.seq);
    noteKind(e.kind);
    if (logEntries.length && e.seq < logEntries[0].seq) {
      logEntries.push(e);
      logEntries.sort((a, b) => b.seq - a.seq);
      trimLog();
      renderLog();
      return;
    }
    logEntries.unshift(e);
    const ul = $('log');
    if (logMatches(e)) ul.insertBefore(logItem(e), ul.firstChild);
    if (logEntries.length > LOG_MAX) {
      trimLog();
      while (ul.children.length > LOG_MAX) ul.removeChild(ul.lastChild);
      const oldest = logEntries[logEntries.length - 1].seq;
      while (ul.lastChild && Number(ul.lastChild.dataset.seq) < oldest) ul.removeChild(ul.lastChild);
    }
    text('log-count', ul.children.length + ' of ' + logEntries.length + ' lines');
  }

  function addLogs(arr) {
    if (!Array.isArray(arr)) return;
    arr.forEach((e) => {
      if (e && typeof e.seq === 'number' && !logSeqs.has(e.seq)) {
        logSeqs.add(e.seq);
        logEntries.push(e);
        noteKind(e.kind);
      }
    });
    logEntries.sort((a, b) => b.seq - a.seq);
    trimLog();
    renderLog();
  }

  /* ---------- the event stream ---------- */

  function setConn(s, label) {
    const el = $('conn-status');
    el.dataset.state = s;
    el.textContent = label || s;
  }

  function connect() {
    if (es) es.close();
    setConn('connecting', 'connecting');
    es = new EventSource(API + 'events');
    es.onopen = () => { setConn('connected', 'connected'); lastStateAt = Date.now(); };
    es.onerror = () => {
      setConn('disconnected', 'disconnected');
      if (es.readyState === EventSource.CLOSED) setTimeout(connect, 2000); /* the browser gave up */
    };
    es.addEventListener('state', (m) => {
      let s;
      try { s = JSON.parse(m.data); } catch (e) { return; }
      lastStateAt = Date.now();
      if ($('conn-status').dataset.state !== 'connected') setConn('connected', 'connected');
      state = s;
      addSamples(s);
      render();
      drawPlot();
    });
    es.addEventListener('log', (m) => {
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

    $('ps-send').addEventListener('click', async () => {
      const slave = Number($('ps-slave').value);
      const op = $('ps-op').value;
      const param = $('ps-param').value.trim();
      if (!Number.isInteger(slave) || !param) { setStatus('parameter service: slave and param needed', 'error'); return; }
      const body = { slave: slave, op: op, param: param, via: $('ps-via').value };
      if (op === 'write') {
        if ($('ps-value').value.trim() === '') { setStatus('parameter service: a value to write', 'error'); return; }
        body.value = valueOf($('ps-value').value);
        body.volatile = $('ps-volatile').checked;
      }
      $('ps-result').textContent = '…';
      const r = await act(op + ' ' + param + ' via ' + body.via, 'POST', 'master/param', body);
      const out = $('ps-result');
      if (!r) { out.textContent = $('status-line').textContent.slice(10); out.dataset.ok = '0'; return; }
      out.dataset.ok = r.ok === false ? '0' : '1';
      out.textContent = r.ok === false
        ? (r.p_number ? r.p_number + ': ' : '') + r.error
        : r.p_number + ' (' + r.index + ') ' + (r.name || '') + ' = ' + (r.text !== undefined ? r.text : r.value);
    });

    /* parameter browser */
    let searchTimer = null;
    $('param-search').addEventListener('input', () => {
      clearTimeout(searchTimer);
      searchTimer = setTimeout(searchParams, 200);
    });
    $('pd-read').addEventListener('click', readParam);
    $('pd-write').addEventListener('click', async () => {
      const c = currentCard();
      if (!c || !paramSel) return;
      const raw = $('pd-write-value').value.trim();
      if (raw === '') { setStatus('a value to write', 'error'); return; }
      const body = { value: valueOf(raw) };
      if ($('pd-volatile').checked) body.volatile = true;
      const r = await act('write ' + paramSel.p_number + ' = ' + raw, 'PUT',
        'cards/' + c.address + '/params/' + encodeURIComponent(paramSel.p_number), body);
      if (r && r.ok !== false) showParamValue(r);
    });

    $('log-kind').addEventListener('change', renderLog);
    $('log-level').addEventListener('change', renderLog);
    $('log-text').addEventListener('input', renderLog);
    $('log-clear').addEventListener('click', () => { logEntries = []; logSeqs.clear(); renderLog(); });

    window.addEventListener('resize', drawPlot);
  }

  async function searchParams() {
    const q = $('param-search').value.trim();
    const ul = $('param-results');
    let list;
    try {
      list = await api('GET', 'params' + (q ? '?q=' + encodeURIComponent(q) : ''));
    } catch (e) {
      setStatus('parameter search: ' + e.message, 'error');
      return;
    }
    ul.textContent = '';
    (Array.isArray(list) ? list : []).forEach((p) => {
      const li = document.createElement('li');
      li.dataset.p = p.p_number;
      li.tabIndex = 0;
      const a = document.createElement('b');
      a.textContent = p.p_number;
      const i = document.createElement('span');
      i.className = 'dim';
      i.textContent = String(p.index);
      const n = document.createElement('span');
      n.textContent = p.name + (p.unit ? ' [' + p.unit + ']' : '') + (p.read_only ? ' (ro)' : '');
      li.appendChild(a); li.appendChild(i); li.appendChild(n);
      const pick = () => { selectParam(p, li); };
      li.addEventListener('click', pick);
      li.addEventListener('keydown', (ev) => { if (ev.key === 'Enter') pick(); });
      if (paramSel && paramSel.p_number === p.p_number) li.classList.add('sel');
      ul.appendChild(li);
    });
    if (!ul.children.length) {
      const li = document.createElement('li');
      li.className = 'dim';
      li.textContent = 'no parameter matches';
      ul.appendChild(li);
    }
  }

  function selectParam(p, li) {
    paramSel = p;
    document.querySelectorAll('#param-results li.sel').forEach((x) => x.classList.remove('sel'));
    if (li) li.classList.add('sel');
    $('param-detail').hidden = false;
    text('pd-pnum', p.p_number);
    text('pd-index', 'index ' + p.index);
    text('pd-name', p.name + (p.unit ? ' [' + p.unit + ']' : ''));
    $('pd-ro').hidden = !p.read_only;
    const dl = $('pd-enums');
    dl.textContent = '';
    (p.enums || []).forEach((e) => {
      const o = document.createElement('option');
      o.value = e.text;
      o.label = e.value + ' = ' + e.text;
      dl.appendChild(o);
    });
    $('pd-write-value').value = '';
    text('pd-value', '…');
    updateEnabled();
    readParam();
  }

  function showParamValue(r) {
    text('pd-value', r.text !== undefined && r.text !== null ? r.text : r.value);
  }

  async function readParam() {
    const c = currentCard();
    if (!c || !paramSel) return;
    try {
      const r = await api('GET', 'cards/' + c.address + '/params/' + encodeURIComponent(paramSel.p_number));
      if (r && r.ok === false) { text('pd-value', 'error'); setStatus('read ' + paramSel.p_number + ': ' + r.error, 'error'); return; }
      showParamValue(r);
    } catch (e) {
      text('pd-value', 'error');
      setStatus('read ' + paramSel.p_number + ': ' + e.message, 'error');
    }
  }

  /* ---------- start ---------- */

  async function start() {
    buildDip();
    buildCwBits();
    LOG_KINDS.forEach(noteKind);
    wire();
    drawPlot();
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
    try {
      addLogs(await api('GET', 'log?since=' + since + '&limit=' + LOG_MAX));
    } catch (e) {
      setStatus('cannot read the log: ' + e.message, 'error');
    }
    searchParams();
  }

  if (document.readyState === 'loading') document.addEventListener('DOMContentLoaded', start);
  else start();
})();
