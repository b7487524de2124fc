import { describe, expect, it } from "vitest";
import { Api, ApiError } from "../src/api";

/** A fetch that answers every request with `body` and `status`. */
function answering(status: number, body: string, type = "application/json"): typeof fetch {
  return () =>
    Promise.resolve(
      new Response(body, {
        status,
        statusText: status === 502 ? "Bad Gateway" : "",
        headers: { "Content-Type": type },
      }),
    );
}

async function failure(p: Promise<unknown>): Promise<ApiError> {
  try {
    await p;
  } catch (e) {
    expect(e).toBeInstanceOf(ApiError);
    return e as ApiError;
  }
  throw new Error("expected a failure");
}

describe("API client errors", () => {
  it("shows the server's one-line message", async () => {
    const api = new Api("", answering(400, JSON.stringify({ error: "unknown label 9 (GET /api/labels)" })));
    const e = await failure(api.labels());
    expect(e.status).toBe(400);
    expect(e.message).toBe("unknown label 9 (GET /api/labels)");
  });

  it("names the status of an answer that is not JSON", async () => {
    const api = new Api("", answering(502, "<html>Bad Gateway</html>", "text/html"));
    expect((await failure(api.cells())).message).toBe("502 Bad Gateway");
  });

  it("refuses a successful answer that is not JSON with a clear message", async () => {
    const api = new Api("", answering(200, "<html>login portal</html>", "text/html"));
    expect((await failure(api.methods())).message).toBe("the server's answer to GET /api/methods is not JSON");
  });

  it("reads the 401 body's auth_required", async () => {
    const api = new Api("", answering(401, JSON.stringify({ error: "sign in", auth_required: true })));
    expect(await api.me()).toBeNull();
    expect(api.authRequired).toBe(true);
  });
});
