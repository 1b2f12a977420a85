// What every browser test needs: a real rayfarmd on a free loopback port with its own results
// folder, Debian's Chromium driven by playwright-core, the API called from node to check what
// the page shows, and an accessibility check of our own.
import { spawn } from 'node:child_process';
import { mkdtemp, readFile, rm } from 'node:fs/promises';
import { tmpdir } from 'node:os';
import { after, before } from 'node:test';
import path from 'node:path';
import { deflateSync } from 'node:zlib';
import { chromium } from 'playwright-core';

export const SOURCE_DIR = path.resolve(import.meta.dirname, '../..');
const CHROMIUM = process.env.CHROMIUM || '/usr/bin/chromium';

// The lecture's small scene: one mirror sphere on a floor under one light (40×30).
export const SCENE = `# a small test scene
camera cam1
{
   pixeldim  40 30
   worlddim  8 6
   viewpoint 4 3 5
}
material chrome
{  ambient  3 3 3
   diffuse  .1 .1 .1
   specular .9 .9 .9
}
material floor
{  ambient  2 2 2
   diffuse  .5 .5 .5
}
light top
{  location   2.56 3.80 -1.5
   emissivity 4 4 4
}
sphere left
{  material chrome
   center   1.25 .75 -4
   radius   .9
}
plane ground
{  material floor
   normal   0 1 0
   point    0 -0.2 0
}
`;

// Starts rayfarmd (RAYFARMD) on 127.0.0.1:<any free port>; resolves once /healthz answers.
export async function startServer(extraArgs = []) {
  const binary = process.env.RAYFARMD;
  if (!binary) throw new Error('set RAYFARMD to the rayfarmd binary');
  const dir = await mkdtemp(path.join(tmpdir(), 'rayfarm-web-'));
  const child = spawn(
    binary,
    ['--host', '127.0.0.1', '--port', '0', '--results-dir', dir, '--workers', '2',
      '--shutdown-grace', '0', '--no-access-log', ...extraArgs],
    { stdio: ['ignore', 'ignore', 'pipe'] },
  );
  let log = '';
  const port = await new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new Error(`rayfarmd did not start:\n${log}`)), 15000);
    child.stderr.on('data', (chunk) => {
      log += chunk;
      const m = /listening on http:\/\/127\.0\.0\.1:(\d+)/.exec(log);
      if (m) {
        clearTimeout(timer);
        resolve(Number(m[1]));
      }
    });
    child.on('exit', (code) => reject(new Error(`rayfarmd exited (${code}):\n${log}`)));
  });
  const url = `http://127.0.0.1:${port}`;
  for (let i = 0; ; i++) {
    try {
      if ((await fetch(`${url}/healthz`)).ok) break;
    } catch {
      if (i > 100) throw new Error(`rayfarmd does not answer:\n${log}`);
    }
    await new Promise((r) => setTimeout(r, 50));
  }
  return {
    url,
    log: () => log,
    // Calls the API from node, as the page's user (same address, optionally the token).
    async api(p, init = {}, token = '') {
      const headers = new Headers(init.headers || {});
      if (token) headers.set('Authorization', `Bearer ${token}`);
      return fetch(url + p, { ...init, headers });
    },
    async bytes(p, token = '') {
      const res = await this.api(p, {}, token);
      if (!res.ok) throw new Error(`${p}: ${res.status} ${await res.text()}`);
      return Buffer.from(await res.arrayBuffer());
    },
    async stop() {
      if (child.exitCode === null) {
        const exited = new Promise((r) => child.once('exit', r));
        child.kill('SIGTERM');
        const timer = setTimeout(() => child.kill('SIGKILL'), 10000);
        await exited;
        clearTimeout(timer);
      }
      await rm(dir, { recursive: true, force: true });
    },
  };
}

export function launchBrowser() {
  return chromium.launch({
    executablePath: CHROMIUM,
    // The machine's network is closed: no background connections, no QUIC, no updates.
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync'],
  });
}

// A page on the server with every console error, page error and request URL recorded.
export async function openPage(browser, server, { width = 1100, height = 900, colorScheme = 'light', hash = '' } = {}) {
  const context = await browser.newContext({ viewport: { width, height }, colorScheme, acceptDownloads: true });
  const page = await context.newPage();
  page.errors = [];
  page.requests = [];
  page.on('pageerror', (e) => page.errors.push(`page error: ${e.message}`));
  page.on('console', (m) => {
    if (m.type() === 'error') page.errors.push(`console: ${m.text()}`);
  });
  page.on('request', (r) => page.requests.push(r.url()));
  page.setDefaultTimeout(20000);
  await page.goto(`${server.url}/${hash}`);
  await page.waitForFunction(() => document.getElementById('server-status').textContent.startsWith('Online'));
  return page;
}

// Console errors other than the browser's own note of an HTTP status the test provoked.
export function unexpectedErrors(page, allowedStatuses = []) {
  return page.errors.filter((e) => {
    const m = /Failed to load resource: the server responded with a status of (\d+)/.exec(e);
    return !(m && allowedStatuses.includes(Number(m[1])));
  });
}

// Every request the page made stayed on the server's origin (or read its own blobs).
export function foreignRequests(page, server) {
  return page.requests.filter((u) => !u.startsWith(`${server.url}/`) && !u.startsWith('blob:') && !u.startsWith('data:'));
}

export async function download(page, click) {
  const [file] = await Promise.all([page.waitForEvent('download'), click()]);
  return { name: file.suggestedFilename(), bytes: await readFile(await file.path()) };
}

// An RGB image as PNG bytes (filter 0 on each row), to upload.
export function encodePng(width, height, rgb) {
  const crcTable = Array.from({ length: 256 }, (_, n) => {
    let c = n;
    for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    return c >>> 0;
  });
  const crc = (buf) => {
    let c = 0xffffffff;
    for (const b of buf) c = crcTable[(c ^ b) & 0xff] ^ (c >>> 8);
    return (c ^ 0xffffffff) >>> 0;
  };
  const chunk = (type, data) => {
    const body = Buffer.concat([Buffer.from(type, 'ascii'), data]);
    const out = Buffer.alloc(body.length + 8);
    out.writeUInt32BE(data.length, 0);
    body.copy(out, 4);
    out.writeUInt32BE(crc(body), body.length + 4);
    return out;
  };
  const header = Buffer.alloc(13);
  header.writeUInt32BE(width, 0);
  header.writeUInt32BE(height, 4);
  header[8] = 8;  // bit depth
  header[9] = 2;  // colour type RGB
  const raw = Buffer.alloc((width * 3 + 1) * height);
  for (let y = 0; y < height; y++) Buffer.from(rgb.subarray(y * width * 3, (y + 1) * width * 3)).copy(raw, y * (width * 3 + 1) + 1);
  return Buffer.concat([
    Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]),
    chunk('IHDR', header),
    chunk('IDAT', deflateSync(raw)),
    chunk('IEND', Buffer.alloc(0)),
  ]);
}

export function encodePpm(width, height, rgb) {
  return Buffer.concat([Buffer.from(`P6\n${width} ${height}\n255\n`, 'ascii'), Buffer.from(rgb)]);
}

// Problems a person using a keyboard, a screen reader or a small screen would meet: controls
// without an accessible name, a progress bar without a value, images without alt text, text
// under 4.5:1 contrast, and a page wider than the window.
export function accessibilityProblems(page) {
  return page.evaluate(() => {
    const problems = [];
    const shown = (el) => el.getClientRects().length > 0 && getComputedStyle(el).visibility !== 'hidden';
    const text = (ids) =>
      (ids || '').split(/\s+/).map((id) => document.getElementById(id)?.textContent || '').join(' ').trim();
    for (const el of document.querySelectorAll('input, select, textarea, button, a[href], [role="progressbar"], [tabindex="0"]')) {
      if (!shown(el)) continue;
      const name =
        (el.getAttribute('aria-label') || '').trim() ||
        text(el.getAttribute('aria-labelledby')) ||
        [...(el.labels || [])].map((l) => l.textContent).join(' ').trim() ||
        (['BUTTON', 'A'].includes(el.tagName) ? el.textContent.trim() : '');
      if (!name) problems.push(`no accessible name: ${el.outerHTML.slice(0, 100)}`);
    }
    for (const el of document.querySelectorAll('[role="progressbar"]'))
      if (shown(el) && !el.hasAttribute('aria-valuenow')) problems.push('a progress bar without aria-valuenow');
    for (const img of document.querySelectorAll('img'))
      if (shown(img) && !img.alt) problems.push(`an image without alt text: ${img.src.slice(0, 60)}`);

    const rgba = (c) => (c.match(/[\d.]+/g) || ['0', '0', '0', '0']).map(Number);
    const luminance = ([r, g, b]) => {
      const f = (v) => ((v /= 255) <= 0.03928 ? v / 12.92 : ((v + 0.055) / 1.055) ** 2.4);
      return 0.2126 * f(r) + 0.7152 * f(g) + 0.0722 * f(b);
    };
    const background = (el) => {
      for (let e = el; e; e = e.parentElement) {
        const c = rgba(getComputedStyle(e).backgroundColor);
        if (c.length < 4 || c[3] > 0) return c.slice(0, 3);
      }
      return [255, 255, 255];
    };
    for (const el of document.querySelectorAll('body *')) {
      if (!shown(el) || el.closest('.visually-hidden, [disabled], option, canvas')) continue;
      const own = [...el.childNodes].filter((n) => n.nodeType === 3).map((n) => n.textContent).join('').trim();
      if (!own) continue;
      const fg = luminance(rgba(getComputedStyle(el).color));
      const bg = luminance(background(el));
      const ratio = (Math.max(fg, bg) + 0.05) / (Math.min(fg, bg) + 0.05);
      if (ratio < 4.5) problems.push(`contrast ${ratio.toFixed(2)}:1 for "${own.slice(0, 40)}"`);
    }
    const root = document.documentElement;
    if (root.scrollWidth > root.clientWidth) problems.push(`the page scrolls sideways: ${root.scrollWidth} px in ${root.clientWidth} px`);
    return problems;
  });
}

// One rayfarmd and one Chromium for a test file: started before its tests, stopped after
// them; `use(server, browser)` hands them to the file.
export function withServerAndBrowser(use, serverArgs = []) {
  let server;
  let browser;
  before(async () => {
    server = await startServer(serverArgs);
    browser = await launchBrowser();
    use(server, browser);
  });
  after(async () => {
    await browser?.close();
    await server?.stop();
  });
}
