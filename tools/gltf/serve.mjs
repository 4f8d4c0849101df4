// A static file server on 127.0.0.1 (a free port) for the browser checks: `resolve(pathname)`
// names the local file of a request (404 when it cannot be read; /favicon.ico answers 204).
import { createServer } from "node:http";
import { readFile } from "node:fs/promises";
import path from "node:path";

const types = {
  ".html": "text/html",
  ".js": "text/javascript",
  ".mjs": "text/javascript",
  ".wasm": "application/wasm",
  ".glb": "model/gltf-binary",
};

export async function serve(resolve) {
  const server = createServer(async (req, res) => {
    const url = new URL(req.url, "http://x");
    if (url.pathname === "/favicon.ico") {
      res.writeHead(204);
      res.end();
      return;
    }
    const local = resolve(url.pathname);
    try {
      const body = await readFile(local);
      res.writeHead(200, { "content-type": types[path.extname(local)] ?? "application/octet-stream" });
      res.end(body);
    } catch {
      res.writeHead(404);
      res.end();
    }
  });
  await new Promise((r) => server.listen(0, "127.0.0.1", r));
  return server;
}
