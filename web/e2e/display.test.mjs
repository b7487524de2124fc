// Looking at a cell, against the real `interslice demo` server: linked views
// (a click on a small view moves the working slice), zoom about the cursor,
// keyboard stepping, window/level and brightness on 8- and 16-bit data, the
// status line, adding a component.
import { after, before, test } from "node:test";
import assert from "node:assert/strict";
import fs from "node:fs";
import path from "node:path";
import { cli, signIn, startBrowser, startDemo, waitTracer } from "./harness.mjs";

let demo;
let br;

const summary = () => br.page.evaluate(() => window.__interslice.tracer().summary());
const client = (axis, u, v) => br.page.evaluate(([a, x, y]) => window.__interslice.tracer().sliceToClient(a, x, y), [axis, u, v]);
const num = async (testid) => Number(await br.page.getByTestId(testid).inputValue());

before(async () => {
  demo = await startDemo();
  // A 16-bit cell next to the demo's 8-bit ones.
  const ph = path.join(demo.scratch, "phantom16");
  cli("phantom", "--out", ph, "--count", "1", "--size", "64", "--bits", "16", "--quiet");
  fs.copyFileSync(path.join(ph, "cell_001.nii.gz"), path.join(demo.dir, "deep_16bit.nii.gz"));
  br = await startBrowser();
  await signIn(br.page, demo.url, "carol");
});

after(async () => {
  await br?.close();
  await demo?.stop();
});

test("a click on a small view moves the working slice there; the keys step by the skip", async () => {
  const { page } = br;
  await page.getByTestId("open-cell-cell_002").click();
  await waitTracer(page, "cell_002");
  assert.equal((await summary()).axis, "z");
  // View x shows (j, k): clicking at k = 40 brings the working z view to slice 40.
  const [x, y] = await client("x", 64.5, 40.5);
  await page.mouse.click(x, y);
  await page.getByTestId("status-slice").filter({ hasText: "slice 40 /" }).waitFor();
  await page.getByTestId("skip-step").fill("4");
  await page.getByTestId("skip-step").press("Enter");
  await page.getByTestId("view-z").focus();
  await page.keyboard.press("ArrowRight");
  await page.getByTestId("status-slice").filter({ hasText: "slice 44 /" }).waitFor();
  await page.keyboard.press("Shift+ArrowRight");
  await page.getByTestId("status-slice").filter({ hasText: "slice 45 /" }).waitFor();
  await page.keyboard.press("ArrowLeft");
  await page.getByTestId("status-slice").filter({ hasText: "slice 41 /" }).waitFor();
  await page.keyboard.press("y");
  assert.equal((await summary()).axis, "y");
  await page.keyboard.press("z");
  assert.equal((await summary()).axis, "z");
});

test("the wheel zooms about the cursor", async () => {
  const { page } = br;
  const [x, y] = await client("z", 40, 50);
  const far0 = await client("z", 80, 50);
  await page.mouse.move(x, y);
  await page.mouse.wheel(0, -400);
  await page.waitForFunction(([fx]) => window.__interslice.tracer().sliceToClient("z", 80, 50)[0] > fx + 20, far0);
  const [x1, y1] = await client("z", 40, 50);
  // Within the rounding of the mouse position to whole CSS pixels.
  assert.ok(Math.hypot(x1 - x, y1 - y) < 1, `the point under the cursor stays (${x1 - x}, ${y1 - y})`);
  await page.keyboard.press("0");
});

test("window/level and brightness on 8-bit data; the status line reads the voxel under the cursor", async () => {
  const { page } = br;
  await page.getByTestId("auto-window").click();
  const lo = await num("window-low");
  const hi = await num("window-high");
  assert.ok(lo >= 0 && hi <= 255 && hi > lo, `8-bit window ${lo}..${hi}`);
  await page.getByTestId("brightness").fill("50");
  assert.ok((await num("window-high")) < hi, "brighter: the window moves down");
  await page.getByTestId("contrast").fill("25");
  const w = (await num("window-high")) - (await num("window-low"));
  assert.ok(Math.abs(w - (hi - lo) / 2) <= 1, `contrast +25 halves the width (${w} vs ${hi - lo})`);
  await page.getByTestId("auto-window").click();
  const [x, y] = await client("z", 64.5, 64.5);
  await page.mouse.move(x, y);
  await page.getByTestId("status-voxel").filter({ hasText: "(64, 64, 41)" }).waitFor();
  assert.match(await page.getByTestId("status-value").textContent(), /^value \d+$/);
});

test("16-bit data: the automatic window and the values are in the raw range", async () => {
  const { page } = br;
  await page.goto(`${demo.url}/#/cells`);
  await page.getByTestId("open-cell-deep_16bit").click();
  await waitTracer(page, "deep_16bit");
  await page.getByTestId("auto-window").click();
  const hi = await num("window-high");
  assert.ok(hi > 255, `16-bit window reaches ${hi}`);
  const [x, y] = await client("z", 32.5, 32.5);
  await page.mouse.move(x, y);
  await page.getByTestId("status-voxel").filter({ hasText: "(32, 32," }).waitFor();
  const v = Number((await page.getByTestId("status-value").textContent()).replace("value ", ""));
  assert.ok(v > 255, `raw 16-bit value under the cursor: ${v}`);
});

test("add a component: it gets a colour and is selected", async () => {
  const { page } = br;
  await page.getByTestId("new-label-name").fill("Nucleolus 3");
  await page.getByTestId("new-label-add").click();
  await page.getByTestId("label-select").locator("option", { hasText: "Nucleolus 3" }).waitFor({ state: "attached" });
  const sel = await page.getByTestId("label-select").inputValue();
  const labels = await page.evaluate(() => fetch("/api/labels").then((r) => r.json()));
  const added = labels.find((l) => l.name === "Nucleolus 3");
  assert.ok(added && /^#[0-9a-f]{6}$/i.test(added.color), "stored with a colour");
  assert.equal(sel, String(added.id));
  const errors = br.errors.filter((e) => !/Failed to load resource/.test(e));
  assert.deepEqual(errors, [], "no errors in the page");
});
