// fpp-scanner's page: the table upload and the exposure setting.

import { apiJson, errorMessage, jsonBody, reportable } from './api.js';
import { $, formatBytes, setMessage } from './dom.js';
import { describeTable, refreshStatus } from './status.js';

export async function uploadTable() {
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

export async function refreshSettings() {
  try {
    const settings = await apiJson('/settings');
    if (document.activeElement !== $('exposure')) $('exposure').value = settings.exposure_us;
  } catch (e) {
    if (reportable(e)) setMessage($('settings-message'), 'Settings: ' + errorMessage(e), 'error');
  }
}

export async function saveSettings(event) {
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
