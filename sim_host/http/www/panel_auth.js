/* DFP21B front panel: the login (docs/api.md, "Security"). dfp-sim prints a URL with its token
 * at start; the panel logs in with it (POST /api/v1/login), the server answers with an HttpOnly
 * session cookie, and the token is dropped from the address bar. GET /api/v1/session decides
 * between the login form and the panel, and gives the role: a viewer sees the panel with every
 * action disabled. A 401 later (dfp-sim started again: the sessions are gone) brings the form
 * back. Loaded after panel_util.js; panelStart and panelStop are in panel.js. */
'use strict';

let role = null;      /* 'operator' or 'viewer' while the panel is shown, else null */
let authOn = true;    /* false: dfp-sim runs with --http-no-auth (no login, no log out) */

function setView(v) {
  document.body.dataset.view = v;
}

function loginError(msg) {
  const el = $('login-error');
  el.textContent = msg || '';
  el.hidden = !msg;
}

/* The login form instead of the panel; msg (if any) on its error line. */
function showLogin(msg) {
  role = null;
  panelStop();
  setView('login');
  loginError(msg);
  setStatus('not logged in', 'info');
  $('login-token').focus();
}

function enterPanel(r) {
  role = r;
  loginError('');
  $('logout').hidden = !authOn;
  setView('panel');
  panelStart();
}

/* Asks the server who this browser is, then shows the panel or the login form (with msg). */
async function checkSession(msg) {
  let s;
  try {
    s = await api('GET', 'session');
  } catch (e) {
    setStatus('cannot reach dfp-sim: ' + e.message + ' (trying again)', 'error');
    setTimeout(() => { checkSession(msg); }, 2000);
    return;
  }
  authOn = !(s && s.auth === false);
  if (s && (s.role === 'operator' || s.role === 'viewer')) enterPanel(s.role);
  else showLogin(msg);
}

/* The session lost while the panel is shown: the stream asks whether to reconnect or log in. */
async function sessionStillValid() {
  const s = await api('GET', 'session');
  return !!(s && (s.role === 'operator' || s.role === 'viewer'));
}

async function login(token) {
  const r = await api('POST', 'login', { token: token });
  return r && r.role;
}

/* ?token=T (the URL dfp-sim printed): logs in with T, then takes T out of the address bar and
 * the history entry, so it is not shown, bookmarked or sent on. Returns an error text or null. */
async function loginFromUrl() {
  const u = new URL(location.href);
  const t = u.searchParams.get('token');
  if (t === null) return null;
  let msg = null;
  try {
    await login(t);
  } catch (e) {
    msg = 'the token in the address was not accepted (' + (e.serverText || e.message) + ')';
  }
  u.searchParams.delete('token');
  history.replaceState(history.state, '', u.pathname + u.search + u.hash);
  return msg;
}

function wireAuth() {
  onUnauthorized = () => {
    if (role !== null) showLogin('the session ended (was dfp-sim started again?): log in again');
  };
  $('login-form').addEventListener('submit', async (ev) => {
    ev.preventDefault();
    const t = $('login-token').value.trim();
    if (!t) { loginError('the token, please'); return; }
    $('login-button').disabled = true;
    try {
      await login(t);
      $('login-token').value = '';
      await checkSession('logged in, but this browser did not keep the session cookie');
    } catch (e) {
      loginError(e.status === 401 ? 'wrong token (HTTP 401)' : e.message);
      $('login-token').select();
    } finally {
      $('login-button').disabled = false;
    }
  });
  $('logout').addEventListener('click', async () => {
    try {
      await api('POST', 'logout');
    } catch (e) {
      /* the session is gone already: the form all the same */
    }
    showLogin('logged out');
  });
}

async function authStart() {
  wireAuth();
  const msg = await loginFromUrl();
  await checkSession(msg);
}
