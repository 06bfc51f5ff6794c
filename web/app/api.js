// HTTP access to rmapd (same origin), with the bearer token when one is set.
//
// The token lives in sessionStorage ('rmap.token'). A 401 asks the page for a token once
// (`onUnauthorized` returns a promise of the new token, shared by every request that hit the
// 401 meanwhile) and retries the request with it.

import { decodeTile } from './tile_codec.js';

const TOKEN_KEY = 'rmap.token';

export class ApiError extends Error {
  constructor(status, code, message) {
    super(message || `${status} ${code}`);
    this.status = status;
    this.code = code;
  }
}

export class Api {
  constructor(origin = window.location.origin) {
    this.origin = origin;
    this.onUnauthorized = null; // () => Promise<string token>
    this.onRequestState = null; // (ok: boolean, error) => void; connectivity of plain HTTP
    this.pendingAuth = null;
    this.requests = 0;
    this.bytes = 0;
  }

  get token() {
    try {
      return window.sessionStorage.getItem(TOKEN_KEY) || '';
    } catch {
      return '';
    }
  }

  set token(value) {
    try {
      if (value) window.sessionStorage.setItem(TOKEN_KEY, value);
      else window.sessionStorage.removeItem(TOKEN_KEY);
    } catch {
      // sessionStorage unavailable (privacy mode): the token lasts until reload only.
    }
    this.memoryToken = value;
  }

  currentToken() {
    return this.token || this.memoryToken || '';
  }

  headers(extra) {
    const h = { ...extra };
    const t = this.currentToken();
    if (t) h.Authorization = `Bearer ${t}`;
    return h;
  }

  /** fetch with auth and one retry after a token prompt on 401. Resolves to the Response (2xx or 304). */
  async request(path, { accept, etag, signal, method = 'GET', body, contentType } = {}) {
    for (let attempt = 0; ; attempt++) {
      const extra = {};
      if (accept) extra.Accept = accept;
      if (etag) extra['If-None-Match'] = etag;
      if (contentType) extra['Content-Type'] = contentType;
      let response;
      try {
        this.requests++;
        response = await fetch(this.origin + path, { method, headers: this.headers(extra), signal, body, cache: 'no-store' });
      } catch (e) {
        if (e.name === 'AbortError') throw e;
        if (this.onRequestState) this.onRequestState(false, e);
        throw new ApiError(0, 'network', `network error: ${e.message}`);
      }
      if (this.onRequestState) this.onRequestState(true);
      if (response.status === 401 && attempt < 3 && this.onUnauthorized) {
        await this.askToken(await errorOf(response));
        continue;
      }
      if (!response.ok && response.status !== 304) {
        const err = await errorOf(response);
        throw new ApiError(response.status, err.code, err.message);
      }
      return response;
    }
  }

  askToken(reason) {
    if (!this.pendingAuth) {
      this.pendingAuth = Promise.resolve(this.onUnauthorized(reason)).then((token) => {
        this.token = token;
        this.pendingAuth = null;
        return token;
      });
    }
    return this.pendingAuth;
  }

  async json(path, options) {
    const response = await this.request(path, options);
    const text = await response.text();
    this.bytes += text.length;
    return JSON.parse(text);
  }

  /** A tile, decoded from protobuf. Resolves to null on 304 (unchanged since `etag`). */
  async tile(map, level, x, y, z, { etag, signal } = {}) {
    const response = await this.request(
      `/v1/maps/${encodeURIComponent(map)}/tiles/${level}/${x}/${y}/${z}`,
      { accept: 'application/x-protobuf', etag, signal },
    );
    if (response.status === 304) return null;
    const buffer = await response.arrayBuffer();
    this.bytes += buffer.byteLength;
    const tile = decodeTile(buffer);
    tile.etag = response.headers.get('ETag');
    return tile;
  }

  /** Status of a GET without reading a body we do not need (404 is an answer, not an error). */
  async probe(path) {
    try {
      const response = await this.request(path);
      if (response.body) response.body.cancel().catch(() => {});
      return response.status;
    } catch (e) {
      if (e instanceof ApiError) return e.status;
      throw e;
    }
  }

  wsUrl(path) {
    const u = new URL(path, this.origin);
    u.protocol = u.protocol === 'https:' ? 'wss:' : 'ws:';
    return u.href;
  }

  /** Subprotocols for the viewer WebSocket: rmap.v1 plus the token (browsers cannot set headers). */
  wsProtocols() {
    const t = this.currentToken();
    return t ? ['rmap.v1', `bearer.${t}`] : ['rmap.v1'];
  }
}

async function errorOf(response) {
  try {
    const body = await response.json();
    if (body && body.error) return { code: body.error.code, message: body.error.message };
  } catch {
    // not JSON
  }
  return { code: `http_${response.status}`, message: `HTTP ${response.status}` };
}
