// Evaluating an automated segmentation against this user's ground truth in the
// UI, against the real `interslice demo` server: run a threshold segmentation,
// compare it (metrics table), show its false positives and false negatives on
// the slices, rate it 1-5 with a comment; a failing comparison is shown as a
// message. The ground truth is the phantom's nucleus on every 5th slice, stored
// through the API (tracing it with the pen is the tracing suite's job).
import { after, before, test } from "node:test";
import assert from "node:assert/strict";
import fs from "node:fs";
import path from "node:path";
import { cli, shot, signIn, startBrowser, startDemo, waitTracer } from "./harness.mjs";

const USER = "bob";
const CELL = "cell_001";

let demo;
let br;
let nucleus;

before(async () => {
  demo = await startDemo();
  br = await startBrowser();
  await signIn(br.page, demo.url, USER);
  const gt = path.join(demo.dir, "ground_truth", `${CELL}_labels.nii.gz`);
  const file = path.join(demo.scratch, "contours.json");
  cli("contours", "extract", gt, "--every", "5", "--out", file);
  const contours = JSON.parse(fs.readFileSync(file, "utf8")).contours.filter((c) => c.label === 2 && c.axis === "z");
  const labels = await br.page.evaluate(() => fetch("/api/labels").then((r) => r.json()));
  nucleus = labels.find((l) => /nucleus/i.test(l.name));
  const stored = await br.page.evaluate(
    async ([cell, label, cs]) => {
      let n = 0;
      for (const c of cs) {
        const r = await fetch(`/api/cells/${cell}/contours`, {
          method: "POST",
          headers: { "Content-Type": "application/json" },
          body: JSON.stringify({ label, axis: "z", index: c.index, points: c.points }),
        });
        if (r.ok) n++;
      }
      return n;
    },
    [CELL, nucleus.id, contours],
  );
  assert.equal(stored, contours.length);
});

after(async () => {
  await br?.close();
  await demo?.stop();
});

test("run a segmentation, compare it with my ground truth, see FP/FN on the slices", async () => {
  const { page } = br;
  await page.getByTestId(`open-cell-${CELL}`).click();
  await waitTracer(page, CELL);
  await page.getByTestId("label-select").selectOption(String(nucleus.id));
  await page.getByTestId("seg-method").selectOption("multi-otsu");
  await page.getByTestId("seg-run").click();
  await page.waitForFunction(
    () => {
      const s = document.querySelector('[data-testid="seg-select"]');
      return s && s.value !== "";
    },
    null,
    { timeout: 60_000 },
  );
  const overlays = [];
  page.on("response", (r) => {
    if (r.url().includes("/overlay/")) overlays.push(r.status());
  });
  await page.getByTestId("evaluate").click();
  const dice = page.getByTestId("metrics-table").locator('td[data-key="dice"]');
  await dice.waitFor({ timeout: 60_000 });
  const d = Number(await dice.textContent());
  assert.ok(d >= 0 && d <= 1, `Dice shown: ${d}`);
  for (const k of ["jaccard", "sensitivity", "precision", "hd95", "assd", "volume_gt", "fp", "fn"]) {
    assert.equal(
      await page.getByTestId("metrics-table").locator(`td[data-key="${k}"]`).count(),
      1,
      `${k} in the table`,
    );
  }
  assert.ok(await page.getByTestId("show-overlay").isChecked(), "the FP/FN overlay is switched on");
  await page.waitForFunction(() => window.__interslice.tracer().summary().overlay, null, { timeout: 30_000 });
  assert.ok(overlays.length >= 1 && overlays.every((s) => s === 200), `overlay answers: ${overlays.join(", ")}`);
  // Closer on the nucleus, so the FP/FN border shows.
  await page.getByTestId("view-z").focus();
  await page.keyboard.press("+");
  await page.keyboard.press("+");
  await page.getByTestId("metrics-table").scrollIntoViewIfNeeded();
  await shot(page, "evaluation");
});

test("rate the segmentation 1-5 with a comment", async () => {
  const { page } = br;
  await page.getByTestId("rating-stars").locator("button").nth(3).click();
  await page.getByTestId("rating-comment").fill("misses the lower pole");
  await page.getByTestId("rating-save").click();
  await page.getByTestId("eval-panel").getByText("misses the lower pole").waitFor();
  const seg = await page.getByTestId("seg-select").inputValue();
  const ratings = await page.evaluate((c) => fetch(`/api/cells/${c}/ratings`).then((r) => r.json()), CELL);
  const mine = ratings.filter((r) => r.segmentation === seg && r.user === USER);
  assert.equal(mine.length, 1);
  assert.equal(mine[0].score, 4);
  assert.equal(mine[0].comment, "misses the lower pole");
});

test("a comparison without ground truth, or that the server fails, is explained", async () => {
  const { page, context } = br;
  // Nothing traced for the cell component: the server's reason is shown.
  await page.getByTestId("label-select").selectOption("1");
  await page.getByTestId("evaluate").click();
  const none = page.getByTestId("metrics-table").locator(".err", { hasText: "nothing traced" });
  await none.waitFor();
  assert.match(await none.textContent(), /^evaluation: nothing traced on cell '[^']+' by this user for label 1$/);
  // A failing server: its one-line message is shown, the screen stays usable.
  const fail = (route) =>
    route.fulfill({
      status: 500,
      contentType: "application/json",
      body: JSON.stringify({ error: "the database is locked" }),
    });
  await context.route("**/evaluate", fail);
  await page.getByTestId("evaluate").click();
  const msg = page.getByTestId("metrics-table").locator(".err");
  await msg.waitFor();
  assert.equal(await msg.textContent(), "evaluation: the database is locked");
  await context.unroute("**/evaluate", fail);
  // An answer that is not JSON (a proxy's error page): still a message, not a blank panel.
  const proxy = (route) => route.fulfill({ status: 502, contentType: "text/html", body: "<html>Bad Gateway</html>" });
  await context.route("**/evaluate", proxy);
  await page.getByTestId("evaluate").click();
  await page.getByTestId("metrics-table").locator(".err", { hasText: "502" }).waitFor();
  await context.unroute("**/evaluate", proxy);
  const errors = br.errors.filter((e) => !/Failed to load resource/.test(e));
  assert.deepEqual(errors, [], "no errors in the page");
});
