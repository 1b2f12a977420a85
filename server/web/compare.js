// The Compare view: two images, or a scene rendered here and an image, through POST /compare
// (its numbers and its heat map); shown side by side, flickering, with a swipe or as the heat
// map, and a pixel inspector that reads both images' values under the pointer or the keys.
import { ApiError, describe, getBlob, request } from './api.js';
import { nameTextures } from './files.js';
import { decodeImage, paint } from './images.js';
import { el, formatNumber } from './ui.js';

const $ = (id) => document.getElementById(id);
const images = { a: null, b: null, heat: null };  // ImageData
let view = 'side';
let showingA = true;
let autoTimer = null;
let point = null;  // the inspected pixel {x, y}

export function initCompare() {
  for (const radio of document.querySelectorAll('input[name="compare-mode"]'))
    radio.addEventListener('change', () => {
      const scene = mode() === 'scene';
      $('compare-images').hidden = scene;
      $('compare-scene').hidden = !scene;
    });
  $('compare-scene-file').addEventListener('change', async () => {
    const file = $('compare-scene-file').files[0];
    if (file) $('compare-scene-text').value = await file.text();
  });
  $('compare-form').addEventListener('submit', (event) => {
    event.preventDefault();
    run();
  });
  for (const radio of document.querySelectorAll('input[name="compare-view"]'))
    radio.addEventListener('change', () => setView(radio.value));
  $('flicker-button').addEventListener('click', flip);
  $('flicker-auto').addEventListener('change', autoFlicker);
  $('swipe').addEventListener('input', swipe);
  const viewer = $('viewer');
  viewer.addEventListener('pointermove', (event) => {
    if (event.target instanceof HTMLCanvasElement) inspectAt(event.target, event.clientX, event.clientY);
  });
  viewer.addEventListener('keydown', onKey);
}

function mode() {
  return document.querySelector('input[name="compare-mode"]:checked').value;
}

function message(text, isError = false) {
  $('compare-message').textContent = text;
  $('compare-message').classList.toggle('error', isError);
}

// The request's parts; null (with a message) when something is missing.
function buildForm() {
  const form = new FormData();
  form.append('threshold', $('compare-threshold').value || '0');
  form.append('max_bad_fraction', $('compare-max-bad').value || '0');
  if ($('compare-neighborhood').checked) form.append('neighborhood', '1');
  if (mode() === 'images') {
    const a = $('compare-a').files[0];
    const b = $('compare-b').files[0];
    if (!a || !b) return message('Choose image A and image B.', true);
    form.append('a', a, a.name);
    form.append('b', b, b.name);
    return { form, a, b };
  }
  const text = $('compare-scene-text').value;
  const image = $('compare-image').files[0];
  if (!text.trim() || !image) return message('Give the scene and choose your image.', true);
  form.append('scene', new Blob([text], { type: 'text/plain' }), 'scene.txt');
  form.append('image', image, image.name);
  if ($('compare-profile').value) form.append('profile', $('compare-profile').value);
  for (const { file, name } of nameTextures(text, $('compare-textures').files)) form.append(name, file, file.name);
  return { form, b: image };
}

async function post(form) {
  return request('/compare', { method: 'POST', body: form });
}

async function run() {
  const built = buildForm();
  if (!built) return;
  message(mode() === 'scene' ? 'Rendering the scene and comparing…' : 'Comparing…');
  try {
    const metrics = await (await post(built.form)).json();
    built.form.append('diff', '1');
    const heatBlob = await (await post(built.form)).blob();
    const aBlob = built.a || (await getBlob(`/jobs/${metrics.reference_job}/image?format=png`));
    [images.a, images.b, images.heat] = await Promise.all([
      decodeImage(aBlob),
      decodeImage(built.b),
      decodeImage(heatBlob),
    ]);
    paint($('canvas-a'), images.a);
    paint($('canvas-b'), images.b);
    paint($('canvas-heat'), images.heat);
    showMetrics(metrics);
    message('');
    $('compare-result').hidden = false;
    point = null;
    $('inspector').textContent = 'Point at a pixel, or focus the images and use the arrow keys, to see both values.';
    setView(view);
    $('compare-verdict').focus();
  } catch (err) {
    const d = err instanceof ApiError ? err.detail : {};
    const where = d.line ? `Line ${d.line}, column ${d.column}: ` : d.path ? `At ${d.path}: ` : '';
    message(`${where}${describe(err)}`, true);
  }
}

function showMetrics(m) {
  const total = m.width * m.height;
  const percent = ((100 * m.differing_pixels) / total).toFixed(2);
  $('compare-verdict').textContent = m.identical
    ? 'The images are identical'
    : `The images ${m.match ? 'match' : 'differ'}: ${m.differing_pixels} of ${total} pixels differ (${percent} %)`;
  const rows = [
    ['Size', `${m.width}×${m.height}`],
    ['Differing pixels', `${m.differing_pixels} (${percent} %)`],
    ['Mean difference', `${formatNumber(m.mean_abs, 4)} levels`],
    ['RMSE', `${formatNumber(m.rmse, 4)} levels`],
    ['PSNR', m.psnr === null ? '∞ (identical)' : `${formatNumber(m.psnr, 4)} dB`],
    ['Largest difference', `${m.max_abs} levels`],
    ['Off by more than 1', String(m.off_by_more_than_1)],
    ['Rules', `threshold ${m.threshold}${m.neighborhood ? ', 3×3 neighbourhood' : ''}, ${m.max_bad_fraction} may differ`],
  ];
  $('compare-metrics').replaceChildren(...rows.flatMap(([k, v]) => [el('dt', {}, k), el('dd', {}, v)]));
}

function setView(next) {
  view = next;
  const viewer = $('viewer');
  viewer.className = `viewer mode-${view}`;
  $('flicker-controls').hidden = view !== 'flicker';
  $('swipe-controls').hidden = view !== 'swipe';
  $('heat-legend').hidden = view !== 'heat';
  if (view !== 'flicker') {
    clearInterval(autoTimer);
    autoTimer = null;
    $('flicker-auto').checked = false;
  }
  showingA = true;
  viewer.classList.toggle('show-b', false);
  $('flicker-showing').textContent = view === 'flicker' ? 'Showing A' : '';
  swipe();
  if (point) inspect(point.x, point.y);
}

function flip() {
  showingA = !showingA;
  $('viewer').classList.toggle('show-b', !showingA);
  $('flicker-showing').textContent = showingA ? 'Showing A' : 'Showing B';
}

function autoFlicker() {
  clearInterval(autoTimer);
  autoTimer = $('flicker-auto').checked ? setInterval(flip, 500) : null;
}

function swipe() {
  // A is clipped from the right: the slider's value is how much of A shows.
  const hidden = 100 - Number($('swipe').value);
  $('canvas-a').parentElement.style.clipPath = view === 'swipe' ? `inset(0 ${hidden}% 0 0)` : '';
}

function onKey(event) {
  if (!images.a) return;
  if (event.key === ' ' && view === 'flicker') {
    event.preventDefault();
    flip();
    return;
  }
  const step = event.shiftKey ? 10 : 1;
  const moves = { ArrowLeft: [-step, 0], ArrowRight: [step, 0], ArrowUp: [0, -step], ArrowDown: [0, step] };
  const move = moves[event.key];
  if (!move) return;
  event.preventDefault();
  const p = point || { x: Math.floor(images.a.width / 2), y: Math.floor(images.a.height / 2) };
  inspect(
    Math.min(images.a.width - 1, Math.max(0, p.x + move[0])),
    Math.min(images.a.height - 1, Math.max(0, p.y + move[1])),
  );
}

function inspectAt(canvas, clientX, clientY) {
  if (!images.a) return;
  const r = canvas.getBoundingClientRect();
  const x = Math.floor(((clientX - r.left) / r.width) * canvas.width);
  const y = Math.floor(((clientY - r.top) / r.height) * canvas.height);
  if (x < 0 || y < 0 || x >= canvas.width || y >= canvas.height) return;
  inspect(x, y);
}

function rgb(image, x, y) {
  if (!image || x >= image.width || y >= image.height) return null;
  const i = (y * image.width + x) * 4;
  return [image.data[i], image.data[i + 1], image.data[i + 2]];
}

function inspect(x, y) {
  point = { x, y };
  const a = rgb(images.a, x, y);
  const b = rgb(images.b, x, y);
  const delta = a && b ? b.map((v, c) => v - a[c]) : null;
  const signed = (d) => (d > 0 ? `+${d}` : String(d));
  $('inspector').textContent =
    `x ${x}, y ${y}: A ${a ? a.join(' ') : '—'} · B ${b ? b.join(' ') : '—'}` +
    (delta ? ` · B − A ${delta.map(signed).join(' ')}` : '');
  $('inspector').dataset.x = x;
  $('inspector').dataset.y = y;
  placeMarker(x, y);
}

// A square around the inspected pixel on the frontmost visible image.
function placeMarker(x, y) {
  const marker = $('marker');
  const viewer = $('viewer');
  const canvas = [...viewer.querySelectorAll('canvas')].find((c) => c.offsetParent !== null && c.getClientRects().length);
  if (!canvas) return;
  const r = canvas.getBoundingClientRect();
  const v = viewer.getBoundingClientRect();
  const size = Math.max(6, r.width / canvas.width);
  marker.style.left = `${r.left - v.left + ((x + 0.5) * r.width) / canvas.width - size / 2}px`;
  marker.style.top = `${r.top - v.top + ((y + 0.5) * r.height) / canvas.height - size / 2}px`;
  marker.style.width = marker.style.height = `${size}px`;
  marker.hidden = false;
}
