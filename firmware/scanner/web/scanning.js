// fpp-scanner's page: a scan followed from its start to its end (progress,
// the end shown once, a scan cut short said so) and started from the page.

import { apiJson, errorMessage, jsonBody } from './api.js';
import { loadCloud } from './cloud.js';
import { $, formatCount, setMessage } from './dom.js';
import { refreshScans } from './scans.js';
import { onPoseDone } from './session.js';
import { page } from './state.js';
import { refreshStatus, setState, updateScanButton } from './status.js';

export function onScanStarted(data) {
  if (page.finished.has(data.id)) return; // repeated after a reconnect
  page.scanId = data.id;
  const progress = $('progress');
  progress.max = Math.max(1, data.frames);
  progress.value = 0;
  setMessage($('scan-status'), 'scanning ' + data.id + ' (' + data.mode + ', from the ' + data.source + '): 0 / ' + data.frames + ' frames');
  setMessage($('scan-error'), '');
  setState('scanning', null);
}

export function onFrameCaptured(data) {
  if (page.finished.has(data.id)) return;
  if (data.id !== page.scanId) onScanStarted({ id: data.id, mode: '?', source: '?', frames: data.frames });
  const progress = $('progress');
  progress.max = Math.max(1, data.frames);
  progress.value = data.frame;
  setMessage($('scan-status'), 'scanning ' + data.id + ': frame ' + data.frame + ' / ' + data.frames);
}

export function onDecoded(data) {
  if (data.id !== page.scanId || page.finished.has(data.id)) return;
  setMessage($('scan-status'), 'decoded ' + data.id + ', writing…');
}

export function onWritten(data) {
  finishScan(data.id, true, data.mode, data.points, null, data.session, data.quality);
}

export function onFailed(data) {
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
export function reconcileScan(last, state) {
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

export async function startScan() {
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
