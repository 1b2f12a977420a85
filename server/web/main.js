// The page's entry: the views by URL hash (#/render, #/jobs, #/jobs/ID, #/compare, #/grade),
// the server's status line, and the access token.
import { ApiError, getJson, onUnauthorized, setToken, token } from './api.js';
import { initCompare } from './compare.js';
import { initGrade } from './grade.js';
import { hideJobs, refresh as refreshJobs, showJobs } from './jobs.js';
import { initRender, refreshSamples, showRenderJob } from './render.js';
import { announce } from './ui.js';

const $ = (id) => document.getElementById(id);
const VIEWS = ['render', 'jobs', 'compare', 'grade'];
const HEALTH_EVERY_MS = 5000;

function route(moveFocus) {
  const m = /^#\/(render|jobs|compare|grade)(?:\/([0-9a-f]{32}))?(?:\?(.*))?$/.exec(location.hash);
  const view = m ? m[1] : 'render';
  for (const v of VIEWS) {
    $(`view-${v}`).hidden = v !== view;
    const link = document.querySelector(`nav a[data-view="${v}"]`);
    if (v === view) link.setAttribute('aria-current', 'page');
    else link.removeAttribute('aria-current');
  }
  if (view === 'jobs') showJobs(m && m[2]);
  else hideJobs();
  if (view === 'render' && m && m[3]) {
    const job = new URLSearchParams(m[3]).get('job');
    if (/^[0-9a-f]{32}$/.test(job || '')) showRenderJob(job);
  }
  // After a click on the navigation, start reading at the new view's heading.
  if (moveFocus) {
    const heading = $(`view-${view}`).querySelector('h2');
    heading.tabIndex = -1;
    heading.focus();
  }
}

let online = null;
async function health() {
  const status = $('server-status');
  try {
    const started = performance.now();
    const h = await getJson('/healthz');
    const ms = Math.round(performance.now() - started);
    status.textContent = `Online · ${h.queue_depth} queued · ${h.running} running · ${h.workers} workers · ${ms} ms`;
    status.className = 'server-status online';
    if (online === false) announce('The server is back online.');
    online = true;
  } catch (err) {
    const shutting = err instanceof ApiError && err.status === 503;
    status.textContent = shutting ? 'The server is shutting down' : 'Offline: the server cannot be reached';
    status.className = 'server-status offline';
    if (online !== false) announce(status.textContent);
    online = false;
  }
}

function tokenMessage(text, isError) {
  $('token-status').textContent = text;
  $('token-status').classList.toggle('error', isError);
  $('token').setAttribute('aria-invalid', isError ? 'true' : 'false');
}

// Asks for the caller's jobs: 401 means this farm wants a (better) token.
async function checkAccess() {
  try {
    await getJson('/jobs');
    return true;
  } catch (err) {
    if (!(err instanceof ApiError && err.status === 401)) return true;  // not a token matter
    return false;
  }
}

function askForToken(refused) {
  $('token-box').open = true;
  tokenMessage(
    refused ? 'That token was refused: check it and try again.' : 'This farm asks for an access token: enter it here.',
    true,
  );
}

function initToken() {
  $('token').value = token();
  onUnauthorized(() => askForToken(Boolean(token())));
  $('token-form').addEventListener('submit', async (event) => {
    event.preventDefault();
    const value = $('token').value.trim();
    setToken(value);
    if (await checkAccess()) {
      tokenMessage(value ? 'Token accepted.' : 'No token: this farm needs none.', false);
      announce('Token accepted.');
      refreshSamples();
      if (!$('view-jobs').hidden) refreshJobs();
    } else {
      setToken('');  // a refused token is not sent again
      askForToken(Boolean(value));
    }
  });
  $('token-forget').addEventListener('click', () => {
    setToken('');
    $('token').value = '';
    tokenMessage('Token forgotten.', false);
  });
}

async function start() {
  initToken();
  initRender();
  initCompare();
  initGrade();
  window.addEventListener('hashchange', () => route(true));
  route(false);
  health();
  setInterval(() => {
    if (!document.hidden) health();
  }, HEALTH_EVERY_MS);
  if (!(await checkAccess())) askForToken(Boolean(token()));
}

start();
