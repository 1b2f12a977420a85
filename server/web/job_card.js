// One job as it runs: state, a progress bar fed by the event stream, the partial image as it
// fills in, ETA, Cancel, and when done the image with its PNG and PPM downloads.
import { ApiError, describe, getBlob, getJson, request, saveBlob, streamEvents } from './api.js';
import { announce, el, formatMs, shortId, sleep } from './ui.js';

const FINAL = new Set(['done', 'failed', 'canceled']);
const PARTIAL_EVERY_MS = 250;  // at most four partial images a second

export class JobCard {
  // onStatus(status) is called on every change (for the tab title and the jobs list).
  constructor(container, id, onStatus = () => {}) {
    this.id = id;
    this.onStatus = onStatus;
    this.abort = new AbortController();
    this.final = false;
    this.finalShown = false;
    this.status = null;
    this.urls = [];
    this.partialAt = 0;
    this.partialProgress = -1;
    this.partialBusy = false;
    this.build(container);
  }

  build(container) {
    const titleId = `job-${this.id}-title`;
    this.title = el('h3', { id: titleId, tabIndex: -1 });
    this.chip = el('span', { class: 'chip' }, '…');
    this.title.append('Job ', el('code', {}, shortId(this.id)), ' ', this.chip);
    this.bar = el('div', { class: 'progress-bar' });
    this.progress = el(
      'div',
      {
        class: 'progress',
        role: 'progressbar',
        'aria-label': 'Render progress',
        'aria-valuemin': '0',
        'aria-valuemax': '100',
        'aria-valuenow': '0',
      },
      this.bar,
    );
    this.figures = el('p', { class: 'figures' });
    this.error = el('p', { class: 'job-error', role: 'alert', hidden: true });
    this.image = el('img', { alt: '' });
    this.caption = el('figcaption');
    this.figure = el('figure', { class: 'job-image', hidden: true }, this.image, this.caption);
    this.cancel = el('button', { type: 'button', class: 'danger' }, 'Cancel');
    this.cancel.addEventListener('click', () => this.cancelJob());
    this.png = el('a', { class: 'button secondary', hidden: true }, 'Download PNG');
    this.ppm = el('button', { type: 'button', class: 'secondary', hidden: true }, 'Download PPM');
    this.ppm.addEventListener('click', () => this.downloadPpm());
    this.root = el(
      'section',
      { class: 'job-card panel', 'aria-labelledby': titleId, 'data-job-id': this.id },
      this.title,
      this.progress,
      this.figures,
      this.error,
      this.figure,
      el('div', { class: 'buttons' }, this.cancel, this.png, this.ppm),
    );
    container.replaceChildren(this.root);
  }

  // The event stream's first event is the job's status as it is, finished or not: no
  // separate first request.
  start() {
    this.watch();
  }

  destroy() {
    this.abort.abort();
    for (const url of this.urls) URL.revokeObjectURL(url);
  }

  // A 404 (expired, or another server) or a 401 ends the watch with a message.
  fatal(err) {
    if (err instanceof ApiError && (err.status === 404 || err.status === 401 || err.status === 403)) {
      this.showError(err.status === 404 ? 'This job is unknown here: it has expired.' : describe(err));
      return true;
    }
    return false;
  }

  async watch() {
    const { signal } = this.abort;
    while (!this.final && !signal.aborted) {
      try {
        await streamEvents(`/jobs/${this.id}/events`, (_, data) => this.update(JSON.parse(data)), signal);
      } catch (err) {
        if (signal.aborted || this.fatal(err)) return;
      }
      // The stream ended or failed before the job did (too many streams, a restart, a dropped
      // connection): poll for a few seconds, then try the stream again.
      for (let i = 0; i < 10 && !this.final && !signal.aborted; i++) {
        await sleep(500, signal);
        try {
          this.update(await getJson(`/jobs/${this.id}`, { signal }));
        } catch (err) {
          if (signal.aborted || this.fatal(err)) return;
        }
      }
    }
  }

  update(status) {
    if (this.final || !status || status.id !== this.id) return;
    const previous = this.status;
    this.status = status;
    const state = status.state;
    const percent = state === 'done' ? 100 : Math.floor((status.progress || 0) * 100);
    this.root.dataset.state = state;
    this.chip.textContent = state;
    this.chip.className = `chip state-${state}`;
    this.progress.setAttribute('aria-valuenow', String(percent));
    this.progress.setAttribute('aria-valuetext', `${percent} %`);
    this.bar.style.width = `${percent}%`;
    this.figures.textContent = this.describe(status, percent);
    this.cancel.hidden = FINAL.has(state);
    if (!previous || previous.state !== state) announce(`Job ${shortId(this.id)}: ${state}`);
    if (state === 'running') this.refreshPartial(status.progress || 0);
    if (FINAL.has(state)) {
      this.final = true;
      this.finish(status);
    }
    this.onStatus(status);
  }

  describe(status, percent) {
    const parts = [`${percent} %`];
    const o = status.options || {};
    if (o.width && o.height) parts.push(`${o.width}×${o.height}`);
    if (status.state === 'queued') {
      parts.push(status.queue_position > 0 ? `place ${status.queue_position} in the queue` : 'queued');
    }
    if (status.elapsed_ms) parts.push(`elapsed ${formatMs(status.elapsed_ms)}`);
    if (status.state === 'running' && status.eta_ms !== null && status.eta_ms !== undefined)
      parts.push(`ETA ${formatMs(status.eta_ms)}`);
    if (o.spp > 1) parts.push(`${status.spp_done || 0} of ${o.spp} samples per pixel`);
    const rps = status.stats && status.stats.rays_per_second;
    if (rps) parts.push(`${(rps / 1e6).toPrecision(3)} M rays/s`);
    return parts.join(' · ');
  }

  async refreshPartial(progress, force = false) {
    const now = performance.now();
    if (!force && (this.partialBusy || progress <= this.partialProgress || now - this.partialAt < PARTIAL_EVERY_MS))
      return;
    this.partialBusy = true;
    this.partialAt = now;
    this.partialProgress = progress;
    try {
      const blob = await getBlob(`/jobs/${this.id}/image?partial=1&format=png`, { signal: this.abort.signal });
      const percent = Math.floor(progress * 100);
      const canceled = this.root.dataset.state === 'canceled';
      if (!(await this.show(blob, `Partial render of job ${shortId(this.id)}, ${percent} % done`))) return;
      this.caption.textContent = canceled ? `Canceled at ${percent} %` : `So far: ${percent} %`;
    } catch {
      // A missed preview is not an error: the next progress event asks again.
    } finally {
      this.partialBusy = false;
    }
  }

  // Shows an image once decoded; a partial one that arrives after the final one is dropped
  // (returns null).
  async show(blob, alt, final = false) {
    const url = URL.createObjectURL(blob);
    this.urls.push(url);
    const img = new Image();
    img.src = url;
    await img.decode();
    if (this.finalShown) return null;
    if (final) this.finalShown = true;
    // Swap only once decoded, so the preview never flashes empty. A small render is shown
    // enlarged by a whole factor (its pixels stay square and sharp).
    const scale = Math.max(1, Math.floor(480 / img.naturalWidth));
    this.image.style.width = `${img.naturalWidth * scale}px`;
    this.image.src = url;
    this.image.alt = alt;
    this.figure.hidden = false;
    while (this.urls.length > 3) URL.revokeObjectURL(this.urls.shift());
    return url;
  }

  async finish(status) {
    if (status.state === 'failed') {
      this.showError(`The render failed: ${status.error ? status.error.message : 'no reason given'}`);
      return;
    }
    if (status.state === 'canceled') {
      this.caption.textContent = `Canceled at ${Math.floor((status.progress || 0) * 100)} %`;
      return;
    }
    try {
      const blob = await getBlob(`/jobs/${this.id}/image`, { signal: this.abort.signal });
      const o = status.options || {};
      const url = await this.show(blob, `Rendered image of job ${shortId(this.id)}, ${o.width}×${o.height} pixels`, true);
      this.urls = this.urls.filter((u) => u !== url);  // kept: the download link uses it
      this.caption.textContent = `Done in ${formatMs(status.elapsed_ms)}`;
      this.png.href = url;
      this.png.download = `rayfarm-${shortId(this.id)}.png`;
      this.png.hidden = false;
      this.ppm.hidden = false;
    } catch (err) {
      if (!this.abort.signal.aborted) this.showError(`The image cannot be fetched: ${describe(err)}`);
    }
  }

  async cancelJob() {
    if (this.canceling) return;
    this.canceling = true;
    const hadFocus = document.activeElement === this.cancel;
    try {
      const res = await request(`/jobs/${this.id}`, { method: 'DELETE' });
      const status = await res.json();
      this.update(status);
      if (status.state === 'canceled') this.refreshPartial(status.progress || 0, true);
    } catch (err) {
      this.showError(`Cannot cancel: ${describe(err)}`);
    } finally {
      this.canceling = false;
    }
    // The button is gone now: keep the keyboard in the card, on its title.
    if (hadFocus && this.cancel.hidden) this.title.focus();
  }

  async downloadPpm() {
    try {
      saveBlob(await getBlob(`/jobs/${this.id}/image?format=ppm`), `rayfarm-${shortId(this.id)}.ppm`);
    } catch (err) {
      this.showError(`The PPM cannot be fetched: ${describe(err)}`);
    }
  }

  showError(text) {
    this.error.textContent = text;
    this.error.hidden = false;
  }
}
