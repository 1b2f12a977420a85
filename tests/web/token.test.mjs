// A farm with a token, in Chromium: the page loads and asks for it, a wrong token is refused
// and not kept, the right one renders with its events streamed under the Authorization
// header (never in a URL), and it lasts for the browser tab's session only.
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { SCENE, openPage, unexpectedErrors, withServerAndBrowser } from './helpers.mjs';

const TOKEN = 's3cret-token-for-the-lab';
let server;
let browser;
withServerAndBrowser((s, b) => {
  server = s;
  browser = b;
}, ['--token', TOKEN]);

test('the page asks for the token, refuses a wrong one and renders with the right one', async () => {
  assert.equal((await server.api('/jobs')).status, 401);
  const page = await openPage(browser, server);
  const status = page.locator('#token-status');
  await status.filter({ hasText: 'This farm asks for an access token' }).waitFor();
  const field = page.getByLabel('Token', { exact: true });
  assert.ok(await field.isVisible(), 'the token field is shown');

  // Without a token, rendering says why it cannot.
  await page.getByLabel('Scene', { exact: true }).fill(SCENE);
  await page.getByRole('button', { name: 'Render', exact: true }).click();
  await page.locator('#render-message', { hasText: 'needs an access token' }).waitFor();

  await field.fill('guess');
  await page.getByRole('button', { name: 'Use token' }).click();
  await status.filter({ hasText: 'That token was refused' }).waitFor();
  assert.equal(await field.getAttribute('aria-invalid'), 'true');
  assert.equal(await page.evaluate(() => sessionStorage.getItem('rayfarm.token')), null);

  await field.fill(TOKEN);
  await page.getByRole('button', { name: 'Use token' }).click();
  await status.filter({ hasText: 'Token accepted' }).waitFor();
  assert.equal(await page.evaluate(() => sessionStorage.getItem('rayfarm.token')), TOKEN);
  assert.equal(await page.evaluate(() => localStorage.length), 0);

  const events = page.waitForRequest((r) => r.url().endsWith('/events'));
  const eventsAnswer = page.waitForResponse((r) => r.url().endsWith('/events'));
  await page.getByRole('button', { name: 'Render', exact: true }).click();
  const request = await events;
  assert.equal(request.headers().authorization, `Bearer ${TOKEN}`);
  const answer = await eventsAnswer;
  assert.equal(answer.status(), 200);
  const card = page.locator('.job-card');
  await page.waitForFunction(() => document.querySelector('.job-card [role=progressbar]')?.getAttribute('aria-valuenow') === '100');
  await card.getByRole('img', { name: /^Rendered/ }).waitFor();
  const id = await card.getAttribute('data-job-id');
  assert.equal((await (await server.api(`/jobs/${id}`, {}, TOKEN)).json()).state, 'done');
  // The stream carried the progress: its body ends with the done event.
  assert.match(await answer.text(), /event: done\ndata: \{.*"state":"done"/s);
  assert.ok(page.requests.every((u) => !u.includes(TOKEN)), 'the token appeared in a URL');

  // A reload keeps the token for this tab: the jobs list loads with it.
  await page.goto(`${server.url}/#/jobs`);
  await page.reload();
  await page.locator(`tr[data-job-id="${id}"] .chip`, { hasText: 'done' }).waitFor();
  assert.equal(await page.locator('#token-box').getAttribute('open'), null);
  assert.deepEqual(unexpectedErrors(page, [401]), []);

  // Another session (a new context) starts without it.
  const other = await openPage(browser, server);
  await other.locator('#token-status', { hasText: 'This farm asks for an access token' }).waitFor();
  await other.context().close();
  await page.context().close();
});
