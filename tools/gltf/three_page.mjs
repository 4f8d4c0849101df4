// Opens a glb that `lustre export scene` wrote in three.js (three_page.html: GLTFLoader, a
// MOZ_lightmap plugin decoding the RGBE light maps), in headless Chromium (Debian's, through
// puppeteer-core; WebGL on SwiftShader), twice: with the light maps and without. Usage:
// `node three_page.mjs FILE.glb [OUT.png]` (OUT.png: the frame with light maps). Prints one JSON
// line: { file, with: {...}, without: {...}, console } and exits 1 when the page fails or logs an
// error.
import { writeFile } from "node:fs/promises";
import path from "node:path";
import puppeteer from "puppeteer-core";
import { serve } from "./serve.mjs";

const [file, out] = process.argv.slice(2);
const here = path.dirname(new URL(import.meta.url).pathname);
const server = await serve((p) => (p === "/scene.glb" ? path.resolve(file) : path.join(here, path.normalize(p))));
const port = server.address().port;
const browser = await puppeteer.launch({
  executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium",
  headless: true,
  args: ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"],
});
const consoleLines = [];
let failed = false;
const result = { file };
try {
  for (const lightmap of [1, 0]) {
    const page = await browser.newPage();
    page.on("console", (m) => {
      if (m.type() === "error" || m.type() === "warn") consoleLines.push(`${m.type()}: ${m.text()}`);
    });
    page.on("pageerror", (e) => consoleLines.push(`pageerror: ${e.message}`));
    await page.goto(`http://127.0.0.1:${port}/three_page.html?file=/scene.glb&width=320&height=180&lightmap=${lightmap}`);
    const r = await page.evaluate(() => window.lustre.ready);
    result[lightmap ? "with" : "without"] = r;
    if (lightmap && out) {
      const url = await page.evaluate(() => window.lustre.capture());
      await writeFile(out, Buffer.from(url.split(",")[1], "base64"));
    }
    await page.close();
  }
} catch (e) {
  consoleLines.push(`failed: ${e}`);
  failed = true;
}
result.console = consoleLines;
if (consoleLines.some((l) => !l.startsWith("warn"))) failed = true;
console.log(JSON.stringify(result));
await browser.close();
server.close();
process.exit(failed ? 1 : 0);
