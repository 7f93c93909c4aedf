// An accessibility checker in the manner of axe-core's rules (no Debian
// package carries axe-core): run in the page by WebDriver, it returns the
// rules it checked and every violation as "rule: element: why". The rules
// are WCAG 2.1 A/AA checks a page's DOM can decide; what needs a person
// (whether a label is apt, reading order) stays out.
(() => {
  const violations = [];
  const rules = [];
  const contrast = {judged: 0, lowest: Infinity}; // text elements whose contrast was decided
  const rule = (id, check) => { rules.push(id); check((el, why) => violations.push(`${id}: ${describe(el)}: ${why}`)); };

  const describe = (el) => {
    if (!el || !el.tagName) return 'document';
    const id = el.id ? '#' + el.id : '';
    const cls = !id && el.classList.length ? '.' + [...el.classList].join('.') : '';
    const text = (el.textContent || '').trim().replace(/\s+/g, ' ').slice(0, 30);
    return `${el.tagName.toLowerCase()}${id}${cls}${text ? ` "${text}"` : ''}`;
  };
  const visible = (el) => {
    if (el.closest('[hidden]')) return false;
    const style = getComputedStyle(el);
    return style.display !== 'none' && style.visibility !== 'hidden' && el.getClientRects().length > 0;
  };
  const byIds = (list) => (list || '').split(/\s+/).filter(Boolean).map((id) => document.getElementById(id));
  // The accessible name as a screen reader computes it, in the usual order.
  const nameOf = (el) => {
    const labelledby = el.getAttribute('aria-labelledby');
    if (labelledby) return byIds(labelledby).map((e) => (e ? e.textContent : '')).join(' ').trim();
    const label = el.getAttribute('aria-label');
    if (label && label.trim()) return label.trim();
    if (el.labels && el.labels.length) return [...el.labels].map((l) => l.textContent).join(' ').trim();
    if (el.tagName === 'INPUT' && ['button', 'submit', 'reset'].includes(el.type)) return (el.value || '').trim();
    if (el.tagName === 'IMG') return (el.getAttribute('alt') || '').trim();
    const own = [...el.childNodes].map((n) => (n.nodeType === Node.TEXT_NODE ? n.textContent
      : n.nodeType === Node.ELEMENT_NODE && n.getAttribute('aria-hidden') !== 'true'
        ? (n.tagName === 'IMG' ? n.getAttribute('alt') || '' : nameOf(n)) : '')).join('').trim();
    return own || (el.getAttribute('title') || '').trim();
  };
  const all = (selector) => [...document.querySelectorAll(selector)];
  const focusable = 'a[href], button, input, select, textarea, [tabindex], summary, [contenteditable="true"]';

  rule('document-title', (fail) => { if (!document.title.trim()) fail(document, 'no <title>'); });
  rule('html-lang', (fail) => {
    if (!/^[a-z]{2,3}(-[A-Za-z0-9]+)*$/.test(document.documentElement.lang)) fail(document.documentElement, 'no valid lang');
  });
  rule('meta-viewport', (fail) => {
    const meta = document.querySelector('meta[name="viewport"]');
    const content = meta ? meta.content.replace(/\s/g, '') : '';
    const max = /maximum-scale=([\d.]+)/.exec(content);
    if (/user-scalable=(no|0)/.test(content) || (max && parseFloat(max[1]) < 2)) fail(meta, 'zoom is blocked');
  });
  rule('duplicate-id', (fail) => {
    const seen = new Set();
    for (const el of all('[id]')) { if (seen.has(el.id)) fail(el, 'id used twice'); seen.add(el.id); }
  });
  rule('label', (fail) => {
    for (const el of all('input, select, textarea, progress, meter')) {
      if (el.type === 'hidden' || ['button', 'submit', 'reset'].includes(el.type)) continue;
      if (!nameOf(el)) fail(el, 'no label, aria-label or aria-labelledby');
    }
  });
  rule('button-name', (fail) => {
    for (const el of all('button, [role="button"], input[type="button"], input[type="submit"]'))
      if (!nameOf(el)) fail(el, 'a button without a name');
  });
  rule('link-name', (fail) => { for (const el of all('a[href]')) if (!nameOf(el)) fail(el, 'a link without a name'); });
  rule('image-alt', (fail) => { for (const el of all('img')) if (!el.hasAttribute('alt')) fail(el, 'no alt'); });
  rule('canvas-name', (fail) => {
    for (const el of all('canvas')) if (visible(el) && !nameOf(el) && el.getAttribute('aria-hidden') !== 'true') fail(el, 'no text for the canvas');
  });
  rule('aria-valid-reference', (fail) => {
    for (const attr of ['aria-labelledby', 'aria-describedby', 'aria-controls'])
      for (const el of all(`[${attr}]`))
        if (byIds(el.getAttribute(attr)).some((e) => !e)) fail(el, `${attr} names a missing id`);
  });
  rule('aria-valid-role', (fail) => {
    const known = new Set(['alert', 'alertdialog', 'application', 'article', 'banner', 'button', 'cell', 'checkbox',
      'columnheader', 'combobox', 'complementary', 'contentinfo', 'dialog', 'document', 'feed', 'figure', 'form',
      'grid', 'gridcell', 'group', 'heading', 'img', 'link', 'list', 'listbox', 'listitem', 'log', 'main', 'marquee',
      'math', 'menu', 'menubar', 'menuitem', 'meter', 'navigation', 'none', 'note', 'option', 'presentation',
      'progressbar', 'radio', 'radiogroup', 'region', 'row', 'rowgroup', 'rowheader', 'scrollbar', 'search',
      'searchbox', 'separator', 'slider', 'spinbutton', 'status', 'switch', 'tab', 'table', 'tablist', 'tabpanel',
      'term', 'textbox', 'timer', 'toolbar', 'tooltip', 'tree', 'treegrid', 'treeitem']);
    for (const el of all('[role]')) if (!known.has(el.getAttribute('role').trim())) fail(el, `role "${el.getAttribute('role')}"`);
  });
  rule('aria-live-value', (fail) => {
    for (const el of all('[aria-live]'))
      if (!['polite', 'assertive', 'off'].includes(el.getAttribute('aria-live'))) fail(el, 'aria-live is not polite, assertive or off');
  });
  rule('aria-hidden-focus', (fail) => {
    for (const el of all('[aria-hidden="true"]'))
      for (const f of [el, ...el.querySelectorAll(focusable)])
        if (f.matches(focusable) && !f.disabled && f.tabIndex >= 0 && visible(f)) fail(f, 'focusable inside aria-hidden');
  });
  rule('tabindex', (fail) => { for (const el of all('[tabindex]')) if (el.tabIndex > 0) fail(el, 'tabindex above 0'); });
  rule('keyboard-reachable', (fail) => {
    for (const el of all('a[href], button, input, select, textarea, summary'))
      if (visible(el) && !el.disabled && el.tabIndex < 0) fail(el, 'a visible control out of the tab order');
  });
  rule('nested-interactive', (fail) => {
    for (const el of all('a[href], button, [role="button"]'))
      if (el.querySelector('a[href], button, input, select, textarea, [role="button"]')) fail(el, 'a control inside a control');
    for (const h of all('h1, h2, h3, h4, h5, h6'))
      if (h.querySelector('a[href], button, input, select, textarea')) fail(h, 'a control inside a heading');
  });
  rule('heading-order', (fail) => {
    const headings = all('h1, h2, h3, h4, h5, h6').filter(visible);
    if (headings.filter((h) => h.tagName === 'H1').length !== 1) fail(document, 'not exactly one visible h1');
    let level = 0;
    for (const h of headings) {
      const next = Number(h.tagName[1]);
      if (next > level + 1) fail(h, `h${next} after h${level}`);
      if (!h.textContent.trim()) fail(h, 'an empty heading');
      level = next;
    }
  });
  rule('list', (fail) => {
    for (const el of all('ul, ol'))
      for (const child of el.children)
        if (!['LI', 'SCRIPT', 'TEMPLATE'].includes(child.tagName)) fail(el, `a <${child.tagName.toLowerCase()}> directly in a list`);
  });
  rule('table-header', (fail) => {
    for (const t of all('table')) if (visible(t) && t.rows.length > 1 && !t.querySelector('th')) fail(t, 'a data table without headers');
  });
  // WCAG 1.4.3: 4.5:1 for text, 3:1 for large text (24 px, or 18.66 px
  // bold); disabled controls are exempt. Backgrounds are the nearest opaque
  // colour behind the text (an image or gradient behind it: not judged).
  rule('color-contrast', (fail) => {
    const parse = (c) => { const m = c.match(/[\d.]+/g); return m ? m.map(Number).concat(m.length === 3 ? [1] : []) : [0, 0, 0, 0]; };
    const luminance = ([r, g, b]) => {
      const f = (v) => { v /= 255; return v <= 0.03928 ? v / 12.92 : ((v + 0.055) / 1.055) ** 2.4; };
      return 0.2126 * f(r) + 0.7152 * f(g) + 0.0722 * f(b);
    };
    const over = (top, bottom) => top.slice(0, 3).map((v, i) => v * top[3] + bottom[i] * (1 - top[3])).concat([1]);
    const background = (el) => {
      const layers = [];
      for (let e = el; e; e = e.parentElement) {
        const s = getComputedStyle(e);
        if (s.backgroundImage !== 'none') return null;
        const c = parse(s.backgroundColor);
        if (c[3] > 0) layers.push(c);
        if (c[3] >= 1) break;
      }
      return layers.reverse().reduce((below, top) => over(top, below), [255, 255, 255, 1]);
    };
    const checked = new Set();
    const walker = document.createTreeWalker(document.body, NodeFilter.SHOW_TEXT);
    for (let node = walker.nextNode(); node; node = walker.nextNode()) {
      const el = node.parentElement;
      if (!node.textContent.trim() || checked.has(el) || !visible(el)) continue;
      checked.add(el);
      if (el.closest('button:disabled, input:disabled, select:disabled, [aria-disabled="true"]')) continue;
      const s = getComputedStyle(el);
      if (parseFloat(s.opacity) < 1) continue;
      const bg = background(el);
      if (!bg) continue;
      const fg = over(parse(s.color), bg);
      const [l1, l2] = [luminance(fg), luminance(bg)].sort((a, b) => b - a);
      const ratio = (l1 + 0.05) / (l2 + 0.05);
      const size = parseFloat(s.fontSize), bold = Number(s.fontWeight) >= 700;
      const needed = size >= 24 || (bold && size >= 18.66) ? 3 : 4.5;
      contrast.judged += 1;
      contrast.lowest = Math.min(contrast.lowest, ratio / needed * 4.5);
      if (ratio < needed) fail(el, `contrast ${ratio.toFixed(2)}:1, needs ${needed}:1 (${s.color} on rgb(${bg.slice(0, 3).map(Math.round)}))`);
    }
  });
  return {rules, violations, contrast};
})();
