// The Compare view in Chromium: two uploaded images (a PNG and a PPM) give POST /compare's
// numbers, the pixel inspector reads both exact values under the pointer and the arrow keys,
// flicker flips with Space, swipe follows its slider, the heat map is the server's; a scene
// rendered here compares with the image it makes.
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { SCENE, encodePng, encodePpm, openPage, unexpectedErrors, withServerAndBrowser } from './helpers.mjs';

let server;
let browser;
withServerAndBrowser((s, b) => {
  server = s;
  browser = b;
});

const W = 16;
const H = 8;
function pixel(x, y) {
  return [(x * 13) % 256, (y * 29) % 256, 100];
}
function image(change) {
  const rgb = new Uint8Array(W * H * 3);
  for (let y = 0; y < H; y++)
    for (let x = 0; x < W; x++) rgb.set(change(x, y) || pixel(x, y), (y * W + x) * 3);
  return rgb;
}
// B differs from A at (3, 2) by +5 red and at (10, 6) by -2 green.
const A = image(() => null);
const B = image((x, y) => {
  const [r, g, b] = pixel(x, y);
  if (x === 3 && y === 2) return [r + 5, g, b];
  if (x === 10 && y === 6) return [r, g - 2, b];
  return null;
});

// The centre of pixel (x, y) of a canvas, in page coordinates.
async function pointAt(canvas, x, y) {
  await canvas.scrollIntoViewIfNeeded();
  const box = await canvas.boundingBox();
  return [box.x + ((x + 0.5) * box.width) / W, box.y + ((y + 0.5) * box.height) / H];
}

test('two images: the metrics are the API\'s, and the inspector shows both values', async () => {
  const png = encodePng(W, H, A);
  const ppm = encodePpm(W, H, B);
  const form = new FormData();
  form.append('a', new Blob([png]), 'a.png');
  form.append('b', new Blob([ppm]), 'b.ppm');
  const expected = await (await server.api('/compare', { method: 'POST', body: form })).json();
  assert.equal(expected.differing_pixels, 2);

  const page = await openPage(browser, server, { hash: '#/compare' });
  await page.getByLabel('Image A (PNG or PPM)').setInputFiles({ name: 'a.png', mimeType: 'image/png', buffer: png });
  await page.getByLabel('Image B (PNG or PPM)').setInputFiles({ name: 'b.ppm', mimeType: 'image/x-portable-pixmap', buffer: ppm });
  await page.getByRole('button', { name: 'Compare', exact: true }).click();
  const verdict = page.locator('#compare-verdict');
  await verdict.waitFor();
  assert.equal(await verdict.textContent(), `The images differ: 2 of ${W * H} pixels differ (1.56 %)`);
  const metrics = Object.fromEntries(
    await page.locator('#compare-metrics dt').evaluateAll((dts) => dts.map((dt) => [dt.textContent, dt.nextElementSibling.textContent])),
  );
  assert.equal(metrics['Largest difference'], `${expected.max_abs} levels`);
  assert.equal(metrics['Differing pixels'], '2 (1.56 %)');
  assert.equal(metrics['Mean difference'], `${Number(expected.mean_abs.toPrecision(4))} levels`);
  assert.equal(metrics.PSNR, `${Number(expected.psnr.toPrecision(4))} dB`);
  assert.equal(metrics.Size, `${W}×${H}`);

  // The inspector under the pointer: both images' exact bytes (a PNG decoded with no colour
  // conversion, a PPM read by the page itself).
  const inspector = page.locator('#inspector');
  const canvasA = page.locator('#canvas-a');
  await page.mouse.move(...(await pointAt(canvasA, 3, 2)));
  const [r, g, b] = pixel(3, 2);
  assert.equal(await inspector.textContent(), `x 3, y 2: A ${r} ${g} ${b} · B ${r + 5} ${g} ${b} · B − A +5 0 0`);
  await page.mouse.move(...(await pointAt(page.locator('#canvas-b'), 10, 6)));
  const [r2, g2, b2] = pixel(10, 6);
  assert.equal(await inspector.textContent(), `x 10, y 6: A ${r2} ${g2} ${b2} · B ${r2} ${g2 - 2} ${b2} · B − A 0 -2 0`);
  // And from the keyboard.
  await page.locator('#viewer').focus();
  await page.keyboard.press('ArrowLeft');
  await page.keyboard.press('ArrowUp');
  assert.match(await inspector.textContent(), /^x 9, y 5: /);

  // Flicker: Space flips which image shows.
  await page.getByLabel('flicker').check();
  await page.getByText('Showing A').waitFor();
  const visibility = () =>
    page.evaluate(() => ['pane-a', 'pane-b'].map((c) => getComputedStyle(document.querySelector(`.${c}`)).visibility));
  assert.deepEqual(await visibility(), ['visible', 'hidden']);
  await page.locator('#viewer').focus();
  await page.keyboard.press('Space');
  await page.getByText('Showing B').waitFor();
  assert.deepEqual(await visibility(), ['hidden', 'visible']);
  await page.getByRole('button', { name: 'Flip A/B (Space)' }).click();
  await page.getByText('Showing A').waitFor();

  // Swipe: the slider (keyboard too) sets how much of A covers B.
  await page.getByLabel('swipe', { exact: true }).check();
  const slider = page.getByLabel('Swipe: A on the left, B on the right');
  await slider.focus();
  await page.keyboard.press('Home');
  const clip = () => page.evaluate(() => document.querySelector('.pane-a').style.clipPath);
  assert.equal(await clip(), 'inset(0px 100% 0px 0px)');
  await page.keyboard.press('End');
  assert.equal(await clip(), 'inset(0px 0% 0px 0px)');

  // The heat map is the server's diff: dark where equal, coloured where they differ.
  await page.getByLabel('heat map').check();
  const heat = await page.evaluate(() => {
    const c = document.getElementById('canvas-heat');
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    const at = (x, y) => [...d.slice((y * c.width + x) * 4, (y * c.width + x) * 4 + 3)];
    return { size: [c.width, c.height], same: at(0, 0), differs: at(3, 2) };
  });
  assert.deepEqual(heat.size, [W, H]);
  assert.deepEqual(heat.same, [0, 0, 0]);
  assert.notDeepEqual(heat.differs, [0, 0, 0]);
  assert.ok(await page.locator('#canvas-heat').isVisible());
  assert.deepEqual(unexpectedErrors(page), []);
  await page.context().close();
});

test('a scene and an image: the scene is rendered here and compared with the image', async () => {
  const rendered = await server.api('/render?wait=1', { method: 'POST', body: SCENE, headers: { 'Content-Type': 'text/plain' } });
  assert.equal(rendered.status, 200);
  const png = Buffer.from(await rendered.arrayBuffer());

  const page = await openPage(browser, server, { hash: '#/compare' });
  await page.getByLabel('a scene\'s render and an image').check();
  await page.getByLabel('Scene (rendered here as image A)').fill(SCENE);
  await page.getByLabel('Image B: yours (PNG or PPM)').setInputFiles({ name: 'mine.png', mimeType: 'image/png', buffer: png });
  await page.getByRole('button', { name: 'Compare', exact: true }).click();
  await page.locator('#compare-verdict', { hasText: 'The images are identical' }).waitFor();
  const [same, size] = await page.evaluate(() => {
    const get = (id) => {
      const c = document.getElementById(id);
      return [...c.getContext('2d').getImageData(0, 0, c.width, c.height).data];
    };
    const a = get('canvas-a');
    const b = get('canvas-b');
    return [a.length === b.length && a.every((v, i) => v === b[i]), [document.getElementById('canvas-a').width, document.getElementById('canvas-a').height]];
  });
  assert.ok(same, 'the reference shown as A differs from the uploaded image');
  assert.deepEqual(size, [40, 30]);

  // Another size is the API's 422, shown as a message.
  const small = encodePng(W, H, A);
  await page.getByLabel('Image B: yours (PNG or PPM)').setInputFiles({ name: 'small.png', mimeType: 'image/png', buffer: small });
  await page.getByRole('button', { name: 'Compare', exact: true }).click();
  await page.locator('#compare-message', { hasText: /size|differ/i }).waitFor();
  assert.deepEqual(unexpectedErrors(page, [422]), []);
  await page.context().close();
});
