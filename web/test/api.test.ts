import { describe, expect, it } from "vitest";
import { Api, ApiError } from "../src/api";
import { decodeSlice } from "../src/windowing";

describe("API client", () => {
  it("reads raw slices with their size and type headers", async () => {
    const body = new Uint8Array([1, 0, 2, 1, 255, 255]);
    const f = (async () => new Response(body, { status: 200, headers: { "X-Width": "3", "X-Height": "1", "X-Dtype": "u16" } })) as typeof fetch;
    const s = await new Api("", f).slice("c1", "z", 4);
    expect([s.width, s.height, s.dtype]).toEqual([3, 1, "u16"]);
    expect(Array.from(decodeSlice(s.data, s.dtype, s.width, s.height))).toEqual([1, 258, 65535]);
  });

  it("turns {error} answers into ApiError with status and message", async () => {
    const f = (async () => new Response(JSON.stringify({ error: "unknown cell 'x'" }), { status: 404 })) as typeof fetch;
    const e = await new Api("", f).cell("x").catch((x) => x);
    expect(e).toBeInstanceOf(ApiError);
    expect(e.status).toBe(404);
    expect(e.message).toBe("unknown cell 'x'");
  });

  it("me() is null when not signed in and reads auth_required", async () => {
    const f401 = (async () => new Response(JSON.stringify({ error: "not signed in", auth_required: true }), { status: 401 })) as typeof fetch;
    const api = new Api("", f401);
    expect(await api.me()).toBeNull();
    expect(api.authRequired).toBe(true);
    const f200 = (async () => new Response(JSON.stringify({ name: "ann", role: "tracer", auth_required: false }), { status: 200 })) as typeof fetch;
    const api2 = new Api("", f200);
    expect((await api2.me())?.name).toBe("ann");
    expect(api2.authRequired).toBe(false);
  });

  it("sends JSON bodies and encodes ids in paths", async () => {
    const seen: { url: string; init?: RequestInit }[] = [];
    const f = (async (url: RequestInfo | URL, init?: RequestInit) => {
      seen.push({ url: String(url), init });
      return new Response(JSON.stringify({ changed: true }), { status: 200 });
    }) as typeof fetch;
    const api = new Api("", f);
    await api.undo("a b/c");
    await api.markEmpty("c1", "y", 7, 2);
    expect(seen[0].url).toBe("/api/cells/a%20b%2Fc/undo");
    expect(seen[1].url).toBe("/api/cells/c1/slices/y/7/empty");
    expect(JSON.parse(String(seen[1].init?.body))).toEqual({ label: 2 });
    expect(api.exportUrl("c1", "nii.gz")).toBe("/api/cells/c1/export?format=nii.gz");
  });
});
