// Opens a folder `lustre publish` wrote in headless Chromium (Debian's, through puppeteer-core)
// with WebGPU on SwiftShader, served from a local static server, and waits for the page's test
// hook. Usage:
//   node web_page.mjs SITE QUERY OUT.png           the first frame of ?QUERY, written to OUT.png
//   node web_page.mjs SITE QUERY --expect TEXT     the page must fail, showing TEXT
// Add --no-webgpu (last) to launch the browser without its WebGPU flags (Chromium 156 then has
// `navigator.gpu` but no adapter on a machine without a GPU). Prints one JSON line: { ready |
// error, message, console } and exits 1 when the page fails (or, with --expect, does not fail
// with TEXT on screen) or its console shows an error or a warning.
import { writeFile } from "node:fs/promises";
import path from "node:path";
import puppeteer from "puppeteer-core";
import { serve } from "./serve.mjs";

const args = process.argv.slice(2);
const noWebgpu = args[args.length - 1] === "--no-webgpu";
if (noWebgpu) args.pop();
const [site, query] = args;
const expect = args[2] === "--expect" ? args[3] : null;
const out = expect === null ? args[2] : null;
const server = await serve((p) => path.join(path.resolve(site), path.normalize(p)));
const port = server.address().port;
const flags = ["--no-sandbox", "--disable-background-networking", "--disable-component-update", "--no-first-run"];
if (!noWebgpu) flags.push("--enable-unsafe-webgpu", "--use-webgpu-adapter=swiftshader");
const browser = await puppeteer.launch({
  executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium",
  headless: true,
  args: flags,
  protocolTimeout: 1_200_000,
});
const consoleLines = [];
const t0 = Date.now();
const result = { site, query };
let failed = false;
try {
  const page = await browser.newPage();
  page.on("console", (m) => {
    if (m.type() === "error" || m.type() === "warn" || m.type() === "warning") consoleLines.push(`${m.type()}: ${m.text()}`);
    else if (process.env.LUSTRE_WEB_LOG) console.error(`${((Date.now() - t0) / 1000).toFixed(1)} s ${m.type()}: ${m.text()}`);
  });
  page.on("pageerror", (e) => consoleLines.push(`pageerror: ${e.message}`));
  await page.goto(`http://127.0.0.1:${port}/index.html?${query}`);
  try {
    result.ready = await page.evaluate(() => window.lustre.ready);
  } catch (e) {
    result.error = String(e.message ?? e);
  }
  result.message = await page.evaluate(() => {
    const m = document.getElementById("message");
    return m.classList.contains("shown") ? m.textContent : null;
  });
  if (expect !== null) {
    // The page must fail visibly with the expected text; its own error line, the browser's
    // 404 line and the browser's warnings (e.g. "No available adapters.") are expected.
    failed = !(result.error && result.message && result.message.includes(expect));
    const own = `error: lustre: ${result.message}`;
    const other = (l) => l !== own && !l.includes("Failed to load resource") && !l.startsWith("warn");
    if (consoleLines.some(other)) failed = true;
  } else {
    if (!result.ready) failed = true;
    if (out && result.ready) {
      const url = await page.evaluate(() => window.lustre.capture());
      await writeFile(out, Buffer.from(url.split(",")[1], "base64"));
    }
    if (consoleLines.length > 0) failed = true;
  }
} catch (e) {
  consoleLines.push(`failed: ${e}`);
  failed = true;
}
result.console = consoleLines;
console.log(JSON.stringify(result));
await browser.close();
server.close();
process.exit(failed ? 1 : 0);
