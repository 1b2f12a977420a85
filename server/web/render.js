// The Render view: a scene (pasted or opened, with its textures) and the options that
// matter, POST /render, then a job card; a scene error shown at its line with a caret; the
// same request as a curl command.
import { ApiError, describe, getJson, request, token } from './api.js';
import { describeNames, nameTextures } from './files.js';
import { JobCard } from './job_card.js';
import { el } from './ui.js';

const $ = (id) => document.getElementById(id);
const FINAL = new Set(['done', 'failed', 'canceled']);
let card = null;
let busy = false;

export function initRender() {
  $('scene-file').addEventListener('change', async () => {
    const file = $('scene-file').files[0];
    if (!file) return;
    $('scene').value = await file.text();
    clearSceneError();
    showTextureNames();
  });
  $('textures').addEventListener('change', showTextureNames);
  $('scene').addEventListener('input', () => $('scene').removeAttribute('aria-invalid'));
  $('render-form').addEventListener('submit', (event) => {
    event.preventDefault();
    submit({ body: $('scene').value });
  });
  $('sample-form').addEventListener('submit', (event) => {
    event.preventDefault();
    if ($('sample').value) submit({ sample: $('sample').value });
  });
  $('curl-button').addEventListener('click', copyCurl);
  refreshSamples();
}

export async function refreshSamples() {
  const select = $('sample');
  try {
    const { samples } = await getJson('/samples');
    select.replaceChildren(
      el('option', { value: '' }, 'choose a sample'),
      ...samples.map((s) => el('option', { value: s.name }, s.description ? `${s.name}: ${s.description}` : s.name)),
    );
    $('sample-form').hidden = samples.length === 0;
  } catch {
    $('sample-form').hidden = true;  // no token yet, or none bundled
  }
}

function options() {
  const params = new URLSearchParams();
  for (const id of ['opt-width', 'opt-height', 'opt-spp', 'opt-depth', 'opt-profile']) {
    const input = $(id);
    if (input.value.trim() !== '') params.set(input.name, input.value.trim());
  }
  return params;
}

function showTextureNames() {
  const named = nameTextures($('scene').value, $('textures').files);
  const names = describeNames(named);
  $('textures-list').textContent = named.length
    ? `Sent as: ${names || named.map((n) => n.name).join(', ')}`
    : '';
}

function message(text, isError = false) {
  const m = $('render-message');
  m.textContent = text;
  m.classList.toggle('error', isError);
}

async function submit({ body, sample }) {
  // A second click while this one is sent is ignored; the button is not disabled, which
  // would drop the keyboard focus.
  if (busy) return;
  busy = true;
  clearSceneError();
  message('Sending…');
  const params = options();
  let init;
  if (sample) {
    params.set('sample', sample);
    init = { method: 'POST' };
  } else {
    const textures = nameTextures(body, $('textures').files);
    if (textures.length) {
      const form = new FormData();
      form.append('scene', new Blob([body], { type: 'text/plain' }), 'scene.txt');
      for (const { file, name } of textures) form.append(name, file, file.name);
      init = { method: 'POST', body: form };
    } else {
      init = { method: 'POST', body, headers: { 'Content-Type': 'text/plain' } };
    }
  }
  $('render-button').setAttribute('aria-disabled', 'true');
  try {
    const job = await (await request(`/render?${params}`, init)).json();
    message('');
    showRenderJob(job.id);
    history.replaceState(null, '', `#/render?job=${job.id}`);
    $('render-job').scrollIntoView({ block: 'nearest', behavior: matchMedia('(prefers-reduced-motion: reduce)').matches ? 'auto' : 'smooth' });
  } catch (err) {
    const d = err instanceof ApiError ? err.detail : {};
    // A place in the scene: a line, or a JSON path (from "/"). An option of the form has its
    // name as its path, and is no error of the scene.
    const inScene = d.line || (typeof d.path === 'string' && d.path.startsWith('/')) ||
      (d.errors && d.errors.length);
    if (!sample && err.status === 400 && inScene) {
      message('The scene has errors: see below the scene.', true);
      showSceneError(d, body);
    } else {
      message(describe(err), true);
    }
  } finally {
    busy = false;
    $('render-button').removeAttribute('aria-disabled');
  }
}

export function showRenderJob(id) {
  if (card && card.id === id) return;
  card?.destroy();
  card = new JobCard($('render-job'), id, (status) => {
    const percent = Math.floor((status.progress || 0) * 100);
    document.title = FINAL.has(status.state) ? 'rayfarm' : `${percent} % · rayfarm`;
  });
  card.start();
}

function clearSceneError() {
  $('scene-error').hidden = true;
  $('scene-error').replaceChildren();
  $('scene').removeAttribute('aria-invalid');
}

// "12 | the line" and, under it, a caret at the column (tabs kept, so it lines up).
export function excerpt(lines, line, column) {
  const source = lines[line - 1] ?? '';
  const gutter = ' '.repeat(String(line).length);
  const before = source.slice(0, Math.max(0, column - 1)).replace(/[^\t]/g, ' ');
  return `${line} | ${source}\n${gutter} | ${before}^`;
}

function showSceneError(detail, text) {
  const box = $('scene-error');
  const errors = detail.errors && detail.errors.length ? detail.errors : [detail];
  const lines = text.split(/\r?\n/);
  box.replaceChildren(
    el('p', { class: 'error-title' }, errors.length > 1 ? `The scene has ${errors.length} errors:` : 'The scene has an error:'),
  );
  for (const e of errors.slice(0, 20)) {
    const where = e.line ? `Line ${e.line}, column ${e.column}` : e.path ? `At ${e.path}` : '';
    const item = el('div', { class: 'scene-error' }, el('p', {}, where ? `${where}: ${e.message}` : e.message));
    if (e.line && e.line <= lines.length) {
      item.append(el('pre', { class: 'excerpt' }, excerpt(lines, e.line, e.column)));
      const go = el('button', { type: 'button', class: 'linkish' }, `Go to line ${e.line}`);
      go.addEventListener('click', () => goTo(lines, e.line, e.column));
      item.append(go);
    }
    box.append(item);
  }
  box.hidden = false;
  $('scene').setAttribute('aria-invalid', 'true');
}

function goTo(lines, line, column) {
  const area = $('scene');
  let offset = 0;
  for (let i = 0; i < line - 1; i++) offset += lines[i].length + 1;
  offset += Math.max(0, column - 1);
  area.focus();
  area.setSelectionRange(offset, Math.min(offset + 1, area.value.length));
  const lineHeight = parseFloat(getComputedStyle(area).lineHeight) || 20;
  area.scrollTop = Math.max(0, (line - 3) * lineHeight);
}

function shellQuote(s) {
  return `'${s.replace(/'/g, `'\\''`)}'`;
}

// The request the Render button sends, as a command that answers the PNG (wait=1).
export function curlCommand(text, params, textures, withToken) {
  const query = new URLSearchParams(params);
  query.set('wait', '1');
  const url = `${location.origin}/render?${query}`;
  const auth = withToken ? ` \\\n  -H "Authorization: Bearer $RAYFARM_TOKEN"` : '';
  if (textures.length) {
    const parts = textures.map(({ name }) => ` \\\n  -F ${shellQuote(`${name}=@${name}`)}`).join('');
    return `# in the scene's folder, the scene saved as scene.txt\ncurl -F 'scene=@scene.txt'${parts}${auth} \\\n  ${shellQuote(url)} -o render.png`;
  }
  let end = 'SCENE';
  while (text.split(/\r?\n/).includes(end)) end += '_END';
  const body = text.endsWith('\n') ? text : `${text}\n`;
  return `curl --data-binary @- -H 'Content-Type: text/plain'${auth} \\\n  ${shellQuote(url)} -o render.png <<'${end}'\n${body}${end}\n`;
}

async function copyCurl() {
  const text = $('scene').value;
  const command = curlCommand(text, options(), nameTextures(text, $('textures').files), Boolean(token()));
  $('curl-command').value = command;
  $('curl-box').hidden = false;
  const tokenNote = token() ? ' Set RAYFARM_TOKEN to your token first.' : '';
  try {
    await navigator.clipboard.writeText(command);
    message(`Copied the curl command.${tokenNote}`);
  } catch {
    // Clipboard access needs a secure origin (https or localhost): select it for the user.
    $('curl-command').focus();
    $('curl-command').select();
    message(`Press Ctrl+C to copy the selected command.${tokenNote}`);
  }
}
