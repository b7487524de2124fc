// End-to-end test of the web UI in real headless Chromium (Debian's
// /usr/bin/chromium driven by playwright-core), with synthesised pen input.
//
//   node e2e/run.mjs --bin ../target/release/interslice [--shots ../docs/screenshots]
//   node e2e/run.mjs --mock            (the node stand-in server; no Dice check)
//
// It starts `interslice demo` on a free loopback port, signs in, opens the
// demo cell, traces the nucleus on every 5th z slice through the UI (outline
// taken from the phantom's ground truth), interpolates, checks the preview,
// the 3D view and the evaluation panel, drops the connection while drawing,
// reloads and finds everything again, exports and checks the Dice of the
// exported nucleus against the ground truth. It prints the slice switch time
// and stroke latency measured in the browser. Everything is bounded in time
// and the server it started is always stopped.
import { spawn } from "node:child_process";
import fs from "node:fs";
import net from "node:net";
import os from "node:os";
import path from "node:path";
import { fileURLToPath } from "node:url";
import { chromium } from "playwright-core";
import { readNifti } from "./nifti.mjs";

const here = path.dirname(fileURLToPath(import.meta.url));
const argv = process.argv.slice(2);
const opt = (name, def) => {
  const i = argv.indexOf(`--${name}`);
  return i >= 0 ? (argv[i + 1] && !argv[i + 1].startsWith("--") ? argv[i + 1] : true) : def;
};
const MOCK = opt("mock", false) === true;
const BIN = opt("bin", path.resolve(here, "../../target/release/interslice"));
const SHOTS = opt("shots", null);
const SKIP = 5;
const TOTAL_LIMIT_MS = 300_000;

let server = null;
let browser = null;
const failures = [];
const check = (ok, what) => {
  console.log(`${ok ? "ok  " : "FAIL"} ${what}`);
  if (!ok) failures.push(what);
};

async function freePort() {
  return new Promise((res, rej) => {
    const s = net.createServer();
    s.listen(0, "127.0.0.1", () => {
      const p = s.address().port;
      s.close(() => res(p));
    });
    s.on("error", rej);
  });
}

async function waitHttp(url, ms) {
  const end = Date.now() + ms;
  while (Date.now() < end) {
    try {
      const r = await fetch(url);
      if (r.status < 500) return;
    } catch {
      /* not yet */
    }
    if (server && server.exitCode !== null) throw new Error(`server exited with ${server.exitCode}`);
    await new Promise((r) => setTimeout(r, 200));
  }
  throw new Error(`server did not answer at ${url} within ${ms} ms`);
}

function stopServer() {
  if (server && server.exitCode === null) {
    server.kill("SIGTERM");
    const s = server;
    setTimeout(() => s.exitCode === null && s.kill("SIGKILL"), 3000).unref();
  }
}

function stats(xs) {
  if (!xs.length) return "n=0";
  const s = [...xs].sort((a, b) => a - b);
  const q = (f) => s[Math.min(s.length - 1, Math.floor(f * (s.length - 1) + 0.5))];
  return `median ${q(0.5).toFixed(1)} ms, p95 ${q(0.95).toFixed(1)} ms, max ${s[s.length - 1].toFixed(1)} ms (n=${s.length})`;
}

/** Boundary of the mask on slice z=k as a star-shaped polygon around its centroid, in (u, v) = (i, j). */
function outline(gt, labels, k, rays = 96) {
  const [nx, ny] = gt.dims;
  const inside = (i, j) => i >= 0 && j >= 0 && i < nx && j < ny && labels.has(gt.data[i + nx * (j + ny * k)]);
  let cx = 0, cy = 0, n = 0;
  for (let j = 0; j < ny; j++) for (let i = 0; i < nx; i++) if (inside(i, j)) (cx += i + 0.5), (cy += j + 0.5), n++;
  if (n < 8) return null;
  cx /= n;
  cy /= n;
  const pts = [];
  for (let r = 0; r < rays; r++) {
    const a = (2 * Math.PI * r) / rays;
    const [dx, dy] = [Math.cos(a), Math.sin(a)];
    let last = 0;
    for (let t = 0; t < Math.max(nx, ny); t += 0.25) {
      if (inside(Math.floor(cx + t * dx), Math.floor(cy + t * dy))) last = t;
    }
    // The pixel-centre rule: the boundary lies half a pixel beyond the last inside sample.
    const t = last + 0.5;
    pts.push([cx + t * dx, cy + t * dy]);
  }
  return pts;
}

function dice(a, b) {
  let tp = 0, na = 0, nb = 0;
  for (let p = 0; p < a.length; p++) {
    if (a[p]) na++;
    if (b[p]) nb++;
    if (a[p] && b[p]) tp++;
  }
  return na + nb === 0 ? 1 : (2 * tp) / (na + nb);
}

async function main() {
  const guard = setTimeout(() => {
    console.error(`FAIL end-to-end test exceeded ${TOTAL_LIMIT_MS / 1000} s`);
    stopServer();
    browser?.close().catch(() => {});
    process.exit(1);
  }, TOTAL_LIMIT_MS);
  guard.unref();

  const dir = fs.mkdtempSync(path.join(os.tmpdir(), "interslice-e2e-"));
  const port = await freePort();
  const base = `http://127.0.0.1:${port}`;
  if (MOCK) {
    server = spawn(process.execPath, [path.join(here, "mock-server.mjs"), "--dir", dir, "--port", String(port)], { stdio: ["ignore", "inherit", "inherit"] });
  } else {
    if (!fs.existsSync(BIN)) throw new Error(`no interslice binary at ${BIN}`);
    server = spawn(BIN, ["demo", "--dir", dir, "--bind", `127.0.0.1:${port}`], { stdio: ["ignore", "inherit", "inherit"] });
  }
  await waitHttp(`${base}/api/me`, 120_000);
  console.log(`server at ${base}, data in ${dir}`);

  const gtDir = path.join(dir, "ground_truth");
  const gtFile = fs.readdirSync(gtDir).filter((f) => /\.nii(\.gz)?$/.test(f)).sort()[0];
  const gt = readNifti(fs.readFileSync(path.join(gtDir, gtFile)));
  // The nucleus with what lies inside it (nucleoli are painted over it, labels 3 and 4).
  const NUC = new Set([2, 3, 4]);
  const [nx, ny, nz] = gt.dims;
  let kmin = nz, kmax = -1;
  for (let k = 0; k < nz; k++)
    for (let p = nx * ny * k; p < nx * ny * (k + 1); p++)
      if (NUC.has(gt.data[p])) {
        kmin = Math.min(kmin, k);
        kmax = Math.max(kmax, k);
        break;
      }
  console.log(`ground truth ${gtFile}: ${gt.dims.join("x")}, nucleus on z ${kmin}..${kmax}`);

  browser = await chromium.launch({
    executablePath: "/usr/bin/chromium",
    args: ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-quic", "--no-first-run", "--disable-component-update", "--disable-sync"],
    timeout: 30_000,
  });
  const context = await browser.newContext({ viewport: { width: 1440, height: 900 }, deviceScaleFactor: 1 });
  const page = await context.newPage();
  page.setDefaultTimeout(20_000);
  const pageErrors = [];
  page.on("pageerror", (e) => pageErrors.push(String(e)));
  const shot = async (name) => {
    if (!SHOTS) return;
    fs.mkdirSync(SHOTS, { recursive: true });
    await page.waitForTimeout(150);
    await page.screenshot({ path: path.join(SHOTS, `${name}.png`) });
  };
  const tid = (id) => page.locator(`[data-testid="${id}"]`);
  const idle = () => page.evaluate(() => window.__interslice.tracer()?.idle());
  const summary = () => page.evaluate(() => window.__interslice.tracer().summary());
  const ready = () => page.waitForFunction(() => window.__interslice.tracer()?.ready === true);
  const figures = () => page.evaluate(() => window.__interslice.tracer().figures);

  // Sign in.
  await page.goto(base + "/");
  await tid("user-name").waitFor();
  await tid("user-name").fill("Ann Tracer");
  await shot("01-sign-in");
  await tid("sign-in").click();
  await tid("cell-list").locator("tbody tr").first().waitFor();
  check(await tid("cell-list").isVisible(), "cell list shown after sign-in");
  await shot("02-cell-list");

  // Open the demo cell (the first of the queue).
  const cellId = await tid("cell-list").locator("tbody tr").first().getAttribute("data-cell");
  await tid(`open-cell-${cellId}`).click();
  await tid("view-z").waitFor();
  await ready();
  await page.waitForTimeout(300);
  for (const id of ["view-x", "view-y", "view-z", "axis-select", "slice-next", "slice-prev", "slice-index", "skip-step", "label-select", "add-contour", "clear-contours", "mark-empty", "undo", "redo", "interpolate", "method-select", "view-3d", "next-cell"])
    check((await tid(id).count()) === 1, `test id ${id} present`);

  await tid("axis-select").selectOption("z");
  const nucleusId = await tid("label-select").evaluate((sel) => [...sel.options].find((o) => /nucleus/i.test(o.text))?.value);
  await tid("label-select").selectOption(nucleusId);
  await tid("skip-step").fill(String(SKIP));
  await tid("skip-step").press("Enter");

  const cdp = await context.newCDPSession(page);
  const pen = (type, x, y, force = 0.6) =>
    cdp.send("Input.dispatchMouseEvent", { type, x, y, button: "left", buttons: type === "mouseReleased" ? 0 : 1, clickCount: 1, pointerType: "pen", force });
  async function trace(k) {
    const poly = outline(gt, NUC, k);
    if (!poly) return false;
    const pts = await page.evaluate((p) => p.map(([u, v]) => window.__interslice.tracer().sliceToClient("z", u, v)), poly);
    await pen("mousePressed", pts[0][0], pts[0][1], 0.3);
    for (let n = 1; n < pts.length; n++) {
      // Two samples per segment, like a pen reporting faster than the points above.
      const [a, b] = [pts[n - 1], pts[n]];
      await pen("mouseMoved", (a[0] + b[0]) / 2, (a[1] + b[1]) / 2, 0.5 + 0.3 * Math.sin(n));
      await pen("mouseMoved", b[0], b[1], 0.5 + 0.3 * Math.sin(n));
    }
    await pen("mouseMoved", pts[0][0], pts[0][1], 0.4);
    await pen("mouseReleased", pts[0][0], pts[0][1], 0);
    return true;
  }

  // A bad first attempt, restarted by putting the pen down again: only the second counts.
  const first = kmin + 2;
  await tid("slice-index").fill(String(first));
  await tid("slice-index").press("Enter");
  await page.waitForFunction((k) => window.__interslice.tracer().summary().index === k, first);
  const [sx, sy] = await page.evaluate(() => window.__interslice.tracer().sliceToClient("z", 10.5, 10.5));
  await pen("mousePressed", sx, sy);
  await pen("mouseMoved", sx + 40, sy + 10);
  await pen("mouseReleased", sx + 40, sy + 10);
  const traced = [];
  let previewOnline = [];
  const plan = [];
  for (let k = first; k <= kmax; k += SKIP) plan.push(k);
  for (const k of plan) {
    if (k !== first) {
      await tid("slice-next").click();
      await page.waitForFunction((kk) => window.__interslice.tracer().summary().index === kk, k);
    }
    const last = k === plan[plan.length - 1];
    // The last contour is drawn while the connection is down: it is kept, shown and sent later.
    if (last) previewOnline = (await figures()).previewLatency.slice();
    if (last) await page.route("**/api/cells/*/contours", (r) => r.abort("internetdisconnected"));
    if (await trace(k)) traced.push(k);
    if (last) {
      await page.waitForTimeout(300);
      const pending = await page.evaluate(() => window.__interslice.app.outbox.pending.length);
      check(pending === 1, `contour drawn offline is queued (${pending} pending)`);
      check((await summary()).drawn.includes(k), "contour drawn offline is shown");
      await page.unroute("**/api/cells/*/contours");
      await page.evaluate(() => window.__interslice.app.outbox.flush());
    }
  }
  await idle();
  check((await page.evaluate(() => window.__interslice.app.outbox.pending.length)) === 0, "queued contour sent after reconnecting");
  let s = await summary();
  check(JSON.stringify(s.drawn) === JSON.stringify(traced), `drawn slices ${JSON.stringify(s.drawn)} = traced ${JSON.stringify(traced)}`);
  check(s.contours === traced.length, `one contour per traced slice (${s.contours})`);

  // Interpolate and look at a skipped slice with the dashed preview.
  await tid("interpolate").click();
  await idle();
  s = await summary();
  check(s.preview, "interpolation preview present");
  const skipped = traced[Math.floor(traced.length / 2)] + 2;
  await tid("slice-index").fill(String(skipped));
  await tid("slice-index").press("Enter");
  await page.waitForFunction((k) => window.__interslice.tracer().summary().index === k, skipped);
  await page.waitForFunction((k) => document.querySelector('[data-testid="status-slice"]').textContent.startsWith(`slice ${k} `), skipped);
  const kind = await tid("status-kind").textContent();
  check(/interpolated/.test(kind), `skipped slice ${skipped} shows as interpolated ("${kind}")`);
  await page.mouse.move(...(await page.evaluate(() => window.__interslice.tracer().sliceToClient("z", 48.5, 50.5))));
  await shot("03-tracing");

  // 3D view.
  await tid("view-3d").click();
  await page.waitForFunction(() => document.querySelector('[data-testid="view-3d"] canvas') && !/computing/.test(document.querySelector(".v3d-msg").textContent), null, { timeout: 60_000 });
  const msg3d = await page.locator(".v3d-msg").textContent();
  check(/nucleus/i.test(msg3d), `3D view shows the nucleus surface ("${msg3d}")`);
  await shot("04-3d-view");

  // Evaluation: Otsu segmentation against this user's ground truth, FP/FN overlay, rating.
  await tid("seg-method").selectOption("otsu");
  await tid("seg-run").click();
  await page.waitForFunction(() => document.querySelector('[data-testid="seg-select"]').value !== "", null, { timeout: 60_000 });
  await tid("evaluate").click();
  await page.waitForFunction(() => document.querySelector('[data-testid="metrics-table"] td[data-key="dice"]') || document.querySelector('[data-testid="metrics-table"] .err'), null, { timeout: 60_000 });
  const diceText = await page.locator('[data-testid="metrics-table"] td[data-key="dice"]').textContent().catch(() => null);
  check(diceText !== null && Number(diceText) > 0, `metrics table shows Dice (${diceText ?? (await tid("metrics-table").textContent())})`);
  await tid("rating-stars").locator("button").nth(3).click();
  await tid("rating-comment").fill("Good boundary; misses the lower cap.");
  await tid("rating-save").click();
  await page.waitForTimeout(500);
  await page.locator("aside.side").evaluate((el) => (el.scrollTop = el.scrollHeight));
  await shot("05-evaluation");

  // Slice switch time: step through slices one by one.
  await tid("skip-step").fill("1");
  await tid("skip-step").press("Enter");
  for (let n = 0; n < 20; n++) {
    await tid(n < 10 ? "slice-next" : "slice-prev").click();
    await page.waitForTimeout(20);
  }
  const fig = await figures();

  // Reload: everything is still there.
  const before = await summary();
  await page.reload();
  await ready();
  await idle();
  const after = await summary();
  check(JSON.stringify(after.drawn) === JSON.stringify(traced), `after reload the drawn slices are there (${JSON.stringify(after.drawn)})`);
  check(after.contours === traced.length && after.index === before.index && after.label === before.label, `after reload: ${after.contours} contours, slice ${after.index}, label ${after.label}`);
  check(after.preview, "after reload the interpolation preview is there");

  // Help overlay and keyboard.
  await page.keyboard.press("?");
  check(await tid("help-overlay").isVisible(), "help overlay opens with ?");
  await shot("06-help");
  await page.keyboard.press("Escape");

  // Export and compare with the ground truth.
  if (!MOCK) {
    const cookies = await context.cookies();
    const cookie = cookies.map((c) => `${c.name}=${c.value}`).join("; ");
    const r = await fetch(`${base}/api/cells/${encodeURIComponent(cellId)}/export?format=nii.gz`, { headers: { cookie } });
    check(r.ok, `export answered ${r.status}`);
    if (r.ok) {
      const ex = readNifti(Buffer.from(await r.arrayBuffer()));
      check(ex.dims.join() === gt.dims.join(), `export dims ${ex.dims.join("x")}`);
      const a = ex.data.map((v) => (v === Number(nucleusId) ? 1 : 0));
      const b = gt.data.map((v) => (NUC.has(v) ? 1 : 0));
      const d = dice(a, b);
      console.log(`Dice of the exported nucleus vs the phantom: ${d.toFixed(4)}`);
      check(d > 0.85, `Dice ${d.toFixed(4)} > 0.85`);
    }
  }

  check(pageErrors.length === 0, `no page errors ${pageErrors.join(" | ")}`);
  console.log(`slice switch time: ${stats(fig.sliceSwitch)}`);
  console.log(`stroke latency (pointer event -> painted frame): ${stats(fig.strokeLatency)}`);
  console.log(`interpolation preview after finishing a contour (online): ${stats(previewOnline)}`);
  fs.rmSync(dir, { recursive: true, force: true });
}

let code = 0;
try {
  await main();
} catch (e) {
  console.error(`FAIL ${e?.stack ?? e}`);
  code = 1;
} finally {
  await browser?.close().catch(() => {});
  stopServer();
}
if (failures.length) code = 1;
console.log(code === 0 ? "end-to-end: all checks passed" : `end-to-end: ${failures.length} check(s) failed`);
process.exit(code);
