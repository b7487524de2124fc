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
  return execFileSync(BIN, args, { encoding: "utf8", env: { ...process.env, ...env }, stdio: ["ignore", "pipe", "pipe"], maxBuffer: 256 << 20 });
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
  const ev = (type, [x, y], extra = {}) => cdp.send("Input.dispatchMouseEvent", { type, x, y, pointerType: "pen", ...extra });
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
