/* DFP21B front panel: the log list (newest first, at most LOG_MAX lines) with its kind, level
 * and text filters, fed from GET /api/v1/log and the stream's log events (those of kind "bus"
 * also go to the bus page, panel_bus.js). */
'use strict';

const LOG_MAX = 500;
const LOG_KINDS = ['dp_state', 'baud', 'watchdog', 'prm', 'cfg', 'diag', 'led', 'param', 'drive',
  'fault', 'speed', 'master', 'ring', 'bus', 'action', 'audit', 'nvm', 'lost'];
const LEVEL_RANK = { error: 0, warn: 1, info: 2, debug: 3 };
let logEntries = [];       /* newest first */
const logSeqs = new Set();

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
  busNoteLog(e);
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
      busNoteLog(e);
    }
  });
  logEntries.sort((a, b) => b.seq - a.seq);
  trimLog();
  renderLog();
}

function wireLog() {
  $('log-kind').addEventListener('change', renderLog);
  $('log-level').addEventListener('change', renderLog);
  $('log-text').addEventListener('input', renderLog);
  $('log-clear').addEventListener('click', () => { logEntries = []; logSeqs.clear(); renderLog(); });
}
