// Signing in to a server that requires accounts (`interslice serve
// --require-login`, as off loopback): the password field is asked for, a wrong
// password is refused with a message, the right one opens the cell list and
// survives a reload, and signing out returns to the form.
import { after, before, test } from "node:test";
import assert from "node:assert/strict";
import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import { cli, cliWith, startBrowser, startServe } from "./harness.mjs";

let server;
let br;

before(async () => {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), "interslice-e2e-accounts-"));
  cli("demo", dir, "--size", "48", "--count", "1", "--no-serve");
  cliWith({ INTERSLICE_PASSWORD: "correct horse" }, "user", "add", "dave", "--dir", dir);
  server = await startServe(dir, ["--require-login"]);
  br = await startBrowser();
});

after(async () => {
  await br?.close();
  await server?.stop();
});

test("an account's password is asked, checked and remembered for the session", async () => {
  const { page } = br;
  await page.goto(server.url);
  const pass = page.getByTestId("user-password");
  // On a loopback address a name is usually enough; this server says otherwise.
  await page.getByTestId("user-name").fill("dave");
  await page.getByTestId("sign-in").click();
  await page.getByTestId("login-error").filter({ hasText: "requires a password" }).waitFor();
  assert.ok(await pass.isVisible(), "the password field is shown");
  await pass.fill("wrong password");
  await page.getByTestId("sign-in").click();
  await page.getByTestId("login-error").filter({ hasText: "wrong name or password" }).waitFor();
  await pass.fill("correct horse");
  await page.getByTestId("sign-in").click();
  await page.getByTestId("cell-list").locator("tbody tr").first().waitFor();
  await page.reload();
  await page.getByTestId("cell-list").locator("tbody tr").first().waitFor();
  await page.getByRole("button", { name: "Sign out" }).click();
  await page.getByTestId("user-name").waitFor();
  const errors = br.errors.filter((e) => !/Failed to load resource/.test(e));
  assert.deepEqual(errors, [], "no errors in the page");
});
