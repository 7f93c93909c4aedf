// fpp-scanner's page: reaching the scanner, status, events, scanning, the
// cloud and the scan list, table upload and settings (the session helper and
// the live preview: session.js), all through the HTTP API
// (firmware/scanner/http-api.md). Every /api/v1 request carries the token;
// server text only ever reaches the page through textContent.
'use strict';

const TOKEN_KEY = 'fpp-scanner.token';
const PREVIEW_PERIOD_MS = 1000;
const EVENTS_RETRY_MS = 2000;
// The server sends a keep-alive every 10 s; silence this long is a dead link.
const EVENTS_SILENCE_MS = 25000;

const page = {
  token: '',
  tokenWorks: false,       // the scanner took page.token at least once
  reachable: true,         // the last request reached the scanner
  lastContact: 0,          // Date.now() of the last answer
  bannerTimer: null,
  state: 'unknown',
  viewer: null,
  eventsGeneration: 0,
  eventsAbort: null,
  scanId: null,            // the scan the progress bar follows
  cloudWanted: null,       // the scan whose cloud the viewer is to show
  finished: new Set(),     // scans whose end the page has shown
  session: '',             // the calibration session shown
  poseId: null,            // the pose being taken
  thumbnails: new Map(),   // pose id -> object URL
  previewTimer: null,
  previewUrl: null,
};

const $ = id => document.getElementById(id);

// ---- API ------------------------------------------------------------------

class ApiError extends Error {
  constructor(status, message) {
    super(message);
    this.status = status;
  }
}

// fetch() on /api/v1 with the token; throws ApiError with the server's
// {"error"} text for any status other than 2xx.
async function api(path, options = {}) {
  const token = page.token;
  if (!token) {
    showAuthProblem('Enter the API token to use the scanner.');
    throw new ApiError(401, 'no token');
  }
  const headers = new Headers(options.headers || {});
  headers.set('Authorization', 'Bearer ' + token);
  let response;
  try {
    response = await fetch('/api/v1' + path, Object.assign({}, options, { headers, cache: 'no-store' }));
  } catch (e) {
    if (e.name === 'AbortError') throw e;
    markUnreachable();
    throw new ApiError(-1, 'the scanner does not answer');
  }
  markContact();
  if (token !== page.token) throw new ApiError(0, 'the token changed'); // a stale answer
  if (response.status === 401) {
    showAuthProblem('The scanner refused the token (401 Unauthorized). Enter the API token: ' +
                    "the first line of the scanner's token file.");
    throw new ApiError(401, 'the scanner refused the token');
  }
  $('auth-message').hidden = true;
  page.tokenWorks = true;
  if (!response.ok) throw new ApiError(response.status, await errorText(response));
  return response;
}

// ---- reaching the scanner ----------------------------------------------------

// Every answer is a contact; a request that gets none marks the scanner
// unreachable: the whole page says so (banner, actions greyed) until the
// next answer, which clears what went stale and reads everything again.
function markContact() {
  page.lastContact = Date.now();
  if (page.reachable) return;
  page.reachable = true;
  clearInterval(page.bannerTimer);
  $('connection-banner').hidden = true;
  document.body.classList.remove('offline');
  setMessage($('scan-error'), '');
  setMessage($('scans-message'), '');
  $('state-error').textContent = '';
  refreshAll();
}

function markUnreachable() {
  if (!page.reachable) return;
  page.reachable = false;
  document.body.classList.add('offline');
  setEventsBadge(false);
  const banner = $('connection-banner');
  const show = () => {
    const since = page.lastContact ? Math.round((Date.now() - page.lastContact) / 1000) : null;
    banner.textContent = 'The scanner does not answer' +
      (since === null ? '' : ' (last contact ' + new Date(page.lastContact).toLocaleTimeString() +
                             ', ' + since + ' s ago)') +
      '. The page tries again every few seconds; what it shows may be out of date.';
  };
  show();
  banner.hidden = false;
  clearInterval(page.bannerTimer);
  page.bannerTimer = setInterval(show, 1000);
  $('scan-button').disabled = true;
}

async function errorText(response) {
  const fallback = response.status + ' ' + response.statusText;
  try {
    const body = await response.json();
    return body && typeof body.error === 'string' ? body.error : fallback;
  } catch (e) {
    return fallback;
  }
}

async function apiJson(path, options) {
  const response = await api(path, options);
  return response.status === 204 ? null : response.json();
}

function jsonBody(method, value) {
  return { method, headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(value) };
}

// Plain words for what a person can act on; the status and the server's
// reason otherwise.
function errorMessage(e) {
  if (!(e instanceof ApiError)) return e.message;
  if (e.status === -1) return 'The scanner does not answer.';
  if (e.status === 409 && /table/.test(e.message))
    return 'No calibration table is installed. Install one below.';
  return e.status ? e.status + ': ' + e.message : e.message;
}

// An error worth a message: not a stale answer, a refused token (the token
// box says so) or an unreachable scanner (the banner says so).
function reportable(e) {
  return !(e instanceof ApiError) || e.status > 0 && e.status !== 401;
}

// Downloads go through fetch (the token is a header, which a plain link
// cannot send), then a Blob URL with the file's name.
async function downloadFile(path, fileName) {
  const response = await api(path);
  const blob = await response.blob();
  const url = URL.createObjectURL(blob);
  const link = document.createElement('a');
  link.href = url;
  link.download = fileName;
  link.hidden = true;
  document.body.appendChild(link);
  link.click();
  link.remove();
  setTimeout(() => URL.revokeObjectURL(url), 60000);
}

// ---- small helpers --------------------------------------------------------

function setMessage(element, text, kind) {
  element.textContent = text;
  element.className = 'message' + (kind ? ' ' + kind : '');
  element.hidden = !text;
}

function formatBytes(n) {
  if (n == null) return '?';
  const units = ['B', 'KiB', 'MiB', 'GiB', 'TiB'];
  let i = 0;
  while (n >= 1024 && i < units.length - 1) { n /= 1024; ++i; }
  return (i === 0 ? n : n.toFixed(1)) + ' ' + units[i];
}

function formatCount(n) {
  return n == null ? '?' : Number(n).toLocaleString('en');
}

function element(tag, text, className) {
  const e = document.createElement(tag);
  if (text != null) e.textContent = text;
  if (className) e.className = className;
  return e;
}

function sleep(ms) {
  return new Promise(resolve => setTimeout(resolve, ms));
}

const pathId = encodeURIComponent;

// ---- token ----------------------------------------------------------------

function showAuthProblem(text) {
  setMessage($('auth-message'), text, 'error');
  setEventsBadge(false);
}

// A new token while one works is tried first: a mistyped one must not
// replace the working one.
async function tryToken(token) {
  if (page.token && page.tokenWorks && token !== page.token) {
    let answer = null;
    try {
      answer = await fetch('/api/v1/status', { headers: { Authorization: 'Bearer ' + token }, cache: 'no-store' });
    } catch (e) { /* unreachable: the banner says so */ }
    if (answer && answer.status === 401) {
      setMessage($('auth-message'), 'The scanner refused that token; the page keeps using the one it had.', 'error');
      return;
    }
  }
  useToken(token);
}

function useToken(token) {
  page.tokenWorks = page.tokenWorks && token === page.token;
  page.token = token;
  try {
    localStorage.setItem(TOKEN_KEY, token);
  } catch (e) { /* private mode: the token lasts for this page only */ }
  $('auth-message').hidden = true;
  startEvents();
  refreshAll();
}

// ---- status ---------------------------------------------------------------

function setState(state, error) {
  page.state = state || 'unknown';
  const s = $('state');
  s.textContent = page.state;
  s.className = 'state ' + page.state;
  $('state-error').textContent = error ? '(' + error + ')' : '';
  updateScanButton();
}

// Scan is off while a scan runs, the scanner is unreachable, or no table is
// installed for a scan that needs one (keeping the capture set needs none).
function updateScanButton() {
  const needsTable = !$('scan-capture').checked;
  $('scan-button').disabled = page.state === 'scanning' || !page.reachable ||
                              (needsTable && page.noTable === true);
}

function describeTable(table) {
  if (!table) return 'none loaded: scans need one (upload a table below)';
  return table.model + ', camera ' + table.camera.width + ' × ' + table.camera.height +
         ', projector ' + table.projector.width + ' × ' + table.projector.height +
         ', ' + formatBytes(table.bytes) + ', hash ' + table.file_fnv1a64 +
         ', installed ' + table.installed_utc;
}

function renderStatus(status) {
  setState(status.state, status.error);
  const board = status.board || {};
  $('board').textContent = board.name + (board.simulated ? ' (simulated)' : '');
  const c = status.camera || {};
  $('camera').textContent = c.width + ' × ' + c.height + ', ' + c.bit_depth + '-bit ' +
                            c.pixel_format + ', exposure ' + c.exposure_us + ' µs';
  const d = status.display || {}, seq = status.sequence || {};
  $('display').textContent = d.width + ' × ' + d.height + '; sequence ' + seq.name + ', ' + seq.frames + ' frames';
  $('table').textContent = describeTable(status.table);
  $('table').title = status.table ? status.table.path : '';
  const st = status.store || {};
  const percent = st.max_bytes ? ' (' + (100 * st.used_bytes / st.max_bytes).toFixed(1) + ' %)' : '';
  $('store').textContent = formatBytes(st.used_bytes) + ' of ' + formatBytes(st.max_bytes) + percent +
                           ', ' + st.scans + ' scans, ' + st.sessions + ' sessions';
  const last = status.last_scan;
  $('last-scan').textContent = !last ? (st.scans ? 'none since the scanner started' : 'none yet')
    : last.id + ' (' + last.mode + '): ' + (last.ok ? formatCount(last.points) + ' points' +
        (last.quality && !last.quality.good ? ', poor: ' + last.quality.reasons.join('; ') : '')
      : 'failed: ' + last.error);
  page.noTable = !status.table;
  $('no-table').hidden = !page.noTable;
  updateScanButton();
  $('board-yaml-hint').textContent = board.session_board
    ? ': may be left out, the simulated board has its own' : ': needed';
  reconcileScan(last, status.state);
}

async function refreshStatus() {
  try {
    renderStatus(await apiJson('/status'));
    return true;
  } catch (e) {
    if (reportable(e)) $('state-error').textContent = '(status: ' + errorMessage(e) + ')';
    return false;
  }
}

async function refreshAll() {
  if (!(await refreshStatus())) return;
  refreshSettings();
  refreshSessions();
  const scans = await refreshScans();
  // Show the newest good cloud unless one is shown already.
  const newest = scans && scans.find(s => s.cloud && (!s.quality || s.quality.good));
  if (newest && !window.fppViewer && !page.cloudWanted) loadCloud(newest.id);
}

// ---- events (server-sent, read through fetch to send the token) -------------

function setEventsBadge(live) {
  const badge = $('events-state');
  badge.textContent = live ? 'live' : 'offline';
  badge.className = 'badge' + (live ? ' live' : '');
}

function startEvents() {
  const generation = ++page.eventsGeneration;
  if (page.eventsAbort) page.eventsAbort.abort();
  runEvents(generation);
}

async function runEvents(generation) {
  while (generation === page.eventsGeneration) {
    const controller = new AbortController();
    page.eventsAbort = controller;
    let silence = null;
    const watch = () => {
      clearTimeout(silence);
      silence = setTimeout(() => controller.abort(), EVENTS_SILENCE_MS);
    };
    try {
      watch();
      const response = await api('/events', { signal: controller.signal, headers: { Accept: 'text/event-stream' } });
      setEventsBadge(true);
      refreshStatus(); // what happened while the stream was down
      await readEventStream(response.body.getReader(), handleEvent, watch);
    } catch (e) {
      if (e.status === 401) return; // wait for a new token
    } finally {
      clearTimeout(silence);
    }
    if (generation !== page.eventsGeneration) return;
    setEventsBadge(false);
    await sleep(EVENTS_RETRY_MS);
    // Whatever happened while the stream was down shows in the status.
    if (generation === page.eventsGeneration) refreshStatus();
  }
}

// The SSE wire format: "field: value" lines, a blank line ends an event,
// lines starting with ':' are comments (the keep-alive).
async function readEventStream(reader, onEvent, onBytes) {
  const decoder = new TextDecoder();
  let buffer = '', name = '', data = [];
  for (;;) {
    const { value, done } = await reader.read();
    if (done) return;
    onBytes();
    buffer += decoder.decode(value, { stream: true });
    let newline;
    while ((newline = buffer.indexOf('\n')) >= 0) {
      let line = buffer.slice(0, newline);
      buffer = buffer.slice(newline + 1);
      if (line.endsWith('\r')) line = line.slice(0, -1);
      if (line === '') {
        if (data.length) onEvent(name || 'message', data.join('\n'));
        name = '';
        data = [];
        continue;
      }
      if (line.startsWith(':')) continue;
      const colon = line.indexOf(':');
      const field = colon < 0 ? line : line.slice(0, colon);
      let text = colon < 0 ? '' : line.slice(colon + 1);
      if (text.startsWith(' ')) text = text.slice(1);
      if (field === 'event') name = text;
      else if (field === 'data') data.push(text);
    }
  }
}

function handleEvent(name, text) {
  let data;
  try {
    data = JSON.parse(text);
  } catch (e) {
    return; // not ours to show
  }
  switch (name) {
    case 'state': onStateEvent(data); break;
    case 'scan-started': onScanStarted(data); break;
    case 'frame-captured': onFrameCaptured(data); break;
    case 'decoded': onDecoded(data); break;
    case 'written': onWritten(data); break;
    case 'failed': onFailed(data); break;
    case 'table':
      setMessage($('table-message'), 'A new table is installed: ' + data.model + ', hash ' + data.file_fnv1a64 + '.');
      refreshStatus();
      break;
    case 'settings':
      if (document.activeElement !== $('exposure')) $('exposure').value = data.exposure_us;
      refreshStatus();
      break;
    case 'deleted': onDeleted(data); break;
  }
}

// A scan, pose or session deleted here or by another client: it goes from
// every list, and its cloud from the viewer.
function onDeleted(data) {
  if (data.session === null && data.id) {
    const row = document.querySelector('#scan-list tr[data-scan-id="' + CSS.escape(data.id) + '"]');
    if (row) row.remove();
    if ((window.fppViewer && window.fppViewer.scanId === data.id) || page.cloudWanted === data.id) {
      page.cloudWanted = null;
      if (page.viewer) page.viewer.clear();
      $('viewer-title').textContent = '';
      $('viewer-info').textContent = '';
      $('viewer-legend').hidden = true;
      setMessage($('viewer-message'), 'Scan ' + data.id + ' was deleted.');
    }
    refreshStatus();
  } else if (data.session) {
    refreshSessions();
    if (data.session === page.session) showSession(data.id ? page.session : '');
  }
}

function onStateEvent(data) {
  const wasScanning = page.state === 'scanning';
  setState(data.state, data.error);
  // A scan that ended while events were lost still ends on the page.
  if (wasScanning && data.state !== 'scanning') refreshStatus();
}

// ---- scanning ---------------------------------------------------------------

function onScanStarted(data) {
  if (page.finished.has(data.id)) return; // repeated after a reconnect
  page.scanId = data.id;
  const progress = $('progress');
  progress.max = Math.max(1, data.frames);
  progress.value = 0;
  setMessage($('scan-status'), 'scanning ' + data.id + ' (' + data.mode + ', from the ' + data.source + '): 0 / ' + data.frames + ' frames');
  setMessage($('scan-error'), '');
  setState('scanning', null);
}

function onFrameCaptured(data) {
  if (page.finished.has(data.id)) return;
  if (data.id !== page.scanId) onScanStarted({ id: data.id, mode: '?', source: '?', frames: data.frames });
  const progress = $('progress');
  progress.max = Math.max(1, data.frames);
  progress.value = data.frame;
  setMessage($('scan-status'), 'scanning ' + data.id + ': frame ' + data.frame + ' / ' + data.frames);
}

function onDecoded(data) {
  if (data.id !== page.scanId || page.finished.has(data.id)) return;
  setMessage($('scan-status'), 'decoded ' + data.id + ', writing…');
}

function onWritten(data) {
  finishScan(data.id, true, data.mode, data.points, null, data.session, data.quality);
}

function onFailed(data) {
  finishScan(data.id, false, null, null, data.error, null, null);
}

function showQuality(id, quality) {
  const poor = quality && !quality.good;
  setMessage($('scan-quality'), poor ? 'Poor scan (' + id + '): ' + quality.reasons.join('; ') + '. ' +
                                        quality.advice : '', 'warning');
}

// Shows a scan's end once, from its event or, if events were lost, the status.
function finishScan(id, ok, mode, points, error, session, quality) {
  if (page.finished.has(id)) return;
  page.finished.add(id);
  page.scanId = id;
  const progress = $('progress');
  if (ok) {
    progress.value = progress.max;
    const what = (mode === 'capture' ? 'capture set' + (points ? ' and ' : '') : '') +
                 (points || mode !== 'capture' ? formatCount(points) + ' points' : '');
    setMessage($('scan-status'), 'written: ' + id + ', ' + what + (session ? ' (session ' + session + ')' : ''));
    setMessage($('scan-error'), '');
    showQuality(id, quality);
  } else {
    setMessage($('scan-status'), 'failed: ' + id);
    setMessage($('scan-error'), 'The scan failed: ' + error, 'error');
    showQuality(id, null);
  }
  if (session || id === page.poseId) onPoseDone(id, ok, error);
  refreshStatus();
  refreshScans().then(scans => {
    const scan = scans && scans.find(s => s.id === id);
    if (ok && scan && scan.cloud) loadCloud(id);
  });
}

// The status after events were lost: the followed scan's end shows, and a
// scan that the scanner no longer runs and never ended (it stopped during
// it) is said to be cut short, its progress reset.
function reconcileScan(last, state) {
  if (last && !page.finished.has(last.id) && (last.id === page.scanId || last.id === page.poseId))
    finishScan(last.id, last.ok, last.mode, last.points, last.error, null, last.quality);
  const id = page.scanId;
  if (id && !page.finished.has(id) && state !== 'scanning' && (!last || last.id !== id)) {
    page.finished.add(id);
    $('progress').value = 0;
    setMessage($('scan-status'), 'Scan ' + id + ' did not finish: the scanner stopped during it, ' +
                                 'and nothing was written.');
    if (id === page.poseId) onPoseDone(id, false, 'the scanner stopped during it');
  }
}

async function startScan() {
  const mode = $('scan-capture').checked ? 'capture' : 'scan';
  setMessage($('scan-error'), '');
  $('scan-button').disabled = true;
  try {
    const started = await apiJson('/scans', jsonBody('POST', { mode }));
    if (page.scanId !== started.id) {
      page.scanId = started.id;
      $('progress').value = 0;
      setMessage($('scan-status'), 'started ' + started.id + ' (' + started.mode + ')');
    }
  } catch (e) {
    if (e.status !== -1) setMessage($('scan-error'), errorMessage(e), 'error');
    updateScanButton();
  }
}

// ---- the cloud ----------------------------------------------------------------

async function loadCloud(id) {
  if (!page.viewer) return;
  page.cloudWanted = id; // the latest request wins over slower earlier ones
  const message = $('viewer-message');
  setMessage(message, 'loading ' + id + '…');
  try {
    const response = await api('/scans/' + pathId(id) + '/cloud.ply');
    const buffer = await response.arrayBuffer();
    if (page.cloudWanted !== id) return;
    const parsed = FppViewer.parsePly(buffer);
    const drawn = page.viewer.show(parsed, id, $('colour-by').value);
    for (const option of $('colour-by').options) option.disabled = !drawn.modes.includes(option.value);
    $('colour-by').value = drawn.colourBy;
    $('viewer-title').textContent = id;
    $('viewer-info').textContent = formatCount(drawn.points) + ' of ' + formatCount(drawn.total) + ' points' +
      (parsed.stride > 1 ? ' (1 in ' + parsed.stride + ')' : '');
    showLegend(drawn.range);
    setMessage($('scans-message'), '');
    setMessage(message, drawn.points ? '' : 'The cloud of ' + id + ' has no points.', drawn.points ? '' : 'warning');
  } catch (e) {
    if (page.cloudWanted !== id) return;
    if (page.viewer) page.viewer.clear();
    $('viewer-title').textContent = '';
    $('viewer-info').textContent = '';
    $('viewer-legend').hidden = true;
    setMessage(message, 'Cannot show ' + id + ': ' + errorMessage(e), 'error');
  }
}

// The colour scale of the view: low and high ends with their unit.
function showLegend(range) {
  $('viewer-legend').hidden = !range;
  if (!range) return;
  const digits = range.unit === 'mm' && range.hi - range.lo < 1 ? 3 : 1;
  $('legend-low').textContent = range.lo.toFixed(digits) + ' ' + range.unit;
  $('legend-high').textContent = range.hi.toFixed(digits) + ' ' + range.unit + ' (' + range.label + ')';
}

function recolour() {
  if (!page.viewer) return;
  const range = page.viewer.recolour($('colour-by').value);
  if (window.fppViewer) showLegend(range);
}

// ---- the scan list ------------------------------------------------------------

function downloadLink(text, path, fileName, className) {
  const link = element('a', text, className);
  link.href = '/api/v1' + path;
  link.download = fileName;
  link.addEventListener('click', event => {
    event.preventDefault();
    downloadFile(path, fileName).catch(e =>
      setMessage($('scans-message'), 'Download of ' + fileName + ' failed: ' + errorMessage(e), 'error'));
  });
  return link;
}

function scanRow(scan) {
  const row = document.createElement('tr');
  row.dataset.scanId = scan.id;
  row.appendChild(element('td', scan.id));
  row.appendChild(element('td', scan.mode, 'optional'));
  row.appendChild(element('td', scan.started_utc));
  row.appendChild(element('td', scan.cloud ? formatCount(scan.points) : '–'));
  const q = scan.quality;
  const quality = element('td', !q ? '–' : q.good ? 'good' : 'poor', q && !q.good ? 'poor' : null);
  if (q && !q.good) {
    quality.title = q.reasons.join('; ') + '. ' + q.advice;
    row.classList.add('poor');
  }
  row.appendChild(quality);
  row.appendChild(element('td', formatBytes(scan.bytes), 'optional'));
  const actions = element('td', null, 'actions');
  const base = '/scans/' + pathId(scan.id);
  if (scan.cloud) {
    const view = element('button', 'View', 'small view');
    view.type = 'button';
    view.addEventListener('click', () => loadCloud(scan.id));
    actions.appendChild(view);
    actions.appendChild(downloadLink('PLY', base + '/cloud.ply', scan.id + '-cloud.ply', 'download-ply'));
  }
  if (scan.capture)
    actions.appendChild(downloadLink('capture.tar', base + '/capture.tar', scan.id + '-capture.tar', 'download-capture'));
  const remove = element('button', 'Delete', 'small danger delete');
  remove.type = 'button';
  remove.addEventListener('click', () => deleteScan(scan.id));
  actions.appendChild(remove);
  row.appendChild(actions);
  return row;
}

async function refreshScans() {
  try {
    const list = (await apiJson('/scans')).scans;
    const body = $('scan-list').tBodies[0];
    body.replaceChildren(...list.map(scanRow));
    if (list.length === 0) {
      const empty = element('td', 'No scans yet.', 'muted');
      empty.colSpan = 7;
      body.appendChild(element('tr')).appendChild(empty);
    }
    setMessage($('scans-message'), '');
    return list;
  } catch (e) {
    if (reportable(e)) setMessage($('scans-message'), 'Scan list: ' + errorMessage(e), 'error');
    return null;
  }
}

async function deleteScan(id) {
  if (!confirm('Delete ' + id + '? Its cloud and capture set are removed from the scanner.')) return;
  try {
    await api('/scans/' + pathId(id), { method: 'DELETE' });
    onDeleted({ id: id, session: null }); // the event says it too
  } catch (e) {
    setMessage($('scans-message'), 'Delete ' + id + ': ' + errorMessage(e), 'error');
  }
  refreshScans();
  refreshStatus();
}

// ---- table and settings ---------------------------------------------------------

async function uploadTable() {
  const file = $('table-file').files[0];
  const message = $('table-message');
  if (!file) {
    setMessage(message, 'Choose a .fpt file first.', 'error');
    return;
  }
  setMessage(message, 'Uploading ' + file.name + ' (' + formatBytes(file.size) + ')…');
  try {
    const table = await apiJson('/table', {
      method: 'PUT', headers: { 'Content-Type': 'application/octet-stream' }, body: await file.arrayBuffer(),
    });
    setMessage(message, 'Installed ' + file.name + ': ' + describeTable(table) + '.');
    refreshStatus();
  } catch (e) {
    setMessage(message, 'The scanner refused ' + file.name + ': ' + errorMessage(e), 'error');
  }
}

async function refreshSettings() {
  try {
    const settings = await apiJson('/settings');
    if (document.activeElement !== $('exposure')) $('exposure').value = settings.exposure_us;
  } catch (e) {
    if (reportable(e)) setMessage($('settings-message'), 'Settings: ' + errorMessage(e), 'error');
  }
}

async function saveSettings(event) {
  event.preventDefault();
  const exposure = Number($('exposure').value);
  try {
    const settings = await apiJson('/settings', jsonBody('PUT', { exposure_us: exposure }));
    $('exposure').value = settings.exposure_us;
    setMessage($('settings-message'), 'Exposure now ' + settings.exposure_us + ' µs.');
  } catch (e) {
    setMessage($('settings-message'), 'Settings refused: ' + errorMessage(e), 'error');
  }
}

// ---- start ----------------------------------------------------------------------

function init() {
  page.viewer = window.THREE ? FppViewer.create($('viewer'), text => setMessage($('viewer-message'), text, 'error')) : null;
  if (!window.THREE) setMessage($('viewer-message'), 'three.js did not load: the 3D view is off.', 'error');

  $('token-form').addEventListener('submit', event => {
    event.preventDefault();
    tryToken($('token').value.trim());
  });
  $('status-refresh').addEventListener('click', refreshStatus);
  $('scan-button').addEventListener('click', startScan);
  $('scan-capture').addEventListener('change', updateScanButton);
  $('scan-preview-on').addEventListener('change', onHelperToggle);
  $('colour-by').addEventListener('change', recolour);
  $('point-size').addEventListener('input', () => page.viewer && page.viewer.setPointSize(Number($('point-size').value)));
  $('view-reset').addEventListener('click', () => page.viewer && page.viewer.resetView());
  $('scans-refresh').addEventListener('click', refreshScans);
  $('calibration').addEventListener('toggle', onHelperToggle);
  $('session-form').addEventListener('submit', createSession);
  $('session-select').addEventListener('change', () => showSession($('session-select').value));
  $('session-download').addEventListener('click', () => {
    const name = page.session;
    downloadFile('/sessions/' + pathId(name) + '/session.tar', name + '-session.tar')
      .catch(e => setMessage($('session-message'), 'Download: ' + errorMessage(e), 'error'));
  });
  $('take-pose').addEventListener('click', takePose);
  $('table-upload').addEventListener('click', uploadTable);
  $('settings-form').addEventListener('submit', saveSettings);

  let saved = '';
  try {
    saved = localStorage.getItem(TOKEN_KEY) || '';
  } catch (e) { /* no storage */ }
  $('token').value = saved;
  if (saved) useToken(saved);
  else showAuthProblem('Enter the API token to use the scanner.');
}

init();
