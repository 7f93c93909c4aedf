// fpp-scanner's page: the calibration session helper (sessions, poses and
// their thumbnails) and the live preview, shown in the helper and beside
// Scan.

import { api, apiJson, errorMessage, jsonBody, reportable } from './api.js';
import { $, element, pathId, setMessage } from './dom.js';
import { page } from './state.js';

const PREVIEW_PERIOD_MS = 1000;

function helperOpen() {
  return $('calibration').open;
}

export async function refreshSessions() {
  try {
    const list = (await apiJson('/sessions')).sessions;
    const select = $('session-select');
    const options = [element('option', '(none)')];
    options[0].value = '';
    for (const s of list) {
      const option = element('option', s.name + ' (' + s.poses + (s.poses === 1 ? ' pose)' : ' poses)'));
      option.value = s.name;
      options.push(option);
    }
    select.replaceChildren(...options);
    select.value = list.some(s => s.name === page.session) ? page.session : '';
    if (select.value !== page.session) showSession('');
  } catch (e) {
    if (reportable(e)) setMessage($('session-message'), 'Sessions: ' + errorMessage(e), 'error');
  }
}

export async function createSession(event) {
  event.preventDefault();
  const name = $('session-name').value.trim();
  const body = { name };
  const yaml = $('board-yaml').value;
  if (yaml.trim()) body.board_yaml = yaml;
  try {
    await apiJson('/sessions', jsonBody('POST', body));
    setMessage($('session-message'), 'Session ' + name + ' created.');
    page.session = name;
    await refreshSessions();
    showSession(name);
  } catch (e) {
    setMessage($('session-message'), 'Create session: ' + errorMessage(e), 'error');
  }
}

export async function showSession(name) {
  page.session = name;
  $('session-select').value = name;
  $('take-pose').disabled = !name || page.poseId !== null;
  $('session-download').disabled = !name;
  if (!name) {
    renderPoses([]);
    return;
  }
  try {
    const session = await apiJson('/sessions/' + pathId(name));
    if (page.session === name) renderPoses(session.poses);
  } catch (e) {
    setMessage($('session-message'), 'Session ' + name + ': ' + errorMessage(e), 'error');
  }
}

function renderPoses(poses) {
  $('pose-count').textContent = String(poses.length);
  const keep = new Set(poses.map(p => p.id));
  for (const [id, url] of page.thumbnails) {
    if (!keep.has(id)) {
      URL.revokeObjectURL(url);
      page.thumbnails.delete(id);
    }
  }
  $('poses').replaceChildren(...poses.map(poseItem));
}

function poseItem(pose) {
  const item = element('li');
  item.dataset.poseId = pose.id;
  const image = element('img');
  image.alt = 'pose ' + pose.id;
  loadThumbnail(page.session, pose.id, image);
  item.appendChild(image);
  item.appendChild(element('div', pose.id, 'pose-id'));
  const remove = element('button', 'Delete', 'small danger');
  remove.type = 'button';
  remove.addEventListener('click', () => deletePose(pose.id));
  item.appendChild(remove);
  return item;
}

async function loadThumbnail(session, id, image) {
  let url = page.thumbnails.get(id);
  if (!url) {
    try {
      const response = await api('/sessions/' + pathId(session) + '/poses/' + pathId(id) + '/texture.png');
      url = URL.createObjectURL(await response.blob());
      page.thumbnails.set(id, url);
    } catch (e) {
      image.alt = 'no texture: ' + errorMessage(e);
      return;
    }
  }
  image.src = url;
}

export async function takePose() {
  const name = page.session;
  if (!name) return;
  $('take-pose').disabled = true;
  try {
    const started = await apiJson('/sessions/' + pathId(name) + '/poses', { method: 'POST' });
    page.poseId = started.id;
    page.scanId = started.id;
    setMessage($('session-message'), 'Taking pose ' + started.id + '…');
  } catch (e) {
    setMessage($('session-message'), 'Take pose: ' + errorMessage(e), 'error');
    $('take-pose').disabled = false;
  }
}

export function onPoseDone(id, ok, error) {
  if (id === page.poseId) {
    page.poseId = null;
    setMessage($('session-message'), ok ? 'Pose ' + id + ' taken.' : 'Pose ' + id + ' failed: ' + error, ok ? '' : 'error');
  }
  $('take-pose').disabled = !page.session;
  if (page.session) {
    showSession(page.session);
    refreshSessions();
  }
}

async function deletePose(id) {
  const name = page.session;
  if (!confirm('Delete pose ' + id + ' from session ' + name + '?')) return;
  try {
    await api('/sessions/' + pathId(name) + '/poses/' + pathId(id), { method: 'DELETE' });
  } catch (e) {
    setMessage($('session-message'), 'Delete pose: ' + errorMessage(e), 'error');
  }
  showSession(name);
  refreshSessions();
}

// ---- live preview ---------------------------------------------------------------

function schedulePreview() {
  clearTimeout(page.previewTimer);
  page.previewTimer = setTimeout(updatePreview, PREVIEW_PERIOD_MS);
}

function previewWanted() {
  return helperOpen() || $('scan-preview-on').checked;
}

function setPreviewInfo(text) {
  $('preview-info').textContent = text;
  $('scan-preview-info').textContent = text;
}

// One preview frame, then the next a second later, while the session helper
// or the scan section's live preview is open.
async function updatePreview() {
  if (!previewWanted()) return;
  if (page.state === 'scanning' || !page.token || document.hidden) {
    if (page.state === 'scanning') setPreviewInfo('preview paused: a scan is running');
    schedulePreview();
    return;
  }
  try {
    const response = await api('/preview.png');
    const saturated = parseFloat(response.headers.get('X-Preview-Saturated'));
    const mean = parseFloat(response.headers.get('X-Preview-Mean'));
    const url = URL.createObjectURL(await response.blob());
    if (page.previewUrl) URL.revokeObjectURL(page.previewUrl);
    page.previewUrl = url;
    $('preview').src = url;
    $('scan-preview').src = url;
    const warning = previewWarning(saturated, mean);
    setPreviewInfo('mean level ' + mean.toFixed(3) + ', saturated ' + (100 * saturated).toFixed(2) + ' %' +
                   (warning ? ': ' + warning : ''));
    setMessage($('preview-warning'), warning, 'warning');
  } catch (e) {
    setPreviewInfo(e.status === 409 ? 'preview paused: a scan is running' : 'preview: ' + errorMessage(e));
  }
  schedulePreview();
}

function previewWarning(saturated, mean) {
  const warnings = [];
  if (saturated > 0.01) warnings.push('saturated: lower the exposure');
  if (mean < 0.05) warnings.push('too dark / board not in view');
  return warnings.join('; ');
}

export function onHelperToggle() {
  if (helperOpen()) refreshSessions();
  $('scan-preview-wrap').hidden = !$('scan-preview-on').checked;
  if (previewWanted()) updatePreview();
  else clearTimeout(page.previewTimer);
}
