// The tracing workflow end to end, against the real `interslice demo` server
// in headless Chromium: sign in, open the demo cell, trace the nucleus with a
// (synthesised) pen on every 5th slice, interpolate, see it in 3D, reload and
// find everything, survive a dropped connection, export and check the Dice
// against the phantom's exact nucleus, move on to the next cell.
//
// It prints the figures measured in the browser (slice switch time, stroke
// latency, save and preview latency) and writes them to E2E_FIGURES if set.
import { after, before, test } from "node:test";
import assert from "node:assert/strict";
import fs from "node:fs";
import path from "node:path";
import {
  cli,
  densify,
  outlines,
  penStroke,
  shot,
  signIn,
  startBrowser,
  startDemo,
  stats,
  toClient,
  waitTracer,
} from "./harness.mjs";

const USER = "alice";
const CELL = "cell_001";
const STEP = 5;

let demo;
let br;
/** label-2 contours of the phantom by z index: every 5th slice and all slices. */
let sparse;
let dense;
let nucleus;
let expectDrawn;
let expectEmpty;
const out = {};
/** The figures of every tracing screen seen (a reload or another cell starts new ones). */
const figures = { sliceSwitch: [], strokeLatency: [], saveLatency: [], previewLatency: [] };

/** Add the current screen's figures to `figures` (before it goes away). */
async function collect() {
  const f = await br.page.evaluate(() => window.__interslice.tracer().figures);
  for (const k of Object.keys(figures)) figures[k].push(...f[k]);
}

const summary = () => br.page.evaluate(() => window.__interslice.tracer().summary());
const idle = () => br.page.evaluate(() => window.__interslice.tracer().idle());

/** Go to slice `i`: Next slice when it is one skip step ahead, else the slice box. */
async function goto(i) {
  const { page } = br;
  const cur = (await summary()).index;
  if (cur === i) return;
  if (i - cur === STEP) await page.getByTestId("slice-next").click();
  else if (cur - i === STEP) await page.getByTestId("slice-prev").click();
  else {
    await page.getByTestId("slice-index").fill(String(i));
    await page.getByTestId("slice-index").press("Enter");
  }
  await page
    .getByTestId("status-slice")
    .filter({ hasText: `slice ${i} /` })
    .waitFor();
}

/** Trace the outline (slice coordinates) with the pen, closing it on the start point; returns the samples sent. */
async function trace(points) {
  const samples = densify(await toClient(br.page, "z", points));
  await penStroke(br.cdp, samples);
  return samples.length;
}

before(async () => {
  demo = await startDemo();
  br = await startBrowser();
  const gt = path.join(demo.dir, "ground_truth", `${CELL}_labels.nii.gz`);
  sparse = outlines(demo, gt, STEP, 2);
  dense = outlines(demo, gt, 1, 2);
  assert.ok(sparse.size >= 4, `the phantom's nucleus spans ${sparse.size} traced slices`);
});

after(async () => {
  await br?.close();
  await demo?.stop();
});

test("sign in and open the demo cell from this user's list", async () => {
  const { page } = br;
  await page.goto(demo.url);
  await shot(page, "sign-in");
  await signIn(page, demo.url, USER);
  await page.getByTestId("current-user").filter({ hasText: USER }).waitFor();
  assert.equal(await page.getByTestId("cell-list").locator("tbody tr").count(), 3);
  await page.getByTestId(`open-cell-${CELL}`).click();
  await waitTracer(page, CELL);
  for (const a of ["x", "y", "z"]) assert.ok(await page.getByTestId(`view-${a}`).isVisible(), `view-${a} shown`);
  const labels = await page.evaluate(() => fetch("/api/labels").then((r) => r.json()));
  nucleus = labels.find((l) => /nucleus/i.test(l.name));
  assert.ok(nucleus, "the project has a Nucleus label");
});

test("choose the axis and the working view follows", async () => {
  const { page } = br;
  await page.getByTestId("axis-select").selectOption("y");
  assert.equal(await page.locator(".slot-main").getByTestId("view-y").count(), 1);
  await page.getByTestId("axis-select").selectOption("z");
  assert.equal(await page.locator(".slot-main").getByTestId("view-z").count(), 1);
  await waitTracer(page, CELL);
});

test("trace the nucleus with the pen on every 5th slice", async () => {
  const { page } = br;
  await page.getByTestId("label-select").selectOption(String(nucleus.id));
  await page.getByTestId("skip-step").fill(String(STEP));
  await page.getByTestId("skip-step").dispatchEvent("change");
  const idx = [...sparse.keys()].sort((a, b) => a - b);
  const first = idx[0];
  const last = idx[idx.length - 1];

  // The slice below the nucleus: drawn, structure absent.
  expectEmpty = [first - STEP, last + STEP].filter((i) => i >= 0 && i < 128);
  await goto(expectEmpty[0]);
  await page.getByTestId("mark-empty").click();
  await page.getByTestId("status-kind").filter({ hasText: "drawn (empty)" }).waitFor();

  for (const [n, i] of idx.entries()) {
    await goto(i);
    const polys = sparse.get(i);
    if (n === 0) {
      // A bad attempt, lifted before Add contour: putting the pen down again restarts it.
      const c = await toClient(page, "z", polys[0]);
      await penStroke(
        br.cdp,
        densify(c)
          .slice(0, 40)
          .map(([x, y]) => [x + 15, y + 15]),
      );
      assert.equal((await summary()).onSlice, 0, "an open stroke is not a contour");
      await trace(polys[0]);
    } else if (n === 1) {
      // An open stroke finished with Add contour.
      const c = densify(await toClient(page, "z", polys[0]));
      await penStroke(br.cdp, c.slice(0, Math.floor(c.length * 0.85)));
      assert.equal((await summary()).onSlice, 0);
      await shot(page, "drawing");
      await page.getByTestId("add-contour").click();
    } else {
      const sent = [];
      for (const p of polys) sent.push(await trace(p));
      // Every pen sample arrives (coalesced events included) with its pressure;
      // only the final one, back on the start point, closes the polygon.
      await idle();
      const stored = await page.evaluate(
        ([c, l, k]) => fetch(`/api/cells/${c}/contours?axis=z&index=${k}&label=${l}`).then((r) => r.json()),
        [CELL, nucleus.id, i],
      );
      assert.deepEqual(
        stored.map((c) => c.points.length),
        sent.map((n) => n - 1),
        `slice ${i}: all pen samples stored`,
      );
      for (const c of stored) {
        assert.equal(c.tool, "pen");
        assert.equal(c.pressure.length, c.points.length);
        assert.ok(new Set(c.pressure.map((p) => p.toFixed(2))).size > 5, "pressure varies along the stroke");
      }
    }
    assert.equal((await summary()).onSlice, polys.length, `slice ${i}: contour sent on lift`);
    if (n === 2) {
      // Clear, undo the clear, redo it, undo again: the contour is back.
      await idle();
      await page.getByTestId("clear-contours").click();
      await idle();
      assert.equal((await summary()).onSlice, 0, "cleared");
      for (const [btn, want] of [
        ["undo", 1],
        ["redo", 0],
        ["undo", 1],
      ]) {
        await page.getByTestId(btn).click();
        await page.waitForFunction((w) => window.__interslice.tracer().summary().onSlice === w, want);
      }
    }
  }
  await goto(expectEmpty[1]);
  await page.getByTestId("mark-empty").click();
  await idle();
  expectDrawn = [...idx, ...expectEmpty].sort((a, b) => a - b);
  const s = await summary();
  assert.deepEqual(s.drawn, expectDrawn);
  assert.deepEqual(s.empty, expectEmpty);
  assert.equal(s.pending, 0, "every change saved");
});

test("interpolate with the chosen method and preview the skipped slices", async () => {
  const { page } = br;
  const methods = await page.getByTestId("method-select").locator("option").allTextContents();
  assert.ok(methods.length >= 2, `methods offered: ${methods.join(", ")}`);
  await page.getByTestId("method-select").selectOption({ index: 0 });
  await page.getByTestId("interpolate").click();
  await idle();
  assert.ok((await summary()).preview, "the preview is there");
  const idx = [...sparse.keys()].sort((a, b) => a - b);
  const mid = idx[Math.floor(idx.length / 2)];
  // Slice switches to slices not fetched yet (the neighbours at the skip step are prefetched).
  const seen = await br.page.evaluate(() => window.__interslice.tracer().figures.sliceSwitch.length);
  for (const i of [3, 121, 17, 96, 41, 77, 9, 110, 58, 30]) await goto(i);
  out.slice_switch_uncached_ms = stats(
    (await br.page.evaluate(() => window.__interslice.tracer().figures.sliceSwitch)).slice(seen),
  );
  await goto(mid + 2);
  await page.getByTestId("status-kind").filter({ hasText: "interpolated" }).waitFor();
  await shot(page, "tracing");
  await page.getByTestId("view-z").focus();
  await page.keyboard.press("?");
  await page.getByTestId("help-overlay").waitFor();
  await shot(page, "help");
  await page.keyboard.press("Escape");
  assert.ok(await page.getByTestId("help-overlay").isHidden());
});

test("3D view of the interpolated surface", async () => {
  const { page } = br;
  await page.getByTestId("view-3d").click();
  await page.getByTestId("view-3d-status").filter({ hasText: nucleus.name }).waitFor({ timeout: 60_000 });
  assert.equal(await page.getByTestId("view-3d").locator("canvas").count(), 1);
  await shot(page, "3d");
});

test("a reload shows everything again", async () => {
  const { page } = br;
  const before = await summary();
  await collect();
  await page.reload();
  await waitTracer(page, CELL);
  const after = await summary();
  assert.equal(after.index, before.index, "same slice");
  assert.equal(after.label, nucleus.id, "same component");
  assert.deepEqual(after.drawn, expectDrawn);
  assert.deepEqual(after.empty, expectEmpty);
  assert.equal(after.contours, before.contours);
  assert.ok(after.preview, "the preview is computed again");
});

test("a stroke drawn while the server is unreachable is kept and sent later, across a reload", async () => {
  const { page, context } = br;
  const extra = [...dense.keys()].find((i) => !sparse.has(i) && i > Math.min(...sparse.keys()));
  await goto(extra);
  const block = (route) =>
    route.request().method() === "GET" ? route.continue() : route.abort("internetdisconnected");
  await context.route("**/api/cells/*/contours", block);
  await trace(dense.get(extra)[0]);
  await page.getByText(/not saved yet/).waitFor();
  await collect();
  await page.reload();
  await waitTracer(page, CELL, { idle: false });
  assert.ok((await summary()).pending >= 1, "still queued after the reload");
  assert.equal((await summary()).onSlice, 1, "and shown");
  await context.unroute("**/api/cells/*/contours", block);
  await page.waitForFunction(() => window.__interslice.tracer().summary().pending === 0, null, { timeout: 30_000 });
  const stored = await page.evaluate(
    (i) => fetch(`/api/cells/cell_001/contours?axis=z&index=${i}`).then((r) => r.json()),
    extra,
  );
  assert.equal(stored.length, 1, "stored once");
  expectDrawn = [...expectDrawn, extra].sort((a, b) => a - b);
});

test("the exported volume matches the phantom's nucleus (Dice > 0.85)", async () => {
  const { page } = br;
  const gt = path.join(demo.dir, "ground_truth", `${CELL}_labels.nii.gz`);
  const viaCli = path.join(demo.scratch, "export-cli.nii.gz");
  cli("export", demo.dir, "--cell", CELL, "--user", USER, "--out", viaCli);
  const dl = page.waitForEvent("download");
  await page.locator("a.exp", { hasText: /^nii\.gz$/ }).click();
  const viaUi = path.join(demo.scratch, "export-ui.nii.gz");
  await (await dl).saveAs(viaUi);
  for (const [how, file] of [
    ["cli", viaCli],
    ["ui", viaUi],
  ]) {
    const m = JSON.parse(cli("evaluate", gt, file, "--label", "2", "--json"));
    out[`dice_${how}`] = m.dice;
    assert.ok(m.dice > 0.85, `${how} export: Dice ${m.dice}`);
  }
});

test("finished cells leave the queue; Next cell opens the next one", async () => {
  const { page } = br;
  await collect();
  await page.locator("#cell-done").check();
  await page.getByTestId("next-cell").click();
  await waitTracer(page, "cell_002");
  await page.goto(`${demo.url}/#/cells`);
  await page.getByTestId("cell-list").locator("tbody tr").first().waitFor();
  const ids = await page
    .getByTestId("cell-list")
    .locator("tbody tr")
    .evaluateAll((rs) => rs.map((r) => r.getAttribute("data-cell")));
  assert.deepEqual(ids, ["cell_002", "cell_003"]);
  await page.locator("#show-done").check();
  await page.locator('[data-cell="cell_001"] .badge.done').waitFor();
  await shot(page, "cell-list");

  out.slice_switch_ms = stats(figures.sliceSwitch);
  out.stroke_latency_ms = stats(figures.strokeLatency);
  out.save_latency_ms = stats(figures.saveLatency);
  out.preview_latency_ms = stats(figures.previewLatency);
  const f = (s) => `median ${s.median.toFixed(1)} ms, p95 ${s.p95.toFixed(1)} ms (n=${s.n})`;
  console.log(`slice switch:    ${f(out.slice_switch_ms)}  (all; not prefetched: ${f(out.slice_switch_uncached_ms)})`);
  console.log(`stroke latency:  ${f(out.stroke_latency_ms)}  (pointer event -> painted)`);
  console.log(`contour saved:   ${f(out.save_latency_ms)}  (pen lift -> stored)`);
  console.log(`preview updated: ${f(out.preview_latency_ms)}  (pen lift -> dashed preview painted)`);
  console.log(`Dice (nucleus):  ${out.dice_cli.toFixed(4)} (export command), ${out.dice_ui.toFixed(4)} (UI download)`);
  if (process.env.E2E_FIGURES) fs.writeFileSync(process.env.E2E_FIGURES, JSON.stringify(out, null, 2) + "\n");
  const errors = br.errors.filter((e) => !/Failed to load resource|ERR_INTERNET_DISCONNECTED/.test(e));
  assert.deepEqual(errors, [], "no errors in the page");
});
