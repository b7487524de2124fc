// What every end-to-end suite needs: the real `interslice` binary serving a
// fresh demo project, headless Chromium driven through playwright-core, and
// pen input synthesised as trusted pointer events (Chrome DevTools Protocol
// `Input.dispatchMouseEvent` with pointerType "pen" and a pressure), so the
// UI's pen path, pointer capture and coalesced events are exercised exactly
// as with a tablet.
import { spawn, execFileSync } from "node:child_process";
import fs from "node:fs";
import net from "node:net";
import os from "node:os";
import path from "node:path";
import { fileURLToPath } from "node:url";
import { chromium } from "playwright-core";

const here = path.dirname(fileURLToPath(import.meta.url));
/** The repository root. */
export const ROOT = path.resolve(here, "../..");
/** The binary under test (INTERSLICE_BIN overrides). */
export const BIN = process.env.INTERSLICE_BIN ?? path.join(ROOT, "target/release/interslice");
const CHROMIUM = process.env.CHROMIUM ?? "/usr/bin/chromium";

/** Run the binary, return its stdout (throws with its stderr on failure). */
export function cli(...args) {
  return cliWith({}, ...args);
}

/** Run the binary with extra environment variables. */
export function cliWith(env, ...args) {
  return execFileSync(BIN, args, {
    encoding: "utf8",
    env: { ...process.env, ...env },
    stdio: ["ignore", "pipe", "pipe"],
    maxBuffer: 256 << 20,
  });
}

async function freePort() {
  return new Promise((resolve, reject) => {
    const s = net.createServer();
    s.once("error", reject);
    s.listen(0, "127.0.0.1", () => {
      const { port } = s.address();
      s.close(() => resolve(port));
    });
  });
}

/**
 * `interslice demo` in a new temporary folder on a free loopback port; resolves
 * once the API answers. `stop()` ends the server and removes the folder.
 */
export async function startDemo({ size = 128 } = {}) {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), "interslice-e2e-"));
  return startServer(dir, (bind) => ["demo", dir, "--bind", bind, "--size", String(size)]);
}

/**
 * `interslice serve DIR` (with `extra` options) on a free loopback port, for a
 * project folder the caller prepared; `stop()` removes it too.
 */
export async function startServe(dir, extra = []) {
  return startServer(dir, (bind) => ["serve", dir, "--bind", bind, ...extra]);
}

async function startServer(dir, argsFor) {
  if (!fs.existsSync(BIN)) throw new Error(`${BIN} not found: build it with cargo build --release -p interslice-cli`);
  // Files the tests write (exports, contours) stay out of the project folder, where they would be listed as cells.
  const scratch = fs.mkdtempSync(path.join(os.tmpdir(), "interslice-e2e-out-"));
  const port = await freePort();
  const url = `http://127.0.0.1:${port}`;
  const log = [];
  const proc = spawn(BIN, argsFor(`127.0.0.1:${port}`), { stdio: ["ignore", "pipe", "pipe"] });
  proc.stdout.on("data", (d) => log.push(String(d)));
  proc.stderr.on("data", (d) => log.push(String(d)));
  let exited = null;
  proc.on("exit", (code) => (exited = code));
  const deadline = Date.now() + 120_000;
  for (;;) {
    if (exited !== null) throw new Error(`interslice exited with ${exited}:\n${log.join("")}`);
    try {
      const r = await fetch(`${url}/api/methods`);
      if (r.ok) break;
    } catch {
      /* not listening yet */
    }
    if (Date.now() > deadline) throw new Error(`interslice did not answer in 120 s:\n${log.join("")}`);
    await new Promise((r) => setTimeout(r, 200));
  }
  return {
    dir,
    scratch,
    url,
    log,
    async stop() {
      if (exited === null) {
        proc.kill("SIGTERM");
        await new Promise((r) => (exited !== null ? r() : proc.once("exit", r)));
      }
      if (!process.env.KEEP_E2E) for (const d of [dir, scratch]) fs.rmSync(d, { recursive: true, force: true });
    },
  };
}

/** Headless Chromium with a fresh profile and a page of a fixed size. */
export async function startBrowser({ width = 1600, height = 1000 } = {}) {
  if (!fs.existsSync(CHROMIUM)) throw new Error(`${CHROMIUM} not found (apt-get install -y chromium)`);
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), "interslice-chromium-"));
  // A persistent context is how playwright takes a fresh --user-data-dir.
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: CHROMIUM,
    headless: true,
    viewport: { width, height },
    deviceScaleFactor: 1,
    acceptDownloads: true,
    args: [
      "--headless",
      "--no-sandbox",
      "--disable-gpu",
      "--disable-background-networking",
      "--disable-quic",
      "--no-first-run",
      "--disable-component-update",
      "--disable-sync",
      // WebGL (the 3D view) through the software rasteriser.
      "--use-angle=swiftshader",
      "--enable-unsafe-swiftshader",
    ],
  });
  const page = context.pages()[0] ?? (await context.newPage());
  const errors = [];
  page.on("pageerror", (e) => errors.push(`page error: ${e.message}`));
  page.on("console", (m) => {
    if (m.type() === "error") errors.push(`console: ${m.text()}`);
  });
  const cdp = await context.newCDPSession(page);
  return {
    context,
    page,
    cdp,
    errors,
    async close() {
      await context.close();
      fs.rmSync(profile, { recursive: true, force: true });
    },
  };
}

/**
 * The outlines of `label` in the label volume `gt` per slice along `axis`
 * (every `every`-th slice), from `interslice contours extract`.
 */
export function outlines(server, gt, every, label, axis = "z") {
  const file = path.join(server.scratch, `contours-${every}-${axis}.json`);
  cli("contours", "extract", gt, "--every", String(every), "--axis", axis, "--out", file);
  const doc = JSON.parse(fs.readFileSync(file, "utf8"));
  const by = new Map();
  for (const c of doc.contours) {
    if (c.label !== label || c.axis !== axis) continue;
    if (!by.has(c.index)) by.set(c.index, []);
    by.get(c.index).push(c.points);
  }
  return by;
}

/** Sign in by name on the sign-in form and wait for the cell list. */
export async function signIn(page, url, name) {
  await page.goto(url);
  await page.getByTestId("user-name").fill(name);
  await page.getByTestId("sign-in").click();
  await page.getByTestId("cell-list").locator("tbody tr").first().waitFor();
}

/** Wait until the tracing screen of `cell` is loaded (and, unless told otherwise, everything saved). */
export async function waitTracer(page, cell, { idle = true } = {}) {
  await page.waitForFunction(
    (c) => {
      const t = window.__interslice?.tracer();
      return t && t.cell.id === c && t.ready;
    },
    cell,
    { timeout: 30_000 },
  );
  if (idle) await page.evaluate(() => window.__interslice.tracer().idle());
}

/** Slice (u, v) -> client coordinates of a view, through the UI's own transform. */
export function toClient(page, axis, pts) {
  return page.evaluate(([a, p]) => p.map(([u, v]) => window.__interslice.tracer().sliceToClient(a, u, v)), [axis, pts]);
}

/**
 * Points every `step` CSS pixels along the closed polyline `pts` (client
 * coordinates), ending back at the start, as a pen moving along it reports.
 */
export function densify(pts, step = 3) {
  const out = [];
  for (let i = 0; i < pts.length; i++) {
    const [x0, y0] = pts[i];
    const [x1, y1] = pts[(i + 1) % pts.length];
    const n = Math.max(1, Math.ceil(Math.hypot(x1 - x0, y1 - y0) / step));
    for (let k = 0; k < n; k++) out.push([x0 + ((x1 - x0) * k) / n, y0 + ((y1 - y0) * k) / n]);
  }
  out.push(pts[0]);
  return out;
}

/**
 * A pen stroke through client points: hover to the start, press, move with a
 * varying pressure, lift. Events are trusted (CDP), so pointer capture and
 * getCoalescedEvents behave as with a real pen.
 */
export async function penStroke(cdp, pts) {
  const ev = (type, [x, y], extra = {}) =>
    cdp.send("Input.dispatchMouseEvent", { type, x, y, pointerType: "pen", ...extra });
  await ev("mouseMoved", pts[0], { button: "none", buttons: 0 });
  await ev("mousePressed", pts[0], { button: "left", buttons: 1, clickCount: 1, force: 0.4 });
  for (let i = 1; i < pts.length; i++) {
    await ev("mouseMoved", pts[i], { button: "left", buttons: 1, force: 0.4 + 0.4 * Math.abs(Math.sin(i / 15)) });
  }
  await ev("mouseReleased", pts[pts.length - 1], { button: "left", buttons: 0, clickCount: 1, force: 0 });
}

/** Median and 95th percentile of a list of numbers. */
export function stats(xs) {
  const s = [...xs].sort((a, b) => a - b);
  const q = (p) => (s.length ? s[Math.min(s.length - 1, Math.floor(p * (s.length - 1) + 0.5))] : NaN);
  return { n: s.length, median: q(0.5), p95: q(0.95), max: s[s.length - 1] ?? NaN };
}

/** Save a screenshot when SCREENSHOTS names a folder. */
export async function shot(page, name) {
  const dir = process.env.SCREENSHOTS;
  if (!dir) return;
  fs.mkdirSync(dir, { recursive: true });
  await page.screenshot({ path: path.join(dir, `${name}.png`) });
}

/** Resolves after the page has painted two more frames (views paint on animation frames). */
export function painted(page) {
  return page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(() => r()))));
}

/**
 * The grey level (red channel) that view `axis` shows at the centre of each
 * slice pixel `[u, v]`, read back from its canvas.
 */
export function canvasGreys(page, axis, pixels) {
  return page.evaluate(
    ([a, ps]) => {
      const t = window.__interslice.tracer();
      const c = document.querySelector(`[data-testid="view-${a}"]`);
      const r = c.getBoundingClientRect();
      const dpr = c.width / r.width;
      const ctx = c.getContext("2d");
      return ps.map(([u, v]) => {
        const [x, y] = t.sliceToClient(a, u + 0.5, v + 0.5);
        return ctx.getImageData(Math.floor((x - r.left) * dpr), Math.floor((y - r.top) * dpr), 1, 1).data[0];
      });
    },
    [axis, pixels],
  );
}

/**
 * What view `axis` shows, from its canvas pixels over the slice (grey pixels
 * only, so crosshairs and contours do not count): the mean and standard
 * deviation of the grey levels, the fractions near black and near white, and
 * `neighbour`: the mean grey difference between pixels one voxel apart
 * divided by that between random pairs of pixels. A picture of anatomy has
 * smooth regions (well below 0.5); noise, such as signed values read as
 * unsigned, has about 1.
 */
export function viewStats(page, axis) {
  return page.evaluate((a) => {
    const t = window.__interslice.tracer();
    const c = document.querySelector(`[data-testid="view-${a}"]`);
    const r = c.getBoundingClientRect();
    const dpr = c.width / r.width;
    const [w, h] = t.sliceSize(a);
    const [cx0, cy0] = t.sliceToClient(a, 0, 0);
    const [cx1, cy1] = t.sliceToClient(a, w, h);
    const x0 = Math.max(0, Math.ceil((cx0 - r.left) * dpr));
    const y0 = Math.max(0, Math.ceil((cy0 - r.top) * dpr));
    const x1 = Math.min(c.width, Math.floor((cx1 - r.left) * dpr));
    const y1 = Math.min(c.height, Math.floor((cy1 - r.top) * dpr));
    const W = x1 - x0;
    const H = y1 - y0;
    const d = c.getContext("2d").getImageData(x0, y0, W, H).data;
    // One voxel's size in canvas pixels (at least 1), so neighbours are distinct voxels.
    const sx = Math.max(1, Math.ceil(((cx1 - cx0) * dpr) / w));
    const sy = Math.max(1, Math.ceil(((cy1 - cy0) * dpr) / h));
    const g = (x, y) => {
      const o = 4 * (x + W * y);
      return d[o] === d[o + 1] && d[o] === d[o + 2] ? d[o] : -1;
    };
    let n = 0,
      sum = 0,
      sum2 = 0,
      black = 0,
      white = 0;
    const greys = [];
    for (let y = 0; y < H; y += sy) {
      for (let x = 0; x < W; x += sx) {
        const v = g(x, y);
        if (v < 0) continue;
        n++;
        sum += v;
        sum2 += v * v;
        if (v < 16) black++;
        if (v > 239) white++;
        greys.push(v);
      }
    }
    let adj = 0,
      na = 0;
    for (let y = 0; y + sy < H; y += sy) {
      for (let x = 0; x + sx < W; x += sx) {
        const v = g(x, y),
          right = g(x + sx, y),
          down = g(x, y + sy);
        if (v < 0) continue;
        if (right >= 0) {
          adj += Math.abs(v - right);
          na++;
        }
        if (down >= 0) {
          adj += Math.abs(v - down);
          na++;
        }
      }
    }
    // Random pairs from a fixed linear congruential sequence (repeatable).
    let seed = 12345,
      rnd = 0;
    const next = () => (seed = (seed * 1103515245 + 12345) % 2147483648) % greys.length;
    for (let k = 0; k < 20000; k++) rnd += Math.abs(greys[next()] - greys[next()]);
    const mean = sum / n;
    return {
      n,
      mean,
      std: Math.sqrt(Math.max(0, sum2 / n - mean * mean)),
      black: black / n,
      white: white / n,
      neighbour: rnd > 0 ? adj / na / (rnd / 20000) : 1,
    };
  }, axis);
}

/**
 * Write a NIfTI-1 file (little-endian, `.nii`): `values` a typed array in x
 * fastest order of type u8, i16, u16, f32 (NIfTI codes 2, 4, 512, 16);
 * `slope`/`inter` the scl_slope/scl_inter the file declares.
 */
export function writeNifti(file, { dims, spacing = [1, 1, 1], values, slope = 0, inter = 0 }) {
  const types = new Map([
    [Uint8Array, [2, 8]],
    [Int16Array, [4, 16]],
    [Uint16Array, [512, 16]],
    [Float32Array, [16, 32]],
  ]);
  const [code, bitpix] = types.get(values.constructor) ?? [];
  if (!code) throw new Error("writeNifti: values must be Uint8Array, Int16Array, Uint16Array or Float32Array");
  if (values.length !== dims[0] * dims[1] * dims[2]) throw new Error("writeNifti: values do not match dims");
  const buf = Buffer.alloc(352 + values.length * (bitpix / 8));
  buf.writeInt32LE(348, 0);
  [3, ...dims, 1, 1, 1, 1].forEach((d, n) => buf.writeInt16LE(d, 40 + 2 * n));
  buf.writeInt16LE(code, 70);
  buf.writeInt16LE(bitpix, 72);
  [1, ...spacing, 1, 1, 1, 1].forEach((p, n) => buf.writeFloatLE(p, 76 + 4 * n));
  buf.writeFloatLE(352, 108);
  buf.writeFloatLE(slope, 112);
  buf.writeFloatLE(inter, 116);
  buf.writeUInt8(2, 123); // mm
  buf.write("n+1\0", 344, "latin1");
  const dv = new DataView(buf.buffer, buf.byteOffset + 352);
  values.forEach((v, i) => {
    if (code === 2) dv.setUint8(i, v);
    else if (code === 4) dv.setInt16(2 * i, v, true);
    else if (code === 512) dv.setUint16(2 * i, v, true);
    else dv.setFloat32(4 * i, v, true);
  });
  fs.writeFileSync(file, buf);
}

/**
 * Pixels of the slice that view `axis` shows whose 3x3 neighbourhood lies
 * wholly in `[lo, hi]` (raw values from the slice route), spread over the
 * slice, at most `max` of them, away from the crosshair lines: `[u, v, value]`.
 */
export function pixelsIn(page, axis, lo, hi, max = 40) {
  return page.evaluate(
    async ([a, lo, hi, max]) => {
      const t = window.__interslice.tracer();
      const [w, h, index] = t.sliceSize(a);
      const r = await fetch(`/api/cells/${t.cell.id}/slices/${a}/${index}`);
      const dtype = r.headers.get("X-Dtype");
      const dv = new DataView(await r.arrayBuffer());
      const at = (u, v) =>
        dtype === "i16"
          ? dv.getInt16(2 * (u + w * v), true)
          : dtype === "u16"
            ? dv.getUint16(2 * (u + w * v), true)
            : dtype === "f32"
              ? dv.getFloat32(4 * (u + w * v), true)
              : dv.getUint8(u + w * v);
      const cross = (u, v) => Math.abs(u + 0.5 - w / 2) < 3 || Math.abs(v + 0.5 - h / 2) < 3;
      const found = [];
      for (let v = 1; v < h - 1; v++) {
        for (let u = 1; u < w - 1; u++) {
          let ok = !cross(u, v);
          for (let dv2 = -1; ok && dv2 <= 1; dv2++)
            for (let du = -1; ok && du <= 1; du++) {
              const x = at(u + du, v + dv2);
              ok = x >= lo && x <= hi;
            }
          if (ok) found.push([u, v, at(u, v)]);
        }
      }
      const step = Math.max(1, Math.floor(found.length / max));
      return found.filter((_, n) => n % step === 0).slice(0, max);
    },
    [axis, lo, hi, max],
  );
}

/** The grey levels view `axis` shows for voxels in `[lo, hi]`, with how many there were. */
export async function greysIn(page, axis, lo, hi) {
  const px = await pixelsIn(page, axis, lo, hi);
  const greys = await canvasGreys(
    page,
    axis,
    px.map(([u, v]) => [u, v]),
  );
  return { n: px.length, min: Math.min(...greys), max: Math.max(...greys) };
}

/**
 * Read an 8-bit `.nii` label volume (what `export?format=nii` and
 * `interslice contours rasterize --out X.nii` write for labels up to 255):
 * its dims and voxels, x fastest.
 */
export function readNiftiU8(file) {
  const buf = fs.readFileSync(file);
  const dims = [1, 2, 3].map((n) => buf.readInt16LE(40 + 2 * n));
  if (buf.readInt16LE(70) !== 2) throw new Error(`${file}: not an 8-bit NIfTI`);
  const offset = Math.round(buf.readFloatLE(108));
  const n = dims[0] * dims[1] * dims[2];
  return { dims, values: new Uint8Array(buf.buffer, buf.byteOffset + offset, n) };
}
