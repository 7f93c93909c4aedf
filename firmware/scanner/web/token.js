// fpp-scanner's page: the API token, kept in localStorage.

import { $, setMessage } from './dom.js';
import { setEventsBadge, startEvents } from './events.js';
import { page } from './state.js';
import { refreshAll } from './status.js';

const TOKEN_KEY = 'fpp-scanner.token';

export function showAuthProblem(text) {
  setMessage($('auth-message'), text, 'error');
  setEventsBadge(false);
}

// A new token while one works is tried first: a mistyped one must not
// replace the working one.
export async function tryToken(token) {
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

export function useToken(token) {
  page.tokenWorks = page.tokenWorks && token === page.token;
  page.token = token;
  try {
    localStorage.setItem(TOKEN_KEY, token);
  } catch (e) { /* private mode: the token lasts for this page only */ }
  $('auth-message').hidden = true;
  startEvents();
  refreshAll();
}

// The token kept from an earlier visit ('' when none).
export function savedToken() {
  try {
    return localStorage.getItem(TOKEN_KEY) || '';
  } catch (e) {
    return ''; // no storage
  }
}
