// Small helpers every view uses: building elements, announcing to screen readers, numbers
// and durations as a person reads them.

// el('p', {class: 'x', hidden: true}, 'text', child): attributes set as properties where the
// element has one (so `hidden` and `htmlFor` work), else as attributes.
export function el(tag, attrs = {}, ...children) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attrs)) {
    if (value === undefined || value === null || value === false) continue;
    if (key === 'class') node.className = value;
    else if (key.startsWith('data-') || key.startsWith('aria-') || key === 'role') node.setAttribute(key, value);
    else if (key in node) node[key] = value;
    else node.setAttribute(key, value);
  }
  node.append(...children.filter((c) => c !== null && c !== undefined));
  return node;
}

export function announce(text) {
  const region = document.getElementById('announce');
  // A change of text is what a live region reads: clear first so a repeat is read again.
  region.textContent = '';
  setTimeout(() => {
    region.textContent = text;
  }, 50);
}

export function formatMs(ms) {
  if (ms === null || ms === undefined) return '';
  if (ms < 1000) return `${Math.round(ms)} ms`;
  const s = ms / 1000;
  if (s < 60) return `${s < 10 ? s.toFixed(1) : Math.round(s)} s`;
  const m = Math.floor(s / 60);
  return `${m} min ${Math.round(s - m * 60)} s`;
}

export function formatNumber(x, digits = 3) {
  if (x === null || x === undefined) return '—';
  if (Number.isInteger(x)) return String(x);
  return Number(x.toPrecision(digits)).toString();
}

export function sleep(ms, signal) {
  return new Promise((resolve) => {
    const t = setTimeout(resolve, ms);
    signal?.addEventListener('abort', () => {
      clearTimeout(t);
      resolve();
    });
  });
}

export function shortId(id) {
  return id.slice(0, 8);
}
