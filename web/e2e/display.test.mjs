// Looking at a cell, against the real `interslice demo` server: linked views
// (a click on a small view moves the working slice), zoom about the cursor,
// keyboard stepping, window/level and brightness on 8- and 16-bit data, the
// status line, adding a component; signed (CT in Hounsfield units), float and
// scaled (NIfTI scl_slope/scl_inter) volumes shown right in all three views.
import { after, before, test } from "node:test";
import assert from "node:assert/strict";
import fs from "node:fs";
import path from "node:path";
import {
  cli,
  greysIn,
  painted,
  pixelsIn,
  signIn,
  startBrowser,
  startDemo,
  viewStats,
  waitTracer,
  writeNifti,
} from "./harness.mjs";

let demo;
let br;

/** Dims of the synthetic scans: all different, so a wrong stride on any axis shows. */
const SCAN = [96, 80, 40];

/**
 * A chest-CT-like volume in Hounsfield units (air -1000 around a body of soft
 * tissue at 40 with two lungs at -850 and a spine at 700, a little noise) and
 * an MR-like float volume (0 outside, a smooth 200..800 inside an
 * ellipsoid), written as int16, as uint16 with scl_inter -1024 (how scanners
 * often store CT: read as calibrated floats) and as float32.
 */
function writeSyntheticScans(dir) {
  const [nx, ny, nz] = SCAN;
  const n = nx * ny * nz;
  const hu = new Int16Array(n);
  const mr = new Float32Array(n);
  let seed = 7;
  const noise = () => ((seed = (seed * 1103515245 + 12345) % 2147483648) / 2147483648 - 0.5) * 2;
  for (let k = 0; k < nz; k++)
    for (let j = 0; j < ny; j++)
      for (let i = 0; i < nx; i++) {
        const p = i + nx * (j + ny * k);
        const e = (x, y, z, rx, ry, rz) => ((i - x) / rx) ** 2 + ((j - y) / ry) ** 2 + ((k - z) / rz) ** 2;
        let v = -1000 + 8 * noise();
        if (e(48, 40, 0, 42, 32, 1e9) < 1) v = 40 + 10 * noise();
        if (e(30, 38, 20, 12, 15, 16) < 1 || e(66, 38, 20, 12, 15, 16) < 1) v = -850 + 20 * noise();
        if (e(48, 64, 0, 6, 5, 1e9) < 1) v = 700 + 30 * noise();
        hu[p] = Math.round(v);
        const r = e(48, 40, 20, 38, 30, 17);
        mr[p] = r < 1 ? 200 + 600 * (1 - r) + 0.37 * noise() : Math.abs(3 * noise());
      }
  const spacing = [0.8, 0.8, 2.5];
  writeNifti(path.join(dir, "ct_i16.nii"), { dims: SCAN, spacing, values: hu });
  writeNifti(path.join(dir, "ct_u16_scaled.nii"), {
    dims: SCAN,
    spacing,
    values: Uint16Array.from(hu, (x) => x + 1024),
    slope: 1,
    inter: -1024,
  });
  writeNifti(path.join(dir, "mr_f32.nii"), { dims: SCAN, spacing, values: mr });
}

const summary = () => br.page.evaluate(() => window.__interslice.tracer().summary());
const client = (axis, u, v) =>
  br.page.evaluate(([a, x, y]) => window.__interslice.tracer().sliceToClient(a, x, y), [axis, u, v]);
const num = async (testid) => Number(await br.page.getByTestId(testid).inputValue());

before(async () => {
  demo = await startDemo();
  // A 16-bit cell next to the demo's 8-bit ones.
  const ph = path.join(demo.scratch, "phantom16");
  cli("phantom", "--out", ph, "--count", "1", "--size", "64", "--bits", "16", "--quiet");
  fs.copyFileSync(path.join(ph, "cell_001.nii.gz"), path.join(demo.dir, "deep_16bit.nii.gz"));
  writeSyntheticScans(demo.dir);
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

test("signed, scaled and float scans: air dark, anatomy in all three views, values in the file's units", async () => {
  const { page } = br;
  for (const [cell, dtype] of [
    ["ct_i16", "i16"],
    ["ct_u16_scaled", "f32"],
    ["mr_f32", "f32"],
  ]) {
    await page.goto(`${demo.url}/#/cells`);
    await page.getByTestId(`open-cell-${cell}`).click();
    await waitTracer(page, cell);
    await painted(page);
    assert.equal(await page.evaluate(() => window.__interslice.tracer().cell.dtype), dtype, cell);
    const ct = cell.startsWith("ct");
    assert.equal(await page.getByTestId("window-preset").inputValue(), ct ? "ct-lung" : "auto", `${cell}: preset`);
    for (const a of ["x", "y", "z"]) {
      const s = await viewStats(page, a);
      assert.ok(
        s.neighbour < 0.5 && s.std > 30,
        `${cell} view ${a}: anatomy, not noise or stripes: ${JSON.stringify(s)}`,
      );
      if (ct) {
        const air = await greysIn(page, a, -1100, -980);
        const tissue = await greysIn(page, a, 20, 60);
        assert.ok(air.n > 0 && air.max <= 62, `${cell} view ${a}: air dark ${JSON.stringify(air)}`);
        assert.ok(tissue.n > 0 && tissue.min >= 234, `${cell} view ${a}: soft tissue bright ${JSON.stringify(tissue)}`);
      } else {
        const outside = await greysIn(page, a, 0, 3);
        const inside = await greysIn(page, a, 700, 800);
        assert.ok(outside.n > 0 && outside.max <= 10, `${cell} view ${a}: background dark ${JSON.stringify(outside)}`);
        assert.ok(inside.n > 0 && inside.min >= 200, `${cell} view ${a}: bright centre ${JSON.stringify(inside)}`);
      }
    }
    // The value under the cursor, as the file means it (Hounsfield units for the scaled file).
    const [[u, v, val]] = await pixelsIn(page, "z", ct ? -1100 : 700, ct ? -980 : 800, 1);
    const [x, y] = await page.evaluate(
      ([uu, vv]) => window.__interslice.tracer().sliceToClient("z", uu + 0.5, vv + 0.5),
      [u, v],
    );
    await page.mouse.move(x, y);
    const want = dtype === "f32" ? String(Number(Math.fround(val).toPrecision(6))) : String(val);
    await page
      .getByTestId("status-value")
      .filter({ hasText: new RegExp(`^value ${want}$`) })
      .waitFor();
    if (ct) assert.ok(Number(want) <= -980, `${cell}: air in Hounsfield units (${want})`);
  }
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
