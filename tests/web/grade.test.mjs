// The Grade view in Chromium: lab1's assignment, its scenes and a student's images give the
// same table as POST /grade's JSON, and the platform files download.
import assert from 'node:assert/strict';
import { readFile } from 'node:fs/promises';
import path from 'node:path';
import { test } from 'node:test';
import { SOURCE_DIR, download, openPage, unexpectedErrors, withServerAndBrowser } from './helpers.mjs';

const LAB = path.join(SOURCE_DIR, 'scenes/assignments/lab1');
const SCENES = ['spheres.txt', 'shadows.txt', 'mirror.txt', 'glint.txt'];
const IMAGES = ['spheres.png', 'shadows.png', 'mirror.png', 'glint.png'];

let server;
let browser;
withServerAndBrowser((s, b) => {
  server = s;
  browser = b;
});

// POST /grade from node, with the parts named by hand as the assignment names them.
async function gradeByApi(student, format) {
  const form = new FormData();
  form.append('format', format);
  form.append('assignment', new Blob([await readFile(path.join(LAB, 'lab1.json'))]), 'lab1.json');
  for (const s of SCENES) form.append(`scenes/${s}`, new Blob([await readFile(path.join(LAB, 'scenes', s))]), s);
  for (const i of IMAGES) form.append(i, new Blob([await readFile(path.join(LAB, 'students', student, i))]), i);
  const res = await server.api('/grade', { method: 'POST', body: form });
  assert.equal(res.status, 200, await res.clone().text());
  return res;
}

test('an assignment, its scenes and a student\'s images give the grading table', async () => {
  const expected = await (await gradeByApi('ben', 'json')).json();
  assert.equal(expected.tests.length, 4);

  const page = await openPage(browser, server, { hash: '#/grade' });
  await page.getByLabel('Assignment (JSON)').setInputFiles(path.join(LAB, 'lab1.json'));
  await page.getByLabel('Its scenes and textures').setInputFiles(SCENES.map((s) => path.join(LAB, 'scenes', s)));
  await page.getByLabel('Your images (PNG or PPM)').setInputFiles(IMAGES.map((i) => path.join(LAB, 'students/ben', i)));
  // The page names each file by the path the assignment gives it.
  await page.getByText('spheres.txt → scenes/spheres.txt').waitFor();
  await page.getByRole('button', { name: 'Grade', exact: true }).click();

  const score = page.locator('#grade-score');
  await score.waitFor();
  assert.equal(await score.textContent(), `${expected.assignment}: ${expected.score} / ${expected.max_score} points`);
  const rows = await page.locator('#grade-table tbody tr[data-test]').evaluateAll((trs) =>
    trs.map((tr) => ({
      name: tr.querySelector('th').textContent,
      points: tr.querySelector('td.points').textContent,
      status: tr.querySelector('.chip').textContent,
      feedback: tr.nextElementSibling.matches('tr.feedback') ? tr.nextElementSibling.textContent : '',
    })),
  );
  assert.deepEqual(
    rows.map(({ name, points, status }) => ({ name, points, status })),
    expected.tests.map((t) => ({ name: t.name, points: `${t.score} / ${t.max_score}`, status: t.status })),
  );
  for (const [i, t] of expected.tests.entries()) {
    assert.ok(rows[i].feedback.includes(t.message), rows[i].feedback);
    for (const h of t.hints) assert.ok(rows[i].feedback.includes(h.message), `hint ${h.code} missing`);
  }
  assert.ok(rows.some((r) => r.feedback.includes('round')), 'ben\'s rounding hint is shown');

  // The platforms' files are the API's answers.
  const junit = await download(page, () => page.getByRole('button', { name: 'JUnit' }).click());
  assert.equal(junit.name, 'junit.xml');
  assert.equal(junit.bytes.toString(), await (await gradeByApi('ben', 'junit')).text());
  assert.deepEqual(unexpectedErrors(page), []);
  await page.context().close();
});

test('a correct student gets full points, and a missing assignment is explained', async () => {
  const page = await openPage(browser, server, { hash: '#/grade' });
  await page.getByRole('button', { name: 'Grade', exact: true }).click();
  await page.locator('#grade-message', { hasText: 'Choose the assignment file' }).waitFor();

  await page.getByLabel('Assignment (JSON)').setInputFiles(path.join(LAB, 'lab1.json'));
  await page.getByLabel('Its scenes and textures').setInputFiles(SCENES.map((s) => path.join(LAB, 'scenes', s)));
  await page.getByLabel('Your images (PNG or PPM)').setInputFiles(IMAGES.map((i) => path.join(LAB, 'students/ada', i)));
  await page.getByRole('button', { name: 'Grade', exact: true }).click();
  await page.locator('#grade-score', { hasText: ': 10 / 10 points' }).waitFor();
  assert.deepEqual(await page.locator('#grade-table .chip').allTextContents(), ['passed', 'passed', 'passed', 'passed']);
  assert.deepEqual(unexpectedErrors(page), []);
  await page.context().close();
});
