// The page for keyboard, screen-reader and phone users, in Chromium: at 360 px wide, in light
// and dark, every view (filled in) has named controls, a valued progress bar, alt texts,
// 4.5:1 contrast and no sideways scroll; the views are reached and used from the keyboard.
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { SCENE, accessibilityProblems, encodePng, openPage, unexpectedErrors, withServerAndBrowser } from './helpers.mjs';

let server;
let browser;
withServerAndBrowser((s, b) => {
  server = s;
  browser = b;
});

for (const colorScheme of ['light', 'dark']) {
  test(`every view passes the checks at 360 px (${colorScheme})`, async () => {
    const page = await openPage(browser, server, { width: 360, height: 740, colorScheme });
    const check = async (what) => assert.deepEqual(await accessibilityProblems(page), [], what);
    await check('render view, empty');

    await page.getByLabel('Scene', { exact: true }).fill(SCENE);
    await page.getByRole('button', { name: 'Render', exact: true }).click();
    await page.locator('.job-card').getByRole('img', { name: /^Rendered/ }).waitFor();
    await page.getByRole('button', { name: 'Copy as curl' }).click();
    await check('render view, a finished job and the curl command');

    await page.getByLabel('Scene', { exact: true }).fill(SCENE.replace('radius', 'radios'));
    await page.getByRole('button', { name: 'Render', exact: true }).click();
    await page.locator('#scene-error').waitFor();
    await check('render view, a scene error');

    await page.getByRole('link', { name: 'Jobs' }).click();
    await page.locator('#jobs-table tbody tr').first().waitFor();
    await check('jobs view');

    await page.getByRole('link', { name: 'Compare' }).click();
    const png = encodePng(4, 2, new Uint8Array(24).fill(90));
    await page.getByLabel('Image A (PNG or PPM)').setInputFiles({ name: 'a.png', mimeType: 'image/png', buffer: png });
    await page.getByLabel('Image B (PNG or PPM)').setInputFiles({ name: 'b.png', mimeType: 'image/png', buffer: png });
    await page.getByRole('button', { name: 'Compare', exact: true }).click();
    await page.locator('#compare-verdict', { hasText: 'identical' }).waitFor();
    await check('compare view with a result');
    await page.getByLabel('flicker').check();
    await check('compare view, flicker');

    await page.getByRole('link', { name: 'Grade' }).click();
    await check('grade view');
    await page.locator('#token-box summary').click();
    await check('the token form');
    assert.deepEqual(unexpectedErrors(page, [400]), []);
    await page.context().close();
  });
}

test('the keyboard alone reaches the views and renders a scene', async () => {
  const page = await openPage(browser, server);
  // Tab to the navigation's "Compare" and follow it: the view's heading takes the focus.
  let focused = '';
  for (let i = 0; i < 10 && focused !== 'Compare'; i++) {
    await page.keyboard.press('Tab');
    focused = await page.evaluate(() => document.activeElement.textContent.trim());
  }
  assert.equal(focused, 'Compare');
  await page.keyboard.press('Enter');
  await page.getByRole('heading', { name: 'Compare images' }).waitFor();
  assert.equal(await page.evaluate(() => document.activeElement.id), 'compare-heading');
  assert.equal(await page.locator('nav a[aria-current="page"]').textContent(), 'Compare');

  // Back to Render, type a scene, and submit it from the keyboard.
  await page.goto(`${server.url}/#/render`);
  await page.getByLabel('Scene', { exact: true }).focus();
  await page.keyboard.insertText(SCENE);
  await page.keyboard.press('Tab');  // to the scene file
  let onRender = false;
  for (let i = 0; i < 15 && !onRender; i++) {
    await page.keyboard.press('Tab');
    onRender = await page.evaluate(() => document.activeElement.id === 'render-button');
  }
  assert.ok(onRender, 'Tab reaches the Render button');
  await page.keyboard.press('Enter');
  await page.locator('.job-card').getByRole('img', { name: /^Rendered/ }).waitFor();
  // The focus ring shows where the keyboard is: still on the Render button.
  const focus = await page.evaluate(() => [document.activeElement.id, getComputedStyle(document.activeElement).outlineStyle]);
  assert.deepEqual(focus, ['render-button', 'solid']);
  assert.deepEqual(unexpectedErrors(page), []);
  await page.context().close();
});
