// Development fallback for rmapd builds without --web-root: one loopback HTTP server that
// serves web/ with rmapd's URL layout (GET / → index.html, /app/<path>, /node_modules/three/
// {build,examples/jsm}/<path>) and the same Content-Security-Policy, and forwards everything
// else (HTTP and WebSocket upgrades) to rmapd, so the page, the API and the viewer stream share
// one origin. The Origin header of upgrades is rewritten to rmapd's own so its Origin check
// passes. Used by the tests only, never by the viewer itself.

import crypto from 'node:crypto';
import fs from 'node:fs';
import http from 'node:http';
import net from 'node:net';
import path from 'node:path';

const TYPES = {
  '.html': 'text/html; charset=utf-8', '.js': 'text/javascript; charset=utf-8', '.mjs': 'text/javascript; charset=utf-8',
  '.css': 'text/css; charset=utf-8', '.json': 'application/json', '.png': 'image/png', '.svg': 'image/svg+xml',
};

/** CSP of index.html: the one rmapd sends, with the hash of the inline import map. */
export function viewerCsp(indexHtml) {
  const hashes = [];
  const re = /<script type="importmap">([\s\S]*?)<\/script>/g;
  for (let m = re.exec(indexHtml); m; m = re.exec(indexHtml)) {
    hashes.push(`'sha256-${crypto.createHash('sha256').update(m[1]).digest('base64')}'`);
  }
  return `default-src 'self'; script-src 'self' ${hashes.join(' ')}; connect-src 'self' ws: wss:; `
    + "img-src 'self' data: blob:; style-src 'self'; object-src 'none'; base-uri 'none'";
}

function staticPath(webRoot, urlPath) {
  if (urlPath === '/' || urlPath === '/index.html') return path.join(webRoot, 'index.html');
  let rel = null;
  if (urlPath.startsWith('/app/')) rel = urlPath.slice(1);
  if (urlPath.startsWith('/node_modules/three/build/') || urlPath.startsWith('/node_modules/three/examples/jsm/')) {
    rel = urlPath.slice(1);
  }
  if (!rel) return null;
  const full = path.resolve(webRoot, decodeURIComponent(rel));
  if (!full.startsWith(path.resolve(webRoot) + path.sep)) return null;
  return full;
}

export function startStaticProxy({ webRoot, apiPort }) {
  const trace = process.env.RMAP_PROXY_TRACE === '1';
  const server = http.createServer((req, res) => {
    const urlPath = new URL(req.url, 'http://x').pathname;
    if (trace) {
      const t0 = Date.now();
      console.log(`${new Date().toISOString().slice(11, 23)} > ${req.method} ${req.url}`);
      res.on('finish', () => console.log(`${new Date().toISOString().slice(11, 23)} < ${res.statusCode} ${req.url} ${Date.now() - t0} ms`));
    }
    const file = req.method === 'GET' ? staticPath(webRoot, urlPath) : null;
    if (file) {
      fs.readFile(file, (err, body) => {
        if (err) {
          res.writeHead(404, { 'Content-Type': 'application/json' });
          res.end('{"error":{"code":"not_found","message":"no such file"}}');
          return;
        }
        const headers = { 'Content-Type': TYPES[path.extname(file)] || 'application/octet-stream', 'Cache-Control': 'no-cache' };
        if (file.endsWith('index.html')) headers['Content-Security-Policy'] = viewerCsp(body.toString('utf8'));
        res.writeHead(200, headers);
        res.end(body);
      });
      return;
    }
    const upstream = http.request({ host: '127.0.0.1', port: apiPort, method: req.method, path: req.url,
      headers: { ...req.headers, host: `127.0.0.1:${apiPort}` } }, (up) => {
      res.writeHead(up.statusCode, up.headers);
      up.pipe(res);
    });
    upstream.on('error', () => { res.writeHead(502); res.end(); });
    req.pipe(upstream);
  });
  const sockets = new Set();
  server.on('connection', (s) => { sockets.add(s); s.on('close', () => sockets.delete(s)); });
  server.on('upgrade', (req, socket, head) => {
    const up = net.connect(apiPort, '127.0.0.1', () => {
      const lines = [`${req.method} ${req.url} HTTP/1.1`];
      for (let i = 0; i < req.rawHeaders.length; i += 2) {
        const name = req.rawHeaders[i];
        let value = req.rawHeaders[i + 1];
        if (/^host$/i.test(name)) value = `127.0.0.1:${apiPort}`;
        if (/^origin$/i.test(name)) value = `http://127.0.0.1:${apiPort}`;
        lines.push(`${name}: ${value}`);
      }
      up.write(lines.join('\r\n') + '\r\n\r\n');
      if (head && head.length) up.write(head);
      up.pipe(socket);
      socket.pipe(up);
    });
    sockets.add(up);
    up.on('close', () => { sockets.delete(up); socket.destroy(); });
    up.on('error', () => socket.destroy());
    socket.on('error', () => up.destroy());
    socket.on('close', () => up.destroy());
  });
  return new Promise((resolve) => {
    server.listen(0, '127.0.0.1', () => {
      const port = server.address().port;
      resolve({
        url: `http://127.0.0.1:${port}`,
        port,
        close: () => new Promise((r) => {
          for (const s of sockets) s.destroy();
          server.close(() => r());
        }),
      });
    });
  });
}

// Stand-alone use: node static_proxy.mjs WEB_ROOT API_PORT → prints the URL.
if (process.argv[1] && path.resolve(process.argv[1]) === path.resolve(new URL(import.meta.url).pathname)) {
  const [webRoot, apiPort] = process.argv.slice(2);
  startStaticProxy({ webRoot, apiPort: Number(apiPort) }).then((p) => console.log(`static proxy on ${p.url}/`));
}
