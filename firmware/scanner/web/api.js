// fpp-scanner's page: the HTTP API client (firmware/scanner/http-api.md).
// Every /api/v1 request carries the token; every answer is a contact, and a
// request that gets none marks the scanner unreachable: the whole page says
// so (banner, actions greyed) until the next answer, which clears what went
// stale and reads everything again.

import { $, setMessage } from './dom.js';
import { setEventsBadge } from './events.js';
import { page } from './state.js';
import { refreshAll } from './status.js';
import { showAuthProblem } from './token.js';

class ApiError extends Error {
  constructor(status, message) {
    super(message);
    this.status = status;
  }
}

// fetch() on /api/v1 with the token; throws ApiError with the server's
// {"error"} text for any status other than 2xx.
export async function api(path, options = {}) {
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

export async function apiJson(path, options) {
  const response = await api(path, options);
  return response.status === 204 ? null : response.json();
}

export function jsonBody(method, value) {
  return { method, headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(value) };
}

// Plain words for what a person can act on; the status and the server's
// reason otherwise.
export function errorMessage(e) {
  if (!(e instanceof ApiError)) return e.message;
  if (e.status === -1) return 'The scanner does not answer.';
  if (e.status === 409 && /table/.test(e.message))
    return 'No calibration table is installed. Install one below.';
  return e.status ? e.status + ': ' + e.message : e.message;
}

// An error worth a message: not a stale answer, a refused token (the token
// box says so) or an unreachable scanner (the banner says so).
export function reportable(e) {
  return !(e instanceof ApiError) || e.status > 0 && e.status !== 401;
}

// Downloads go through fetch (the token is a header, which a plain link
// cannot send), then a Blob URL with the file's name.
export async function downloadFile(path, fileName) {
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
