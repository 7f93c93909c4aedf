// fpp-scanner's page: its start. The page is native ES modules without a
// build step: state.js (what the page knows), dom.js, api.js (the HTTP API
// client and reaching the scanner), token.js, status.js, events.js,
// scanning.js, cloud.js with viewer.js (the 3D view), scans.js, settings.js
// and session.js (the calibration helper and the live preview).

import { downloadFile, errorMessage } from './api.js';
import { recolour } from './cloud.js';
import { $, pathId, setMessage } from './dom.js';
import { startScan } from './scanning.js';
import { refreshScans } from './scans.js';
import { createSession, onHelperToggle, showSession, takePose } from './session.js';
import { saveSettings, uploadTable } from './settings.js';
import { page } from './state.js';
import { refreshStatus, updateScanButton } from './status.js';
import { savedToken, showAuthProblem, tryToken, useToken } from './token.js';
import { FppViewer } from './viewer.js';

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

  const saved = savedToken();
  $('token').value = saved;
  if (saved) useToken(saved);
  else showAuthProblem('Enter the API token to use the scanner.');
}

init();
