// fpp-scanner's page: small DOM and formatting helpers. Server text only
// ever reaches the page through textContent.

export const $ = id => document.getElementById(id);

export function setMessage(element, text, kind) {
  element.textContent = text;
  element.className = 'message' + (kind ? ' ' + kind : '');
  element.hidden = !text;
}

export function formatBytes(n) {
  if (n == null) return '?';
  const units = ['B', 'KiB', 'MiB', 'GiB', 'TiB'];
  let i = 0;
  while (n >= 1024 && i < units.length - 1) { n /= 1024; ++i; }
  return (i === 0 ? n : n.toFixed(1)) + ' ' + units[i];
}

export function formatCount(n) {
  return n == null ? '?' : Number(n).toLocaleString('en');
}

export function element(tag, text, className) {
  const e = document.createElement(tag);
  if (text != null) e.textContent = text;
  if (className) e.className = className;
  return e;
}

export function sleep(ms) {
  return new Promise(resolve => setTimeout(resolve, ms));
}

export const pathId = encodeURIComponent;
