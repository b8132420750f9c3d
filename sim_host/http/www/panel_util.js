/* DFP21B front panel: formatting helpers, the status line and one call of the control API
 * (docs/api.md). Loaded first; the other panel files use these. */
'use strict';

const API = 'api/v1/';
const $ = (id) => document.getElementById(id);

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

/* Called with the server's text when a call answers 401 (the session is gone, e.g. dfp-sim was
 * started again): panel_auth.js sets it to bring the login form back. */
let onUnauthorized = null;

/* One API call, with the session cookie (same origin only). Resolves to the parsed JSON body; an
 * HTTP error rejects with the server's {"error": ...} text. Every state-changing call says
 * Content-Type: application/json, with or without a body: the server refuses it otherwise
 * (415), which is what keeps another site's plain form or beacon from acting. */
async function api(method, path, body) {
  const opt = { method: method, credentials: 'same-origin', headers: { Accept: 'application/json' } };
  if (method !== 'GET' && method !== 'HEAD') opt.headers['Content-Type'] = 'application/json';
  if (body !== undefined) opt.body = JSON.stringify(body);
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
    if (res.status === 401 && path !== 'login' && onUnauthorized) onUnauthorized(msg);
    const err = new Error('HTTP ' + res.status + ': ' + msg);
    err.status = res.status;
    err.serverText = msg;
    throw err;
  }
  return data;
}
