// fpp-scanner's page: the event stream (server-sent events, read through
// fetch to send the token), reconnected after a silence or a drop, and each
// event handed to the part of the page it concerns.

import { api } from './api.js';
import { $, setMessage, sleep } from './dom.js';
import { onDecoded, onFailed, onFrameCaptured, onScanStarted, onWritten } from './scanning.js';
import { onDeleted } from './scans.js';
import { page } from './state.js';
import { refreshStatus, setState } from './status.js';

const EVENTS_RETRY_MS = 2000;

// The server sends a keep-alive every 10 s; silence this long is a dead link.
const EVENTS_SILENCE_MS = 25000;

export function setEventsBadge(live) {
  const badge = $('events-state');
  badge.textContent = live ? 'live' : 'offline';
  badge.className = 'badge' + (live ? ' live' : '');
}

export function startEvents() {
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

// Each event to the part of the page it concerns (also how a replay is
// tested: the browser test imports this module).
export function handleEvent(name, text) {
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

function onStateEvent(data) {
  const wasScanning = page.state === 'scanning';
  setState(data.state, data.error);
  // A scan that ended while events were lost still ends on the page.
  if (wasScanning && data.state !== 'scanning') refreshStatus();
}
