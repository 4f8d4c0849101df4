// The page's JavaScript: fetch, input and drawing only. Every pass is lustre-gpu's WGSL,
// compiled into lustre_web_bg.wasm, on the browser's WebGPU (lustre-web's `Page`).
//
// URL parameters: camera=NAME (a scene camera), size=WxH (the frame, default 640x360),
// samples=N (glossy samples per pixel; given, the frame is the regular one `lustre render
// --samples N` draws and is not refined), rays=N (camera rays per pixel, default 4),
// refine=N (progressive frames added while the camera rests, default 16; 0 when samples is
// given), probe=N (probe face size, default 128, as `lustre render --probe-size`).
//
// Test hook: window.lustre.ready resolves when the first frame is on the canvas (with the
// adapter and the times); window.lustre.capture() resolves to that or the latest frame as a PNG
// data URL, read back from the render target.
import init, { Page } from "./lustre_web.js";

const q = new URLSearchParams(location.search);
const canvas = document.getElementById("view");
const stats = document.getElementById("stats");
const views = document.getElementById("views");
const message = document.getElementById("message");

let readyResolve, readyReject;
const ready = new Promise((res, rej) => { readyResolve = res; readyReject = rej; });
let page = null;
window.lustre = {
  ready,
  capture: async () => {
    if (!page) throw new Error("no frame: the scene has not loaded");
    const png = await page.png(1.0);
    return await new Promise((res) => {
      const r = new FileReader();
      r.onload = () => res(r.result);
      r.readAsDataURL(new Blob([png], { type: "image/png" }));
    });
  },
};

function fail(text) {
  message.textContent = text;
  message.className = "shown error";
  stats.textContent = "error";
  console.error(`lustre: ${text}`);
  readyReject(new Error(text));
}
window.addEventListener("error", (e) => fail(`${e.message}`));
window.addEventListener("unhandledrejection", (e) => fail(`${e.reason?.message ?? e.reason}`));

function int(name, fallback, lo, hi) {
  const v = q.get(name);
  if (v === null) return fallback;
  const n = Number(v);
  if (!Number.isInteger(n) || n < lo || n > hi) throw new Error(`?${name}=${v}: must be an integer in ${lo}..${hi}`);
  return n;
}

async function main() {
  const sizeArg = q.get("size") ?? "640x360";
  const m = /^(\d+)x(\d+)$/.exec(sizeArg);
  if (!m) throw new Error(`?size=${sizeArg}: give WxH, e.g. 640x360`);
  const [w, h] = [Number(m[1]), Number(m[2])];
  const fixed = q.has("samples");
  const samples = int("samples", 16, 1, 4096);
  const rays = int("rays", 4, 1, 64);
  let refine = int("refine", fixed ? 0 : 16, 0, 256);
  const probe = int("probe", 128, 8, 1024);

  if (!("gpu" in navigator)) {
    throw new Error("This browser has no WebGPU (navigator.gpu is missing). Open the page in a current Chrome or Edge (113 or later), or another browser with WebGPU enabled, served over http://localhost or https.");
  }

  message.textContent = "Loading the renderer…";
  await init();
  message.textContent = "Loading the scene…";
  const res = await fetch("scene.glb");
  if (!res.ok) throw new Error(`scene.glb: ${res.status} ${res.statusText} (the published folder is incomplete: publish it again with lustre publish)`);
  const bytes = new Uint8Array(await res.arrayBuffer());
  console.log(`lustre: scene.glb, ${bytes.length} bytes`);
  message.textContent = "Compiling the passes and capturing the probes…";
  const t0 = performance.now();
  page = await Page.open(bytes, "scene.glb", probe, w, h);
  const loadMs = performance.now() - t0;
  console.log(`lustre: ${page.adapter()}; loaded in ${loadMs.toFixed(0)} ms; probes (ms):\n${page.probes()}`);
  page.configure(w, h, samples, rays);
  const camera = q.get("camera");
  page.use_camera(camera ?? undefined);

  // The camera menu: scene cameras, then camera paths (played).
  for (const name of page.cameras()) views.add(new Option(`camera: ${name}`, `c:${name}`));
  page.paths().forEach((name, i) => views.add(new Option(`path: ${name}`, `p:${i}`)));
  if (camera) views.value = `c:${camera}`;
  let playing = null; // { index, start }
  views.addEventListener("change", () => {
    const v = views.value;
    if (v.startsWith("c:")) { playing = null; page.use_camera(v.slice(2)); }
    else playing = { index: Number(v.slice(2)), start: performance.now() };
    views.blur();
  });

  canvas.width = w;
  canvas.height = h;
  const g = canvas.getContext("2d");
  message.className = "";

  // Input: WASD / arrows walk, Q/E down/up, Shift faster; drag to look; on touch, one finger
  // looks and two walk.
  const keys = new Set();
  addEventListener("keydown", (e) => keys.add(e.code));
  addEventListener("keyup", (e) => keys.delete(e.code));
  let look = [0, 0];
  let pointer = null;
  const touches = new Map();
  canvas.addEventListener("pointerdown", (e) => { canvas.setPointerCapture(e.pointerId); touches.set(e.pointerId, [e.clientX, e.clientY]); pointer = e.pointerId; });
  canvas.addEventListener("pointerup", (e) => { touches.delete(e.pointerId); });
  canvas.addEventListener("pointercancel", (e) => { touches.delete(e.pointerId); });
  let touchWalk = 0;
  canvas.addEventListener("pointermove", (e) => {
    const last = touches.get(e.pointerId);
    if (!last) return;
    const [dx, dy] = [e.clientX - last[0], e.clientY - last[1]];
    touches.set(e.pointerId, [e.clientX, e.clientY]);
    if (touches.size >= 2) touchWalk += -dy * 0.01;
    else { look[0] += dx * 0.004; look[1] += -dy * 0.004; }
  });

  let busy = false;
  let lastMove = performance.now();
  let last = performance.now();
  let firstDone = false;
  let frameMs = 0;
  const ms = (x) => x.toFixed(1);

  async function tick(now) {
    requestAnimationFrame(tick);
    const dt = Math.min((now - last) / 1000, 0.1);
    last = now;
    const speed = (keys.has("ShiftLeft") || keys.has("ShiftRight") ? 6 : 1.5) * dt;
    const axis = (a, b) => (keys.has(a) ? 1 : 0) - (keys.has(b) ? 1 : 0);
    const fwd = (axis("KeyW", "KeyS") + axis("ArrowUp", "ArrowDown")) * speed + touchWalk;
    const right = axis("KeyD", "KeyA") * speed;
    const up = axis("KeyE", "KeyQ") * speed;
    const turn = axis("ArrowRight", "ArrowLeft") * dt * 1.5;
    touchWalk = 0;
    if (fwd || right || up || turn || look[0] || look[1]) {
      if (playing) { playing = null; }
      page.walk(fwd, right, up, look[0] + turn, look[1]);
      look = [0, 0];
      lastMove = now;
    }
    if (playing) {
      const d = page.path_duration(playing.index);
      page.use_path(playing.index, d > 0 ? ((now - playing.start) / 1000) % d : 0);
      lastMove = now;
    }
    if (busy) return;
    const resting = now - lastMove > 300;
    const work = page.render(resting ? refine : 0);
    if (work.startsWith("unchanged")) return;
    busy = true;
    const t0 = performance.now();
    const px = await page.pixels(1.0);
    g.putImageData(new ImageData(px, w, h), 0, 0);
    frameMs = performance.now() - t0;
    stats.textContent = `${w}×${h}, ${samples} samples, ${rays} rays/px — frame ${ms(frameMs)} ms (${work.split(" ")[0]}, ${work.split(" ")[1]} frame(s))\n${page.adapter()}`;
    busy = false;
    if (!firstDone) {
      firstDone = true;
      readyResolve({ adapter: page.adapter(), load_ms: loadMs, frame_ms: frameMs, probes: page.probes(), size: [w, h], samples, rays });
    }
  }
  requestAnimationFrame(tick);
}

main().catch((e) => fail(e?.message ?? String(e)));
