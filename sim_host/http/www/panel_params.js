/* DFP21B front panel: parameter services. The browser reads and writes the selected card's drive
 * directly (GET/PUT /api/v1/cards/{a}/params/{p}); the service box runs one over the bus through
 * the master (POST /api/v1/master/param, via the channel, data set 47 or class 2). */
'use strict';

let paramSel = null;       /* selected entry of the parameter browser */

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

function wireParams() {
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
}
