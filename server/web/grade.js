// The Grade view: an assignment (uploaded with its scenes, or stored on the server) and a
// student's images through POST /grade; the result as a table, and as the platforms' files.
import { ApiError, describe, request, saveBlob } from './api.js';
import { describeNames, nameAssignmentFiles } from './files.js';
import { el, formatNumber } from './ui.js';

const $ = (id) => document.getElementById(id);
const FILE_NAMES = {
  gradescope: 'results.json',
  prairielearn: 'results.json',
  junit: 'junit.xml',
  html: 'report.html',
  json: 'grade.json',
};

export function initGrade() {
  $('grade-form').addEventListener('submit', (event) => {
    event.preventDefault();
    run();
  });
  for (const id of ['grade-assignment', 'grade-scenes', 'grade-images'])
    $(id).addEventListener('change', previewNames);
  for (const button of document.querySelectorAll('#grade-result button[data-format]'))
    button.addEventListener('click', () => download(button.dataset.format));
}

function message(text, isError = false) {
  $('grade-message').textContent = text;
  $('grade-message').classList.toggle('error', isError);
}

async function assignmentJson(file) {
  try {
    return JSON.parse(await file.text());
  } catch {
    return {};  // the server places the syntax error
  }
}

async function namedFiles() {
  const file = $('grade-assignment').files[0];
  const images = [...$('grade-images').files];
  if (!file) return images.map((f) => ({ file: f, name: f.name }));
  return nameAssignmentFiles(await assignmentJson(file), [...$('grade-scenes').files], images);
}

async function previewNames() {
  const names = describeNames(await namedFiles());
  $('grade-files').textContent = names ? `Sent as: ${names}` : '';
}

// The multipart request for `format`; throws with a message when something is missing.
async function buildForm(format) {
  const file = $('grade-assignment').files[0];
  const stored = $('grade-stored').value.trim();
  if (!file && !stored) throw new Error('Choose the assignment file, or name an assignment stored on the server.');
  if (!$('grade-images').files.length) throw new Error('Choose your images.');
  const form = new FormData();
  form.append('format', format);
  if (file) form.append('assignment', file, file.name);
  else form.append('assignment', stored);
  for (const { file: f, name } of await namedFiles()) form.append(name, f, f.name);
  return form;
}

async function run() {
  message('Grading: rendering the references…');
  try {
    const result = await (await request('/grade', { method: 'POST', body: await buildForm('json') })).json();
    show(result);
    message('');
  } catch (err) {
    const d = err instanceof ApiError ? err.detail : {};
    const where = d.path ? ` (at ${d.path})` : '';
    message(`${describe(err)}${where}`, true);
  }
}

function show(result) {
  const score = `${formatNumber(result.score, 6)} / ${formatNumber(result.max_score, 6)}`;
  $('grade-score').textContent = `${result.assignment || 'Assignment'}: ${score} points`;
  // Each test is two rows: its name, points and status, then its feedback across the table
  // (hints are sentences: a column of their own would be a sliver on a phone).
  const rows = (result.tests || []).flatMap((t, i) => {
    const id = `grade-test-${i}`;
    const feedback = el('td', { colSpan: 3, headers: `${id} grade-feedback-heading` }, el('p', {}, t.message || ''));
    if (t.hints && t.hints.length)
      feedback.append(el('ul', { class: 'hints' }, ...t.hints.map((h) => el('li', {}, h.message))));
    if (t.error) feedback.append(el('p', { class: 'error' }, t.error));
    return [
      el(
        'tr',
        { 'data-test': t.name },
        el('th', { scope: 'row', id }, t.name),
        el('td', { class: 'points' }, `${formatNumber(t.score, 6)} / ${formatNumber(t.max_score, 6)}`),
        el('td', {}, el('span', { class: `chip state-${t.status === 'passed' ? 'done' : 'failed'}` }, t.status)),
      ),
      el('tr', { class: 'feedback', 'data-feedback-for': t.name }, feedback),
    ];
  });
  if (result.error) message(`Grader error: ${result.error}`, true);
  $('grade-table').querySelector('tbody').replaceChildren(...rows);
  $('grade-result').hidden = false;
  $('grade-score').focus();
}

async function download(format) {
  try {
    const blob = await (await request('/grade', { method: 'POST', body: await buildForm(format) })).blob();
    saveBlob(blob, FILE_NAMES[format] || 'results');
  } catch (err) {
    message(describe(err), true);
  }
}
