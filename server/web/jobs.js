// The Jobs view: this client's jobs (GET /jobs), refreshed every second while shown, rows
// kept in place so focus stays where it was; #/jobs/ID opens one job's card above the table.
import { describe, getJson, request } from './api.js';
import { JobCard } from './job_card.js';
import { el, shortId } from './ui.js';

const $ = (id) => document.getElementById(id);
const FINAL = new Set(['done', 'failed', 'canceled']);
const EVERY_MS = 1000;
let timer = null;
let card = null;
const rows = new Map();  // job id -> {tr, cells}

export function showJobs(id) {
  if (id && (!card || card.id !== id)) {
    card?.destroy();
    card = new JobCard($('jobs-card'), id, () => {});
    card.start();
  } else if (!id) {
    card?.destroy();
    card = null;
    $('jobs-card').replaceChildren();
  }
  if (!timer) {
    refresh();
    timer = setInterval(() => {
      if (!document.hidden) refresh();
    }, EVERY_MS);
  }
}

export function hideJobs() {
  clearInterval(timer);
  timer = null;
  card?.destroy();
  card = null;
}

export async function refresh() {
  try {
    const { jobs } = await getJson('/jobs');
    show(jobs);
    $('jobs-updated').textContent = `Updated ${new Date().toLocaleTimeString()}`;
  } catch (err) {
    $('jobs-updated').textContent = `Cannot list your jobs: ${describe(err)}`;
  }
}

function makeRow(id) {
  const cells = {
    state: el('span', { class: 'chip' }),
    progress: el('span'),
    bar: el('span', { class: 'mini-bar' }),
    size: el('td'),
    spp: el('td'),
    created: el('td', { class: 'col-created' }),
    link: el('a', { href: `#/jobs/${id}` }, el('code', {}, shortId(id))),
    cancel: el('button', { type: 'button', class: 'danger small', 'aria-label': `Cancel job ${shortId(id)}` }, 'Cancel'),
  };
  cells.cancel.addEventListener('click', async () => {
    const hadFocus = document.activeElement === cells.cancel;
    try {
      await request(`/jobs/${id}`, { method: 'DELETE' });
    } catch (err) {
      $('jobs-updated').textContent = `Cannot cancel job ${shortId(id)}: ${describe(err)}`;
    }
    await refresh();
    // The button hides once the job is canceled: keep the keyboard on the row's link.
    if (hadFocus && cells.cancel.hidden) cells.link.focus();
  });
  const tr = el(
    'tr',
    { 'data-job-id': id },
    el('td', {}, cells.link),
    el('td', {}, cells.state),
    el('td', {}, cells.progress, el('span', { class: 'mini-track', 'aria-hidden': 'true' }, cells.bar)),
    cells.size,
    cells.spp,
    cells.created,
    el('td', {}, cells.cancel),
  );
  return { tr, cells };
}

function show(jobs) {
  const body = $('jobs-table').querySelector('tbody');
  const seen = new Set();
  let previous = null;
  for (const job of jobs) {
    seen.add(job.id);
    let row = rows.get(job.id);
    if (!row) {
      row = makeRow(job.id);
      rows.set(job.id, row);
    }
    const { cells } = row;
    const percent = job.state === 'done' ? 100 : Math.floor((job.progress || 0) * 100);
    cells.state.textContent = job.state;
    cells.state.className = `chip state-${job.state}`;
    cells.progress.textContent = `${percent} %`;
    cells.bar.style.width = `${percent}%`;
    const o = job.options || {};
    cells.size.textContent = o.width && o.height ? `${o.width}×${o.height}` : '';
    cells.spp.textContent = o.spp ?? '';
    cells.created.textContent = job.created_at ? new Date(job.created_at).toLocaleTimeString() : '';
    cells.cancel.hidden = FINAL.has(job.state);
    // In order, newest first, moving only rows that are out of place.
    const expected = previous ? previous.nextSibling : body.firstChild;
    if (expected !== row.tr) body.insertBefore(row.tr, expected);
    previous = row.tr;
  }
  for (const [id, row] of rows) {
    if (!seen.has(id)) {
      row.tr.remove();
      rows.delete(id);
    }
  }
  $('jobs-empty').hidden = jobs.length > 0;
}
