// fpp-scanner's page: the cloud panel: a scan's PLY fetched and drawn by the
// viewer (viewer.js), its colours and legend.

import { api, errorMessage } from './api.js';
import { $, formatCount, pathId, setMessage } from './dom.js';
import { page } from './state.js';
import { FppViewer } from './viewer.js';

export async function loadCloud(id) {
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
    clearCloud('Cannot show ' + id + ': ' + errorMessage(e), 'error');
  }
}

// The scan whose cloud is on screen (null when none).
export function shownScan() {
  const shown = page.viewer ? page.viewer.shown() : null;
  return shown ? shown.scanId : null;
}

// The viewer emptied, with `text` in its message line.
export function clearCloud(text, kind) {
  page.cloudWanted = null;
  if (page.viewer) page.viewer.clear();
  $('viewer-title').textContent = '';
  $('viewer-info').textContent = '';
  $('viewer-legend').hidden = true;
  setMessage($('viewer-message'), text, kind);
}

// The colour scale of the view: low and high ends with their unit.
function showLegend(range) {
  $('viewer-legend').hidden = !range;
  if (!range) return;
  const digits = range.unit === 'mm' && range.hi - range.lo < 1 ? 3 : 1;
  $('legend-low').textContent = range.lo.toFixed(digits) + ' ' + range.unit;
  $('legend-high').textContent = range.hi.toFixed(digits) + ' ' + range.unit + ' (' + range.label + ')';
}

export function recolour() {
  if (!page.viewer) return;
  const range = page.viewer.recolour($('colour-by').value);
  if (shownScan()) showLegend(range);
}
