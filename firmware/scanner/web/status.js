// fpp-scanner's page: the scanner's status, its state and the Scan button.

import { apiJson, errorMessage, reportable } from './api.js';
import { loadCloud, shownScan } from './cloud.js';
import { $, formatBytes, formatCount } from './dom.js';
import { reconcileScan } from './scanning.js';
import { refreshScans } from './scans.js';
import { refreshSessions } from './session.js';
import { refreshSettings } from './settings.js';
import { page } from './state.js';

export function setState(state, error) {
  page.state = state || 'unknown';
  const s = $('state');
  s.textContent = page.state;
  s.className = 'state ' + page.state;
  $('state-error').textContent = error ? '(' + error + ')' : '';
  updateScanButton();
}

// Scan is off while a scan runs, the scanner is unreachable, or no table is
// installed for a scan that needs one (keeping the capture set needs none).
export function updateScanButton() {
  const needsTable = !$('scan-capture').checked;
  $('scan-button').disabled = page.state === 'scanning' || !page.reachable ||
                              (needsTable && page.noTable === true);
}

export function describeTable(table) {
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

export async function refreshStatus() {
  try {
    renderStatus(await apiJson('/status'));
    return true;
  } catch (e) {
    if (reportable(e)) $('state-error').textContent = '(status: ' + errorMessage(e) + ')';
    return false;
  }
}

export async function refreshAll() {
  if (!(await refreshStatus())) return;
  refreshSettings();
  refreshSessions();
  const scans = await refreshScans();
  // Show the newest good cloud unless one is shown already.
  const newest = scans && scans.find(s => s.cloud && (!s.quality || s.quality.good));
  if (newest && !shownScan() && !page.cloudWanted) loadCloud(newest.id);
}
