// fpp-scanner's page: the scan list (rows on wide screens, cards on phones),
// downloads and deletes, and scans deleted elsewhere.

import { api, apiJson, downloadFile, errorMessage, reportable } from './api.js';
import { clearCloud, loadCloud, shownScan } from './cloud.js';
import { $, element, formatBytes, formatCount, pathId, setMessage } from './dom.js';
import { refreshSessions, showSession } from './session.js';
import { page } from './state.js';
import { refreshStatus } from './status.js';

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

export async function refreshScans() {
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

// A scan, pose or session deleted here or by another client: it goes from
// every list, and its cloud from the viewer.
export function onDeleted(data) {
  if (data.session === null && data.id) {
    const row = document.querySelector('#scan-list tr[data-scan-id="' + CSS.escape(data.id) + '"]');
    if (row) row.remove();
    if (shownScan() === data.id || page.cloudWanted === data.id) clearCloud('Scan ' + data.id + ' was deleted.');
    refreshStatus();
  } else if (data.session) {
    refreshSessions();
    if (data.session === page.session) showSession(data.id ? page.session : '');
  }
}
