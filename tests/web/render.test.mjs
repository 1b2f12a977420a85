// The Render view and the Jobs view in Chromium: a pasted scene renders with its progress
// streamed, the finished image and its downloads are the API's bytes, "copy as curl" makes
// the same image, Cancel stops a slow render, a bad scene shows its line and a caret, and
// the jobs list follows jobs submitted elsewhere.
import assert from 'node:assert/strict';
import { execFile } from 'node:child_process';
import { mkdtemp, readFile, rm } from 'node:fs/promises';
import { tmpdir } from 'node:os';
import path from 'node:path';
import { test } from 'node:test';
import { promisify } from 'node:util';
import { SCENE, SOURCE_DIR, download, foreignRequests, openPage, unexpectedErrors, withServerAndBrowser } from './helpers.mjs';

let server;
let browser;
withServerAndBrowser((s, b) => {
  server = s;
  browser = b;
});

async function jobIdOf(card) {
  return card.getAttribute('data-job-id');
}

test('a pasted scene renders with streamed progress, and its downloads are the API\'s bytes', async () => {
  const page = await openPage(browser, server);
  assert.equal(await page.title(), 'rayfarm');
  await page.getByLabel('Scene', { exact: true }).fill(SCENE);
  await page.getByLabel('Width').fill('64');
  await page.getByLabel('Height').fill('48');
  await page.getByLabel('Samples per pixel').fill('4');
  const events = page.waitForResponse((r) => r.url().endsWith('/events'));
  await page.getByRole('button', { name: 'Render', exact: true }).click();

  const card = page.locator('.job-card');
  const bar = card.getByRole('progressbar', { name: 'Render progress' });
  await bar.waitFor();
  const stream = await events;
  assert.equal(stream.status(), 200);
  assert.equal(stream.headers()['content-type'], 'text/event-stream');
  await page.waitForFunction(() => document.querySelector('.job-card [role=progressbar]').getAttribute('aria-valuenow') === '100');
  await assert.doesNotReject(card.locator('.chip', { hasText: 'done' }).waitFor());

  const image = card.getByRole('img', { name: /^Rendered/ });
  await image.waitFor();
  const size = await image.evaluate((img) => [img.naturalWidth, img.naturalHeight]);
  assert.deepEqual(size, [64, 48]);

  const id = await jobIdOf(card);
  assert.match(id, /^[0-9a-f]{32}$/);
  assert.equal(new URL(page.url()).hash, `#/render?job=${id}`);
  const status = await (await server.api(`/jobs/${id}`)).json();
  assert.equal(status.state, 'done');
  assert.deepEqual([status.options.width, status.options.height, status.options.spp], [64, 48, 4]);

  const png = await download(page, () => card.getByRole('link', { name: 'Download PNG' }).click());
  assert.equal(png.name, `rayfarm-${id.slice(0, 8)}.png`);
  assert.ok(png.bytes.equals(await server.bytes(`/jobs/${id}/image`)), 'the PNG download differs from GET /jobs/ID/image');
  const ppm = await download(page, () => card.getByRole('button', { name: 'Download PPM' }).click());
  assert.ok(ppm.bytes.equals(await server.bytes(`/jobs/${id}/image?format=ppm`)), 'the PPM download differs');
  assert.equal(ppm.bytes.subarray(0, 2).toString(), 'P6');

  // "Copy as curl" gives a command that, run, answers the same image.
  await page.getByRole('button', { name: 'Copy as curl' }).click();
  const command = await page.getByLabel('The same request with curl').inputValue();
  assert.match(command, /^curl --data-binary @- /);
  assert.ok(command.includes(`${server.url}/render?width=64&height=48&spp=4&wait=1`), command);
  const dir = await mkdtemp(path.join(tmpdir(), 'rayfarm-curl-'));
  try {
    await promisify(execFile)('bash', ['-c', command], { cwd: dir });
    assert.ok((await readFile(path.join(dir, 'render.png'))).equals(png.bytes), 'curl rendered other bytes');
  } finally {
    await rm(dir, { recursive: true, force: true });
  }

  // The job is in the URL: a reload shows it again.
  await page.reload();
  await page.locator('.job-card').getByRole('img', { name: /^Rendered/ }).waitFor();
  assert.deepEqual(foreignRequests(page, server), []);
  assert.deepEqual(unexpectedErrors(page), []);
  await page.context().close();
});

test('a scene file and its textures upload under the paths the scene names', async () => {
  const scenes = path.join(SOURCE_DIR, 'scenes');
  const names = ['bricks.ppm', 'checker.ppm', 'slide.ppm'];
  const page = await openPage(browser, server);
  const view = page.locator('#view-render');
  await view.getByLabel('Scene file', { exact: true }).setInputFiles(path.join(scenes, 'textures.txt'));
  await page.waitForFunction(() => document.getElementById('scene').value.includes('texture bricks'));
  await view.getByLabel('Textures (PPM files the scene names)').setInputFiles(names.map((n) => path.join(scenes, 'textures', n)));
  await view.getByText('bricks.ppm → textures/bricks.ppm, checker.ppm → textures/checker.ppm, slide.ppm → textures/slide.ppm').waitFor();
  await page.getByLabel('Width').fill('160');
  await page.getByLabel('Height').fill('120');
  await page.getByRole('button', { name: 'Render', exact: true }).click();
  const card = page.locator('.job-card');
  await card.getByRole('img', { name: /^Rendered/ }).waitFor();
  const id = await jobIdOf(card);

  // The same upload by hand, parts named as the scene names them: the same image.
  const form = new FormData();
  form.append('scene', new Blob([await readFile(path.join(scenes, 'textures.txt'))]), 'textures.txt');
  for (const n of names) form.append(`textures/${n}`, new Blob([await readFile(path.join(scenes, 'textures', n))]), n);
  const byHand = await server.api('/render?width=160&height=120&wait=1', { method: 'POST', body: form });
  assert.equal(byHand.status, 200);
  assert.ok(Buffer.from(await byHand.arrayBuffer()).equals(await server.bytes(`/jobs/${id}/image`)));
  assert.deepEqual(unexpectedErrors(page), []);
  await page.context().close();
});

test('Cancel stops a slow render after its partial image and ETA show', async () => {
  const page = await openPage(browser, server);
  await page.getByLabel('Scene', { exact: true }).fill(SCENE);
  await page.getByLabel('Width').fill('800');
  await page.getByLabel('Height').fill('600');
  await page.getByLabel('Samples per pixel').fill('1024');
  await page.getByRole('button', { name: 'Render', exact: true }).click();
  const card = page.locator('.job-card');
  await card.locator('.chip', { hasText: 'running' }).waitFor();
  // The partial image fills in while it runs, at the job's size.
  const partial = card.getByRole('img', { name: /^Partial render/ });
  await partial.waitFor();
  assert.equal(await partial.evaluate((img) => img.naturalWidth), 800);
  await card.locator('.figures', { hasText: 'ETA' }).waitFor();
  const id = await jobIdOf(card);
  assert.equal((await (await server.api(`/jobs/${id}`)).json()).state, 'running');

  const clicked = Date.now();
  await card.getByRole('button', { name: 'Cancel' }).click();
  await card.locator('.chip', { hasText: 'canceled' }).waitFor({ timeout: 5000 });
  assert.ok(Date.now() - clicked < 5000);
  assert.equal((await (await server.api(`/jobs/${id}`)).json()).state, 'canceled');
  const percent = Number(await card.getByRole('progressbar').getAttribute('aria-valuenow'));
  assert.ok(percent < 100, `canceled at ${percent} %`);
  await card.getByText(/^Canceled at \d+ %$/).waitFor();
  assert.equal(await card.getByRole('button', { name: 'Cancel' }).count(), 0);
  assert.equal(await card.getByRole('link', { name: 'Download PNG' }).count(), 0);
  assert.deepEqual(unexpectedErrors(page), []);
  await page.context().close();
});

test('a bad scene shows each error at its line with a caret under its column', async () => {
  const lines = SCENE.split('\n');
  const bad = lines.map((l) => l.replace('   diffuse  .5 .5 .5', '   difuse  .5 .5 .5')).join('\n');
  const badLine = bad.split('\n').findIndex((l) => l.includes('difuse')) + 1;
  // What the API says about it: the page must show exactly this place.
  const answer = await server.api('/render', { method: 'POST', body: bad, headers: { 'Content-Type': 'text/plain' } });
  assert.equal(answer.status, 400);
  const { error } = await answer.json();
  assert.equal(error.code, 'invalid_scene');
  assert.equal(error.line, badLine);

  const page = await openPage(browser, server);
  await page.getByLabel('Scene', { exact: true }).fill(bad);
  await page.getByRole('button', { name: 'Render', exact: true }).click();
  const box = page.getByRole('alert').filter({ hasText: 'The scene has' });
  await box.waitFor();
  const where = `Line ${error.line}, column ${error.column}: ${error.message}`;
  assert.ok((await box.textContent()).includes(where), await box.textContent());
  const excerpt = (await box.locator('pre.excerpt').first().textContent()).split('\n');
  assert.equal(excerpt[0], `${badLine} | ${bad.split('\n')[badLine - 1]}`);
  const caretLine = `${' '.repeat(String(badLine).length)} | ${' '.repeat(error.column - 1)}^`;
  assert.equal(excerpt[1], caretLine);
  assert.equal(await page.getByLabel('Scene', { exact: true }).getAttribute('aria-invalid'), 'true');
  assert.equal(await page.locator('.job-card').count(), 0);

  // "Go to line" puts the cursor on the error.
  await box.getByRole('button', { name: `Go to line ${badLine}` }).click();
  const caret = await page.getByLabel('Scene', { exact: true }).evaluate((t) => t.selectionStart);
  const before = bad.split('\n').slice(0, badLine - 1).join('\n').length + 1;
  assert.equal(caret, before + error.column - 1);

  // The server stays up, and a fixed scene renders.
  assert.equal((await server.api('/healthz')).status, 200);
  await page.getByLabel('Scene', { exact: true }).fill(SCENE);
  await page.getByRole('button', { name: 'Render', exact: true }).click();
  await page.locator('.job-card').getByRole('img', { name: /^Rendered/ }).waitFor();
  assert.equal(await box.count(), 0);
  assert.deepEqual(unexpectedErrors(page, [400]), []);
  await page.context().close();
});

test('an option the server refuses is said as the option\'s error, not pinned to the scene', async () => {
  const page = await openPage(browser, server);
  await page.getByLabel('Scene', { exact: true }).fill(SCENE);
  await page.getByLabel('Samples per pixel').fill('1.5');
  await page.getByRole('button', { name: 'Render', exact: true }).click();
  const said = page.locator('#render-message');
  await said.filter({ hasText: 'spp' }).waitFor();
  const text = await said.textContent();
  assert.ok(text.includes('option spp must be an integer'), text);
  assert.ok(!text.includes('The scene has'), text);
  assert.equal(await page.locator('#scene-error').isHidden(), true);
  assert.notEqual(await page.getByLabel('Scene', { exact: true }).getAttribute('aria-invalid'), 'true');
  assert.equal(await page.locator('.job-card').count(), 0);
  assert.deepEqual(unexpectedErrors(page, [400]), []);
  await page.context().close();
});

test('the jobs list shows jobs submitted elsewhere and their states, live', async () => {
  const page = await openPage(browser, server, { hash: '#/jobs' });
  await page.getByRole('heading', { name: 'Your jobs' }).waitFor();
  // Submitted from node: the same client (address) as the page.
  const submit = async (query) => {
    const res = await server.api(`/render?${query}`, { method: 'POST', body: SCENE, headers: { 'Content-Type': 'text/plain' } });
    assert.equal(res.status, 202);
    return (await res.json()).id;
  };
  const quick = await submit('width=32&height=24');
  const row = page.locator(`tr[data-job-id="${quick}"]`);
  await row.locator('.chip', { hasText: 'done' }).waitFor({ timeout: 5000 });
  assert.equal(await row.getByRole('cell').nth(3).textContent(), '32×24');

  const slow = await submit('width=800&height=600&spp=1024');
  const slowRow = page.locator(`tr[data-job-id="${slow}"]`);
  await slowRow.locator('.chip', { hasText: /queued|running/ }).waitFor({ timeout: 5000 });
  // Newest first.
  assert.equal(await page.locator('#jobs-table tbody tr').first().getAttribute('data-job-id'), slow);
  await slowRow.getByRole('button', { name: `Cancel job ${slow.slice(0, 8)}` }).click();
  await slowRow.locator('.chip', { hasText: 'canceled' }).waitFor({ timeout: 5000 });
  assert.equal((await (await server.api(`/jobs/${slow}`)).json()).state, 'canceled');

  // A job's link opens its card above the list.
  await row.getByRole('link').click();
  assert.equal(new URL(page.url()).hash, `#/jobs/${quick}`);
  await page.locator('#jobs-card .job-card').getByRole('img', { name: /^Rendered/ }).waitFor();
  assert.deepEqual(unexpectedErrors(page), []);
  await page.context().close();
});
