// Talking to rayfarmd: the token (kept in this tab's sessionStorage), JSON errors as
// exceptions, and server-sent events read from a streaming fetch, because EventSource cannot
// send the Authorization header.

const TOKEN_KEY = 'rayfarm.token';
const listeners = new Set();

export function token() {
  return sessionStorage.getItem(TOKEN_KEY) || '';
}

export function setToken(value) {
  if (value) sessionStorage.setItem(TOKEN_KEY, value);
  else sessionStorage.removeItem(TOKEN_KEY);
}

// Called with the failed request's ApiError whenever the server asks for a (better) token.
export function onUnauthorized(fn) {
  listeners.add(fn);
}

export class ApiError extends Error {
  constructor(status, body, response) {
    const e = (body && body.error) || {};
    super(e.message || `the server answered ${status}`);
    this.status = status;
    this.code = e.code || 'http_error';
    this.detail = e;  // line, column, path, limit, errors: as the API sends them
    this.body = body;
    this.retryAfter = response ? Number(response.headers.get('Retry-After')) || 0 : 0;
  }
}

// fetch() with the token; a non-2xx answer throws ApiError, a failed connection a plain Error.
export async function request(path, options = {}) {
  const headers = new Headers(options.headers || {});
  const t = token();
  if (t) headers.set('Authorization', `Bearer ${t}`);
  let response;
  try {
    response = await fetch(path, { ...options, headers, cache: 'no-store' });
  } catch (err) {
    if (err.name === 'AbortError') throw err;
    throw new Error('the server cannot be reached');
  }
  if (response.ok) return response;
  let body = null;
  try {
    body = await response.json();
  } catch {
    body = null;
  }
  const error = new ApiError(response.status, body, response);
  if (response.status === 401) for (const fn of listeners) fn(error);
  throw error;
}

export async function getJson(path, options) {
  return (await request(path, options)).json();
}

export async function getBlob(path, options) {
  return (await request(path, options)).blob();
}

// Reads text/event-stream from `path`, calling onEvent(name, data) per event, until the
// server ends the stream or `signal` aborts. Throws as request() does.
export async function streamEvents(path, onEvent, signal) {
  const response = await request(path, { signal, headers: { Accept: 'text/event-stream' } });
  const reader = response.body.pipeThrough(new TextDecoderStream()).getReader();
  let buffer = '';
  for (;;) {
    const { value, done } = await reader.read();
    if (done) return;
    buffer += value.replace(/\r/g, '');
    let end;
    while ((end = buffer.indexOf('\n\n')) >= 0) {
      const block = buffer.slice(0, end);
      buffer = buffer.slice(end + 2);
      let name = 'message';
      const data = [];
      for (const line of block.split('\n')) {
        if (line === '' || line.startsWith(':')) continue;  // comments keep the stream open
        const colon = line.indexOf(':');
        const field = colon < 0 ? line : line.slice(0, colon);
        const text = colon < 0 ? '' : line.slice(colon + 1).replace(/^ /, '');
        if (field === 'event') name = text;
        else if (field === 'data') data.push(text);
      }
      if (data.length) onEvent(name, data.join('\n'));
    }
  }
}

// Saves a blob as a file through a temporary link (downloads cannot carry a header).
export function saveBlob(blob, filename) {
  const url = URL.createObjectURL(blob);
  const a = document.createElement('a');
  a.href = url;
  a.download = filename;
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 60000);
}

// A message for a person: what went wrong and, where the API says, where.
export function describe(err) {
  if (!(err instanceof ApiError)) return err.message || String(err);
  let text = err.message;
  if (err.status === 401)
    text = token()
      ? 'The access token was refused: check it under "Access token" above.'
      : 'This farm needs an access token: enter it under "Access token" above.';
  if (err.status === 429 && err.retryAfter) text += ` Try again in ${err.retryAfter} s.`;
  if (err.detail.limit) text += ` (limit: ${err.detail.limit})`;
  return text;
}
